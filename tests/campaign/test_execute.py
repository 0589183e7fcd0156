"""Campaigns on a real dask LocalCluster running real OpenFOAM; records; resume; failures."""

import os
import re
import shutil
import signal
import socket
import subprocess
import sys
import threading
import time
import warnings
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path

import dask
import distributed  # noqa: F401 (its defaults in dask.config before a test overrides one)
import h5py
import numpy as np
import pytest
from foamlib import FoamFile

from mfflap.campaign.cases import CfdCase, grid_cases
from mfflap.campaign.execute import (
    CampaignSetup,
    campaign_status,
    fraction_simulated,
    run_campaign,
)
from mfflap.cfd.openfoam.retry_log import (
    LEGACY_RETRY_LOG,
    RETRY_LOG,
    append_retry,
    budget_retries,
    read_retry_log,
)
from mfflap.cfd.openfoam.run_motion import run_motion
from mfflap.cfd.openfoam.runner import dies_with_caller, openfoam_available, run_case
from mfflap.cfd.openfoam.setups import case_mesh_and_solver
from mfflap.cfd.openfoam.writer import SolverSettings, write_case
from mfflap.config import IdentificationGrid
from mfflap.errors import CfdRunError, ConfigError, MfflapError
from mfflap.hydro import MorisonModel
from mfflap.kinematics import RampHarmonicMotion
from mfflap.metrics import pearson
from mfflap.records.record import CfdRecord, read_record, read_records, write_record
from mfflap.records.retries import (
    FORCES_BEYOND_BOUND,
    RERUN_REQUESTED,
    SAME_LOSS_AGAIN,
    TIME_STEP_COLLAPSED,
    Retry,
)
from mfflap.study_tables import CfdSettings
from mfflap.toml_io import read_toml

SHORT = CfdCase(1.0, 0.3, 90.0, 10.0, duration=0.04, ramp_time=0.02)
OTHER = CfdCase(2.0, 0.1, 45.0, 10.0, duration=0.04, ramp_time=0.02)


def test_grid_covers_every_frequency_first_and_caps_duration():
    grid = IdentificationGrid()
    cases = grid_cases(grid)
    assert len(cases) == 125
    assert len({c.case_id for c in cases}) == 125
    assert {c.frequency for c in cases[:5]} == set(grid.frequencies)
    assert cases[0].heave_amplitude == 0.3 and cases[0].phase_deg == 90.0
    for c in cases:
        assert c.duration == pytest.approx(min(grid.n_cycles / c.frequency, grid.max_duration))
        assert "." not in c.case_id
    sub = grid_cases(grid, heave_amplitudes=[0.1, 0.5], phases_deg=[90])
    assert len(sub) == 10
    with pytest.raises(ConfigError, match=r"0\.33 is not on the grid"):
        grid_cases(grid, heave_amplitudes=[0.33])


def synthetic_record(name="syn", n=200) -> CfdRecord:
    motion = RampHarmonicMotion(1.0, 0.3, np.deg2rad(10), np.pi / 2)
    state = motion.sample(np.linspace(0, 2, n))
    loads = MorisonModel().loads(state)
    return CfdRecord(name, state, loads, {"kind": "ramp_harmonic", "frequency": 1.0},
                     {"solver": "test"})


def test_record_round_trip_and_atomic_write(tmp_path):
    rec = synthetic_record()
    path = write_record(tmp_path / "syn.h5", rec)
    assert not list(tmp_path.glob(".*tmp"))
    back = read_record(path)
    np.testing.assert_array_equal(back.loads.normal_force, rec.loads.normal_force)
    np.testing.assert_array_equal(back.state.pitch_angle, rec.state.pitch_angle)
    assert back.parameters["frequency"] == 1.0 and back.provenance["solver"] == "test"
    # a leftover temporary file of a killed writer is not a record
    (tmp_path / ".half.h5.123.tmp").write_bytes(b"\x89HDF")
    assert [r.name for r in read_records(tmp_path)] == ["syn"]
    small = read_record(write_record(tmp_path / "small.h5", rec, single_precision=True))
    assert small.loads.normal_force.dtype == np.float64  # read back as float64
    np.testing.assert_allclose(small.loads.normal_force, rec.loads.normal_force, rtol=1e-6,
                               atol=1e-6 * np.abs(rec.loads.normal_force).max())
    np.testing.assert_array_equal(small.time, rec.time)  # time stays double
    w = back.window(1.0)
    assert w.time[0] >= 1.0 and len(w.time) == len(w.state.time)


def test_record_with_nan_is_refused_naming_file_and_sample(tmp_path):
    rec = synthetic_record()
    rec.loads.normal_force[17] = np.nan
    path = write_record(tmp_path / "bad.h5", rec)
    with pytest.raises(MfflapError, match=r"bad\.h5: loads/normal_force is not finite at "
                                          r"sample 17"):
        read_record(path)


@pytest.mark.openfoam
def test_restart_continues_from_last_written_time(tmp_path):
    """A run stopped early continues from its last written time; the force folders merge."""
    assert openfoam_available()
    motion = SHORT.motion()
    case_dir = tmp_path / "c"
    # the case run_motion writes for 0.06 s, run to 0.03 s and stopped there (a run whose
    # end time was changed is another run: run_motion refuses to resume it)
    write_case(case_dir, motion, 0.06, ramp_time=0.02,
               solver=SolverSettings(write_interval=0.06 / 4))
    control = case_dir / "system" / "controlDict"
    text = control.read_text()
    control.write_text(text.replace("endTime         0.06;", "endTime         0.03;"))
    run_case(case_dir, timeout_s=300)
    control.write_text(text)
    told: list[str] = []
    rec = run_motion(case_dir, motion, "c", {}, end_time=0.06, ramp_time=0.02,
                     progress=told.append)
    folders = sorted(p.name for p in (case_dir / "postProcessing" / "forces").iterdir())
    assert len(folders) == 2 and folders[0] == "0"
    assert told[0] == f"pimpleFoam from t = {folders[1]} s; log: {case_dir / 'log.pimpleFoam'}"
    assert np.all(np.diff(rec.time) > 0) and rec.time[-1] > 0.058
    log = (case_dir / "log.pimpleFoam").read_text()
    assert log.count("Starting time loop") == 2
    model = MorisonModel().loads(rec.state)
    after = rec.time > 0.02
    assert pearson(rec.loads.normal_force[after], model.normal_force[after]) > 0.8


@pytest.mark.openfoam
def test_campaign_on_local_cluster_resumes_and_reports_failures(tmp_path, capfd):
    """Real LocalCluster, two worker processes, real pimpleFoam; dask's default HTTP port
    taken (as by another campaign) costs not even a warning."""
    assert openfoam_available()
    out = tmp_path / "camp"
    failing = CfdCase(0.0, 0.2, 90.0, 10.0, duration=1.0, ramp_time=0.5)  # f = 0: refused
    setup = CampaignSetup(timeout_s=900.0, single_precision=True)
    with socket.socket() as taken, warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            taken.bind(("127.0.0.1", 8787))
            taken.listen()
        except OSError:
            pass  # already taken by someone else: the same situation
        statuses = run_campaign([SHORT, OTHER, failing], out, setup, n_workers=2, poll_s=0.2)
    assert not [w for w in caught if "already in use" in str(w.message)]
    bar = capfd.readouterr().err
    assert "CFD cases: 100%" in bar and "3.00/3" in bar, bar[-500:]
    states = {s.case_id: s.state for s in statuses}
    assert states == {SHORT.case_id: "done", OTHER.case_id: "done", failing.case_id: "failed"}
    failed = next(s for s in statuses if s.state == "failed")
    assert "frequency must be finite and > 0" in failed.message
    records = {r.name: r for r in read_records(out)}
    assert set(records) == {SHORT.case_id, OTHER.case_id}
    rec = records[SHORT.case_id]
    assert rec.provenance["openfoam_build"].startswith("OPENFOAM=1912")
    assert rec.provenance["mesh"] == "coarse" and rec.provenance["cpu_time_s"] > 0
    assert rec.provenance["flow_velocity_m_per_s"] == 0.3  # what it was run for, read back
    assert rec.provenance["fluid_kinematic_viscosity_m2_per_s"] == 1e-6  # by identification
    assert rec.provenance["plate_thickness_m"] == 0.003
    assert 0 <= rec.provenance["n_steps_bounding_epsilon"] <= rec.provenance["n_time_steps"]
    assert rec.parameters["frequency"] == 1.0
    assert rec.provenance["storage"] == "float32"  # written compact, like the fixtures
    with h5py.File(out / f"{SHORT.case_id}.h5") as h5:
        assert h5["loads/normal_force"].dtype == np.float32
        assert h5["loads/time"].dtype == np.float64
    assert not (out / "cases" / SHORT.case_id).exists()  # cleaned after success
    mtime = (out / f"{SHORT.case_id}.h5").stat().st_mtime_ns
    again = run_campaign([SHORT, OTHER, failing], out, setup, n_workers=1, progress=False)
    assert [s.state for s in again] == ["done", "done", "failed"]
    assert all(s.message == "already finished" for s in again[:2])
    assert (out / f"{SHORT.case_id}.h5").stat().st_mtime_ns == mtime  # never rerun
    assert [s.state for s in campaign_status(out)] == ["done", "done", "failed"]
    with pytest.raises(ConfigError, match=r"another setup \(mesh: 'coarse' in the folder, "
                                          r"'medium' asked\); ") as refused:
        run_campaign([SHORT], out, CampaignSetup(mesh="medium"), progress=False)
    assert "timeout_s" not in str(refused.value)  # a time limit is not a setup (no result
    # depends on it): a case that timed out is rerun with a longer one


def test_the_progress_bar_says_which_run_in_flight_was_retried_and_how(tmp_path):
    """A run retried from t = 0 s takes its simulated share back to nothing, so the bar
    steps back (a case of campaigns/table1_coarse_co2_from_start went from 97 % to 4 %);
    its postfix says why: the last case in flight retried, with its retry count and how it
    went on (rerun requests do not count)."""
    from mfflap.campaign.execute import retries_in_flight
    for case_id, retries in (("a", []), ("b", [
            Retry(TIME_STEP_COLLAPSED, 1.69, 0.0, "the inletOutlet far field"),
            Retry(RERUN_REQUESTED, None, None, "")]),
            ("c", [Retry(FORCES_BEYOND_BOUND, 1.4, 1.125, "maxCo 2", 4.0),
                   Retry(SAME_LOSS_AGAIN, 1.4, 0.0, "max Co 2", 2.0, 4.0)])):
        (tmp_path / "cases" / case_id).mkdir(parents=True)
        for retry in retries:
            append_retry(tmp_path / "cases" / case_id, retry)
    assert retries_in_flight(tmp_path, ["a", "missing"]) == ""
    assert retries_in_flight(tmp_path, ["a", "b"]) == (
        "b: retry 1, resumed from t = 0 s with the inletOutlet far field")
    assert retries_in_flight(tmp_path, ["b", "c"]) == "c: retry 2, rerun from t = 0 s with max Co 2"


