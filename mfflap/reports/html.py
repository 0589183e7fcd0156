"""A small self-contained HTML report: sections of text, tables and embedded PNG figures."""

from __future__ import annotations

import base64
import datetime as _dt
import html
import io
import re
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

import jinja2
import numpy as np
from matplotlib.figure import Figure

from mfflap.atomic_write import commit, temporary_beside
from mfflap.version import __version__

_TEMPLATE = jinja2.Template("""<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><title>{{ title }}</title>
<style>
body { font-family: sans-serif; max-width: 1100px; margin: 2em auto; color: #222; }
table { border-collapse: collapse; margin: 1em 0; }
td, th { border: 1px solid #bbb; padding: 3px 8px; text-align: right; }
th { background: #eee; } td:first-child, th:first-child { text-align: left; }
.warn { background: #fff3cd; border-left: 4px solid #e0a800; padding: 0.5em 1em; }
pre { font-size: 85%; overflow-x: auto; }
img { max-width: 100%; } figure { margin: 1em 0; } figcaption { color: #555; }
</style></head><body>
<h1>{{ title }}</h1><p>{{ subtitle }}</p>
{% for s in sections %}<section id="s{{ loop.index }}"><h2>{{ s.title }}</h2>
{% for block in s.blocks %}{{ block }}
{% endfor %}</section>
{% if loop.first and sections|length > 2 %}<nav><h2>Contents</h2><ol>
{% for t in sections[1:] %}<li><a href="#s{{ loop.index + 1 }}">{{ t.title }}</a></li>
{% endfor %}</ol></nav>{% endif %}{% endfor %}
<hr><p><small>mfflap {{ version }}, {{ created }}</small></p></body></html>
""")


def figure_html(fig: Figure, caption: str = "", dpi: int = 110) -> str:
    """An ``<figure>`` with the PNG embedded (base64), drawn once as the figure is laid out
    (its own layout must keep its text within its canvas); closes the figure."""
    # matplotlib takes about a second to load: only figures need it
    import matplotlib.pyplot as plt
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    # drawn once: savefig would lay out a figure that tight_layout() laid out already again,
    # in a pass of its own that costs as much as the drawing (a layout engine of the figure
    # still runs in the one draw)
    fig.set_dpi(dpi)
    buf = io.BytesIO()
    FigureCanvasAgg(fig).print_png(buf)
    plt.close(fig)
    data = base64.b64encode(buf.getvalue()).decode()
    return (f'<figure><img src="data:image/png;base64,{data}" alt="{html.escape(caption)}">'
            f"<figcaption>{html.escape(caption)}</figcaption></figure>")


def signed_percent(fraction: float | None) -> str:
    """A fraction as a signed percentage with one decimal, or a dash where it was not
    computed (None or NaN)."""
    return "–" if fraction is None or not np.isfinite(fraction) else f"{fraction:+.1%}"


def _first_line_and_fold(text: str) -> tuple[str, str]:
    """``text``'s first line (escaped) and the rest folded into a ``<details>`` block.

    The rest keeps its lines in a ``<pre>``, headed by its ``--- label ---`` line when it
    has one (an error's "last log lines"), else by "more"; "" when there is no rest.
    """
    first, _, rest = text.partition("\n")
    if not rest.strip():
        return html.escape(text), ""
    label = "more"
    header = re.match(r"\s*--- (.+?) ---[ \t]*\n", rest)
    if header:
        label, rest = header.group(1), rest[header.end():]
    return html.escape(first), (f"<details><summary>{html.escape(label)}</summary>"
                                f"<pre>{html.escape(rest.strip(chr(10)))}</pre></details>")


def folded_html(summary: str, body: str) -> str:
    """``body`` (HTML) folded under a ``<details>`` line reading ``summary``, for what a
    reader opens only to check where a number came from."""
    return f"<details><summary>{html.escape(summary)}</summary>{body}</details>"


def table_html(header: Sequence[str], rows: Sequence[Sequence[object]]) -> str:
    """A table; floats are shown with 4 significant digits, None as a dash, text of several
    lines as its first line with the rest folded (see `text_html`)."""
    def cell(v):
        if v is None:
            return "-"
        return f"{v:.4g}" if isinstance(v, float) else "".join(_first_line_and_fold(str(v)))

    head = "".join(f"<th>{html.escape(h)}</th>" for h in header)
    body = "".join("<tr>" + "".join(f"<td>{cell(v)}</td>" for v in r) + "</tr>" for r in rows)
    return f"<table><tr>{head}</tr>{body}</table>"


def text_html(text: str, warn: bool = False) -> str:
    """A paragraph (escaped); ``warn`` highlights it.

    Text of several lines (an error with the solver's last log lines) keeps its first line
    as the paragraph and the rest line by line in a folded ``<pre>`` block, headed by its
    ``--- label ---`` line when it has one, so the log stays readable and out of the way.
    """
    cls = ' class="warn"' if warn else ""
    first, fold = _first_line_and_fold(text)
    if not fold:
        return f"<p{cls}>{first}</p>"
    return f"<div{cls}><p>{first}</p>{fold}</div>"


@dataclass
class Section:
    """A titled section of HTML blocks."""

    title: str
    blocks: list[str] = field(default_factory=list)


@dataclass
class Report:
    """A report being assembled."""

    title: str
    subtitle: str = ""
    sections: list[Section] = field(default_factory=list)

    def section(self, title: str) -> Section:
        """Start a new section and return it."""
        s = Section(title)
        self.sections.append(s)
        return s

    def write(self, path: str | Path) -> Path:
        """Write the HTML file."""
        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        # beside it first, then in its place: a stop while writing keeps the report before
        beside = temporary_beside(path)
        try:
            beside.write_text(_TEMPLATE.render(
                title=html.escape(self.title), subtitle=html.escape(self.subtitle),
                sections=self.sections, version=__version__,
                created=_dt.datetime.now(_dt.UTC).strftime("%Y-%m-%d %H:%M UTC")))
            commit(beside, path)
        finally:
            beside.unlink(missing_ok=True)
        return path
