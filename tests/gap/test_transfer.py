"""Whether a diagnosed effect carries over to CFD runs outside the diagnosed cases."""

import json
from pathlib import Path

import h5py
import numpy as np
import pytest
from click.testing import CliRunner

from mfflap.errors import MfflapError
from mfflap.gap.blindtest import trial_cases
from mfflap.gap.diagnose import default_candidates
from mfflap.gap.transfer import BASE, check_transfer, held_out_motions, motion_period
from mfflap.hydro import MorisonModel
from mfflap.hydro.loads import Loads
from mfflap.identification.data import CaseData
from mfflap.identification.workflow import failed_cases, pooled_records
from mfflap.kinematics.state import KinematicState
from mfflap.records.record import CfdRecord, fixture_dir, write_record

CASE = "cases/paper2026.toml"
CANDIDATES = default_candidates()
BASE_MODEL = MorisonModel().with_coefficients({"normal_added_mass": 0.9, "normal_drag": 4.0,
                                               "tangential_added_mass": 0.3,
                                               "tangential_drag": 0.7})
LIFT_SLOPE = 4.5


def _two_harmonic_state(period: float, n_cycles: float = 3.0, n: int = 1500,
                        pitch: tuple[float, float] = (0.35, 0.08),
                        heave: tuple[float, float] = (0.25, 0.04)) -> KinematicState:
    """theta = a1 sin(w t) + a3 sin(3 w t), h = b1 cos(w t) + b3 cos(3 w t) - (b1 + b3):
    a motion of no single harmonic, as optimised ones are (heave zero at t = 0)."""
    t = np.linspace(0.0, n_cycles * period, n)
    w = 2 * np.pi / period
    (a1, a3), (b1, b3) = pitch, heave
    th = a1 * np.sin(w * t) + a3 * np.sin(3 * w * t)
    td = a1 * w * np.cos(w * t) + 3 * a3 * w * np.cos(3 * w * t)
    tdd = -a1 * w**2 * np.sin(w * t) - 9 * a3 * w**2 * np.sin(3 * w * t)
    h = b1 * np.cos(w * t) + b3 * np.cos(3 * w * t) - (b1 + b3)
    hd = -b1 * w * np.sin(w * t) - 3 * b3 * w * np.sin(3 * w * t)
    hdd = -b1 * w**2 * np.cos(w * t) - 9 * b3 * w**2 * np.cos(3 * w * t)
    return KinematicState(t, th, td, tdd, h, hd, hdd)


def _loads(state: KinematicState, with_wake: bool) -> Loads:
    loads = BASE_MODEL.loads(state)
    if with_wake:
        wake = CANDIDATES["wake_lag"].regressor(state)
        loads = Loads(state.time, loads.normal_force + LIFT_SLOPE * wake.normal_force,
                      loads.tangential_force, loads.moment + LIFT_SLOPE * wake.moment)
    return loads


def _fit_cases(with_wake: bool) -> list[CaseData]:
    cases = trial_cases(np.random.default_rng(5), 12)
    return [CaseData(c.name, c.parameters, c.state, _loads(c.state, with_wake)) for c in cases]


def _held_out_records(with_wake: bool) -> list[CfdRecord]:
    out = []
    for i, (period, pitch) in enumerate(((0.6, (0.35, 0.08)), (1.1, (0.5, -0.1)),
                                         (2.5, (0.2, 0.05)))):
        state = _two_harmonic_state(period, pitch=pitch)
        out.append(CfdRecord(f"optimised_{i}", state, _loads(state, with_wake),
                             {"kind": "periodic_spline", "period": period,
                              "label": f"motion {i}"}))
    return out


def test_an_effect_of_the_physics_carries_over_with_its_coefficient():
    """The fits' cases and the held-out runs share the effect: adding it predicts the runs
    exactly, and the fit on the cases finds its coefficient."""
    motions, excluded = held_out_motions(_held_out_records(True))
    assert excluded == {} and [m.label for m in motions] == ["motion 0", "motion 1", "motion 2"]
    check = check_transfer(_fit_cases(True), motions, BASE_MODEL.terms, CANDIDATES,
                           ["wake_lag"], residual_scaling="case")
    assert check.carries_over and check.gain > 0.999 and check.n_better["wake_lag"] == 3
    assert check.coefficients["wake_lag"]["wake_lag"] == pytest.approx(LIFT_SLOPE, rel=1e-6)
    assert check.coefficients[BASE].keys() == BASE_MODEL.coefficients.keys()
    for m in motions:  # the compared window is the run's last period
        t = m.case.state.time
        assert t[-1] - t[0] == pytest.approx(float(m.case.parameters["period"]))
    for m in check.motions:
        assert max(m.nrmse["wake_lag"].values()) < 1e-6  # the wake acts on F_n and M only:
        assert min(m.nrmse[BASE]["normal_force"], m.nrmse[BASE]["moment"]) > 1e-3
        assert m.mean_thrust["wake_lag"] == pytest.approx(m.mean_thrust["cfd"], abs=1e-6)
        assert m.error[BASE] == pytest.approx(np.mean([v**2 for v in m.nrmse[BASE].values()]))
    assert check.verdict.startswith("wake_lag carries over to the 3 held-out motion(s): "
                                    "their error ")
    assert "lower on 3 of 3" in check.verdict and "too few for a significance test" in (
        check.verdict)


