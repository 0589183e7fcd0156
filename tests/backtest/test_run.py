"""Back-test (keys, fixture lookup, comparison, live OpenFOAM), VTK export, and `mfflap run`."""

from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner
from shipped_settings import as_shipped

from mfflap.backtest.compare import compare_last_cycle
from mfflap.backtest.run import backtest_motion, cfd_motion, motion_key
from mfflap.cfd.imposed_motion import imposed_state
from mfflap.cfd.openfoam.runner import openfoam_available
from mfflap.errors import MfflapError
from mfflap.hydro import MorisonModel
from mfflap.kinematics.convert import harmonic_to_discrete
from mfflap.kinematics.discrete import DiscreteMotion
from mfflap.performance import thrust_and_power
from mfflap.records.record import CfdRecord, read_record, write_record

CASE = Path(__file__).parents[2] / "cases" / "paper2026.toml"
MOTION = harmonic_to_discrete(1.5, 0.2, np.deg2rad(30), np.deg2rad(90), 40)


def model_record(motion: DiscreteMotion, n_cycles=3.0, name=None) -> CfdRecord:
    """A 'CFD' record made by the model itself on the imposed spline kinematics."""
    spline = cfd_motion(motion)
    t = np.linspace(0, n_cycles * spline.period, 1500)
    ramp = 0.5 * spline.period
    state = imposed_state(spline, t, ramp)
    loads = MorisonModel().loads(state)
    key = motion_key(motion)
    return CfdRecord(name or f"backtest_{key}", state, loads,
                     {"kind": "periodic_spline", "period": spline.period, "ramp_time": ramp,
                      "motion_key": key})


def test_motion_key_is_stable_to_last_bits_and_tells_motions_apart():
    k = motion_key(MOTION)
    nudged = DiscreteMotion(MOTION.pitch_acceleration * (1 + 1e-12),
                            MOTION.heave_acceleration, MOTION.time_step * (1 + 1e-12))
    assert motion_key(nudged) == k
    other = harmonic_to_discrete(1.5, 0.2, np.deg2rad(31), np.deg2rad(90), 40)
    assert motion_key(other) != k


def test_comparison_of_the_model_with_itself_is_perfect():
    rec = model_record(MOTION)
    period = cfd_motion(MOTION).period
    c = compare_last_cycle(rec, MorisonModel(), period, max_power=1e9)
    assert c.nrmse["thrust"] == pytest.approx(0, abs=1e-12)
    assert c.pearson["input_power"] == pytest.approx(1.0)
    assert c.mean_thrust_error == pytest.approx(0, abs=1e-12)
    assert c.cycle_to_cycle_thrust_change < 1e-3  # periodic after the ramp
    assert c.time[-1] - c.time[0] == pytest.approx(period, rel=0.01)
    # the power limit check uses the CFD's instantaneous power over the last cycle
    _, power = thrust_and_power(rec.loads, rec.state)
    limit = 0.9 * float(power[rec.time >= rec.time[-1] - period].max())
    assert not compare_last_cycle(rec, MorisonModel(), period, limit).max_power_ok


def test_a_numerical_burst_in_the_cfd_is_bridged_and_listed():
    rec = model_record(MOTION)
    period = cfd_motion(MOTION).period
    clean = compare_last_cycle(rec, MorisonModel(), period, max_power=1e9)
    assert clean.numerical_bursts == []
    # 30 microsecond steps in the last cycle where the forces go off by 10^4 ranges
    i = int(np.searchsorted(rec.time, rec.time[-1] - 0.4 * period))
    burst_t = rec.time[i] + 1e-9 * period * np.arange(1, 31)
    t = np.concatenate([rec.time[:i + 1], burst_t, rec.time[i + 1:]])
    state = imposed_state(cfd_motion(MOTION), t, rec.parameters["ramp_time"])
    loads = MorisonModel().loads(state)
    bump = 1e4 * np.ptp(loads.normal_force) * np.sin(np.pi * np.arange(1, 31) / 31)
    for k in ("normal_force", "tangential_force", "moment"):
        getattr(loads, k)[i + 1:i + 31] += bump
    hit = compare_last_cycle(CfdRecord(rec.name, state, loads, rec.parameters),
                             MorisonModel(), period, max_power=1.01 * clean.cfd_max_power)
    assert len(hit.numerical_bursts) == 1
    assert hit.nrmse["thrust"] < 0.01 and hit.mean_thrust_error == pytest.approx(0, abs=1e-3)
    assert hit.max_power_ok  # the burst's 10^4-fold power is not the motion's


def test_a_cfd_run_that_lost_its_numerics_gets_no_verdict(tmp_path):
    """Forces that grow over the last cycle to 20 times what the motion can drive (no jump
    sharp enough for a burst): the comparison refuses them, and the back-test says why
    instead of judging the model."""
    rec = model_record(MOTION)
    period = cfd_motion(MOTION).period
    t = rec.time
    growth = np.exp(np.clip(t - (t[-1] - 0.6 * period), 0, None) / (0.1 * period)) - 1.0
    grown = rec.loads.normal_force + np.ptp(rec.loads.normal_force) * growth
    lost = CfdRecord(rec.name, rec.state, type(rec.loads)(
        t, grown, rec.loads.tangential_force, rec.loads.moment), rec.parameters)
    assert grown.max() > 20 * np.abs(rec.loads.normal_force).max()
    with pytest.raises(MfflapError, match="leave what the motion can drive"):
        compare_last_cycle(lost, MorisonModel(), period, max_power=1e9)
    folder = tmp_path / "bt"
    write_record(folder / f"backtest_{motion_key(MOTION)}.h5", lost)
    outcome = backtest_motion(MOTION, "β = 0", MorisonModel(), 50.0, fixture_folders=[folder])
    assert outcome.status == "not back-tested" and "lost its numerics" in outcome.source
    assert outcome.comparison is None