@pytest.mark.openfoam
def test_a_finished_run_that_lost_its_numerics_is_lost_and_rerun_on_request(tmp_path):
    """A real record whose F_n after the ramp is made 10,000 times larger (what a run that
    lost its numerics leaves): status "lost" with where; a plain rerun keeps it; with
    retry_failed it is kept aside as .lost.h5 and the case runs again, to "done"."""
    from mfflap.records.record import LOST_SUFFIX

    out = tmp_path / "camp"
    setup = CampaignSetup(timeout_s=900.0)
    run_campaign([SHORT], out, setup, progress=False)
    path = out / f"{SHORT.case_id}.h5"
    rec = read_record(path)
    grown = rec.loads.normal_force * np.where(rec.time > 0.03, 1e4, 1.0)
    lost = CfdRecord(rec.name, rec.state, type(rec.loads)(
        rec.time, grown, rec.loads.tangential_force, rec.loads.moment,
        source=rec.loads.source), rec.parameters, rec.provenance)
    write_record(path, lost)
    (status,) = campaign_status(out)
    assert status.state == "lost"
    assert "its forces leave what the motion can drive, t = 0.03" in status.message
    assert run_campaign([SHORT], out, setup, progress=False)[0].message == "already finished"
    (again,) = run_campaign([SHORT], out, setup, progress=False, retry_failed=True)
    assert again.state == "done" and again.message.endswith("s CPU")
    kept = read_record(out / f"{SHORT.case_id}{LOST_SUFFIX}")
    np.testing.assert_array_equal(kept.loads.normal_force, grown)
    assert [s.state for s in campaign_status(out)] == ["done"]
    assert [r.name for r in read_records(out)] == [SHORT.case_id]  # not the one kept aside


@pytest.mark.openfoam
def test_a_record_cut_short_is_unreadable_then_kept_aside_and_its_case_rerun(tmp_path):
    """A record cut short (a copy interrupted, a full disk) used to stop `campaign status`
    with the h5py error of that one file, and a resumed campaign counted it as done for
    ever; now status calls it "unreadable" and the next run keeps it aside and reruns it."""
    from mfflap.records.record import UNREADABLE_SUFFIX

    out = tmp_path / "camp"
    setup = CampaignSetup(timeout_s=900.0)
    run_campaign([SHORT, OTHER], out, setup, progress=False)
    path = out / f"{SHORT.case_id}.h5"
    whole = path.read_bytes()
    path.write_bytes(whole[:5000])
    states = {s.case_id: s for s in campaign_status(out)}
    assert states[OTHER.case_id].state == "done"
    assert states[SHORT.case_id].state == "unreadable"
    assert f"{path}: cannot be opened as an HDF5 file" in states[SHORT.case_id].message
    assert f"keeps it as {SHORT.case_id}{UNREADABLE_SUFFIX}" in states[SHORT.case_id].message
    again = {s.case_id: s for s in run_campaign([SHORT, OTHER], out, setup, progress=False)}
    assert again[OTHER.case_id].message == "already finished"
    assert again[SHORT.case_id].state == "done" and again[SHORT.case_id].message.endswith(
        "s CPU")
    assert (out / f"{SHORT.case_id}{UNREADABLE_SUFFIX}").read_bytes() == whole[:5000]
    assert read_record(path).name == SHORT.case_id
    assert sorted(r.name for r in read_records(out)) == sorted([SHORT.case_id,
                                                               OTHER.case_id])
    assert [s.state for s in campaign_status(out)] == ["done", "done"]


def _flip_chunk_bytes(path: Path, dataset: str) -> None:
    """Flip bytes in the middle of the first compressed chunk of ``dataset``: the file
    opens and lists its datasets, but reading that one fails inside its filter."""
    with h5py.File(path) as f:
        info = f[dataset].id.get_chunk_info(0)
    data = bytearray(path.read_bytes())
    middle = info.byte_offset + info.size // 2
    data[middle:middle + 64] = bytes(b ^ 0xFF for b in data[middle:middle + 64])
    path.write_bytes(bytes(data))


def test_a_record_with_a_damaged_compressed_chunk_is_unreadable_not_a_crash(tmp_path):
    """A record that opens but whose gzip chunk of loads/normal_force is damaged is
    "unreadable" to `campaign status` (kept aside by the next run, like a record cut short),
    an UnreadableRecordError naming the file to the library, and exit status 2 naming the
    file to `mfflap identify`."""
    from click.testing import CliRunner

    from mfflap.cli.main import cli
    from mfflap.errors import UnreadableRecordError

    shipped = Path(__file__).parents[2] / "campaigns" / "table1_coarse_all_y_plus"
    out = tmp_path / "camp"
    out.mkdir()
    shutil.copy(shipped / "campaign.toml", out)
    name = "f1p000_h0p300_phi090p0.h5"
    shutil.copy(shipped / name, out)
    _flip_chunk_bytes(out / name, "loads/normal_force")
    with pytest.raises(UnreadableRecordError) as info:
        read_record(out / name)
    assert info.value.path == str(out / name)
    states = {s.case_id: s for s in campaign_status(out)}
    assert states["f1p000_h0p300_phi090p0"].state == "unreadable"
    assert str(out / name) in states["f1p000_h0p300_phi090p0"].message
    case_file = Path(__file__).parents[2] / "cases" / "paper2026.toml"
    res = CliRunner().invoke(cli, ["identify", str(case_file), "--fixtures", str(out)])
    assert res.exit_code == 2, res.output
    assert str(out / name) in res.output and "Traceback" not in res.output


def test_status_tells_how_far_a_started_run_got(tmp_path):
    """A case folder with a solver log and no record is "started"; the message reads the
    real pimpleFoam log's last time step, the folder a rerun resumes from, the retries."""
    from mfflap.cfd.openfoam.solver_log import solver_progress

    out = tmp_path / "camp"
    out.mkdir()
    (out / "campaign.toml").write_text(
        f'[setup]\nmesh = "coarse"\n\n[cases.{SHORT.case_id}]\nfrequency = 1.0\n\n'
        f'[cases.{OTHER.case_id}]\nfrequency = 2.0\n')
    case_dir = out / "cases" / SHORT.case_id
    written = "FoamFile {}\n\n// " + "*" * 73 + " //\n"  # how OpenFOAM ends a file
    for folder in ("0", "0.5", "1.25"):
        (case_dir / folder).mkdir(parents=True)
        if folder != "1.25":  # a folder written in part: not one to resume from
            (case_dir / folder / "U").write_text(written)
        (case_dir / folder / "p").write_text(written)
    (case_dir / "mfflap_case.toml").write_text("end_time = 3.0\n")
    assert campaign_status(out)[0].state == "pending"  # no solver log yet: not begun
    log = (Path(__file__).parents[1] / "data" / "openfoam_v1912" / "collapsed_dt.log").read_text()
    (case_dir / "log.pimpleFoam").write_text(log)
    # the text log of a case written before the log was JSON counts as well
    (case_dir / LEGACY_RETRY_LOG).write_text("time step collapsed; resumed from the last "
                                             "written time with the inletOutlet far field\n")
    assert solver_progress(case_dir) == (pytest.approx(1.3821858), pytest.approx(7.3073054e-26))
    started, other = campaign_status(out)
    assert (started.state, other.state) == ("started", "pending")
    assert started.fraction_simulated == pytest.approx(1.3821858 / 3.0)
    assert other.fraction_simulated is None
    assert started.message == ("t = 1.382 of 3 s simulated (46%), time step 7.3e-26 s; a rerun "
                               "resumes from t = 0.5 s; 1 retry")
    assert solver_progress(tmp_path) is None
    shares = fraction_simulated(out, [SHORT.case_id, OTHER.case_id])
    assert shares == {SHORT.case_id: pytest.approx(1.3821858 / 3.0)}


def test_a_record_half_written_when_its_worker_died_is_cleared_on_the_next_call(tmp_path):
    """write_record's temporary file, left when the process writing it was killed, is
    removed when the campaign is run again; finished records stay."""
    out = tmp_path / "camp"
    out.mkdir()
    rec = synthetic_record(SHORT.case_id)
    write_record(out / f"{SHORT.case_id}.h5", rec)
    stale = out / f".{OTHER.case_id}.h5.12345.tmp"
    stale.write_bytes(b"\x89HDF\r\n")
    (status,) = run_campaign([SHORT], out, CampaignSetup(), progress=False)
    assert status.message == "already finished"
    assert not stale.exists() and (out / f"{SHORT.case_id}.h5").exists()


def test_status_of_a_folder_that_is_not_a_campaign(tmp_path):
    with pytest.raises(MfflapError, match=r"no campaign\.toml"):
        campaign_status(Path(tmp_path))


@pytest.mark.openfoam
def test_a_run_that_cannot_finish_in_time_fails_cleanly_with_its_log(tmp_path):
    from mfflap.campaign.execute import run_one

    long_case = CfdCase(0.5, 0.2, 90.0, 10.0, duration=100.0, ramp_time=0.5)
    status = run_one(long_case, str(tmp_path), CampaignSetup(timeout_s=3.0))
    assert status.state == "failed" and "timed out after 3.0 s" in status.message
    note = (tmp_path / f"{long_case.case_id}.failed.toml").read_text()
    assert "log_tail" in note and ("Solving for" in note or "tabulated6DoFMotion" in note)
    assert (tmp_path / "cases" / long_case.case_id).is_dir()  # kept for a restart


@pytest.mark.openfoam
def test_collapsed_time_step_is_retried_with_a_lower_courant_limit(tmp_path):
    """Every attempt 'collapses' (the watchdog threshold is above any real step): the run
    is resumed with the inletOutlet far field, then with maxCo 4 -> 2 -> 1 (upwind k-epsilon
    on the last try), then reported; the solver accepts the changed fields and schemes."""
    from mfflap.errors import CfdRunError

    case_dir = tmp_path / "c"
    with pytest.raises(CfdRunError, match="time step collapsed"):
        run_motion(case_dir, SHORT.motion(), "c", {}, 1.0, ramp_time=0.02, min_time_step=1.0)
    assert FoamFile(case_dir / "system" / "controlDict")["maxCo"] == 1
    schemes = FoamFile(case_dir / "system" / "fvSchemes")["divSchemes"]
    assert schemes["div(phi,k)"] == schemes["div(phi,epsilon)"] == ("Gauss", "upwind")
    assert schemes["div(phi,U)"] == ("Gauss", "linearUpwind", "grad(U)")  # momentum untouched
    assert (case_dir / "log.pimpleFoam").read_text().count("Starting time loop") == 4
    assert "type inletOutlet;" in (case_dir / "0" / "U").read_text()
    assert "type fixedValue;" in (case_dir / "0" / "p").read_text()
    retries, _ = read_retry_log(case_dir)
    assert [r.remedy for r in retries] == [
        "the inletOutlet far field", "maxCo 2", "maxCo 1 and first-order upwind k and epsilon"]


