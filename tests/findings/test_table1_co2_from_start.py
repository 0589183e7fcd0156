"""The one run of the max Co 2 campaign whose retry resumed it part-way within the fitted
window, rerun from the start (campaigns/table1_coarse_co2_from_start, real OpenFOAM,
`mfflap campaign run --retries-from-start`): how far that run and the
identification move when it runs one set-up throughout (campaigns/README.md)."""

from pathlib import Path

import pytest

from mfflap.campaign.compare import compare_campaigns
from mfflap.records.as_run import as_run_since_s
from mfflap.records.record import read_record, record_paths

pytestmark = pytest.mark.findings  # shipped research data, not code

ROOT = Path(__file__).parents[2]
CO2 = ROOT / "campaigns" / "table1_coarse_co2"
FROM_START = ROOT / "campaigns" / "table1_coarse_co2_from_start"
CASE = "f2p000_h0p300_phi090p0"
#: identification's default start-up discarded, s (mfflap.identification.data.prepare_case)
DISCARD_S = 0.75
#: where the campaign's run resumed with the inletOutlet far field, s (its write before
#: the breach)
RESUMED_FROM_S = 1.125


def test_the_one_mixed_run_of_the_campaign_was_rerun_as_one_set_up():
    """Of the campaign's 43 runs only f = 2 Hz, h = 0.3 m, phi = 90 deg changed its settings
    after the discarded start-up. Rerun from t = 0 s, it left the force bound at the same
    flow time as the campaign's run (the two are one deterministic run up to there), and
    ran through from t = 0 s with the inletOutlet far field."""
    mixed = [p.stem for p in record_paths(CO2) if as_run_since_s(read_record(p)) > DISCARD_S]
    assert mixed == [CASE]
    resumed, rerun = (read_record(d / f"{CASE}.h5") for d in (CO2, FROM_START))
    assert [p.stem for p in record_paths(FROM_START)] == [CASE]
    assert as_run_since_s(resumed) == RESUMED_FROM_S and as_run_since_s(rerun) == 0.0
    assert rerun.parameters == resumed.parameters
    breach = "forces beyond what the motion can drive from t = 1.43513 s"
    assert resumed.provenance["retries"].startswith(breach)
    assert rerun.provenance["retries"].startswith(breach)
    assert rerun.provenance["retries"].endswith(
        "resumed from t = 0 s with the inletOutlet far field")
    assert resumed.provenance["retries"].endswith(
        f"resumed from t = {RESUMED_FROM_S:g} s with the inletOutlet far field")


@pytest.mark.parametrize(("start_s", "end_s", "normal", "moment", "thrust"), [
    (DISCARD_S, None, (0.02, 0.03), (0.025, 0.035), (0.04, 0.06)),
    (None, RESUMED_FROM_S, (0.01, 0.02), (0.015, 0.025), (0.01, 0.03)),
    (RESUMED_FROM_S, None, (0.055, 0.075), (0.055, 0.075), (0.06, 0.08)),
])
@pytest.mark.slow
def test_the_resumed_run_reads_a_few_per_cent_above_one_set_up(start_s, end_s, normal,
                                                                 moment, thrust):
    """Over the fitted window (0.75-1.5 s) the campaign's run is 2.6 % NRMSE (F_n) from the
    one-set-up run, with 5 % more mean thrust. Before its resume (the ramp's end to
    1.125 s: freestream against inletOutlet far field, the same state otherwise) the two
    are 1.5 % apart, after it (the freestream run's flow continued with inletOutlet)
    6.5 %: the resumed stretch is where they part."""
    result = compare_campaigns(CO2, FROM_START, start_s, end_s)
    (case,) = result.cases
    assert case.case_id == CASE and len(result.only_a) == 42 and not result.only_b
    assert normal[0] < case.nrmse_normal_force < normal[1]
    assert moment[0] < case.nrmse_moment < moment[1]
    assert thrust[0] < case.thrust_difference < thrust[1]


@pytest.mark.parametrize("residual_scaling", ["grid", "case"])
@pytest.mark.slow
def test_the_one_set_up_run_leaves_the_identification_where_it_was(residual_scaling):
    """Uniform weighting on the campaign's 43 cases, as run against with the one-set-up
    rerun in its place: every coefficient moves by under a tenth of its bootstrap spread,
    and the beta = 0 optimum's mean thrust and frequency by under 0.5 %."""
    from mfflap.config import load_case
    from mfflap.identification.workflow import identify_strategies, load_cases
    from mfflap.optimisation.study import default_sweep
    from mfflap.pipeline import coefficient_sensitivity

    case = load_case(ROOT / "cases" / "paper2026.toml")
    as_run = record_paths(CO2)
    one_set_up = [FROM_START / p.name if p.stem == CASE else p for p in as_run]
    fits = {}
    for label, paths in (("as_run", as_run), ("one_set_up", one_set_up)):
        cases, excluded = load_cases(case, paths)
        assert len(cases) == 43 and not excluded
        fits[label] = identify_strategies(case, cases, excluded, ["uniform"], n_bootstrap=200,
                                          residual_scaling=residual_scaling)["uniform"]
    before, after = fits["as_run"], fits["one_set_up"]
    assert before.coefficients != after.coefficients
    for term in before.fitted_terms:
        spread = max(before.standard_error[term], after.standard_error[term])
        assert abs(after.coefficients[term] - before.coefficients[term]) < 0.1 * spread, term
    optima = coefficient_sensitivity(case, fits, default_sweep(case), lambda _: None)
    summary = {k: r.summary for k, (_, r) in optima.items()}
    for quantity in ("mean_thrust", "frequency"):
        assert float(getattr(summary["one_set_up"], quantity)) == pytest.approx(
            float(getattr(summary["as_run"], quantity)), rel=0.005), quantity