def test_fixture_lookup_by_key_then_by_tolerance_and_missing_is_reported(tmp_path):
    folder = tmp_path / "bt"
    write_record(folder / f"backtest_{motion_key(MOTION)}.h5", model_record(MOTION))
    found = backtest_motion(MOTION, "β = 0", MorisonModel(), 50.0, fixture_folders=[folder])
    assert found.status == "back-tested" and found.source.startswith("fixture backtest_")
    # a motion a hair away (another machine's optimum) hashes differently but still matches
    near = DiscreteMotion(MOTION.pitch_acceleration * (1 + 2e-4), MOTION.heave_acceleration,
                          MOTION.time_step)
    assert motion_key(near) != motion_key(MOTION)
    assert backtest_motion(near, "near", MorisonModel(), 50.0,
                           fixture_folders=[folder]).status == "back-tested"
    far = harmonic_to_discrete(1.0, 0.3, np.deg2rad(20), np.deg2rad(90), 40)
    missing = backtest_motion(far, "far", MorisonModel(), 50.0, fixture_folders=[folder])
    assert missing.status == "not back-tested" and motion_key(far) in missing.source
    assert missing.comparison is None


def test_a_live_backtest_goes_on_with_its_record_as_saved(tmp_path, monkeypatch):
    """A live back-test saved in single precision is compared as saved, so a rerun that
    finds the saved record (a series of rounds resumed after it stopped) has the same
    numbers to the last bit: once a resumed series' next optimum came out 6e-6
    away from the one whose case the stopped run had written, and that case was refused."""
    from mfflap.backtest import run as backtest_run

    monkeypatch.setattr(backtest_run, "run_backtest_case",
                        lambda motion, label, name, **kwargs: model_record(motion, name=name))
    live = backtest_motion(MOTION, "β = 0", MorisonModel(), 50.0, live=True,
                           work_dir=tmp_path / "w", save_to=tmp_path / "fx")
    assert live.source == "live OpenFOAM"
    again = backtest_motion(MOTION, "β = 0", MorisonModel(), 50.0,
                            fixture_folders=[tmp_path / "fx"])
    assert again.source.startswith("fixture backtest_")
    exact = model_record(MOTION).loads.normal_force
    assert not np.array_equal(live.record.loads.normal_force, exact)  # single precision
    np.testing.assert_array_equal(live.record.loads.normal_force,
                                  again.record.loads.normal_force)
    assert live.comparison.cfd_mean_thrust == again.comparison.cfd_mean_thrust
    assert live.comparison.cfd_mean_power == again.comparison.cfd_mean_power


@pytest.mark.openfoam
def test_live_backtest_runs_openfoam_and_saves_a_fixture(tmp_path):
    assert openfoam_available()
    # 0.6 periods of 4 Hz: the run (0.15 s) outlasts the back-test's half-period ramp
    fast = harmonic_to_discrete(4.0, 0.05, np.deg2rad(10), np.deg2rad(90), 20)
    told: list[str] = []
    out = backtest_motion(fast, "fast", MorisonModel(), 50.0, live=True, work_dir=tmp_path,
                          n_cycles=0.6, save_to=tmp_path / "fx", progress=told.append)
    assert out.status == "back-tested" and out.source == "live OpenFOAM"
    assert told[0].startswith("meshing ") and told[1].startswith("pimpleFoam started")
    saved = tmp_path / "fx" / f"backtest_{out.key}.h5"
    assert saved.exists()
    again = backtest_motion(fast, "fast", MorisonModel(), 50.0, fixture_folders=[saved.parent])
    assert again.source == f"fixture {saved.name}"
    assert again.comparison.cfd_mean_thrust == pytest.approx(out.comparison.cfd_mean_thrust,
                                                             rel=1e-4)
    # a named set-up: its mesh and solver settings reach the run and its record
    from mfflap.cfd.openfoam.setups import setup

    affordable = setup("affordable")
    other = harmonic_to_discrete(4.0, 0.05, np.deg2rad(12), np.deg2rad(90), 20)
    out = backtest_motion(other, "affordable", MorisonModel(), 50.0, live=True,
                          work_dir=tmp_path, n_cycles=0.6, save_to=tmp_path / "fx",
                          mesh=affordable.mesh.name, solver=affordable.solver)
    assert out.status == "back-tested"
    record = read_record(tmp_path / "fx" / f"backtest_{out.key}.h5")
    assert record.provenance["mesh"] == "graded"
    assert record.provenance["solver_velocity_convection"] == "LUST"
    assert record.provenance["solver_n_outer_correctors"] == 1


def test_vtk_time_series_reads_back_in_pyvista(tmp_path):
    import pyvista as pv

    from mfflap.export.vtk import export_motion

    pvd = export_motion(tmp_path, MOTION, MorisonModel(), name="m", n_frames=20)
    reader = pv.get_reader(str(pvd))
    assert len(reader.time_values) == 20
    t, pitch, heave = MOTION.full_cycle_positions()
    reader.set_active_time_value(reader.time_values[5])
    mesh = reader.read()[0]
    k = np.unique(np.linspace(0, len(t) - 1, 20).round().astype(int))[5]
    assert mesh.point_data["heave_m"][0] == pytest.approx(heave[k])
    # the trailing edge sits at chord x (cos, sin) of the pitch from the leading edge
    xmax = mesh.points[:, 0].max()
    assert xmax == pytest.approx(0.16 * np.cos(pitch[k]), rel=1e-5)
    # each file names the frame its coordinates are in: the CFD case's, heave along y
    frame = str(np.asarray(pv.read(tmp_path / "m_0005.vtp").field_data["frame"])[0])
    assert frame.startswith("CFD case") and "y heave" in frame
    assert mesh.points[:, 1].min() == pytest.approx(heave[k] + min(
        0.0, 0.16 * np.sin(pitch[k])), abs=1e-6)