def _short_run_retried_once(tmp_path, monkeypatch, run_case_instead, calls):
    """run_motion of SHORT to 0.04 s in ``tmp_path / "c"``, with ``run_case_instead`` (which
    appends each case it runs to ``calls``) as its run_case, retried once and then finished
    with the inletOutlet far field: (the retry's progress line, the record)."""
    from mfflap.cfd.openfoam import run_motion as openfoam_run

    monkeypatch.setattr(openfoam_run, "run_case", run_case_instead)
    told = []
    rec = run_motion(tmp_path / "c", SHORT.motion(), "c", {}, 0.04, ramp_time=0.02,
                     bound_watch_every_s=1e6, progress=told.append)
    assert len(calls) == 2
    [retry] = [m for m in told if m.startswith("retry ")]
    assert rec.provenance["as_run_far_field"] == "inletOutlet"
    assert np.all(np.diff(rec.time) > 0) and rec.time[-1] == pytest.approx(0.04, abs=1e-3)
    assert (tmp_path / "c" / "log.pimpleFoam").read_text().count("Starting time loop") == 2
    return retry, rec


@pytest.mark.openfoam
def test_a_run_whose_force_log_times_repeat_is_retried_from_before_them(tmp_path, monkeypatch):
    """A time step that collapses below the written precision too briefly for the runner to
    see leaves a finished run whose force log repeats a time (a back-test on the
    coarse mesh: t = 4.3245473 s twice, its forces near 1e9 N, then on to its end). The
    first real run here is given such a time just before 0.035 s: it is retried from the last
    time written before it (0.03 s) with the next remedy, and the record is the rerun's."""
    from mfflap.cfd.openfoam import run_motion as openfoam_run

    real = openfoam_run.run_case
    calls, repeated = [], []

    def repeats_a_time_once(case_dir, **kwargs):
        real(case_dir, **kwargs)
        calls.append(case_dir)
        if len(calls) == 1:
            for stem in ("force", "moment"):
                path = case_dir / "postProcessing" / "forces" / "0" / f"{stem}.dat"
                lines = path.read_text().splitlines(keepends=True)
                i = next(k for k, line in enumerate(lines)
                         if not line.startswith("#") and float(line.split()[0]) > 0.035)
                path.write_text("".join([*lines[:i], lines[i - 1], *lines[i:]]))
                repeated.append(lines[i - 1].split()[0])

    retry, rec = _short_run_retried_once(tmp_path, monkeypatch, repeats_a_time_once, calls)
    assert 0.034 < float(repeated[0]) < 0.035  # the row before the first after 0.035 s
    assert retry == (f"retry 1 of 3: time step collapsed at t = {float(repeated[0])!r} s (the "
                     "force log's times repeat there); resumed from t = 0.03 s with the "
                     "inletOutlet far field")
    assert rec.provenance["retries"] == retry.removeprefix("retry 1 of 3: ")


def _first_step_after(text: str, start: int, after_s: float, what: str
                      ) -> tuple[tuple[int, int], str]:
    """The first time step of the log ``text`` (from byte ``start`` on) taken after
    ``after_s``: where its ``what`` ("deltaT" or "Courant") value stands in ``text``, and
    the time the runner reports for it (for a time step the time it reached, for a Courant
    number the time its step began at)."""
    began = None
    for m in re.finditer(r"^deltaT = (\S+)\nTime = (\S+)$|^Time = (\S+)$|"
                         r"^Courant Number mean: \S+ max: (\S+)$", text, re.M):
        if m.start() < start:
            continue
        if what == "deltaT" and m[1] and float(m[2]) > after_s:
            return m.span(1), m[2]
        began = m[2] or m[3] or began
        if what == "Courant" and m[4] and began is not None and float(began) > after_s:
            return m.span(4), began
    raise AssertionError(f"no {what} after t = {after_s} s in the log")


@pytest.mark.openfoam
@pytest.mark.parametrize("what, value, error", [("deltaT", "1.5e-08", "time step collapsed"),
                                                ("Courant", "250", "Courant number exploded")])
def test_a_brief_divergence_seen_after_later_writes_is_retried_from_the_write_before_it(
        tmp_path, monkeypatch, what, value, error):
    """A time step that collapses for a moment, or a Courant number that explodes, is seen
    after it (at the runner's next look, or once the solver has exited), possibly after the
    solver wrote fields past it, which are spoiled. The first real run here is judged as the
    runner judges a finished run, with its first step after 0.035 s given a time step of
    1.5e-8 s (as a real coarse-mesh back-test's was for a moment) or a Courant number of
    250: it is retried from 0.03 s, the last write before it, with the next remedy, not from
    its end time 0.04 s, where it would have had nothing left to run."""
    from mfflap.cfd.openfoam import run_motion as openfoam_run
    from mfflap.cfd.openfoam import runner
    from mfflap.cfd.openfoam.time_step_watch import TimeStepWatch

    real = openfoam_run.run_case
    calls, reported_at = [], []

    def diverges_once_after_its_writes(case_dir, **kwargs):
        log = case_dir / "log.pimpleFoam"
        start = log.stat().st_size if log.is_file() else 0
        real(case_dir, **kwargs)
        calls.append(case_dir)
        if len(calls) == 1:
            text = log.read_text()
            (first, last), at = _first_step_after(text, start, 0.035, what)
            log.write_text(f"{text[:first]}{value}{text[last:]}")
            reported_at.append(at)
            watch = TimeStepWatch(log, kwargs["min_time_step"], start_byte=start)
            watch.read(to_end=True)
            if (diverged := runner._diverged("pimpleFoam", watch, case_dir, log,
                                             runner.MAX_COURANT_ABORT, exited=True)) is not None:
                raise diverged

    retry, _ = _short_run_retried_once(tmp_path, monkeypatch, diverges_once_after_its_writes,
                                       calls)
    assert 0.035 < float(reported_at[0]) < 0.04
    assert retry == (f"retry 1 of 3: {error} at t = {reported_at[0]} s; resumed from t = "
                     "0.03 s with the inletOutlet far field")


@pytest.mark.openfoam
def test_forces_beyond_the_bound_are_retried_from_the_written_time_before_them(tmp_path):
    """Every attempt 'loses its numerics' after the ramp (the bound is scaled down a
    millionfold): each retry rewinds to the last time written before the breach (0.03 s;
    the case keeps the last two of its four writes), drops the later fields and force
    output, changes the case like a collapse does and reruns pimpleFoam from there. The
    third breach, at the same flow time after the Courant limit was halved, has the run
    rerun from t = 0 at max Co 2 (the flow written at 0.03 s may have been spoiled); the
    fourth, the same again, ends the retries."""
    from mfflap.cfd.openfoam.forces import read_forces
    from mfflap.errors import CfdRunError

    case_dir = tmp_path / "c"
    with pytest.raises(CfdRunError, match=r"the forces leave what the motion can drive, "
                       r"t = 0\.03.*where they left it before the run was rerun from t = 0 s "
                       r"\(t = 0\.03.*\): the mesh, the far field or the turbulence model does "
                       r"not hold this motion at max Co 2; after 3 retries: forces beyond .* "
                       r"with the inletOutlet far field; forces beyond .* with maxCo 2; "
                       r"rerun from t = 0 s with max Co 2"):
        run_motion(case_dir, SHORT.motion(), "c", {}, 0.04, ramp_time=0.035,
                   force_bound_factor=1e-6)
    retries, _ = read_retry_log(case_dir)
    assert len(retries) == 3
    assert all(r.cause == FORCES_BEYOND_BOUND and r.failed_at_s == pytest.approx(0.03, abs=5e-3)
               and r.resumed_from_s == pytest.approx(0.03) for r in retries[:2])
    assert [r.remedy for r in retries[:2]] == ["the inletOutlet far field", "maxCo 2"]
    assert (retries[2].cause, retries[2].resumed_from_s, retries[2].max_courant) == (
        SAME_LOSS_AGAIN, 0.0, 2.0)
    assert retries[2].failed_at_s == pytest.approx(0.03, abs=5e-3)
    log = (case_dir / "log.pimpleFoam").read_text()
    assert log.count("Starting time loop") == 4
    assert log.count("Time = 0.01\n") == 2  # the first 0.03 s ran twice: at max Co 4 and 2
    assert sorted(p.name for p in (case_dir / "postProcessing" / "forces").iterdir()) == ["0"]
    history = read_forces(case_dir)  # the last attempt's forces from 0 s on, one history
    assert np.all(np.diff(history.time) > 0)
    assert history.time[-1] == pytest.approx(0.04, abs=1e-3)


@pytest.mark.openfoam
def test_a_loss_at_the_same_flow_time_is_rerun_from_the_start_once(tmp_path, monkeypatch):
    """Real pimpleFoam reruns with a scripted bound judgement: the loss at t = 0.036 s stays
    put at max Co 4 (inletOutlet) and 2; the rerun from t = 0 at max Co 2 holds, as
    f = 1 Hz, h = 0.5 m, phi = 135 deg did. The record says so; every field written before
    the rerun went, so its forces are the rerun's alone."""
    from mfflap.cfd.openfoam import run_motion as openfoam_run
    from mfflap.records.force_envelope import EnvelopeBreach

    verdicts = iter([0.036, 0.0361, 0.0362, None])

    def scripted(*args, **kwargs):
        start = next(verdicts)
        return None if start is None else EnvelopeBreach(start, start + 1e-3, 3, start, 5.0)

    monkeypatch.setattr(openfoam_run, "_forces_beyond_bound", scripted)
    case_dir = tmp_path / "c"
    rec = run_motion(case_dir, SHORT.motion(), "c", {}, 0.04, ramp_time=0.035,
                     bound_watch_every_s=1e6)
    assert rec.provenance["retries"].split("; ")[-1].startswith(
        "rerun from t = 0 s with max Co 2: the forces left what the motion can drive from "
        "t = 0.0362 s again, as at max Co 4")
    assert FoamFile(case_dir / "system" / "controlDict")["maxCo"] == 2
    assert (rec.provenance["solver_max_courant"], rec.provenance["as_run_max_courant"]) == (
        4.0, 2.0)
    assert (rec.provenance["solver_far_field"], rec.provenance["as_run_far_field"]) == (
        "freestream", "inletOutlet")
    log = (case_dir / "log.pimpleFoam").read_text()
    assert log.count("Starting time loop") == 4 and log.count("Time = 0.01\n") == 2
    assert rec.time[0] < 0.005 and np.all(np.diff(rec.time) > 0)
    assert rec.time[-1] == pytest.approx(0.04, abs=1e-3)


