"""One run at a time in a case folder: a second run is refused naming the first, a killed
holder leaves no stale lock, and the lock is re-entrant within a thread."""

from __future__ import annotations

import os
import re
import signal
import subprocess
import sys
import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import pytest
from click.testing import CliRunner

from mfflap.cfd.openfoam.case_lock import LOCK_FILE, CaseBusyError, case_lock, lock_holder
from mfflap.errors import CfdRunError

CASE = Path(__file__).resolve().parents[3] / "cases" / "paper2026.toml"

#: a process that holds a case's lock until it is killed
HOLDER = ("import sys, time\nfrom mfflap.cfd.openfoam.case_lock import case_lock\n"
          "with case_lock(sys.argv[1]):\n    print('held', flush=True)\n    time.sleep(600)\n")


def _holder(case: Path) -> subprocess.Popen:
    proc = subprocess.Popen([sys.executable, "-c", HOLDER, str(case)], stdout=subprocess.PIPE,
                            text=True)
    assert proc.stdout.readline().strip() == "held"
    return proc


def test_another_process_holding_the_case_is_named_and_a_killed_one_frees_it(tmp_path):
    case = tmp_path / "case"
    proc = _holder(case)
    try:
        with pytest.raises(CaseBusyError, match=rf"case {re.escape(str(case))}: the case is "
                                              rf"being run by another process \(pid {proc.pid} "
                                              r"since \d{4}-\d\d-\d\dT"):
            with case_lock(case):
                pass
    finally:
        proc.send_signal(signal.SIGKILL)  # no clean-up: the kernel drops the lock
        proc.wait()
    assert (case / LOCK_FILE).is_file()
    with case_lock(case):  # the file stays, unlocked
        assert f"pid {os.getpid()} since" in (case / LOCK_FILE).read_text()


def test_the_lock_is_reentrant_in_a_thread_and_refused_to_another(tmp_path):
    case = tmp_path / "case"
    errors: list[Exception] = []

    def other() -> None:
        try:
            with case_lock(case):
                pass
        except CfdRunError as err:
            errors.append(err)

    with case_lock(case), case_lock(case):  # run_motion around run_case
        thread = threading.Thread(target=other)
        thread.start()
        thread.join()
    assert len(errors) == 1 and "another thread of this process" in str(errors[0])
    other()  # released: the other thread may take it now
    assert len(errors) == 1


@pytest.mark.openfoam
def test_a_second_cfd_run_of_a_running_case_is_refused_and_the_first_finishes(tmp_path):
    from mfflap.cfd.openfoam.forces import read_forces
    from mfflap.cfd.openfoam.solver_log import solver_progress
    from mfflap.cli.main import cli

    case = tmp_path / "case"
    res = CliRunner().invoke(cli, ["cfd", "write", str(CASE), str(case), "--cycles", "0.1"])
    assert res.exit_code == 0, res.output
    first = subprocess.Popen([sys.executable, "-c", "from mfflap.cli.main import cli; cli()",
                              "cfd", "run", str(case)], stdout=subprocess.PIPE,
                             stderr=subprocess.PIPE, text=True)
    deadline = time.monotonic() + 300
    while solver_progress(case) is None and time.monotonic() < deadline:
        time.sleep(0.2)
    log_before = (case / "log.pimpleFoam").stat().st_size
    second = CliRunner().invoke(cli, ["cfd", "run", str(case)])
    assert first.poll() is None, first.communicate()  # still running when refused
    assert second.exit_code == 2
    assert f"being run by another process (pid {first.pid} since" in second.output
    assert "pimpleFoam started" not in second.output
    _, err = first.communicate(timeout=300)
    assert first.returncode == 0, err
    text = (case / "log.pimpleFoam").read_text()
    assert text.count("Starting time loop") == 1 and len(text) > log_before
    assert read_forces(case).time[-1] == pytest.approx(0.1, abs=1e-3)


def test_lock_holder_names_the_holder_without_taking_or_creating_the_lock(tmp_path):
    """Nobody (no lock file, a free one) is None; a holding process is named; a probe that
    meets a run taking the lock at that moment does not make the run fail."""
    case = tmp_path / "case"
    assert lock_holder(case) is None and not case.exists()  # nothing created
    proc = _holder(case)
    try:
        assert lock_holder(case).startswith(f"pid {proc.pid} since ")
    finally:
        proc.send_signal(signal.SIGKILL)
        proc.wait()
    assert lock_holder(case) is None  # the file stays, free
    with case_lock(case):
        assert lock_holder(case) == (case / LOCK_FILE).read_text()  # this process counts
        assert issubclass(CaseBusyError, CfdRunError)
    with _probed_in_a_loop(case):
        for _ in range(200):  # each would be refused if a probe's lock counted as a run's
            with case_lock(case):
                pass


