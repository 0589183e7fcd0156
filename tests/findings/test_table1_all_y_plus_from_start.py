"""The all_y_plus campaign with its runs that a retry resumed part-way within the fitted
window rerun from the start (campaigns/table1_coarse_all_y_plus_from_start, real OpenFOAM,
`mfflap campaign run --retries-from-start`): how far fitting a run that mixes
two set-ups moves the identification (campaigns/README.md)."""

from pathlib import Path

import numpy as np
import pytest

from mfflap.records.as_run import as_run_since_s
from mfflap.records.record import read_record, record_paths

pytestmark = pytest.mark.findings  # shipped research data, not code

ROOT = Path(__file__).parents[2]
RESUMED = ROOT / "campaigns" / "table1_coarse_all_y_plus"
FROM_START = ROOT / "campaigns" / "table1_coarse_all_y_plus_from_start"
#: identification's default start-up discarded, s (mfflap.identification.data.prepare_case)
DISCARD_S = 0.75
RERUN = {"f0p200_h0p500_phi135p0", "f0p500_h0p300_phi135p0", "f0p500_h0p500_phi045p0",
         "f0p500_h0p500_phi090p0", "f1p000_h0p100_phi045p0", "f1p000_h0p100_phi135p0",
         "f1p000_h0p500_phi045p0", "f2p000_h0p100_phi090p0", "f2p000_h0p300_phi045p0",
         "f2p000_h0p300_phi090p0"}


@pytest.fixture(scope="module")
def comparison():
    """`campaign compare` of the campaign as run (A) against its reruns from the start (B)."""
    from mfflap.campaign.compare import compare_campaigns

    return compare_campaigns(RESUMED, FROM_START)


def test_the_runs_resumed_within_the_fitted_window_were_rerun_as_one_set_up():
    """The ten runs whose last settings began after the discarded start-up were rerun from
    t = 0 s with every retry; the other 33 records and the two failures are the campaign's
    own, byte for byte, so the two folders differ in those ten runs only."""
    resumed = {p.stem: p for p in record_paths(RESUMED)}
    from_start = {p.stem: p for p in record_paths(FROM_START)}
    assert resumed.keys() == from_start.keys() and len(resumed) == 43
    mixed = {name for name, path in resumed.items()
             if as_run_since_s(read_record(path)) > DISCARD_S}
    assert mixed == RERUN
    for name in RERUN:
        rerun = read_record(from_start[name])
        assert as_run_since_s(rerun) == 0.0
        retries = rerun.provenance["retries"].split("; resumed from ")[1:]
        assert retries and all(r.startswith("t = 0 s with ") for r in retries)
        assert rerun.parameters == read_record(resumed[name]).parameters
    for name in resumed.keys() - RERUN:
        assert from_start[name].read_bytes() == resumed[name].read_bytes(), name
    for failed in RESUMED.glob("*.failed.toml"):
        assert (FROM_START / failed.name).read_bytes() == failed.read_bytes()


def test_one_set_up_moves_each_runs_forces_about_as_much_as_the_wall_treatment(comparison):
    """Over each case's window after its ramp, the ten runs move by 0.7-6.4 % NRMSE in F_n
    (median 3.9 %) and up to 8.6 % in M: the far field the run began with (freestream,
    where the retry changed it to inletOutlet) is what differs. That is about what the
    wall treatment moves the same grid by (median 3.7 %, campaigns/README.md). The mean
    thrust moves by less than 6 % where it is above 2 N; the three runs near a balance of
    thrust and drag (under 1.2 N) move by less than 0.6 N."""
    result = comparison
    assert len(result.cases) == 43 and not result.only_a and not result.only_b
    rerun = [c for c in result.cases if c.case_id in RERUN]
    assert all(c.nrmse_normal_force == c.nrmse_moment == 0.0
               for c in result.cases if c.case_id not in RERUN)
    normal = [c.nrmse_normal_force for c in rerun]
    assert 0.005 < min(normal) and max(normal) < 0.07
    assert np.median(normal) == pytest.approx(0.039, abs=0.003)
    assert max(c.nrmse_moment for c in rerun) < 0.09
    for case in rerun:
        if abs(case.mean_thrust_b_n) > 2.0:
            assert case.mean_thrust_a_n == pytest.approx(case.mean_thrust_b_n, rel=0.06)
        else:
            assert abs(case.mean_thrust_a_n - case.mean_thrust_b_n) < 0.6


@pytest.mark.parametrize("residual_scaling", ["grid", "case"])
@pytest.mark.slow
def test_fitting_runs_that_mix_two_set_ups_barely_moves_the_identification(
        comparison, residual_scaling):
    """Uniform weighting on the 43 cases, the ten mixed runs as run against their one-set-up
    reruns: every coefficient moves within its bootstrap spread, the normal drag and the
    normal added mass by under 4 %, and the beta = 0 optimum's mean thrust and frequency by
    under 1 %. The identification's note on a mixed run (rerun it with
    --retries-from-start) is advice, not a correction the fit needs."""
    from mfflap.config import load_case
    from mfflap.identification.workflow import identify_strategies, load_cases
    from mfflap.optimisation.study import default_sweep
    from mfflap.pipeline import coefficient_sensitivity

    case = load_case(ROOT / "cases" / "paper2026.toml")
    names = [f"{c.case_id}.h5" for c in comparison.cases]
    fits = {}
    for label, folder in (("resumed", RESUMED), ("from_start", FROM_START)):
        cases, excluded = load_cases(case, [folder / n for n in names])
        assert len(cases) == 43 and not excluded
        fits[label] = identify_strategies(case, cases, excluded, ["uniform"], n_bootstrap=200,
                                          residual_scaling=residual_scaling)["uniform"]
    resumed, from_start = fits["resumed"], fits["from_start"]
    for term in resumed.fitted_terms:
        spread = max(resumed.standard_error[term], from_start.standard_error[term])
        assert abs(from_start.coefficients[term] - resumed.coefficients[term]) < spread, term
    for term in ("normal_drag", "normal_added_mass"):
        assert from_start.coefficients[term] == pytest.approx(resumed.coefficients[term],
                                                              rel=0.04), term
    optima = coefficient_sensitivity(case, fits, default_sweep(case), lambda _: None)
    summary = {k: r.summary for k, (_, r) in optima.items()}
    assert float(summary["from_start"].mean_thrust) == pytest.approx(
        float(summary["resumed"].mean_thrust), rel=0.01)
    assert float(summary["from_start"].frequency) == pytest.approx(
        float(summary["resumed"].frequency), rel=0.01)