@pytest.mark.openfoam
def test_a_loss_that_moves_with_the_time_step_keeps_being_retried(tmp_path, monkeypatch):
    """Real pimpleFoam reruns with a scripted bound judgement: a breach that moves by more
    than SAME_BREACH_FRACTION of c / U after the Courant limit was halved is retried on to
    the last remedy (max Co 1, upwind k-epsilon), unlike one that stays put."""
    from mfflap.cfd.openfoam import run_motion as openfoam_run
    from mfflap.errors import CfdRunError
    from mfflap.records.force_envelope import EnvelopeBreach

    starts = iter([0.036, 0.037, 0.012, 0.039])  # the third moved by 25 ms > 0.02 c / U

    def scripted(*args, **kwargs):
        start = next(starts)
        return EnvelopeBreach(start, start + 1e-3, 3, start, 5.0)

    monkeypatch.setattr(openfoam_run, "_forces_beyond_bound", scripted)
    from mfflap.parameters import FreeStream, Plate
    assert openfoam_run.SAME_BREACH_FRACTION * Plate().chord / FreeStream().velocity < 0.025
    case_dir = tmp_path / "c"
    with pytest.raises(CfdRunError, match="3 retries did not cure it"):
        run_motion(case_dir, SHORT.motion(), "c", {}, 0.04, ramp_time=0.035,
                   bound_watch_every_s=1e6)
    retries, _ = read_retry_log(case_dir)
    assert [r.remedy for r in retries] == [
        "the inletOutlet far field", "maxCo 2", "maxCo 1 and first-order upwind k and epsilon"]
    # before any kept write
    assert (retries[2].failed_at_s, retries[2].max_courant) == (pytest.approx(0.012), 2.0)
    assert retries[2].resumed_from_s == 0.0
    assert (case_dir / "log.pimpleFoam").read_text().count("Starting time loop") == 4


@pytest.mark.openfoam
def test_a_run_leaving_the_bound_is_stopped_while_it_runs(tmp_path):
    """The forces are checked while pimpleFoam runs: a run beyond the (scaled-down) bound
    stops long before its end time instead of computing the lost stretch."""
    from mfflap.cfd.openfoam.forces import read_forces
    from mfflap.cfd.openfoam.run_motion import ForcesBeyondBound
    from mfflap.errors import RunStoppedByWatch

    case_dir = tmp_path / "c"
    with pytest.raises(RunStoppedByWatch, match=re.escape(
            "pimpleFoam stopped: the forces leave what the motion can drive, t = 0.0")) as info:
        run_motion(case_dir, SHORT.motion(), "c", {}, 0.5, ramp_time=0.02,
                   force_bound_factor=1e-6, bound_watch_every_s=0.5, max_retries=0)
    assert isinstance(info.value.reason, ForcesBeyondBound)
    stopped_at = read_forces(case_dir).time[-1]
    assert stopped_at < 0.25 and 0.0 <= info.value.reason.breach.start_s <= stopped_at


@pytest.mark.openfoam
def test_retries_of_an_earlier_call_reach_the_record_of_the_call_that_finishes(tmp_path):
    """A first call switches the far field after a 'collapse' and gives up (one retry); a
    later call resumes the same case to the end. The record says the far field changed,
    although mfflap_case.toml still says freestream."""
    from mfflap.errors import CfdRunError

    case_dir = tmp_path / "c"
    solver = SolverSettings(write_interval=0.25)  # nothing written before the 'collapse'
    with pytest.raises(CfdRunError, match=r"time step collapsed.*; after 1 retry: time step "
                       r"collapsed at t = [0-9.e-]+ s; resumed from t = 0 s with the "
                       r"inletOutlet"):
        run_motion(case_dir, SHORT.motion(), "c", {}, 1.0, ramp_time=0.02, min_time_step=1.0,
                   max_retries=1, solver=solver)
    # the run cut to 0.02 s by hand, in both files (a case of another end time is another
    # run, which run_motion refuses to resume)
    for name, old, new in (("system/controlDict", "endTime         1.0;", "endTime 0.02;"),
                           ("mfflap_case.toml", "end_time = 1.0\n", "end_time = 0.02\n")):
        path = case_dir / name
        assert old in path.read_text()
        path.write_text(path.read_text().replace(old, new))
    rec = run_motion(case_dir, SHORT.motion(), "c", {}, 0.02, ramp_time=0.02, solver=solver)
    assert rec.time[-1] == pytest.approx(0.02, abs=1e-3)
    assert re.fullmatch(r"time step collapsed at t = [0-9.e-]+ s; resumed from t = 0 s with "
                        r"the inletOutlet far field", rec.provenance["retries"])
    assert rec.provenance["solver_far_field"] == "freestream"



@pytest.mark.openfoam
def test_a_resumed_run_has_what_is_left_of_its_retries_until_a_rerun_is_requested(tmp_path):
    """Every attempt 'collapses'. A first call spends its one retry; a second call (a killed
    campaign resumed) allowed two in all has one left, not two; after request_rerun (what
    --retry-failed does) a third call has a new budget, its remedy following on from the
    case's settings (max Co 2 -> 1)."""
    from mfflap.cfd.openfoam.retry_log import request_rerun
    from mfflap.errors import CfdRunError

    case_dir = tmp_path / "c"
    with pytest.raises(CfdRunError, match="after 1 retry:"):
        run_motion(case_dir, SHORT.motion(), "c", {}, 1.0, ramp_time=0.02, min_time_step=1.0,
                   max_retries=1)
    with pytest.raises(CfdRunError, match=r"after 2 retries:.*with maxCo 2 and first-order "
                       r"upwind k and epsilon\n"):
        run_motion(case_dir, SHORT.motion(), "c", {}, 1.0, ramp_time=0.02, min_time_step=1.0,
                   max_retries=2)
    log = case_dir / "log.pimpleFoam"
    assert log.read_text().count("Starting time loop") == 4  # 2 + 2, not 2 + 3
    request_rerun(case_dir)
    with pytest.raises(CfdRunError, match=r"after 3 retries:.*; rerun requested: .*with maxCo 1\n"):
        run_motion(case_dir, SHORT.motion(), "c", {}, 1.0, ramp_time=0.02, min_time_step=1.0,
                   max_retries=1)
    assert log.read_text().count("Starting time loop") == 6
    retries, _ = read_retry_log(case_dir)
    assert retries[2].cause == RERUN_REQUESTED and len(retries) == 4
    assert FoamFile(case_dir / "system" / "controlDict")["maxCo"] == 1


@pytest.mark.openfoam
def test_an_earlier_calls_breach_counts_for_the_same_flow_time_rule(tmp_path, monkeypatch):
    """Real pimpleFoam reruns with a scripted bound judgement that always finds the loss at
    t = 0.036 s. A first call (two retries: inletOutlet at max Co 4, then max Co 2) gives up;
    a second call allowed three finds it again at max Co 2 and, the breach of the earlier
    call at max Co 4 (read from the case's retry log) being the same flow time, spends its
    last retry on a rerun from t = 0, not on max Co 1; the loss there ends it."""
    from mfflap.cfd.openfoam import run_motion as openfoam_run
    from mfflap.errors import CfdRunError
    from mfflap.records.force_envelope import EnvelopeBreach

    def scripted(*args, **kwargs):
        return EnvelopeBreach(0.036, 0.037, 3, 0.036, 5.0)

    monkeypatch.setattr(openfoam_run, "_forces_beyond_bound", scripted)
    case_dir = tmp_path / "c"
    with pytest.raises(CfdRunError, match="2 retries did not cure it"):
        run_motion(case_dir, SHORT.motion(), "c", {}, 0.04, ramp_time=0.035,
                   bound_watch_every_s=1e6, max_retries=2)
    notes, _ = read_retry_log(case_dir)
    assert [(r.cause, r.failed_at_s, r.max_courant) for r in notes] == [
        (FORCES_BEYOND_BOUND, 0.036, 4.0)] * 2
    with pytest.raises(CfdRunError, match=r"where they left it before the run was rerun from "
                       r"t = 0 s \(t = 0\.036 s\): .* at max Co 2; after 3 retries"):
        run_motion(case_dir, SHORT.motion(), "c", {}, 0.04, ramp_time=0.035,
                   bound_watch_every_s=1e6, max_retries=3)
    later, _ = read_retry_log(case_dir)
    assert later[:2] == notes and len(later) == 3
    assert (later[2].cause, later[2].resumed_from_s) == (SAME_LOSS_AGAIN, 0.0)
    assert (later[2].max_courant, later[2].earlier_max_courant) == (2.0, 4.0)
    assert FoamFile(case_dir / "system" / "controlDict")["maxCo"] == 2
    # three runs in the first call; in the second, none for the run that had reached its
    # end time (its forces are judged as they are), then the rerun from t = 0
    assert (case_dir / "log.pimpleFoam").read_text().count("Starting time loop") == 4


@pytest.mark.slow
def test_retry_failed_gives_a_failed_case_a_new_budget_of_retries(tmp_path):
    """A failed case's folder is kept; a plain rerun of the campaign leaves it as it is,
    --retry-failed marks a new budget of retries in its retry log before running it again
    (on a real LocalCluster; the case fails again at once, its motion being refused)."""
    out = tmp_path / "camp"
    failing = CfdCase(0.0, 0.2, 90.0, 10.0, duration=1.0, ramp_time=0.5)  # f = 0: refused
    setup = CampaignSetup(timeout_s=60.0)
    (status,) = run_campaign([failing], out, setup, n_workers=1, progress=False)
    assert status.state == "failed"
    retry_log = out / "cases" / failing.case_id / RETRY_LOG
    retry_log.parent.mkdir(parents=True)
    collapsed = Retry(TIME_STEP_COLLAPSED, 0.5, 0.25, "maxCo 1")
    append_retry(retry_log.parent, collapsed)
    assert run_campaign([failing], out, setup, n_workers=1, progress=False)[0].state == "failed"
    assert read_retry_log(retry_log.parent) == ([collapsed], [])
    (again,) = run_campaign([failing], out, setup, n_workers=1, progress=False,
                            retry_failed=True)
    assert again.state == "failed" and "frequency must be finite" in again.message
    assert [r.cause for r in read_retry_log(retry_log.parent)[0]] == [TIME_STEP_COLLAPSED,
                                                                      RERUN_REQUESTED]