def test_an_effect_confined_to_the_fits_cases_does_not_carry_over():
    """The cases carry the effect, the held-out runs not (as when an effect of the
    identification grid's sinusoids is absent from the optimised motions): it makes the
    predictions of those runs worse, and the verdict says so."""
    motions, _ = held_out_motions(_held_out_records(False))
    check = check_transfer(_fit_cases(True), motions, BASE_MODEL.terms, CANDIDATES,
                           ("wake_lag",), claimed=False, residual_scaling="grid")
    assert not check.carries_over and check.gain < 0
    assert check.verdict.startswith("wake_lag (the best candidate, not claimed) does not "
                                    "carry over to the 3 held-out motion(s): their error ")
    assert f"{-check.gain:.1%} higher" in check.verdict
    with pytest.raises(MfflapError, match="must name candidates"):
        check_transfer(_fit_cases(True), motions, BASE_MODEL.terms, CANDIDATES, ["wake"])


def test_the_window_is_the_last_period_and_a_run_shorter_than_one_is_left_out():
    rec = _held_out_records(True)[0]
    assert motion_period(rec) == 0.6
    by_frequency = CfdRecord("f", rec.state, rec.loads, {"frequency": 2.0})
    garbled = CfdRecord("g", rec.state, rec.loads, {"period": "soon"})
    assert motion_period(by_frequency) == 0.5 and motion_period(garbled) is None
    short = CfdRecord("short", rec.state, rec.loads, {"period": 5.0})
    motions, excluded = held_out_motions([by_frequency, garbled, short], discard_time=0.3)
    assert [m.name for m in motions] == ["f", "g"]
    assert motions[0].case.state.time[0] == pytest.approx(rec.time[-1] - 0.5)
    assert motions[1].case.state.time[0] == pytest.approx(0.3)  # no period: after the discard
    assert excluded == {"short": "it ran 1.8 s, less than one period (5 s)"}
    # the history the predictions see is the whole run, not the window
    assert motions[0].history.time[0] == rec.time[0]


def test_a_back_test_failure_file_is_named_by_its_case_and_drops_out_when_it_was_rerun():
    folder = fixture_dir("backtest")
    assert set(failed_cases(folder)) == {"backtest_3a6d9eea8fc019d2"}
    records, failed = pooled_records(folder)
    assert "backtest_3a6d9eea8fc019d2" in {r.name for r in records} and failed == {}


@pytest.mark.slow
def test_gap_cli_checks_the_claim_on_the_shipped_back_tests(tmp_path):
    """On the shipped CFD the wake lag is claimed with case scaling, and does not carry over
    to the shipped back-tests (real OpenFOAM runs of the paper's four motions and of
    an optimum with the fixed phase, all motions the fits never saw)."""
    from mfflap.cli.main import cli

    out = tmp_path / "gap.h5"
    args = ["gap", "diagnose", CASE, "--set", 'identification.residual_scaling="case"',
            "--check-on", str(fixture_dir("backtest")), "--output", str(out)]
    res = CliRunner().invoke(cli, [*args, "--json"])
    assert res.exit_code == 0, res.output
    transfer = json.loads(res.output[res.output.index("{"):])["transfer"]
    assert transfer["effect"] == ["wake_lag"] and transfer["claimed"] is True
    assert transfer["carries_over"] is False and transfer["excluded"] == {}
    n_records = len(list(fixture_dir("backtest").glob("*.h5")))
    assert n_records >= 4 and len(transfer["motions"]) == n_records
    assert {m["label"] for m in transfer["motions"]} == {"best sinusoid", "β = 0", "β = 0.5",
                                                         "β = 1"}
    res = CliRunner().invoke(cli, args)
    assert res.exit_code == 0, res.output
    assert f"on runs outside the cases: {transfer['verdict']}" in res.output
    with h5py.File(out) as h5:
        g = h5["gap/transfer"]
        assert g.attrs["verdict"] == transfer["verdict"]
        assert json.loads(g.attrs["effect"]) == ["wake_lag"]
        assert g["nrmse_normal_force_effect"].shape == (n_records,)
        assert g["mean_thrust_cfd"].attrs["units"] == "N"
        assert np.allclose(g["error/wake_lag"][()],
                           [m["error"]["wake_lag"] for m in transfer["motions"]])
    html = out.with_suffix(".html").read_text()
    assert "Does it carry over to runs outside the cases?" in html
    # a run the fits saw is refused: it says nothing about carrying over
    res = CliRunner().invoke(cli, ["gap", "diagnose", CASE, "--check-on",
                                   str(fixture_dir("table1_coarse") / "f0p100_h0p100_phi045p0.h5"),
                                   "--output", str(out)])
    assert res.exit_code != 0
    assert "f0p100_h0p100_phi045p0 are also among the diagnosed cases" in res.output