@pytest.mark.slow
def test_main_job_runs_end_to_end_on_the_shipped_fixtures(tmp_path):
    """`mfflap run` on the shipped CFD fixtures: every stage, one report, one HDF5 file."""
    from mfflap.cli.main import cli
    from mfflap.results import ResultsFile

    out = tmp_path / "run"
    res = CliRunner().invoke(cli, ["run", str(CASE), "--out", str(out), *as_shipped(
        "--set", "optimisation.starts=1", "--set", "optimisation.ipopt=false",
        "--set", "optimisation.gain_table=false"), "--json"])
    assert res.exit_code == 0, res.output
    import json

    summary = json.loads(res.output[res.output.index("{\n"):])
    assert set(summary["optimised"]) == {"0", "0.5", "1"}
    assert set(summary["coefficients"]) == {"uniform", "low", "high"}
    assert summary["most_influential_case"]["uniform"]["normal_drag"] == (
        "f2p000_h0p500_phi135p0")
    unpolished = {k for k in summary["backtest"] if not k.endswith("polished")}
    assert "gap_verdict" in summary and unpolished == {"best sinusoid", "β = 0", "β = 0.5",
                                                       "β = 1"}
    # the shipped case file fits on the grid's scale; the fixtures' errors ask for "case"
    assert summary["residual_scaling"]["uniform"] == {"used": "grid", "asked": "grid",
                                                      "errors_ask_for": ["case"]}
    assert summary["gap_residual_scaling"] == "grid"
    # and on the terminal, before the JSON: whether the fit weighs the runs as their errors
    # say, and the gap verdict
    assert ('identification (uniform weighting): residual RMS grows with the run\'s load RMS'
            in res.output and 'which residual scaling "case" weighs the runs by, not "grid"'
            in res.output)
    assert f"gap diagnosis: {summary['gap_verdict']}" in res.output
    # the gap diagnosis runs after the back-test and checks its best candidate (grid
    # scaling claims none) on the four back-tested runs, which no fit saw
    transfer = summary["gap_transfer"]
    assert transfer["claimed"] is False and len(transfer["effect"]) == 1
    assert "the 4 held-out motion(s)" in transfer["verdict"]
    assert f"on the back-tested motions: {transfer['verdict']}" in res.output
    # where the motions lie against the identification data: the β = 1 optimum within it;
    # the β = 0 optimum pitches faster than any identification case, and its regressors
    # leave the data's ellipsoid
    cov = summary["coverage"]
    assert set(cov) == set(summary["backtest"])
    assert cov["β = 1"]["extrapolated"] is False
    assert "peak |pitch acceleration|" in cov["β = 0"]["outside"]
    assert cov["β = 0"]["leverage_ratio"] > 1
    assert f"β = 0: {cov['β = 0']['said']}" in res.output
    html = (out / "report.html").read_text()
    assert "Does it carry over to runs outside the cases?" in html
    assert "Do the motions lie within the identification data?" in html
    for title in ("Identified coefficients", "Optimised motions", "Back-test against CFD",
                  "Coefficient sensitivity", "Sinusoidal sweep", "Sim-to-real gap",
                  "Gradient check (Fig. 6)"):
        assert title in html
    assert html.count("<img") >= 15
    # the two failed fixtures' log lines stay lines, folded under their reasons: in the
    # summary's problems and in the table of cases left out of the fit
    assert html.count("<summary>last log lines</summary><pre>PIMPLE: iteration 1\n") == 4
    with ResultsFile(out / "results.h5") as rf:
        assert "paper2026" in rf.config_toml
        assert {"identification", "optimisation", "backtest", "sensitivity", "gap",
                "gradient_check"} <= set(rf.h5)
        check = rf.h5["gradient_check/beta_0.00"]
        assert check.attrs["controls_error_complex_step"] < 1e-10
        assert check["adjoint"].shape == check["complex_step"].shape == (41,)
        statuses = {rf.h5[f"backtest/{k}"].attrs["status"] for k in rf.h5["backtest"]}
        assert len(json.loads(rf.h5["gap/transfer"].attrs["motion_names"])) == 4
        assert rf.h5["coverage/beta__0"].attrs["label"] == "β = 0"
        assert json.loads(rf.h5["coverage/beta__0"].attrs["coverage"]) == cov["β = 0"]
        assert statuses <= {"back-tested", "not back-tested"}
    assert list((out / "vtk").glob("*.pvd"))


@pytest.mark.slow
def test_a_stop_during_the_main_jobs_optimisation_writes_the_betas_optimised_before(
        tmp_path, sigterm_before):
    """`mfflap run` stopped by SIGTERM as beta = 0.5 starts: results.h5 and report.html
    hold identification, the sweep and beta = 0, name the stage and the betas left out
    (before, the finished betas were lost with the stage)."""
    import mfflap.optimisation.study as study_module
    from mfflap.cli.main import cli
    from mfflap.results import ResultsFile

    sigterm_before(study_module, "multistart", 0.5)
    out = tmp_path / "run"
    res = CliRunner().invoke(cli, ["run", str(CASE), "--out", str(out), *as_shipped(
        "--set", "optimisation.starts=1", "--set", "optimisation.ipopt=false",
        "--set", "optimisation.gain_table=false")])
    assert res.exit_code == 1, res.output
    assert "interrupted (optimisation): " in res.output
    left = "interrupted during beta = 0.5: beta 0.5, 1 not optimised (optimised: 0)"
    with ResultsFile(out / "results.h5") as rf:
        assert rf.h5.attrs["interrupted_stage"] == "optimisation"
        assert f"optimisation: {left}" in rf.h5.attrs["problems"]
        assert list(rf.h5["optimisation/sqp"]) == ["beta_0.00"]
        assert rf.h5["optimisation"].attrs["interrupted_beta"] == 0.5
        assert "identification" in rf.h5 and "backtest" not in rf.h5
    html = (out / "report.html").read_text()
    assert f"Incomplete: {left}." in html and "Optimised motions" in html


def test_a_failed_cfd_run_is_reported_with_its_reason(tmp_path):
    folder = tmp_path / "bt"
    folder.mkdir()
    key = motion_key(MOTION)
    (folder / f"backtest_{key}.failed.toml").write_text(
        f'motion_key = "{key}"\nerror = "case x: pimpleFoam diverged: the time step collapsed"\n')
    out = backtest_motion(MOTION, "β = 1", MorisonModel(), 50.0, fixture_folders=[folder])
    assert out.status == "not back-tested"
    assert "failed" in out.source and "time step collapsed" in out.source