def test_status_counts_retries_not_rerun_requests(tmp_path):
    """The retry log's rerun requests are not retries, in a started case's status nor in
    the budget of its next call."""
    from mfflap.cfd.openfoam.run_motion import _earlier_breach

    out = tmp_path / "camp"
    case_dir = out / "cases" / SHORT.case_id
    (case_dir / "0").mkdir(parents=True)
    (out / "campaign.toml").write_text(
        f'[setup]\nmesh = "coarse"\n\n[cases.{SHORT.case_id}]\nfrequency = 1.0\n')
    (case_dir / "mfflap_case.toml").write_text("end_time = 3.0\n")
    (case_dir / "log.pimpleFoam").write_text(
        (Path(__file__).parents[1] / "data" / "openfoam_v1912" / "collapsed_dt.log").read_text())
    breach = Retry(FORCES_BEYOND_BOUND, 1.2, 1.0, "maxCo 1", 2.0)
    collapsed = Retry(TIME_STEP_COLLAPSED, 0.7, 0.5, "the inletOutlet far field")
    for retry in (collapsed, breach, Retry(RERUN_REQUESTED, None, None, "")):
        append_retry(case_dir, retry)
    assert campaign_status(out)[0].message.endswith("; 2 retries")
    assert budget_retries(case_dir) == ([], 0)
    append_retry(case_dir, breach)
    assert campaign_status(out)[0].message.endswith("; 3 retries")
    assert budget_retries(case_dir) == ([breach], 0)
    assert _earlier_breach([breach]) == (1.2, 2.0)
    assert _earlier_breach([collapsed]) is None

def test_manifest_written_before_the_pressure_solver_setting_still_resumes(tmp_path):
    """campaign.toml files written before pressure_solver/pressure_tolerance, far_field,
    velocity_convection, frame and wall_treatment existed describe PCG runs at 1e-7 with the
    freestream far field, linearUpwind U, the moving mesh and the log-law wall functions:
    they resume with those settings and refuse GAMG, LUST, the plate's frame or another wall
    treatment."""
    from dataclasses import asdict, replace

    from mfflap.campaign.execute import CampaignSetup, _write_manifest
    from mfflap.cfd.case_inputs import ADDED_SOLVER_SETTINGS
    from mfflap.toml_io import dumps, read_toml

    cases = grid_cases(IdentificationGrid(frequencies=(1.0,), heave_amplitudes=(0.1,),
                                          phases_deg=(90.0,)))
    setup = CampaignSetup()
    old = setup.as_dict()
    old["solver"] = {k: v for k, v in asdict(setup.solver).items()
                     if k not in ADDED_SOLVER_SETTINGS}
    assert len(old["solver"]) == len(asdict(setup.solver)) - 8
    (tmp_path / "campaign.toml").write_text(dumps({"setup": old, "cases": {}}))
    _write_manifest(tmp_path, cases, setup)  # same runs: accepted
    assert read_toml(tmp_path / "campaign.toml")["setup"]["solver"]["pressure_solver"] == "PCG"
    solver = read_toml(tmp_path / "campaign.toml")["setup"]["solver"]
    assert solver["velocity_convection"] == "linearUpwind"
    assert solver["pressure_final_rel_tol"] == 0.0
    assert solver["turbulence_convection"] == "limitedLinear"
    assert solver["frame"] == "inertial"
    assert solver["wall_treatment"] == "log_law"
    for change in ({"pressure_solver": "GAMG"}, {"velocity_convection": "LUST"},
                   {"wall_treatment": "all_y_plus"},
                   {"pressure_final_rel_tol": 0.01}, {"turbulence_convection": "upwind"},
                   {"frame": "plate", "far_field": "inletOutlet"}):
        other = replace(setup, solver=replace(setup.solver, **change))
        with pytest.raises(ConfigError, match="another setup"):
            _write_manifest(tmp_path, cases, other)


@pytest.mark.slow
def test_far_field_switch_rewrites_binary_time_folders_and_the_run_resumes(tmp_path):
    """A real run writes binary fields; the far-field switch edits only the patch dictionary
    text of U and p in every time folder, and pimpleFoam resumes from them."""
    from dataclasses import replace

    from mfflap.cfd.openfoam.retry_edits import use_inlet_outlet_far_field
    from mfflap.cfd.openfoam.runner import run_case
    from mfflap.cfd.openfoam.writer import SolverSettings, write_case

    solver = replace(SolverSettings(), write_interval=0.01)
    case = write_case(tmp_path / "c", SHORT.motion(), end_time=0.02, solver=solver)
    run_case(case, timeout_s=300)
    written = [p for p in case.iterdir() if p.name not in ("0",) and (p / "U").is_file()]
    assert written and b"freestreamVelocity" in (written[-1] / "U").read_bytes()
    assert use_inlet_outlet_far_field(case) is True
    assert use_inlet_outlet_far_field(case) is False  # nothing left to switch
    for folder in [case / "0", *written]:
        u, p = (folder / "U").read_bytes(), (folder / "p").read_bytes()
        assert b"inletOutlet" in u and b"freestream" not in u and b"freestream" not in p
    control = case / "system" / "controlDict"
    control.write_text(control.read_text().replace("endTime         0.02;",
                                                   "endTime         0.03;"))
    run_case(case, timeout_s=300)
    assert (case / "log.pimpleFoam").read_text().count("Starting time loop") == 2


def test_solver_setting_selects_the_far_field_and_refuses_unknown_ones(tmp_path):
    from dataclasses import replace

    from mfflap.cfd.openfoam.writer import SolverSettings, write_case

    with pytest.raises(ConfigError, match="far_field"):
        SolverSettings(far_field="farfield")
    case = write_case(tmp_path / "c", SHORT.motion(), end_time=0.02,
                      solver=replace(SolverSettings(), far_field="inletOutlet"))
    assert "type inletOutlet;" in (case / "0" / "U").read_text()
    assert "type fixedValue; value uniform 0;" in (case / "0" / "p").read_text()
    default = write_case(tmp_path / "d", SHORT.motion(), end_time=0.02)
    assert "freestreamVelocity" in (default / "0" / "U").read_text()


def test_the_settings_as_run_follow_every_remedy_a_retry_applies(tmp_path):
    """A written case's settings as run are its set-up's; after the three remedies of
    run_motion's retries (inletOutlet, half maxCo, upwind k-epsilon) they are the new ones."""
    from mfflap.cfd.openfoam.run_motion import (
        as_run_settings,
        lower_courant_limit,
        use_inlet_outlet_far_field,
        use_upwind_turbulence,
    )
    from mfflap.cfd.openfoam.writer import SolverSettings, write_case

    solver = SolverSettings()
    case = write_case(tmp_path / "c", SHORT.motion(), end_time=0.02, solver=solver)
    assert as_run_settings(case) == {
        "as_run_max_courant": solver.max_courant, "as_run_far_field": solver.far_field,
        "as_run_turbulence_convection": solver.turbulence_convection,
        "as_run_wall_treatment": solver.wall_treatment}
    assert use_inlet_outlet_far_field(case) and use_upwind_turbulence(case)
    lower_courant_limit(case)
    assert as_run_settings(case) == {
        "as_run_max_courant": solver.max_courant / 2, "as_run_far_field": "inletOutlet",
        "as_run_turbulence_convection": "upwind", "as_run_wall_treatment": "log_law"}


@pytest.mark.openfoam
def test_campaign_command_runs_a_named_set_up(tmp_path):
    """--setup affordable: the manifest and the written case carry the set-up's mesh and
    solver settings (the run itself is cut short by the timeout)."""
    from click.testing import CliRunner

    from mfflap.cli.main import cli
    from mfflap.toml_io import read_toml

    case = Path(__file__).parents[2] / "cases" / "paper2026.toml"
    out = tmp_path / "camp"
    grid = ["--set", "identification.frequencies=[2]",
            "--set", "identification.heave_amplitudes=[0.1]",
            "--set", "identification.phases_deg=[90]"]
    both = CliRunner().invoke(cli, ["campaign", "run", str(case), "--out", str(out), *grid,
                                    "--mesh", "finest", "--setup", "affordable"])
    assert both.exit_code != 0 and "finest" in both.output and not out.exists()
    unknown = CliRunner().invoke(cli, ["campaign", "run", str(case), "--out", str(out), *grid,
                                       "--setup", "cheapest", "--dry-run"])
    assert unknown.exit_code != 0 and "setups.toml" in unknown.output
    assert "cheapest" in unknown.output
    res = CliRunner().invoke(cli, ["campaign", "run", str(case), "--out", str(out), *grid,
                                   "--setup", "affordable", "--set", "cfd.timeout_s=3",
                                   "--set", "cfd.keep_case_dirs=true"])
    assert res.exit_code == 1, res.output  # the case failed (timed out): not a whole campaign
    assert ("exit status 1: 1 of 1 cases not done (1 failed: `--retry-failed` reruns them)"
            in res.stderr)
    manifest = read_toml(out / "campaign.toml")["setup"]
    assert manifest["mesh"] == "graded"
    assert manifest["solver"]["velocity_convection"] == "LUST"
    assert manifest["solver"]["n_outer_correctors"] == 1
    assert manifest["solver"]["pressure_final_rel_tol"] == 0.01
    (case_dir,) = (out / "cases").iterdir()
    assert "Gauss LUST grad(U)" in (case_dir / "system" / "fvSchemes").read_text()
    assert "FAILED f2p000_h0p100_phi090p0" in res.output


def test_a_case_the_folder_lists_with_other_values_is_refused_before_anything_runs(tmp_path):
    """A case id keeps f, h and phi: the same id with another duration, ramp or pitch ramp
    rate (n_cycles or pitch_ramp_rate_deg changed in the case file) would take the folder's
    record or run of the listed case for the one asked. Refused, by `campaign run` and its
    --dry-run, naming the values both ways; other and new cases pass."""
    from click.testing import CliRunner

    from mfflap.campaign.execute import _write_manifest, check_same_cases
    from mfflap.cli.main import cli

    out = tmp_path / "camp"
    out.mkdir()
    listed = CfdCase(2.0, 0.1, 90.0, 10.0, duration=1.5, ramp_time=0.125)  # paper2026's
    # the set-up `campaign run` asks by default
    _write_manifest(out, [listed], CampaignSetup(solver=case_mesh_and_solver(CfdSettings())[1]))
    check_same_cases(out, [listed, OTHER])  # the same values, and a case not listed
    longer = CfdCase(2.0, 0.1, 90.0, 10.0, duration=2.5, ramp_time=0.125)
    with pytest.raises(ConfigError, match=r"duration: 1\.5 in the folder, 2\.5 asked") as err:
        check_same_cases(out, [OTHER, longer])
    assert err.value.key == f"cases.{listed.case_id}"
    case = tmp_path / "case.toml"
    text = (Path(__file__).parents[2] / "cases" / "paper2026.toml").read_text()
    case.write_text(text.replace("pitch_ramp_rate_deg = 10.0", "pitch_ramp_rate_deg = 5.0"))
    for dry_run in (["--dry-run"], []):
        res = CliRunner().invoke(cli, ["campaign", "run", str(case), "--out", str(out),
                                       "--set", "identification.frequencies=[2]",
                                       "--set", "identification.heave_amplitudes=[0.1]",
                                       "--set", "identification.phases_deg=[90]", *dry_run])
        assert res.exit_code == 2, res.output
        assert (f"{out / 'campaign.toml'}: cases.{listed.case_id}: this folder holds case "
                f"{listed.case_id} with other values (pitch_ramp_rate_deg: 10.0 in the "
                "folder, 5.0 asked)") in " ".join(res.output.split())
    assert sorted(p.name for p in out.iterdir()) == ["campaign.toml"]


