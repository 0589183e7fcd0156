"""Progress of a running pimpleFoam: the lines `mfflap cfd run` prints while it waits."""

from __future__ import annotations

import os
import re
from pathlib import Path

import pytest
from click.testing import CliRunner

from mfflap.cfd.openfoam.control_dict import end_time
from mfflap.cfd.openfoam.run_progress import RunProgress, describe_progress

DATA = Path(__file__).parents[2] / "data" / "openfoam_v1912"
CASE = Path(__file__).resolve().parents[3] / "cases" / "paper2026.toml"


def test_a_progress_line_gives_the_share_and_the_time_left_at_the_rate_so_far():
    # 0.25 of 1 s simulated at 0.01 s per second: 0.75 s left takes 75 s
    line = describe_progress(0.25, 2.5e-4, 1.0, 30.0, 0.01)
    assert line == ("t = 0.25 s of 1 s (25.0 %), time step 0.00025 s, 30 s elapsed, "
                    "about 1 min 15 s left")
    assert describe_progress(0.5, 1e-3, None, 4000.0, 0.01) == \
        "t = 0.5 s, time step 0.001 s, 1 h 06 min elapsed"  # no end time: no share, no ETA
    assert "left" not in describe_progress(0.1, 1e-3, 1.0, 1.0, None)


def test_run_progress_reads_a_growing_real_log(tmp_path):
    """Two calls while a real v1912 log grows: the second has a rate, so a time left."""
    real = (DATA / "log.pimpleFoam.bounding").read_text()  # three time steps
    (tmp_path / "system").mkdir()
    (tmp_path / "system" / "controlDict").write_text("startTime 0;\nendTime         0.01;\n")
    assert end_time(tmp_path) == pytest.approx(0.01)
    steps = [m.start() for m in re.finditer(r"^Time = ", real, re.M)]
    log = tmp_path / "log.pimpleFoam"
    log.write_text(real[:steps[1]])  # one step done
    clock = iter([0.0, 10.0, 20.0])
    lines: list[str] = []
    progress = RunProgress(tmp_path, lines.append, clock=lambda: next(clock))
    progress()
    log.write_text(real)  # the run goes on
    progress()
    times = [float(re.match(r"t = (\S+) s of 0.01 s", line).group(1)) for line in lines]
    assert len(lines) == 2 and times[0] < times[1]
    assert "left" not in lines[0] and "left" in lines[1]
    rate = (times[1] - times[0]) / 10.0
    left = (0.01 - times[1]) / rate
    assert f"about {round(left) // 60} min" in lines[1] or f"about {round(left)} s" in lines[1]


def test_no_log_yet_reports_nothing(tmp_path):
    lines: list[str] = []
    RunProgress(tmp_path, lines.append)()
    assert lines == [] and end_time(tmp_path) is None


@pytest.mark.openfoam
def test_cfd_run_prints_progress_on_stderr_while_openfoam_runs(tmp_path):
    """A real run of a fifth of a cycle on the coarse mesh: meshing, start and at least one
    progress line go to stderr; stdout keeps the summary."""
    from mfflap.cli.main import cli

    case = tmp_path / "case"
    res = CliRunner().invoke(cli, ["cfd", "write", str(CASE), str(case), "--cycles", "0.2"])
    assert res.exit_code == 0, res.output
    res = CliRunner().invoke(cli, ["cfd", "run", str(case), "--progress-every", "0.5"])
    assert res.exit_code == 0, res.output
    assert f"[cfd run] meshing {case}" in res.stderr
    assert "[cfd run] pimpleFoam started; log: " in res.stderr
    shares = [float(s) for s in re.findall(r"of 0.2 s \((\S+) %\)", res.stderr)]
    assert shares and shares == sorted(shares) and 0 < shares[-1] <= 100
    assert "[cfd run]" not in res.stdout and res.stdout.startswith(f"finished {case}")


@pytest.mark.openfoam
def test_cfd_run_decomposed_on_two_ranks(tmp_path):
    """`cfd run --procs 2`: decomposed once, run under mpirun, forces from the master."""
    import json

    from mfflap.cli.main import cli

    case = tmp_path / "case"
    res = CliRunner().invoke(cli, ["cfd", "write", str(CASE), str(case), "--cycles", "0.03"])
    assert res.exit_code == 0, res.output
    res = CliRunner().invoke(cli, ["cfd", "run", str(case), "--procs", "0"])
    assert res.exit_code == 2 and "--procs" in res.output
    res = CliRunner().invoke(cli, ["cfd", "run", str(case), "--procs", "2", "--json"])
    assert res.exit_code == 0, res.output
    assert "pimpleFoam started on 2 processes" in res.stderr
    assert (case / "processor0").is_dir() and (case / "processor1").is_dir()
    assert "nProcs : 2" in (case / "log.pimpleFoam").read_text()
    summary = json.loads(res.stdout)
    assert summary["n_procs"] == 2 and summary["n_time_steps"] > 10