def test_a_live_run_asked_for_and_not_had_is_said_beside_the_fixture_used(tmp_path):
    """A live run that failed used to be replaced by the fixture's name without a word: the
    report read as if the fixture were what was asked for."""
    from mfflap.backtest.workflow import backtest_all
    from mfflap.config import load_case
    from mfflap.errors import ConfigError
    from mfflap.pipeline import RunOptions

    folder = tmp_path / "bt"
    write_record(folder / f"backtest_{motion_key(MOTION)}.h5", model_record(MOTION))
    spaced = tmp_path / "live runs"
    out = backtest_motion(MOTION, "β = 0", MorisonModel(), 50.0, fixture_folders=[folder],
                          live=True, work_dir=spaced)
    assert out.status == "back-tested"
    assert out.source.startswith(f"fixture backtest_{motion_key(MOTION)}.h5 instead of a live "
                                 "run: ")
    assert ("OpenFOAM cannot run a case in" in out.source if openfoam_available() else
            "OpenFOAM is not installed" in out.source)
    none = backtest_motion(MOTION, "β = 0", MorisonModel(), 50.0, fixture_folders=[folder],
                           live=True)
    assert none.source.endswith("instead of a live run: " + (
        "no work folder for the live run" if openfoam_available() else
        "OpenFOAM is not installed"))
    # without live nothing is said beyond the fixture
    assert backtest_motion(MOTION, "β = 0", MorisonModel(), 50.0,
                           fixture_folders=[folder]).source == (
        f"fixture backtest_{motion_key(MOTION)}.h5")
    # the workflow and the main job refuse such a folder before the first run
    said = []
    with pytest.raises(ConfigError, match="OpenFOAM cannot run a case in"):
        backtest_all(load_case(CASE), {"β = 0": MOTION}, MorisonModel(),
                     fixture_folders=[folder], live=True, work_dir=spaced / "w",
                     progress=said.append)
    assert said == [] and not spaced.exists()
    with pytest.raises(ConfigError, match="OpenFOAM cannot run a case in"):
        RunOptions(live=True, work_dir=spaced / "cfd_cases")
    RunOptions(live=False, work_dir=spaced / "cfd_cases")  # not run: not checked


def test_backtest_command_refuses_an_unknown_mesh_for_a_set_up(optimisation_file, tmp_path):
    from click.testing import CliRunner

    from mfflap.cli.main import cli

    res = CliRunner().invoke(cli, ["backtest", str(optimisation_file), "--live", "--mesh",
                                   "finest", "--setup", "affordable", "--work",
                                   str(tmp_path / "work")])
    assert res.exit_code == 2 and "finest" in res.output and "meshes.toml" in res.output
    assert "cfd.mesh" in res.output and not (tmp_path / "work").exists()