@pytest.mark.openfoam
def test_campaign_command_exit_status_says_whether_every_case_is_done(tmp_path):
    """A case that fails (timed out) gives exit status 1 after the summary, so that a
    script's next step does not take the campaign as complete; `--retry-failed` with a longer
    time limit (not a setup of its own) then runs it (half a cycle at 2 Hz on the coarse
    mesh, about 20 s) and the status is 0."""
    from click.testing import CliRunner

    from mfflap.cli.main import cli
    from mfflap.toml_io import read_toml

    case = tmp_path / "short.toml"
    text = (Path(__file__).parents[2] / "cases" / "paper2026.toml").read_text()
    case.write_text(text.replace("n_cycles = 3.0", "n_cycles = 0.5"))
    out = tmp_path / "camp"
    args = ["campaign", "run", str(case), "--out", str(out),
            "--set", "identification.frequencies=[2]",
            "--set", "identification.heave_amplitudes=[0.1]",
            "--set", "identification.phases_deg=[90]"]
    failed = CliRunner().invoke(cli, [*args, "--set", "cfd.timeout_s=1"])
    assert failed.exit_code == 1, failed.output
    assert "0/1 cases done" in failed.stdout and "FAILED f2p000_h0p100_phi090p0" in failed.stdout
    assert "exit status 1: 1 of 1 cases not done (1 failed" in failed.stderr
    done = CliRunner().invoke(cli, [*args, "--retry-failed"])  # the default time limit
    assert done.exit_code == 0, done.output
    assert "1/1 cases done" in done.stdout and "exit status" not in done.stderr
    assert read_toml(out / "campaign.toml")["setup"]["timeout_s"] == 6 * 3600.0  # the last


def _solvers_in(case_dir: Path) -> list[str]:
    """Command lines of the processes running in ``case_dir`` (read from /proc)."""
    found = []
    for proc in Path("/proc").iterdir():
        try:
            command = (proc / "cmdline").read_bytes().replace(b"\0", b" ").decode()
        except OSError:
            continue
        if proc.name.isdigit() and f"-case {case_dir}" in command:
            found.append(command)
    return found


def _solvers_left(case_dir: Path, wait_s: float = 60.0) -> list[str]:
    """The processes still running in ``case_dir`` after waiting up to ``wait_s`` for them
    to end (a signalled solver writes its last step first, which takes seconds on a loaded
    machine); those left are killed, whatever the test then asserts."""
    deadline = time.monotonic() + wait_s
    while _solvers_in(case_dir) and time.monotonic() < deadline:
        time.sleep(0.1)
    left = _solvers_in(case_dir)
    for command in left:
        subprocess.run(["pkill", "-KILL", "-f", command.strip()], check=False)
    return left


def _wait_for_solver(log: Path, timeout_s: float = 120.0) -> None:
    deadline = time.monotonic() + timeout_s
    while not (log.is_file() and "\nTime = " in log.read_text()):
        assert time.monotonic() < deadline, f"{log}: the solver did not start"
        time.sleep(0.1)


@pytest.mark.openfoam
@pytest.mark.parametrize("n_procs", [1, 2])
def test_a_solver_dies_with_the_process_that_runs_it(tmp_path, n_procs):
    """A Python process running a case, killed with SIGKILL (as the out-of-memory killer or
    a dask nanny kills a worker), takes its pimpleFoam with it, serial or mpirun and its
    ranks: no orphan goes on writing into the case that a rerun resumes. The solver first
    writes the time step it reached (every rank), so the rerun loses nothing."""
    from mfflap.cfd.openfoam.solver_log import solver_progress
    from mfflap.cfd.openfoam.time_folders import latest_solution_time

    case_dir = tmp_path / "c"
    script = ("import sys\n"
              "from mfflap.campaign.cases import CfdCase\n"
              "from mfflap.cfd.openfoam.run_motion import run_motion\n"
              "case = CfdCase(1.0, 0.3, 90.0, 10.0, duration=2.0, ramp_time=0.5)\n"
              "run_motion(sys.argv[1], case.motion(), 'c', {}, end_time=2.0, ramp_time=0.5,\n"
              "           n_procs=int(sys.argv[2]))\n")
    runner = subprocess.Popen([sys.executable, "-c", script, str(case_dir), str(n_procs)])
    try:
        _wait_for_solver(case_dir / "log.pimpleFoam")
        assert _solvers_in(case_dir), "no solver found in /proc"
        # past its first steps (however loaded the machine): a stop without a write would
        # lose them
        deadline = time.monotonic() + 120.0
        while (solver_progress(case_dir) or (0.0,))[0] <= 0.012:
            assert time.monotonic() < deadline, "the solver did not get to t = 0.012 s"
            time.sleep(0.1)
    finally:
        runner.kill()
        runner.wait()
    assert not _solvers_left(case_dir)

    reached, time_step = solver_progress(case_dir)
    written = latest_solution_time(case_dir)
    assert float(written) == pytest.approx(reached, abs=0.5 * time_step)
    assert reached > 0.01  # not the start: the regular writes are 0.5 s apart
    if n_procs > 1:
        assert (case_dir / "processor1" / written / "U").is_file()


@pytest.mark.openfoam
def test_a_decomposed_run_stopped_for_its_timeout_leaves_no_rank_running(tmp_path):
    """mpirun is stopped so that it stops its ranks: when the timeout's error arrives no
    solver runs in the case any more (killed at once, mpirun left them running a second or
    two, while a retry could already be resuming the case)."""
    case_dir = tmp_path / "c"
    case = CfdCase(1.0, 0.3, 90.0, 10.0, duration=2.0, ramp_time=0.5)
    write_case(case_dir, case.motion(), 2.0, ramp_time=0.5)
    with pytest.raises(CfdRunError, match="timed out after 8") as timed_out:
        run_case(case_dir, n_procs=2, timeout_s=8.0)
    assert "Time = " in (case_dir / "log.pimpleFoam").read_text()
    running = _solvers_in(case_dir)
    _solvers_left(case_dir, wait_s=0.0)
    assert not running
    # both ranks wrote the time step they had reached, where a rerun resumes: nothing lost
    from mfflap.cfd.openfoam.solver_log import solver_progress
    from mfflap.cfd.openfoam.time_folders import latest_solution_time

    written = latest_solution_time(case_dir)
    reached, time_step = solver_progress(case_dir)
    assert float(written) == pytest.approx(reached, abs=0.5 * time_step)
    assert f"it wrote its fields at t = {written} s, where a rerun resumes" in str(
        timed_out.value)
    assert (case_dir / "processor1" / written / "U").is_file()


def test_a_solver_whose_caller_died_before_it_started_does_not_start(tmp_path):
    """The wrapped command starts only from the process that wrapped it: started by another
    (as when its caller dies between the fork and the kernel's death-signal request, and
    init adopts it) it does not run at all."""
    marker = tmp_path / "ran"
    command = dies_with_caller(["touch", str(marker)])
    assert command[0].endswith("setpriv")
    relay = "import subprocess, sys; subprocess.run(sys.argv[1:], check=False)"
    subprocess.run([sys.executable, "-c", relay, *command], check=True)
    assert not marker.exists()
    subprocess.run(command, check=True)
    assert marker.exists()


@dataclass(frozen=True)
class WorkerKillingCase(CfdCase):
    """A case whose dask worker is killed (SIGKILL) once its solver runs, as the
    out-of-memory killer would: every time, or only the first time (``once_marker``)."""

    solver_log: str = ""
    once_marker: str = ""

    def motion(self) -> RampHarmonicMotion:
        if not (self.once_marker and Path(self.once_marker).exists()):
            if self.once_marker:
                Path(self.once_marker).touch()

            def kill_when_solving() -> None:
                _wait_for_solver(Path(self.solver_log))
                os.kill(os.getpid(), signal.SIGKILL)

            threading.Thread(target=kill_when_solving, daemon=True).start()
        return super().motion()


@pytest.mark.openfoam
def test_a_worker_killed_under_its_run_fails_that_case_only(tmp_path):
    """Real LocalCluster: a case whose worker process dies under it on every worker it is
    given (dask's KilledWorker) is written and reported as failed, and its solver is gone;
    the other case finishes, and the campaign status and a rerun keep the failure."""
    out = tmp_path / "camp"
    killer_id = CfdCase(1.0, 0.5, 90.0, 10.0, duration=1.0, ramp_time=0.2).case_id
    killer = WorkerKillingCase(1.0, 0.5, 90.0, 10.0, duration=1.0, ramp_time=0.2,
                               solver_log=str(out / "cases" / killer_id / "log.pimpleFoam"))
    setup = CampaignSetup(timeout_s=600.0, keep_case_dirs=True)
    with dask.config.set({"distributed.scheduler.allowed-failures": 1}):
        statuses = run_campaign([killer, SHORT], out, setup, n_workers=2, progress=False)
    assert [s.state for s in statuses] == ["failed", "done"]
    assert statuses[0].message.startswith("its dask worker process died under the run on 2 "
                                          "workers (the out-of-memory killer")
    failed = read_toml(out / f"{killer_id}.failed.toml")
    assert "KilledWorker" in failed["log_tail"] and "--retry-failed" in failed["error"]
    assert not _solvers_left(out / "cases" / killer_id)
    assert [s.state for s in campaign_status(out)] == ["failed", "done"]
    assert [s.state for s in run_campaign([killer, SHORT], out, setup, n_workers=1,
                                          progress=False)] == ["failed", "done"]


