"""The run report's summary (mfflap.reports.summary): what the run found and whether CFD
confirmed it, on the first screen of a real browser."""

import shutil
from pathlib import Path

import pytest
from shipped_settings import SHIPPED_SETTINGS

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
    """The main job on the shipped records (one start, no IPOPT) with the settings its
    back-tests were optimised with: its case, outcome and report."""
    config = load_case(CASE, SHIPPED_SETTINGS)
    outcome = run_study(config, RunOptions(n_starts=1, with_ipopt=False, sensitivity=False),
                        progress=lambda m: None)
    html = tmp_path_factory.mktemp("report") / "report.html"
    write_run_report(config, outcome, html, "the shipped records")
    return config, outcome, html


@pytest.mark.slow
def test_the_summary_gives_each_motions_model_and_cfd_figures(run):
    config, outcome, _ = run
    rows = {r[0]: r for r in motion_rows(config, outcome)}
    assert set(rows) == {"best sinusoid", "β = 0", "β = 0.5", "β = 1"}
    for label, o in outcome.backtests.items():
        c = o.comparison
        assert rows[label][1:5] == [c.model_mean_thrust, c.cfd_mean_thrust,
                                    c.model_mean_power, c.cfd_mean_power]
        assert rows[label][-1] == ("yes" if c.max_power_ok else "NO")
    said = " ".join(headline(config, outcome))
    assert "in CFD (the model predicted" in said and "P_max = 50 W" in said
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
        assert "over the best feasible sinusoid in CFD" in shown
        for o in outcome.backtests.values():
            assert f"{o.comparison.cfd_mean_thrust:.4g}" in shown
        assert "P_max = 50 W" in shown
        contents = driver.find_element(By.TAG_NAME, "nav")
        assert contents.rect["y"] > summary.rect["y"]
        titles = [a.text for a in contents.find_elements(By.TAG_NAME, "a")]
        assert "Back-test against CFD" in titles
    finally:
        driver.quit()