@pytest.mark.openfoam
def test_ctrl_c_during_a_live_back_test_writes_the_stages_finished_before(tmp_path,
                                                                         solvers_left):
    """SIGINT to `mfflap run --live` while OpenFOAM runs a back-test: the solver is
    stopped, report.html and results.h5 hold identification and optimisation, name the
    stage stopped, and the message says the cases resume."""
    import re
    import signal
    import subprocess
    import sys
    import time

    from mfflap.cfd.openfoam.solver_log import solver_progress
    from mfflap.results import ResultsFile

    assert openfoam_available()
    out = tmp_path / "run"
    proc = subprocess.Popen(
        [sys.executable, "-c", "from mfflap.cli.main import cli; cli()", "run", str(CASE),
         "--out", str(out), *as_shipped("--set", "optimisation.starts=1",
                                        "--set", "optimisation.ipopt=false",
                                        "--set", "optimisation.gain_table=false"), "--live"],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    deadline = time.monotonic() + 600
    while time.monotonic() < deadline and proc.poll() is None and not any(
            solver_progress(d) for d in (out / "cfd_cases").glob("*") if d.is_dir()):
        time.sleep(0.5)  # until a back-test's solver has taken time steps
    assert proc.poll() is None, proc.communicate()
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 1, err
    assert re.search(rf"interrupted \(back-test\): {re.escape(str(out))}/report.html and "
                     r".*the same command with --overwrite runs the whole study again, and "
                     r"live back-test cases "
                     rf"in {re.escape(str(out / 'cfd_cases'))} resume", err), err
    assert solvers_left(f"pimpleFoam -case {out}") == ""  # no solver left writing into the case
    with ResultsFile(out / "results.h5") as rf:
        assert rf.h5.attrs["interrupted_stage"] == "back-test"
        assert {"identification", "optimisation"} <= set(rf.h5)
        assert "back-test: interrupted (Ctrl-C)" in rf.h5.attrs["problems"]
        assert "sensitivity" not in rf.h5  # a later stage: not run
    html = (out / "report.html").read_text()
    assert "Optimised motions" in html and "back-test: interrupted (Ctrl-C)" in html


def test_backtest_command_lists_each_motion_and_why_it_was_not_back_tested(
        tmp_path, optimisation_file):
    """Fixture folders without these motions: both motions (the best sinusoid and β = 0.5)
    are listed as not back-tested, with the folder searched, in text and in JSON."""
    import json

    from mfflap.cli.main import cli

    empty = tmp_path / "none"
    empty.mkdir()
    res = CliRunner().invoke(cli, ["backtest", str(optimisation_file), "--fixtures",
                                   str(empty), "--json"])
    assert res.exit_code == 1, res.output  # shown, but not taken as a complete back-test
    assert "2 of 2 motions not back-tested (best sinusoid, β = 0.5)" in res.stderr
    data = json.loads(res.stdout)
    assert list(data["motions"]) == ["best sinusoid", "β = 0.5"]
    assert {d["status"] for d in data["motions"].values()} == {"not back-tested"}
    assert data["cfd_thrust_gain"] is None
    assert data["cfd_thrust_gain_missing"] == "there is no β = 0 motion (not optimised)"
    text = CliRunner().invoke(cli, ["backtest", str(optimisation_file), "--fixtures",
                                    str(empty)])
    assert text.exit_code == 1 and text.stdout.count("NOT BACK-TESTED") == 2


def test_a_fixture_stands_in_for_a_failed_live_run_only_if_it_is_that_runs_cfd(tmp_path,
                                                                              capsys):
    """A live run asked for on another mesh or set-up and not had (here: no work folder)
    used to fall back to the fixture of the default set-up, shown as back-tested: the
    fixture now stands in only when its mesh and solver settings are those asked."""
    from dataclasses import replace

    from mfflap.cfd.openfoam.writer import SolverSettings

    folder = tmp_path / "bt"
    record = model_record(MOTION)
    record.provenance.update({"mesh": "coarse", "solver_max_courant": 4.0,
                              "solver_write_interval": 0.3})  # as the shipped ones say
    write_record(folder / f"backtest_{motion_key(MOTION)}.h5", record)
    args = (MOTION, "β = 0", MorisonModel(), 50.0)
    same = backtest_motion(*args, fixture_folders=[folder], live=True)
    assert same.status == "back-tested" and "instead of a live run" in same.source
    from mfflap.cli.backtest import _show

    _show({"β = 0": same}, as_json=False)  # the text says it beside the numbers too
    assert (f"CFD: fixture backtest_{motion_key(MOTION)}.h5 instead of a live run: "
            in capsys.readouterr().out)
    for mesh, solver, said in (
            ("graded", None, "was run on mesh 'coarse', not 'graded' as asked"),
            ("coarse", replace(SolverSettings(), max_courant=2.0),
             "was run with max_courant = 4.0, not 2.0 as asked"),
            # kept before the wall treatment was: run with the log-law wall functions
            ("coarse", replace(SolverSettings(), wall_treatment="all_y_plus"),
             "was run with wall_treatment = 'log_law', not 'all_y_plus' as asked")):
        other = backtest_motion(*args, fixture_folders=[folder], live=True, mesh=mesh,
                                solver=solver)
        assert other.status == "not back-tested", other.source
        assert other.source.endswith(f"; fixture backtest_{motion_key(MOTION)}.h5 {said}")
    # without --live the fixtures are read as they were made, whatever their set-up
    assert backtest_motion(*args, fixture_folders=[folder], mesh="graded").status == (
        "back-tested")


def test_backtest_command_exits_0_when_every_motion_is_back_tested(optimisation_file):
    """The shipped fixtures hold both motions: both are compared, and the exit status is 0
    (1 is kept for motions left out, above)."""
    from mfflap.cli.main import cli

    res = CliRunner().invoke(cli, ["backtest", str(optimisation_file)])
    assert res.exit_code == 0, res.output
    assert res.stdout.count("thrust CFD") == 2 and "NOT BACK-TESTED" not in res.stdout
    assert "exit status" not in res.stderr


@pytest.mark.openfoam
def test_ctrl_c_during_a_live_backtest_command_shows_what_was_done_and_how_to_resume(
        tmp_path, optimisation_file, solvers_left):
    """SIGINT to `mfflap backtest --live` while OpenFOAM runs the first motion: the solver
    is stopped, the message names the motion and the folder its run resumes from."""
    import signal
    import subprocess
    import sys
    import time

    from mfflap.cfd.openfoam.solver_log import solver_progress

    assert openfoam_available()
    work = tmp_path / "work"
    proc = subprocess.Popen(
        [sys.executable, "-c", "from mfflap.cli.main import cli; cli()", "backtest",
         str(optimisation_file), "--live", "--work", str(work), "--fixtures", str(tmp_path)],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    deadline = time.monotonic() + 300
    while time.monotonic() < deadline and proc.poll() is None and not any(
            solver_progress(d) for d in work.glob("*") if d.is_dir()):
        time.sleep(0.5)
    assert proc.poll() is None, proc.communicate()
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 1, err
    assert ("interrupted during the back-test of best sinusoid: 0 of 2 motions back-tested; "
            f"the same command resumes the live runs in {work} from their "
            "last written times") in err, err
    assert solvers_left(f"pimpleFoam -case {work}") == ""


def test_the_gain_in_cfd_is_not_a_ratio_to_a_drag():
    """A CFD gain needs both motions back-tested and a best sinusoid that makes thrust."""
    from types import SimpleNamespace

    from mfflap.backtest.run import BacktestOutcome
    from mfflap.backtest.workflow import gain_in_cfd, no_gain_in_cfd_reason

    def outcome(label, thrust):
        comparison = None if thrust is None else SimpleNamespace(cfd_mean_thrust=thrust)
        return BacktestOutcome(label, "k", "back-tested" if comparison else "not back-tested",
                               "fixture", comparison=comparison)

    def outcomes(optimised, sinusoid):
        return {"β = 0": outcome("β = 0", optimised),
                "best sinusoid": outcome("best sinusoid", sinusoid)}

    assert gain_in_cfd(outcomes(0.3, 0.2)) == pytest.approx(0.5)
    assert no_gain_in_cfd_reason(outcomes(0.3, 0.2)) is None
    assert gain_in_cfd(outcomes(-0.01, -0.07)) is None
    assert "best sinusoid in CFD makes no thrust (-0.07 N)" in \
        no_gain_in_cfd_reason(outcomes(-0.01, -0.07))
    assert gain_in_cfd(outcomes(None, 0.2)) is None
    assert no_gain_in_cfd_reason(outcomes(None, 0.2)) == "β = 0 was not back-tested"
    assert no_gain_in_cfd_reason({}) == "there is no β = 0 motion (not optimised)"


@pytest.mark.parametrize("coefficients", ["case", "uniform"])
@pytest.mark.slow
def test_the_main_job_kept_within_the_identification_data(tmp_path, coefficients):
    """`mfflap run` with optimisation.within_data: the pitch envelope, period bounds and
    heave limit are what the identification cases reach, the optimised motions keep to them
    (within the coverage's tolerance), and the case file stored with the results says so; with the
    case file's coefficients and with those identified from the CFD."""
    import json

    from mfflap.cli.main import cli
    from mfflap.identification.coverage import CoverageReference
    from mfflap.results import ResultsFile

    out = tmp_path / "run"
    # three starts, as the main job's default: its motions' back-tests ship as fixtures
    res = CliRunner().invoke(cli, ["run", str(CASE), "--out", str(out), *as_shipped(
        "--set", "optimisation.ipopt=false", "--set", "optimisation.gain_table=false",
        "--set", "optimisation.within_data=true", "--set",
        f"optimisation.coefficients={coefficients}"), "--json"])
    assert res.exit_code == 0, res.output
    summary = json.loads(res.output[res.output.index("{\n"):])
    limits = summary["within_data_limits"]
    cov = summary["coverage"]
    ranges = next(iter(cov.values()))["ranges"]
    assert limits["max_pitch_deg"] == pytest.approx(ranges["pitch amplitude"][1])
    assert limits["max_pitch_rate"] == pytest.approx(ranges["peak |pitch rate|"][1])
    assert limits["max_pitch_acceleration"] == pytest.approx(
        ranges["peak |pitch acceleration|"][1])
    assert limits["min_period"] == pytest.approx(1 / ranges["frequency"][1])
    assert limits["max_period"] == pytest.approx(1 / ranges["frequency"][0])
    assert limits["max_heave"] == pytest.approx(min(0.5, ranges["heave amplitude"][1]))
    assert "optimisation kept within the identification data: max_pitch_deg = " in res.output
    for label, c in cov.items():  # the variables the limits hold stay within the data
        if label.endswith("polished"):  # the polish weighs them as penalties against the
            continue                    # vortex model's thrust, and may step past them
        held = {"frequency", "pitch amplitude", "peak |pitch rate|",
                "peak |pitch acceleration|"}
        assert not held & set(c["outside"]), (label, c["said"])
    assert cov["best sinusoid"]["extrapolated"] is False
    # every motion back-tested from the shipped fixtures of these motions (real OpenFOAM)
    # (the polishes of these optima have no shipped CFD)
    assert {k: b["status"] for k, b in summary["backtest"].items()
            if not k.endswith("polished")} == dict.fromkeys(
        [k for k in cov if not k.endswith("polished")], "back-tested")
    from mfflap.records.record import fixture_dir

    shipped = {f"fixture {p.name}" for p in fixture_dir("backtest_within_data").glob("*.h5")}
    # (a record of beta = 1's least-power cycle may be matched shifted in time: its phase is
    # free, and machines that round differently find it elsewhere)
    sources = {b["source"].split(" (the same periodic motion shifted")[0]
               for k, b in summary["backtest"].items() if not k.endswith("polished")}
    assert len(sources) == 4 and sources <= shipped
    # the held-out motions: the four optima and any polish whose CFD ships (a polish that
    # stays at its optimum shares the optimum's record)
    held_out = sum(b["status"] == "back-tested" for b in summary["backtest"].values())
    assert held_out >= 4
    assert f"the {held_out} held-out motion(s)" in summary["gap_transfer"]["verdict"]
    # what docs/findings/optimised_motions.md says of these back-tests: with the paper's
    # coefficients the model gives
    # about half of CFD's mean thrust and power; identified from this CFD, within 5 % on
    # the best sinusoid and 20 % on the beta = 0 optimum
    # (the polishes of these optima have no shipped CFD, or share an optimum's)
    bt = {k: b for k, b in summary["backtest"].items() if not k.endswith("polished")}
    for label in ("best sinusoid", "β = 0"):
        errors = (bt[label]["mean_thrust_error"], bt[label]["mean_power_error"])
        if coefficients == "case":
            assert all(-0.6 < e < -0.4 for e in errors), (label, errors)
        else:
            bound = 0.05 if label == "best sinusoid" else 0.2
            assert all(abs(e) < bound for e in errors), (label, errors)
    # two of these runs were resumed by a retry a quarter into their last cycle
    # (docs/findings/optimised_motions.md, "Retries and one set-up"): said in the JSON and the
    # report for
    # those alone
    mixed = {"fixture backtest_598a5388e592df63.h5", "fixture backtest_de1ba4adb3e991be.h5"}
    assert {label for label, b in bt.items() if b["compared_cycles_mixed_set_up"]} == {
        label for label, b in bt.items() if b["source"] in mixed}
    assert len(sources & mixed) == 1  # case: the best sinusoid's; identified: beta = 0's
    report = (out / "report.html").read_text()
    assert report.count("its means mix two set-ups") == 1
    # the back-test table says how each CFD run ran, and since when for the one retried late
    assert "<th>CFD as run</th>" in report
    assert report.count("mesh coarse, max Co ") == sum(
        b["status"] == "back-tested" for b in summary["backtest"].values())
    assert "s (a retry resumed it)" in report
    with ResultsFile(out / "results.h5") as rf:
        assert f"max_pitch_rate = {limits['max_pitch_rate']!r}" in rf.config_toml
    # the limits are the data's: the same reference gives them
    from mfflap.config import load_case
    from mfflap.identification.data import prepare_cases
    from mfflap.records.record import read_records

    case = load_case(CASE)
    cases, _ = prepare_cases(read_records(fixture_dir("table1_coarse")),
                             case.identification.discard_time,
                             plate=case.plate, fluid=case.fluid, stream=case.flow)
    ref = CoverageReference.from_cases(cases, case.morison_model(), case.flow.velocity)
    assert ref.ranges["peak |pitch rate|"][1] == pytest.approx(limits["max_pitch_rate"])


@pytest.mark.slow
def test_within_data_without_identification_cases_says_so_and_optimises_unlimited(tmp_path):
    from mfflap.config import load_case
    from mfflap.pipeline import RunOptions, run_study

    empty = tmp_path / "no_records"
    empty.mkdir()
    options = RunOptions(fixtures=(empty,), n_starts=1, with_ipopt=False, sensitivity=False,
                         within_data=True, work_dir=tmp_path / "cases")
    outcome = run_study(load_case(CASE), options, progress=lambda m: None)
    assert any(p.startswith("identification:") for p in outcome.problems)
    assert ("optimisation: not kept within the identification data (asked): there are no "
            "identification cases") in outcome.problems
    assert outcome.within_data_limits == {} and outcome.coverage == {}
    assert outcome.study is not None  # the optimisation ran, unlimited
    assert outcome.config.optimisation.max_pitch_rate is None


def test_backtest_motion_option_picks_motions_and_refuses_one_not_in_the_file(
        optimisation_file):
    from mfflap.cli.main import cli

    for name in ("0.5", "β = 0.5", "beta 0.5", "β=0.50"):
        res = CliRunner().invoke(cli, ["backtest", str(optimisation_file), "--motion", name,
                                       "--json"])
        assert res.exit_code == 0, (name, res.output)
        import json

        assert list(json.loads(res.stdout)["motions"]) == ["β = 0.5"], name
    res = CliRunner().invoke(cli, ["backtest", str(optimisation_file), "--motion", "0.3"])
    assert res.exit_code == 2
    assert "'0.3' is none of the file's motions: 'best sinusoid', 'β = 0.5'" in res.output


def test_a_live_backtest_takes_a_motion_saved_before_on_the_same_set_up(optimisation_file,
                                                                       tmp_path):
    """`--save-to` holds the records of earlier live calls: a motion found there, run for
    this case on the mesh and set-up asked, is not run again (no case is written); one run
    on another mesh is."""
    import shutil

    from mfflap.cli.main import cli
    from mfflap.records.record import fixture_dir

    saved = tmp_path / "saved"
    saved.mkdir()
    for path in fixture_dir("backtest").glob("backtest_*.h5"):
        shutil.copy(path, saved / path.name)
    work = tmp_path / "work"
    # the saved records ran 2.5 periods after the ramp at max Co 4 with the freestream far
    # field and the log-law wall functions
    res = CliRunner().invoke(cli, ["backtest", str(optimisation_file), "--live", "--work",
                                   str(work), "--save-to", str(saved), "--json",
                                   "--set", "backtest.cycles=2.5",
                                   "--set", "cfd.max_courant=4.0",
                                   "--set", 'cfd.far_field="freestream"',
                                   "--set", 'cfd.wall_treatment="log_law"'])
    assert res.exit_code == 0, res.output
    import json

    out = json.loads(res.stdout)["motions"]
    assert len(out) == 2
    for label, o in out.items():
        assert o["status"] == "back-tested", label
        assert o["source"] == (f"live OpenFOAM, run before "
                               f"({saved / ('backtest_' + o['motion_key'])}.h5)"), label
    assert not work.exists()  # nothing was run
    # asked on another mesh or for another plate, the saved runs are not those: run again
    from mfflap.backtest.run import FixtureMatch, _done_before
    from mfflap.config import loads_case
    from mfflap.optimisation.store import read_result
    from mfflap.parameters import Plate
    from mfflap.results import ResultsFile

    with ResultsFile(optimisation_file) as rf:
        motion = read_result(rf, f"optimisation/sqp/{sorted(rf.h5['optimisation/sqp'])[0]}"
                             ).motion
        model = loads_case(rf.config_toml).morison_model()
    key = motion_key(motion)
    assert _done_before(motion, key, [saved], model, "coarse", None)[1] == FixtureMatch(
        saved / f"backtest_{key}.h5")
    assert _done_before(motion, key, [saved], model, "medium", None) == (None, None)
    other = MorisonModel(plate=Plate(chord=0.2))
    assert _done_before(motion, key, [saved], other, "coarse", None) == (None, None)


@pytest.mark.openfoam
def test_a_motion_whose_case_another_run_holds_is_not_recorded_as_failed(tmp_path):
    """A live back-test of a case another thread or process is running is not started, and
    no failure is saved beside the records (it is busy, not failed: a failure record would
    stand in for the motion's CFD in later look-ups)."""
    import threading

    from mfflap.cfd.openfoam.case_lock import case_lock

    assert openfoam_available()
    key = motion_key(MOTION)
    case = tmp_path / "work" / f"backtest_{key}"
    case.mkdir(parents=True)
    held, release = threading.Event(), threading.Event()

    def hold():
        with case_lock(case):
            held.set()
            release.wait(60)

    holder = threading.Thread(target=hold)
    holder.start()
    try:
        held.wait(10)
        out = backtest_motion(MOTION, "β = 0", MorisonModel(), 50.0, live=True,
                              work_dir=tmp_path / "work", save_to=tmp_path / "saved")
    finally:
        release.set()
        holder.join()
    assert out.status == "not back-tested"
    assert out.source.startswith("live OpenFOAM run not started: ")
    assert "another thread of this process is running the case" in out.source
    assert not list((tmp_path / "saved").glob("*.failed.toml"))


def test_the_look_up_takes_a_record_of_a_motion_within_its_tolerance_and_no_other(tmp_path):
    """A motion without a record of its own key is matched to a record whose imposed
    kinematics (after the start-up ramp) lie within the tolerance of its own; a motion
    further off, or of another period, is not."""
    from dataclasses import replace

    from mfflap.backtest.run import matching_fixture
    from mfflap.hydro.loads import Loads
    from mfflap.kinematics.convert import harmonic_to_discrete
    from mfflap.kinematics.discrete import DiscreteMotion

    motion = harmonic_to_discrete(0.8, 0.3, 0.5, 1.5, 40)
    spline = cfd_motion(motion)
    t = np.linspace(0.0, 3 * spline.period, 1201)
    state = spline.sample(t)
    h0 = spline.sample(np.array([0.0])).heave_position[0]
    state = replace(state, heave_position=state.heave_position - h0)
    zero = np.zeros_like(t)
    write_record(tmp_path / "backtest_run_before.h5", CfdRecord(
        "backtest_run_before", state, Loads(t, zero, zero, zero),
        {"kind": "table", "period": spline.period, "ramp_time": 0.0}))

    def scaled(factor: float) -> DiscreteMotion:
        return DiscreteMotion(factor * motion.pitch_acceleration, motion.heave_acceleration,
                              motion.time_step)

    found = matching_fixture("own", motion, [tmp_path])
    assert found.path == tmp_path / "backtest_run_before.h5" and found.shift_s == 0.0
    assert matching_fixture("near", scaled(1.001), [tmp_path]) is not None  # 0.1 % off
    assert matching_fixture("far", scaled(1.01), [tmp_path]) is None  # 1 % off
    slower = DiscreteMotion(motion.pitch_acceleration, motion.heave_acceleration,
                            motion.time_step * 1.01)
    assert matching_fixture("slower", slower, [tmp_path]) is None  # another period
    # a record of the motion's own key is taken first
    write_record(tmp_path / "backtest_far.h5", CfdRecord(
        "backtest_far", state, Loads(t, zero, zero, zero), {"kind": "table", "period": 1.0}))
    assert matching_fixture("far", scaled(1.01), [tmp_path]).path == tmp_path / "backtest_far.h5"


@pytest.mark.parametrize("shift_share", [0.25, -0.4, 0.013])
def test_the_look_up_takes_a_record_of_the_same_periodic_motion_shifted_in_time(
        tmp_path, shift_share):
    """A record of the motion's cycle begun at another point of it (the CFD at t that of the
    motion at t + s) is matched, with s, and the back-test's source says so: a periodic
    optimum whose phase nothing fixes (beta = 1's least power) is found at other phases on
    machines that round differently. A motion of the same period whose pitch is shifted
    against its heave (another motion) is not matched at any shift."""
    from dataclasses import replace

    from mfflap.backtest.run import FixtureMatch, cycle_shift, matching_fixture
    from mfflap.hydro.loads import Loads
    from mfflap.kinematics.convert import harmonic_to_discrete

    motion = harmonic_to_discrete(0.8, 0.3, 0.5, 1.5, 40)
    spline = cfd_motion(motion)
    shift = shift_share * spline.period
    t = np.linspace(0.0, 3 * spline.period, 2401)
    state = spline.sample(t + shift)  # the CFD starts at zero displacement
    state = replace(state, time=t,
                    heave_position=state.heave_position - state.heave_position[0])
    zero = np.zeros_like(t)
    record = CfdRecord("backtest_shifted", state, Loads(t, zero, zero, zero),
                       {"kind": "table", "period": spline.period, "ramp_time": 0.0})
    write_record(tmp_path / "backtest_shifted.h5", record)
    found = matching_fixture("own", motion, [tmp_path])
    assert found is not None and found.path == tmp_path / "backtest_shifted.h5"
    assert found.shift_s == pytest.approx(shift, abs=1e-4 * spline.period)
    assert f"shifted in time by {shift:+.4g} s" in found.describe()
    assert FixtureMatch(found.path).describe() == "fixture backtest_shifted.h5"
    # live, a record run before is taken shifted too, and its source says so as well
    outcome = backtest_motion(motion, "β = 1", MorisonModel(), 50.0, live=True,
                              done_folders=[tmp_path])
    assert outcome.source == (f"live OpenFOAM, run before ({tmp_path / 'backtest_shifted.h5'}"
                              f", the same periodic motion shifted in time by {shift:+.4g} s)")
    # pitch leading heave by another phase: the same period, another motion
    other = harmonic_to_discrete(0.8, 0.3, 0.5, 1.3, 40)
    assert cycle_shift(record, cfd_motion(other)) is None
    assert matching_fixture("other", other, [tmp_path]) is None
    # a record that ends before a period follows its ramp has no cycle to match
    short = CfdRecord("backtest_short", state, Loads(t, zero, zero, zero),
                      {"kind": "table", "period": spline.period, "ramp_time": 2.5 * t[-1]})
    assert cycle_shift(short, spline) is None


@pytest.mark.slow
@pytest.mark.parametrize("threads", ["1", "2"])
def test_the_main_job_as_shipped_back_tests_every_optimum_from_the_shipped_cfd(tmp_path,
                                                                            threads):
    """`mfflap run` of the shipped case file with nothing set, as the README runs it, on one
    and two OpenBLAS threads: it optimises with the coefficients it identified, the phase
    fixed, and finds a shipped OpenFOAM run of every motion in backtest_main_job, whose
    means it compares over the last two of three cycles."""
    import json
    import os
    import subprocess
    import sys

    from mfflap.records.record import fixture_dir

    env = {**os.environ, "OPENBLAS_NUM_THREADS": threads}
    done = subprocess.run([sys.executable, "-c", "from mfflap.cli.main import cli; cli()",
                           "run", str(CASE), "--out", str(tmp_path / "run"), "--json"],
                          env=env, capture_output=True, text=True, timeout=1200)
    assert done.returncode == 0, done.stderr[-3000:]
    summary = json.loads(done.stdout[done.stdout.index("{"):])
    assert summary["optimised_with"] == "uniform"
    assert {k: v["used"] for k, v in summary["residual_scaling"].items()}["uniform"] == "case"
    shipped = {f"fixture {p.name}" for name in ("backtest_main_job", "backtest_polish_bandwidth")
               for p in fixture_dir(name).glob("*.h5")}
    backtests = summary["backtest"]
    # the optima and the best sinusoid from the shipped CFD; the β = 0 optimum's polish on the
    # vortex model too, where it ends at the motion whose CFD ships: the vortex model's
    # chaotic wake lets round-off below its rounding (another CPU's BLAS kernels) steer it
    # elsewhere, and then it says so
    assert {"best sinusoid", "β = 0", "β = 0.5", "β = 1", "β = 0 polished"} <= set(backtests)
    optima = {k: b for k, b in backtests.items() if not k.endswith("polished")}
    assert {b["status"] for b in optima.values()} == {"back-tested"}, backtests
    assert {b["source"] for b in optima.values()} <= shipped
    for label, b in backtests.items():
        if label.endswith("polished"):
            assert (b["status"] == "back-tested" and b["source"].split(" (the same periodic")[0]
                    in shipped) or "no CFD fixture for motion key" in b["source"], b
    assert {b["cycles_averaged"] for b in backtests.values()
            if b["status"] == "back-tested"} == {2}
    # every back-tested motion on the three levels: Morison, the vortex model and CFD
    import h5py

    with h5py.File(tmp_path / "run" / "results.h5") as h5:
        ladder = {h5["model_ladder"][k].attrs["label"]: h5["model_ladder"][k]
                  for k in h5["model_ladder"]}
        assert set(ladder) == {k for k, b in backtests.items() if b["status"] == "back-tested"}
        beta0 = ladder["β = 0"]
        assert json.loads(beta0.attrs["levels"]) == ["cfd", "morison", "vortex"]
        assert beta0["peak_power"].attrs["units"] == "W"
        cfd_peak, morison_peak, vortex_peak = beta0["peak_power"][()]
        # over the last two periods: at least the last one's peak
        assert cfd_peak >= 0.999 * backtests["β = 0"]["cfd_max_power"]
        assert abs(vortex_peak - cfd_peak) < abs(morison_peak - cfd_peak)
    html = (tmp_path / "run" / "report.html").read_text()
    assert "Three levels: Morison, the discrete-vortex model and CFD" in html