@pytest.mark.openfoam
def test_a_case_whose_worker_died_once_resumes_on_another_and_finishes(tmp_path):
    """Real LocalCluster: the worker running a case is killed once its solver has begun;
    dask gives the case to the other worker, which resumes it in the same folder where the
    first solver stopped and writes its record. The first solver wrote the time step it had
    reached as its worker died, and held the case until it had: it did not run beside the
    second, and the second did not start over from t = 0."""
    out = tmp_path / "camp"
    case = WorkerKillingCase(1.0, 0.3, 90.0, 10.0, duration=0.1, ramp_time=0.02,
                             solver_log=str(out / "cases" / SHORT.case_id / "log.pimpleFoam"),
                             once_marker=str(tmp_path / "killed_once"))
    setup = CampaignSetup(timeout_s=600.0, keep_case_dirs=True)
    (status,) = run_campaign([case], out, setup, n_workers=2, progress=False)
    assert (tmp_path / "killed_once").exists()
    assert status.state == "done", status.message
    log = (out / "cases" / case.case_id / "log.pimpleFoam").read_text()
    assert log.count("Starting time loop") == 2
    first_run, second_run = log.split("Starting time loop")[1:]
    reached = float(re.findall(r"^Time = (\S+)$", first_run, re.M)[-1])
    resumed = float(re.findall(r"^Time = (\S+)$", second_run, re.M)[0])
    assert reached > 0 and reached < resumed < reached + 1e-3  # its first step after it
    rec = read_record(out / f"{case.case_id}.h5")
    assert np.all(np.diff(rec.time) > 0) and rec.time[-1] > 0.098
    assert not _solvers_left(out / "cases" / case.case_id)


@contextmanager
def _external_cluster() -> Iterator[tuple[str, subprocess.Popen, subprocess.Popen]]:
    """A dask scheduler and one single-threaded worker started from the command line, each
    in a session of its own (as dask-jobqueue's batch jobs are: a terminal's Ctrl-C does not
    reach them); both killed on leaving. Yields the address, the scheduler and the worker."""
    with socket.socket() as free:
        free.bind(("127.0.0.1", 0))
        port = free.getsockname()[1]
    address = f"tcp://127.0.0.1:{port}"
    dask_cli = [sys.executable, "-m", "dask"]
    scheduler = subprocess.Popen([*dask_cli, "scheduler", "--host", "127.0.0.1", "--port",
                                  str(port), "--dashboard-address", "127.0.0.1:0"],
                                 stderr=subprocess.DEVNULL, start_new_session=True)
    worker = subprocess.Popen([*dask_cli, "worker", address, "--nthreads", "1"],
                              stderr=subprocess.DEVNULL, start_new_session=True)
    try:
        yield address, scheduler, worker
    finally:
        for process in (scheduler, worker):
            os.killpg(process.pid, signal.SIGKILL)
            process.wait()


@pytest.mark.openfoam
def test_a_lost_scheduler_stops_the_campaign_with_nothing_marked_failed(tmp_path):
    """An external dask scheduler (as dask-jobqueue starts one) killed while a case runs:
    the campaign stops with an error naming the folder and the case, which is not written as
    failed, so that rerunning the command resumes it."""
    out = tmp_path / "camp"
    case = CfdCase(1.0, 0.3, 90.0, 10.0, duration=1.0, ramp_time=0.2)
    with _external_cluster() as (address, scheduler, _):
        def kill_scheduler_when_solving() -> None:
            _wait_for_solver(out / "cases" / case.case_id / "log.pimpleFoam")
            scheduler.kill()

        killer = threading.Thread(target=kill_scheduler_when_solving, daemon=True)
        killer.start()
        with pytest.raises(MfflapError) as lost:
            run_campaign([case], out, CampaignSetup(), scheduler_address=address,
                         progress=False)
    assert str(out) in str(lost.value) and case.case_id in str(lost.value)
    assert "rerun the same command" in str(lost.value)
    assert not list(out.glob("*.failed.toml"))
    from mfflap.cfd.openfoam.case_lock import lock_holder

    deadline = time.monotonic() + 30  # the nanny's worker process dies a moment after it
    while lock_holder(out / "cases" / case.case_id) and time.monotonic() < deadline:
        time.sleep(0.1)
    assert [s.state for s in campaign_status(out)] == ["started"]


@pytest.mark.openfoam
@pytest.mark.parametrize("command_name", ["campaign run", "cfd linear-check"])
def test_an_interrupted_campaign_stops_its_solvers_and_says_how_to_resume(tmp_path,
                                                                          command_name,
                                                                          solvers_left):
    """Ctrl-C (SIGINT to the job's process group) on `mfflap campaign run` or `mfflap cfd
    linear-check` (a campaign of small motions): the dask workers ignore it, the solver of
    the case in flight writes the step it reached and stops, the LocalCluster is stopped,
    the message counts the cases, and `campaign status` lists the one stopped part-way."""
    assert openfoam_available()
    from mfflap.campaign.execute import campaign_status
    from mfflap.campaign.linear_check import SMALL_MOTIONS
    from mfflap.cfd.openfoam.solver_log import solver_progress

    case_file = Path(__file__).parents[2] / "cases" / "paper2026.toml"
    out = tmp_path / "camp"
    arguments = {"campaign run": [str(case_file), "--out", str(out),
                                  "--set", "identification.frequencies=[0.5]",
                                  "--set", "identification.heave_amplitudes=[0.1]",
                                  "--set", "identification.phases_deg=[90]"],
                 "cfd linear-check": [str(out), "--cases", SMALL_MOTIONS[0].case_id]}
    command = [sys.executable, "-c", "from mfflap.cli.main import cli; cli()",
               *command_name.split(), *arguments[command_name]]
    proc = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            process_group=0,  # a shell's job: Ctrl-C reaches all of it
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    deadline = time.monotonic() + 300
    case_dirs = out / "cases"
    while time.monotonic() < deadline and not any(
            solver_progress(d) for d in case_dirs.glob("*") if d.is_dir()):
        time.sleep(0.5)  # until a solver has taken time steps
    time.sleep(1.0)  # past its first steps: a stop without a write would lose this second
    assert proc.poll() is None, proc.communicate()
    os.killpg(proc.pid, signal.SIGINT)  # the campaign and its dask workers, as a terminal does
    _, err = proc.communicate(timeout=180)
    assert proc.returncode == 1, err
    assert re.search(rf"interrupted: 0 of 1 cases done in {re.escape(str(out))}, 1 stopped "
                     "part-way; the same command resumes them", err), err
    # no solver left writing into the case (pdeathsig's SIGTERM reaches it as its worker dies)
    assert solvers_left(f"pimpleFoam -case {case_dirs}") == ""
    assert [s.state for s in campaign_status(out)] == ["started"]
    # the solver in flight wrote the step it had reached: the rerun loses nothing
    from mfflap.cfd.openfoam.time_folders import latest_solution_time

    (case_dir,) = [d for d in case_dirs.iterdir() if d.is_dir()]
    reached, time_step = solver_progress(case_dir)
    assert float(latest_solution_time(case_dir)) == pytest.approx(reached, abs=0.5 * time_step)
    assert not list(out.glob("*.failed.toml"))


#: a process that holds a case folder's run lock until it is killed
_LOCK_HOLDER = ("import sys, time\nfrom mfflap.cfd.openfoam.case_lock import case_lock\n"
                "with case_lock(sys.argv[1]):\n    print('held', flush=True)\n"
                "    time.sleep(600)\n")


@pytest.mark.slow
def test_a_case_another_process_runs_is_left_to_it_not_failed(tmp_path):
    """A campaign meeting a case whose run lock another process holds (a second campaign on
    the same folder, a `cfd run` of the case) leaves it to that process: status "busy"
    naming the holder, nothing written into the case, no .failed.toml; `campaign status`
    lists it as running, and pending once the holder is gone."""
    from click.testing import CliRunner

    from mfflap.cfd.openfoam.case_lock import LOCK_FILE
    from mfflap.cli.main import cli

    out = tmp_path / "camp"
    case_dir = out / "cases" / SHORT.case_id
    holder = subprocess.Popen([sys.executable, "-c", _LOCK_HOLDER, str(case_dir)],
                              stdout=subprocess.PIPE, text=True)
    try:
        assert holder.stdout.readline().strip() == "held"
        (status,) = run_campaign([SHORT], out, CampaignSetup(), progress=False)
        assert status.state == "busy", status
        assert f"being run by another process (pid {holder.pid} since" in status.message
        assert [p.name for p in case_dir.iterdir()] == [LOCK_FILE]  # nothing written
        assert not list(out.glob("*.failed.toml")) and not list(out.glob("cases/*.writing"))
        (running,) = campaign_status(out)
        assert running.state == "running" and running.message.startswith(
            f"by pid {holder.pid} since ")
        listed = CliRunner().invoke(cli, ["campaign", "status", str(out)])
        assert listed.exit_code == 0 and "0 failed, 1 running, 0 started" in listed.output
        case_file = Path(__file__).parents[2] / "cases" / "paper2026.toml"
        (out / "campaign.toml").unlink()  # it lists SHORT's 0.04 s, not the grid's 3 s
        # the same case id as SHORT
        left = CliRunner().invoke(cli, ["campaign", "run", str(case_file), "--out", str(out),
                                        "--set", "identification.frequencies=[1]",
                                        "--set", "identification.heave_amplitudes=[0.3]",
                                        "--set", "identification.phases_deg=[90]"])
        assert left.exit_code == 1, left.output  # not done by this command
        assert f"BUSY {SHORT.case_id}: " in left.stdout
        assert f"being run by another process (pid {holder.pid}" in left.stdout
        assert left.stderr.endswith("exit status 1: 1 of 1 cases not done\n"), left.stderr
    finally:
        holder.kill()
        holder.wait()
    assert [s.state for s in campaign_status(out)] == ["pending"]


