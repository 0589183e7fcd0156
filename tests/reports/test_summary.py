"""The run report's summary (mfflap.reports.summary): what the run found and whether CFD
confirmed it, on the first screen of a real browser."""

import shutil
from pathlib import Path

import pytest

from mfflap.config import load_case
from mfflap.pipeline import RunOptions, run_study
from mfflap.reports.run import write_run_report
from mfflap.reports.summary import _efficiency, headline, motion_rows

CASE = Path(__file__).parents[2] / "cases" / "paper2026.toml"


def test_efficiency_is_given_only_where_a_motion_makes_thrust_for_power():
    assert _efficiency(10.0, 30.0, 0.3) == "10%"
    assert _efficiency(-1.0, 0.2, 0.3) == "–"  # drag, not propulsion
    assert _efficiency(1.0, 0.0, 0.3) == "–"


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    """The main job on the shipped records as the case file sets it (no IPOPT, no
    coefficient sensitivity), whose back-tests ship in backtest_main_job: its case, outcome
    and report."""
    from dataclasses import replace

    config = load_case(CASE)
    folder = tmp_path_factory.mktemp("report")
    options = replace(RunOptions.for_case(config, folder), with_ipopt=False,
                      sensitivity=False, vtk_dir=None)
    outcome = run_study(config, options, progress=lambda m: None)
    html = folder / "report.html"
    write_run_report(config, outcome, html, "the shipped records")
    return config, outcome, html


@pytest.mark.slow
def test_the_summary_gives_each_motions_model_and_cfd_figures(run):
    config, outcome, _ = run
    rows = {r[0]: r for r in motion_rows(config, outcome)}
    assert {"best sinusoid", "β = 0", "β = 0.5", "β = 1", "β = 0 polished"} <= set(rows)
    for label, o in outcome.backtests.items():
        c = o.comparison
        if c is None:  # a polish that ended where no CFD ships (see test_run's main job)
            assert label.endswith("polished") and "no CFD fixture" in o.source
            continue
        assert rows[label][1:5] == [c.model_mean_thrust, c.cfd_mean_thrust,
                                    c.model_mean_power, c.cfd_mean_power]
        assert rows[label][-1] == ("yes" if c.max_power_ok else "NO")
    lines = headline(config, outcome)
    said = " ".join(lines)
    assert "in CFD (the model predicted" in said and "P_max = 50 W" in said
    # first: the best motion within P_max in CFD against the best sinusoid within it in CFD
    baseline = outcome.cfd_baseline
    assert baseline is not None and baseline.best is not None
    assert lines[0].startswith("Within P_max = 50 W in CFD: ")
    assert f"{baseline.best.mean_thrust_n:.3g} ± " in lines[0]
    # the polish's CFD, against the vortex model's prediction of it, where it ships
    polished = outcome.backtests["β = 0 polished"].comparison
    assert polished is None or (
        f"β = 0 gives {polished.cfd_mean_thrust:.3g} N mean thrust in CFD at a peak power "
        f"of {polished.cfd_max_power:.3g} W") in said
    assert outcome.gap[0].verdict in said


@pytest.mark.slow
def test_the_summarys_numbers_are_on_the_first_screen_in_chromium(run):
    """Headless Chromium (Debian's, through its WebDriver) opens the report in a 1280 x 900
    window: the headline, the CFD mean thrust of every back-tested motion and the verdict
    are drawn above the fold, the contents list follows the summary."""
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service
    from selenium.webdriver.common.by import By

    _, outcome, html = run
    options = webdriver.ChromeOptions()
    for arg in ("--headless=new", "--no-sandbox", "--disable-gpu", "--window-size=1280,900"):
        options.add_argument(arg)
    options.binary_location = shutil.which("chromium") or "/usr/bin/chromium"
    driver = webdriver.Chrome(options=options,
                              service=Service(shutil.which("chromedriver")))
    try:
        driver.get(html.as_uri())
        height = driver.execute_script("return window.innerHeight")
        summary = driver.find_element(By.ID, "s1")
        assert summary.find_element(By.TAG_NAME, "h2").text == "Summary"
        visible = [e for e in summary.find_elements(By.CSS_SELECTOR, "p, td")
                   if e.rect["y"] + e.rect["height"] <= height]
        shown = " ".join(e.text for e in visible)
        assert "Within P_max = 50 W in CFD: " in shown  # the CFD-confirmed pair first
        assert "over the model's best feasible sinusoid in CFD" in shown
        for o in outcome.backtests.values():
            if o.comparison is not None:
                assert f"{o.comparison.cfd_mean_thrust:.4g}" in shown
        assert "P_max = 50 W" in shown
        contents = driver.find_element(By.TAG_NAME, "nav")
        assert contents.rect["y"] > summary.rect["y"]
        titles = [a.text for a in contents.find_elements(By.TAG_NAME, "a")]
        assert "Back-test against CFD" in titles
    finally:
        driver.quit()


def _fit_of(fig) -> tuple[float, float]:
    """How far a figure's drawn content runs past its canvas (> 0: clipped) and the
    widest empty margin inside it, inches."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    canvas = FigureCanvasAgg(fig)
    canvas.draw()
    box = fig.get_tightbbox(canvas.get_renderer())
    width, height = fig.get_size_inches()
    over = max(-box.x0, -box.y0, box.x1 - width, box.y1 - height)
    margin = max(box.x0, box.y0, width - box.x1, height - box.y1)
    return float(over), float(margin)


@pytest.mark.slow
def test_every_report_figure_fits_its_canvas(run, monkeypatch, tmp_path):
    """The report saves each figure as laid out, once (no second layout pass to trim it):
    so each figure's text and legends must lie within its canvas, with no wide empty
    margin."""
    import sys

    config, outcome, _ = run
    seen: list[tuple[str, float, float]] = []
    for name, module in list(sys.modules.items()):
        original = getattr(module, "figure_html", None)
        if name.startswith("mfflap.reports") and callable(original):
            def checked(fig, caption="", dpi=110, _original=original):
                seen.append((caption, *_fit_of(fig)))
                return _original(fig, caption, dpi)
            monkeypatch.setattr(module, "figure_html", checked)
    write_run_report(config, outcome, tmp_path / "report.html", "the shipped records")
    assert len(seen) >= 15
    clipped = [(c, over) for c, over, _ in seen if over > 0.02]
    assert not clipped, clipped
    loose = [(c, margin) for c, _, margin in seen if margin > 0.6]
    assert not loose, loose
