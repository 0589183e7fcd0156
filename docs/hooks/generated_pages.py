"""MkDocs hook: pages whose text the code writes (the case-file reference) or that live
outside docs/ (the changelog)."""

from __future__ import annotations

import re
from pathlib import Path

#: the marker a page holds where the case-file reference goes
CASE_FILE_MARKER = "<!-- case-file-reference -->"
#: the marker a page holds where CHANGELOG.md goes
CHANGELOG_MARKER = "<!-- changelog -->"


def on_page_markdown(markdown: str, page, config, files) -> str:
    """Replace the marker with the reference written from mfflap's case-file dataclasses."""
    if CHANGELOG_MARKER in markdown:
        changelog = Path(config["config_file_path"]).parent / "CHANGELOG.md"
        text = changelog.read_text().split("\n", 1)[1]  # the page has its own title
        markdown = markdown.replace(CHANGELOG_MARKER, text)
    if CASE_FILE_MARKER in markdown:
        from mfflap.config_reference import case_file_reference_markdown

        markdown = markdown.replace(CASE_FILE_MARKER, case_file_reference_markdown())
    return markdown


#: a default mkdocs-click shows for an option without one (click's own marker)
_UNSET_DEFAULT = re.compile(r"<td><code>Sentinel\.UNSET</code></td>")
#: a Sphinx cross-reference role left in a numpydoc docstring (:func:`name`), as rendered
_SPHINX_ROLE = re.compile(r":(?:func|class|meth|mod|data|attr|exc|obj):<code>~?([^<]*)</code>")


def on_page_content(html: str, page, config, files) -> str:
    """The command-line table without click's marker for "no default", and the docstrings'
    Sphinx roles as plain code (the name alone where the role shortened it with ``~``)."""
    html = _UNSET_DEFAULT.sub("<td>(none)</td>", html)
    return _SPHINX_ROLE.sub(lambda m: f"<code>{m.group(1)}</code>", html)