def test_a_case_is_written_whole_under_its_lock(tmp_path):
    """run_motion writes a new case only while it holds the case's lock: refused, it leaves
    the folder as it was; a folder a killed write left half-done (files but no
    mfflap_case.toml, a stale .writing sibling) is replaced by a whole case."""
    from mfflap.cfd.openfoam.case_lock import LOCK_FILE, CaseBusyError, case_lock
    from mfflap.cfd.openfoam.run_motion import _write_case_whole

    motion = SHORT.motion()
    case_dir = tmp_path / "cases" / "c"
    holder = subprocess.Popen([sys.executable, "-c", _LOCK_HOLDER, str(case_dir)],
                              stdout=subprocess.PIPE, text=True)
    try:
        assert holder.stdout.readline().strip() == "held"
        with pytest.raises(CaseBusyError):
            run_motion(case_dir, motion, "c", {}, SHORT.duration, ramp_time=SHORT.ramp_time)
        assert sorted(p.name for p in tmp_path.joinpath("cases").iterdir()) == ["c"]
        assert [p.name for p in case_dir.iterdir()] == [LOCK_FILE]
    finally:
        holder.kill()
        holder.wait()
    (case_dir / "0.01").mkdir()  # what a write killed part-way, or a killed move, leaves
    (case_dir / "0.01" / "U").write_text("partial")
    (case_dir / "log.blockMesh").write_text("partial")
    stale = case_dir.with_name("c.writing")
    (stale / "system").mkdir(parents=True)

    def write(tmp: Path) -> None:
        write_case(tmp, motion, SHORT.duration, ramp_time=SHORT.ramp_time)

    with case_lock(case_dir):
        _write_case_whole(case_dir, write)
    fresh = tmp_path / "fresh"
    write(fresh)
    listing = sorted(p.relative_to(fresh) for p in fresh.rglob("*"))
    assert sorted(p.relative_to(case_dir) for p in case_dir.rglob("*")
                  if p.name != LOCK_FILE) == listing
    assert (case_dir / "system" / "controlDict").read_text() == (
        fresh / "system" / "controlDict").read_text()
    assert not stale.exists() and (case_dir / LOCK_FILE).is_file()

    def killed(tmp: Path) -> None:
        write(tmp)
        raise KeyboardInterrupt  # killed before the move

    (case_dir / "mfflap_case.toml").unlink()
    with case_lock(case_dir), pytest.raises(KeyboardInterrupt):
        _write_case_whole(case_dir, killed)
    assert not (case_dir / "mfflap_case.toml").exists()  # still not a written case


@pytest.mark.openfoam
def test_an_interrupted_campaign_on_an_external_cluster_has_its_solvers_write(tmp_path):
    """Ctrl-C on `mfflap campaign run --scheduler ADDR` (a cluster of dask-jobqueue's kind,
    whose workers the terminal's Ctrl-C does not reach): the worker's solver writes the step
    it reached and stops, the worker lives on for the next campaign, and the case is listed
    as stopped part-way, not failed. The case queued behind it does not start on the worker
    it frees (it would run to its end unattended)."""
    from mfflap.campaign.execute import campaign_status
    from mfflap.cfd.openfoam.case_lock import lock_holder
    from mfflap.cfd.openfoam.solver_log import solver_progress
    from mfflap.cfd.openfoam.time_folders import latest_solution_time

    case_file = Path(__file__).parents[2] / "cases" / "paper2026.toml"
    out = tmp_path / "camp"
    with _external_cluster() as (address, scheduler, worker):
        command = [sys.executable, "-c", "from mfflap.cli.main import cli; cli()", "campaign",
                   "run", str(case_file), "--out", str(out),
                       "--set", "identification.frequencies=[0.5]",
                       "--set", "identification.heave_amplitudes=[0.1]",
                       "--set", "identification.phases_deg=[90,135]", "--scheduler",
                       address]
        proc = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                text=True, process_group=0,
                                preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
        deadline = time.monotonic() + 300

        def reached_s() -> float:
            return max([(solver_progress(d) or (0.0,))[0] for d in out.glob("cases/*")
                        if d.is_dir()], default=0.0)

        # past its first steps (a stop without a write would lose them), however busy the
        # machine is
        while time.monotonic() < deadline and reached_s() <= 0.01:
            time.sleep(0.2)
        assert proc.poll() is None, proc.communicate()
        os.killpg(proc.pid, signal.SIGINT)
        _, err = proc.communicate(timeout=180)
        time.sleep(3.0)  # time for the queued case to start, had it been left queued
        (case_dir,) = [d for d in (out / "cases").iterdir() if d.is_dir()]
        deadline = time.monotonic() + 60  # the worker's task ends once its solver has
        while lock_holder(case_dir) and time.monotonic() < deadline:
            time.sleep(0.1)
        assert not _solvers_left(case_dir, wait_s=0.0)
        assert worker.poll() is None and scheduler.poll() is None  # the cluster lives on
    assert proc.returncode == 1, err
    assert "interrupted: 0 of 2 cases done" in err and "1 stopped part-way" in err, err
    assert sorted(s.state for s in campaign_status(out)) == ["pending", "started"]
    reached, time_step = solver_progress(case_dir)
    assert float(latest_solution_time(case_dir)) == pytest.approx(reached, abs=0.5 * time_step)
    assert reached > 0.01 and not list(out.glob("*.failed.toml"))


@pytest.mark.openfoam
def test_a_stopped_campaign_case_starts_no_application_afterwards(tmp_path):
    """A case whose worker is asked to stop before its solver starts (still writing or
    meshing its case when the campaign's Ctrl-C arrives; a cluster's worker outlives the
    campaign) starts nothing more: RunStopped, no mesh, no solver. A case begun after that
    block (the worker's next campaign) runs as usual."""
    from mfflap.cfd.openfoam.runner import RunStopped, stop_running_solvers, stoppable

    case_dir = tmp_path / "c"
    write_case(case_dir, SHORT.motion(), SHORT.duration, ramp_time=SHORT.ramp_time)
    inside, asked, outcome = threading.Event(), threading.Event(), []

    def run_in_a_campaign_block() -> None:
        with stoppable():
            inside.set()
            asked.wait(30)
            try:
                run_case(case_dir)
            except RunStopped as stopped:
                outcome.append(stopped)

    worker = threading.Thread(target=run_in_a_campaign_block)
    worker.start()
    assert inside.wait(30)
    assert stop_running_solvers(0.0) == 0  # no solver running yet
    asked.set()
    worker.join(60)
    (stopped,) = outcome
    assert "blockMesh not started: the run was asked to stop; a rerun resumes from t = 0 s" \
        in str(stopped)
    assert not (case_dir / "log.blockMesh").exists()
    with stoppable():  # the next block is not stopped
        from mfflap.cfd.openfoam.runner import run_application

        run_application(case_dir, "blockMesh", timeout_s=60)
    assert (case_dir / "constant" / "polyMesh" / "points").is_file()


@pytest.mark.slow
def test_a_stopped_campaign_waits_for_its_workers_to_let_go_of_their_cases(tmp_path,
                                                                           monkeypatch):
    """A worker that outlives the campaign lets go of its case a moment after its solver
    stopped: the campaign waits for that (its last status then says stopped part-way, not
    running; seen under load in CI), and no longer than RELEASE_WAIT_S for a case another
    process keeps."""
    import mfflap.campaign.execute as execute
    from mfflap.cfd.openfoam.case_lock import lock_holder

    holder_code = ("import sys, time\nfrom mfflap.cfd.openfoam.case_lock import case_lock\n"
                   "with case_lock(sys.argv[1]):\n    print('held', flush=True)\n"
                   "    time.sleep(float(sys.argv[2]))\n")
    out = tmp_path / "camp"

    def hold(case_id: str, seconds: float) -> subprocess.Popen:
        proc = subprocess.Popen([sys.executable, "-c", holder_code,
                                 str(out / "cases" / case_id), str(seconds)],
                                stdout=subprocess.PIPE, text=True)
        assert proc.stdout.readline().strip() == "held"
        return proc

    letting_go = hold("a", 3.0)
    assert lock_holder(out / "cases" / "a") is not None  # held when the wait begins
    execute._wait_for_release(out, ["a", "never-run"])
    assert lock_holder(out / "cases" / "a") is None and letting_go.wait(5) == 0
    letting_go.wait()
    monkeypatch.setattr(execute, "RELEASE_WAIT_S", 0.5)
    keeping = hold("b", 600.0)
    try:
        started = time.monotonic()
        execute._wait_for_release(out, ["b"])
        assert 0.5 <= time.monotonic() - started < 5.0
    finally:
        keeping.kill()
        keeping.wait()


def test_a_folder_of_another_setup_names_what_differs(tmp_path):
    """The shipped Co 2 campaign's manifest against the affordable set-up: refused before any
    case runs, naming each setting that differs with both values."""
    from mfflap.cfd.openfoam.setups import setup

    out = tmp_path / "campaign"
    out.mkdir()
    shutil.copy(Path(__file__).parents[2] / "campaigns" / "table1_coarse_co2" / "campaign.toml",
                out / "campaign.toml")
    affordable = setup("affordable")
    with pytest.raises(ConfigError) as err:
        run_campaign([SHORT], out, CampaignSetup(mesh=affordable.mesh.name,
                                                 solver=affordable.solver), progress=False)
    message = str(err.value)
    assert "mesh: 'coarse' in the folder, 'graded' asked" in message
    assert "solver.max_courant: 2.0 in the folder, 4.0 asked" in message
    assert "; ...)" in message  # more than four differences: the first four shown
    assert not (out / "cases").exists() and not list(out.glob("*.h5"))


def test_a_dry_run_lists_each_case_with_its_state_or_refuses_as_the_run_would(tmp_path):
    """Part of the shipped Co 2 campaign: one case done, one failed, the rest pending; with
    another set-up the dry run is refused as the run would be, and nothing is written."""
    from click.testing import CliRunner

    from mfflap.cli.main import cli

    source = Path(__file__).parents[2] / "campaigns" / "table1_coarse_co2"
    out = tmp_path / "campaign"
    out.mkdir()
    for name in ("campaign.toml", "f1p000_h0p300_phi090p0.h5",
                 "f0p500_h0p500_phi135p0.failed.toml"):
        shutil.copy(source / name, out / name)
    case = Path(__file__).parents[2] / "cases" / "paper2026.toml"
    before = sorted(p.name for p in out.iterdir())
    args = ["campaign", "run", str(case), "--out", str(out), "--dry-run",
            "--set", "identification.frequencies=[0.5,1]",
            "--set", "identification.heave_amplitudes=[0.3,0.5]",
            "--set", "identification.phases_deg=[90,135]"]
    res = CliRunner().invoke(cli, [*args, "--setup", "coarse_co2"])
    assert res.exit_code == 0, res.output
    states = {line.split()[0]: line.split()[-1] for line in res.output.splitlines()}
    assert states["f1p000_h0p300_phi090p0"] == "done"
    assert states["f0p500_h0p500_phi135p0"] == "failed"
    assert set(states.values()) == {"done", "failed", "pending"} and len(states) == 8
    res = CliRunner().invoke(cli, [*args, "--setup", "affordable"])
    assert res.exit_code != 0 and "another setup (mesh: 'coarse' in the folder" in res.output
    res = CliRunner().invoke(cli, [*args[:3], "--out", str(tmp_path / "new"), "--dry-run",
                                   "--set", "identification.frequencies=[1]",
                                   "--set", "identification.phases_deg=[90]"])
    assert res.exit_code == 0 and res.output.split()[-1] == "pending"
    assert sorted(p.name for p in out.iterdir()) == before and not (tmp_path / "new").exists()
