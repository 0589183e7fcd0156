"""The HTML report's text blocks: a failed run's log lines stay lines, folded away."""

import re

from mfflap.errors import CfdRunError
from mfflap.reports.html import Report, text_html


def test_a_one_line_text_is_one_escaped_paragraph():
    assert text_html("F_n < 2 % & M", warn=True) == '<p class="warn">F_n &lt; 2 % &amp; M</p>'


def test_a_failed_runs_log_lines_are_kept_line_by_line_in_a_folded_block(tmp_path):
    log = "PIMPLE: iteration 1\nDICPCG:  Solving for p, <residual> = 1e-3\nTime = 0.83"
    err = CfdRunError("pimpleFoam stopped: the time step collapsed", case="cases/f1",
                      log_tail=log)
    block = text_html(f"identification: case f1 left out: {err}", warn=True)
    first = ("identification: case f1 left out: case cases/f1: pimpleFoam stopped: the time "
             "step collapsed")
    assert block.startswith(f'<div class="warn"><p>{first}</p><details>')
    assert "<summary>last log lines</summary>" in block
    pre = re.search(r"<pre>(.*)</pre>", block, re.S).group(1)
    assert pre.splitlines() == ["PIMPLE: iteration 1",
                                "DICPCG:  Solving for p, &lt;residual&gt; = 1e-3",
                                "Time = 0.83"]
    # without a "--- label ---" line the rest is folded under "more"
    assert "<summary>more</summary><pre>second\nthird</pre>" in text_html("first\nsecond\nthird")
    report = Report("r")
    report.section("Summary").blocks.append(block)
    page = report.write(tmp_path / "report.html").read_text()
    assert "pre {" in page and block in page


def test_a_table_cell_of_several_lines_folds_its_rest():
    from mfflap.reports.html import table_html

    table = table_html(["case", "reason"], [("f1", "CFD failed\n--- last log lines ---\na\nb"),
                                            ("f2", 0.123456)])
    assert "<td>CFD failed<details><summary>last log lines</summary><pre>a\nb</pre>" in table
    assert "<td>0.1235</td>" in table