def test_records_written_and_read_back_are_checked_alike(tmp_path):
    """The check reads held-out runs from record files as the CLI does."""
    from mfflap.records.record import read_records

    for rec in _held_out_records(True):
        write_record(tmp_path / f"{rec.name}.h5", rec)
    motions, excluded = held_out_motions(read_records(tmp_path))
    direct, _ = held_out_motions(_held_out_records(True))
    assert excluded == {} and len(motions) == 3
    a = check_transfer(_fit_cases(True), motions, BASE_MODEL.terms, CANDIDATES, ["wake_lag"])
    b = check_transfer(_fit_cases(True), direct, BASE_MODEL.terms, CANDIDATES, ["wake_lag"])
    assert a.gains == pytest.approx(b.gains)


def test_each_held_out_motion_carries_cfd_s_own_repeat_nrmse_into_the_check_and_file(tmp_path):
    """A run that repeats its period has CFD's own NRMSE near zero; noise in the compared
    period raises it; a run with no whole period before the compared one has none (NaN,
    null in JSON) rather than a figure read off the start-up."""
    from mfflap.gap.store import write_transfer
    from mfflap.results import ResultsFile

    records = _held_out_records(False)
    rng = np.random.default_rng(2)
    noisy = records[1]
    last = noisy.time >= noisy.time[-1] - 1.1
    fn = noisy.loads.normal_force.copy()
    fn[last] += 0.05 * np.ptp(fn) * rng.standard_normal(last.sum())
    records[1] = CfdRecord(noisy.name, noisy.state,
                           Loads(noisy.time, fn, noisy.loads.tangential_force,
                                 noisy.loads.moment), noisy.parameters)
    short = _two_harmonic_state(0.8, n_cycles=1.5, n=600)
    records.append(CfdRecord("short", short, _loads(short, False),
                             {"kind": "periodic_spline", "period": 0.8}))
    motions, excluded = held_out_motions(records)
    assert excluded == {}
    own = {m.name: m.cfd_repeat_nrmse for m in motions}
    assert own["optimised_0"]["normal_force"] < 1e-3
    assert 0.03 < own["optimised_1"]["normal_force"] < 0.1
    assert own["optimised_1"]["moment"] < 1e-3
    assert all(np.isnan(v) for v in own["short"].values())
    check = check_transfer(_fit_cases(False), motions, BASE_MODEL.terms, CANDIDATES,
                           ["wake_lag"], residual_scaling="case")
    as_json = json.loads(json.dumps(check.as_dict(), allow_nan=False))
    assert as_json["motions"][3]["cfd_repeat_nrmse"]["normal_force"] is None
    assert as_json["motions"][1]["cfd_repeat_nrmse"]["normal_force"] == pytest.approx(
        own["optimised_1"]["normal_force"])
    with ResultsFile(tmp_path / "t.h5", "w") as rf:
        write_transfer(rf, check)
    with h5py.File(tmp_path / "t.h5") as h5:
        stored = h5["gap/transfer/cfd_repeat_nrmse_normal_force"][()]
    assert stored[1] == pytest.approx(own["optimised_1"]["normal_force"])
    assert np.isnan(stored[3])
    from mfflap.reports.gap import add_transfer_section
    from mfflap.reports.html import Report

    report = Report("transfer", "")
    add_transfer_section(report, check)
    page = Path(report.write(tmp_path / "t.html")).read_text()
    assert "own NRMSE [%] normal_force / tangential_force / moment" in page
    assert f"{100 * own['optimised_1']['normal_force']:.1f} / " in page
    assert "- / - / -" in page
