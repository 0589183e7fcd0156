"""MkDocs hook: pages whose text the code writes (the case-file reference) or that live
outside docs/ (the changelog)."""

from __future__ import annotations

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