@contextmanager
def _probed_in_a_loop(case: Path) -> Iterator[None]:
    """A thread calling lock_holder(case) as fast as it can while the block runs."""
    stop = threading.Event()

    def probe() -> None:
        while not stop.is_set():
            lock_holder(case)

    prober = threading.Thread(target=probe)
    prober.start()
    try:
        yield
    finally:
        stop.set()
        prober.join()


def test_a_busy_prober_does_not_make_a_run_fail_however_short_the_wait(tmp_path, monkeypatch):
    """On a loaded machine one pause can outlast the whole quick wait; the run still tries
    enough times to pass a prober holding the lock for microseconds at a time. With a single
    try, about a quarter of these runs were refused."""
    import mfflap.cfd.openfoam.case_lock as case_lock_module

    monkeypatch.setattr(case_lock_module, "_QUICK_WAIT_S", 0.0)
    case = tmp_path / "case"
    with case_lock(case):
        pass
    refused = 0
    with _probed_in_a_loop(case):
        for _ in range(300):
            try:
                with case_lock(case):
                    pass
            except CaseBusyError:
                refused += 1
    assert refused == 0


#: a process that holds a case's lock and shares it with a child that lives ``argv[2]`` s
SHARING_HOLDER = (
    "import subprocess, sys, time\n"
    "from mfflap.cfd.openfoam.case_lock import case_lock, held_descriptor\n"
    "with case_lock(sys.argv[1]):\n"
    "    fd = held_descriptor(sys.argv[1])\n"
    "    child = subprocess.Popen(['sleep', sys.argv[2]], pass_fds=(fd,),\n"
    "                             start_new_session=True)\n"
    "    print(child.pid, flush=True)\n"
    "    time.sleep(600)\n")


def _sharing_holder(case: Path, child_s: float) -> tuple[subprocess.Popen, int]:
    proc = subprocess.Popen([sys.executable, "-c", SHARING_HOLDER, str(case), str(child_s)],
                            stdout=subprocess.PIPE, text=True)
    return proc, int(proc.stdout.readline())


@pytest.mark.slow
def test_a_lock_shared_with_a_solver_outlives_its_killed_holder_until_the_solver_ends(
        tmp_path):
    """A holder killed outright while the process it shares the lock with (a solver writing
    the step it reached) still runs: the case stays locked, `lock_holder` says the holder
    is gone and its solver is writing, and a run waits for that solver instead of being
    refused (a dask worker given the case of a worker just killed)."""
    case = tmp_path / "case"
    proc, child = _sharing_holder(case, 3.0)
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    killed = time.monotonic()
    holder = lock_holder(case)
    assert holder is not None and holder.startswith(f"pid {proc.pid} since ")
    assert holder.endswith("that process is gone, its solver is writing the step it reached")
    with case_lock(case):
        waited_s = time.monotonic() - killed
        assert not _running(child)  # it ended before the lock was given
    assert waited_s > 1.0


def _running(pid: int) -> bool:
    """True if the process exists and is not a zombie (an orphan init has not reaped)."""
    try:
        stat = Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        return False
    return stat.rsplit(")", 1)[1].split()[0] != "Z"


@pytest.mark.slow
def test_a_solver_left_running_by_its_killed_holder_is_named_after_the_wait(tmp_path,
                                                                            monkeypatch):
    """One that does not end within ORPHAN_WAIT_S: the run is refused, the message says the
    holder is gone and how to stop what still runs; a holder that is alive is refused at
    once, without that wait."""
    import mfflap.cfd.openfoam.case_lock as case_lock_module

    monkeypatch.setattr(case_lock_module, "ORPHAN_WAIT_S", 0.5)
    case = tmp_path / "case"
    proc, child = _sharing_holder(case, 600.0)
    try:
        proc.send_signal(signal.SIGKILL)
        proc.wait()
        with pytest.raises(CaseBusyError, match=r"held by a solver whose caller \(pid "
                                                rf"{proc.pid} since .*\) is gone: asked to "
                                                r"write its fields and stop, it still runs "
                                                r"after 0\.5 s; stop it \(pkill -f"):
            with case_lock(case):
                pass
    finally:
        os.kill(child, signal.SIGKILL)
    monkeypatch.setattr(case_lock_module, "ORPHAN_WAIT_S", 60.0)
    alive = _holder(case)
    try:
        started = time.monotonic()
        with pytest.raises(CaseBusyError, match="being run by another process"):
            with case_lock(case):
                pass
        assert time.monotonic() - started < 5.0
    finally:
        alive.send_signal(signal.SIGKILL)
        alive.wait()