@pytest.mark.parametrize("stop", ["SIGINT to the group", "SIGTERM", "SIGUSR1",
                                  "SIGUSR1 to every process"])
@pytest.mark.openfoam
def test_an_interrupted_cfd_run_stops_its_solver_and_says_where_it_resumes(tmp_path, stop):
    """Ctrl-C (SIGINT to the job's process group, as a terminal sends it), SIGTERM (kill,
    scancel) or SIGUSR1 (SLURM's --signal before a time limit; under srun it reaches the
    solver too, which then has it twice) to `mfflap cfd run`:
    pimpleFoam writes its fields at the time step it reached and stops (a second past its
    last regular write, which a restart would otherwise lose), the message says so, and the
    next `cfd run` resumes there and finishes."""
    import signal
    import subprocess
    import sys
    import time

    from mfflap.cfd.openfoam.forces import read_forces
    from mfflap.cfd.openfoam.solver_log import solver_progress
    from mfflap.cfd.openfoam.time_folders import latest_solution_time
    from mfflap.cli.main import cli

    case = tmp_path / "case"
    res = CliRunner().invoke(cli, ["cfd", "write", str(CASE), str(case), "--cycles", "0.2",
                                   "--set", "cfd.writes=8"])
    assert res.exit_code == 0, res.output
    command = [sys.executable, "-c", "from mfflap.cli.main import cli; cli()", "cfd", "run",
               str(case)]
    proc = subprocess.Popen(command,  # in a process group of its own, like a shell's job
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            process_group=0,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    deadline = time.monotonic() + 300
    while latest_solution_time(case) in (None, "0") and time.monotonic() < deadline:
        time.sleep(0.2)  # until a first time folder is written whole
    time.sleep(1.0)  # past it: a regular write would lose this second
    assert proc.poll() is None, proc.communicate()
    if stop == "SIGINT to the group":
        os.killpg(proc.pid, signal.SIGINT)  # Ctrl-C in a terminal: the whole foreground group
    else:
        proc.send_signal(getattr(signal, stop.split()[0]))
    if stop == "SIGUSR1 to every process":
        subprocess.run(["pkill", "-USR1", "-f", f"pimpleFoam -case {case}"], check=True)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 1, err
    resumed = latest_solution_time(case)
    reached, time_step = solver_progress(case)
    assert float(resumed) == pytest.approx(reached, abs=0.5 * time_step)  # nothing lost
    assert (f"interrupted: pimpleFoam wrote its fields at t = {resumed} s and stopped; "
            f"`mfflap cfd run {case}` resumes there") in err, err
    running = subprocess.run(["pgrep", "-f", f"pimpleFoam -case {case}"], capture_output=True)
    assert running.returncode == 1  # no solver left writing into the case
    res = CliRunner().invoke(cli, ["cfd", "run", str(case)])
    assert res.exit_code == 0, res.output
    assert f"pimpleFoam from t = {resumed} s" in res.stderr
    assert read_forces(case).time[-1] == pytest.approx(0.2, abs=1e-3)
    assert (case / "log.pimpleFoam").read_text().count("Starting time loop") == 2


@pytest.mark.openfoam
def test_an_interrupted_mesh_study_keeps_its_finished_runs_and_says_so(tmp_path):
    """Ctrl-C (SIGINT) on `mfflap cfd convergence` after its first run: that run's record is
    kept and named, the solver in flight is stopped, and the rerun does not redo the first."""
    import signal
    import subprocess
    import sys
    import time

    out = tmp_path / "conv"
    command = [sys.executable, "-c", "from mfflap.cli.main import cli; cli()", "cfd",
               "convergence", str(CASE), str(out), "--meshes", "coarse,medium",
               "--courant", "4", "--cycles", "0.3"]
    proc = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    deadline = time.monotonic() + 600
    while not (out / "coarse_co4.h5").exists() and time.monotonic() < deadline:
        time.sleep(0.2)
    time.sleep(3)  # into the medium mesh's run
    assert proc.poll() is None, proc.communicate()
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 1, err
    assert (f"interrupted: the runs finished so far are kept in {out} (coarse_co4); the same "
            "command reruns none of them") in err
    running = subprocess.run(["pgrep", "-f", f"pimpleFoam -case {out}"], capture_output=True)
    assert running.returncode == 1  # no solver left writing into the study
    assert not (out / "medium_co4.h5").exists()


@pytest.mark.openfoam
def test_a_solver_stopped_by_a_signal_of_its_own_is_not_a_finished_run(tmp_path):
    """SIGUSR1 sent to pimpleFoam alone (not to mfflap): it writes and ends without an
    error before its end time; `cfd run` says so with exit status 2 instead of
    "finished", and the next `cfd run` resumes there and finishes, writing at its end."""
    import signal
    import subprocess
    import sys
    import time

    from mfflap.cfd.openfoam.forces import read_forces
    from mfflap.cfd.openfoam.solver_log import solver_progress
    from mfflap.cfd.openfoam.time_folders import latest_solution_time
    from mfflap.cli.main import cli

    case = tmp_path / "case"
    res = CliRunner().invoke(cli, ["cfd", "write", str(CASE), str(case), "--cycles", "0.1"])
    assert res.exit_code == 0, res.output
    proc = subprocess.Popen([sys.executable, "-c", "from mfflap.cli.main import cli; cli()",
                             "cfd", "run", str(case)], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    deadline = time.monotonic() + 300
    while solver_progress(case) is None and time.monotonic() < deadline:
        time.sleep(0.2)
    assert proc.poll() is None, proc.communicate()
    subprocess.run(["pkill", "-USR1", "-f", f"pimpleFoam -case {case}"], check=True)
    out, err = proc.communicate(timeout=120)
    assert proc.returncode == 2, (out, err)
    resumed = latest_solution_time(case)
    assert re.search(r"pimpleFoam stopped without an error at t = \S+ s, before its end time "
                     rf"0\.1 s \(a stop signal sent to the solver itself\?\); a rerun resumes "
                     rf"from t = {re.escape(resumed)} s", err), err
    assert "finished" not in out and 0 < float(resumed) < 0.1
    res = CliRunner().invoke(cli, ["cfd", "run", str(case)])
    assert res.exit_code == 0, res.output
    assert read_forces(case).time[-1] == pytest.approx(0.1, abs=1e-3)
    # resumed between two writes, OpenFOAM counts its write times from there: the interval
    # is shortened to divide the time left, so the run still writes at its end time
    assert latest_solution_time(case) == "0.1"
    interval = float(re.search(r"^writeInterval\s+(\S+);", (
        case / "system" / "controlDict").read_text(), re.M).group(1))
    n_writes = (0.1 - float(resumed)) / interval
    assert interval <= 0.025 and n_writes == pytest.approx(round(n_writes), abs=1e-6)


@pytest.mark.openfoam
def test_cfd_run_reports_the_plates_y_plus_against_the_wall_functions(tmp_path):
    """A real run written with cfd.y_plus and the log-law wall functions (0.1 s): `cfd run`
    gives the plate's y+ from the yPlus function object, in text and JSON, and says that its
    average lies below the wall functions' log-law range (the first cells sit at y+ of a
    few; the plate's maximum, at its edges, may pass 30)."""
    import json

    from mfflap.cfd.openfoam.yplus import read_y_plus
    from mfflap.cli.main import cli

    case = tmp_path / "yp"
    res = CliRunner().invoke(cli, ["cfd", "write", str(CASE), str(case), "--set",
                                   "cfd.y_plus=true", "--set", 'cfd.wall_treatment="log_law"',
                                   "--cycles", "0.1", "--ramp-time", "0.04"])
    assert res.exit_code == 0, res.output
    text = CliRunner().invoke(cli, ["cfd", "run", str(case)])
    assert text.exit_code == 0, text.output
    history = read_y_plus(case)
    data = json.loads(CliRunner().invoke(cli, ["cfd", "run", str(case), "--json"]).stdout)
    assert data["y_plus_mean"] == pytest.approx(history.average.mean())
    assert 0 < data["y_plus_min"] < data["y_plus_mean"] < data["y_plus_max"]
    assert data["y_plus_mean"] < 30
    assert data["y_plus_share_below_log_law"] == 1.0
    assert data["wall_function_note"].startswith(
        "the plate's average y+ lies outside the wall functions' log-law range (30-300)")
    assert f"y+ on the plate: mean {data['y_plus_mean']:.3g} (from" in text.stdout
    assert "below 30 for 100% of the output times" in " ".join(text.stdout.split())
