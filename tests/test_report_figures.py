"""Report figures embedded in HTML (mfflap.reports.html.figure_html)."""

import base64
import io
import re

import matplotlib.pyplot as plt
from PIL import Image

from mfflap.reports.html import figure_html


def _png_size(html: str) -> tuple[int, int]:
    data = re.search(r'base64,([^"]+)"', html).group(1)
    return Image.open(io.BytesIO(base64.b64decode(data))).size


def test_a_laid_out_figure_is_drawn_at_its_size_and_another_is_cropped_to_its_ink():
    open_before = set(plt.get_fignums())  # other tests' figures in this process
    laid_out, ax = plt.subplots(figsize=(4, 3))
    ax.plot([0, 1], [0, 1])
    laid_out.tight_layout()
    assert _png_size(figure_html(laid_out, "a", dpi=100)) == (400, 300)
    loose, ax = plt.subplots(figsize=(4, 3))
    ax.plot([0, 1], [0, 1])
    ax.set_ylabel("a label far off the axes", labelpad=60)
    width, height = _png_size(figure_html(loose, "b", dpi=100))
    assert (width, height) != (400, 300)  # its bounding box, the label kept
    constrained, ax = plt.subplots(figsize=(4, 3), layout="constrained")
    html = figure_html(constrained, "c <d>", dpi=100)
    assert _png_size(html) == (400, 300)
    assert "<figcaption>c &lt;d&gt;</figcaption>" in html
    assert set(plt.get_fignums()) == open_before  # each of these figures closed
