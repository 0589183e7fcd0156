"""Run an OpenFOAM case: blockMesh, checkMesh, pimpleFoam, with a timeout and divergence
detection. Logs are kept in the case folder (log.<application>)."""

from __future__ import annotations

import math
import os
import shutil
import signal
import subprocess
import threading
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path

from mfflap.cfd.openfoam.case_lock import case_lock, held_descriptor
from mfflap.cfd.openfoam.case_path import check_case_path
from mfflap.cfd.openfoam.control_dict import align_writes_to_end, end_time, set_start_time
from mfflap.cfd.openfoam.foam_files import foam_file
from mfflap.cfd.openfoam.release import require_supported_release
from mfflap.cfd.openfoam.run_progress import RunProgress
from mfflap.cfd.openfoam.solver_log import (
    DELTA_T_LINE,
    DIVERGED,
    TIME_LINE,
    failure_reason,
    read_tail,
    solver_progress,
)
from mfflap.cfd.openfoam.time_folders import (
    is_time_folder,
    latest_solution_time,
    processor_folders,
)
from mfflap.cfd.openfoam.time_step_watch import TimeStepWatch
from mfflap.errors import (
    COURANT_EXPLODED,
    TIME_STEP_COLLAPSED,
    CfdRunError,
    ConfigError,
    RunStoppedByWatch,
    SolverDiverged,
)


def openfoam_available() -> bool:
    """True if the OpenFOAM solvers are on PATH."""
    return shutil.which("pimpleFoam") is not None and shutil.which("blockMesh") is not None


def _env() -> dict[str, str]:
    env = dict(os.environ)
    env.setdefault("WM_PROJECT_DIR", "/usr/share/openfoam")
    return env


def dies_with_caller(command: list[str], death_signal: str = "TERM") -> list[str]:
    """``command`` wrapped so that it gets ``death_signal`` (SIGTERM: it stops) when the
    thread that starts it dies.

    A solver outlives a Python process killed with SIGKILL (a dask worker lost to the
    out-of-memory killer or killed by its nanny): the orphan would go on writing into its
    case while dask reruns the same case, resumed in the same folder, beside it.
    util-linux's ``setpriv --pdeathsig`` asks the kernel to signal it instead; mpirun passes
    SIGTERM and SIGUSR1 on to its ranks. A solver started with :data:`WRITE_AND_STOP_SIGNAL`
    set is given that one, so that it writes the time step it reached before it stops. A
    parent that died before the request was made cannot signal it, so the command then
    starts only if its parent is still this process (prctl(2)'s advice). Where setpriv is
    missing the command is returned as it is.
    """
    setpriv = shutil.which("setpriv")
    if setpriv is None:
        return command
    parent_alive = f'[ "$PPID" = {os.getpid()} ] && exec "$@"'
    return [setpriv, "--pdeathsig", death_signal, "--", "sh", "-c", parent_alive, "sh",
            *command]


def stop(proc: subprocess.Popen, grace_s: float = 10.0) -> None:
    """Stop a solver and wait until it has: SIGTERM, then SIGKILL after ``grace_s``.

    SIGTERM lets mpirun stop its ranks before it exits; killed at once, it leaves them
    running on their own for a second or two, long enough to write into the case that a
    retry is already resuming.
    """
    proc.terminate()
    try:
        proc.wait(timeout=grace_s)
    except subprocess.TimeoutExpired:
        proc.kill()
        proc.wait()


#: the signal that makes an OpenFOAM solver write its fields at the end of the time step it
#: is in and stop (openfoam.com's ``stopAtWriteNowSignal`` optimisation switch, set on the
#: solver's command line; mpirun passes it on to its ranks, which write the same time)
WRITE_AND_STOP_SIGNAL = signal.SIGUSR1


def write_and_stop(proc: subprocess.Popen, grace_s: float) -> bool:
    """Ask a solver started with :data:`WRITE_AND_STOP_SIGNAL` set to write its fields and
    stop; wait up to ``grace_s`` for it. True if it stopped (a solver still running is left
    to :func:`stop`)."""
    proc.send_signal(WRITE_AND_STOP_SIGNAL)
    try:
        proc.wait(timeout=grace_s)
    except subprocess.TimeoutExpired:
        return False
    return True


class RunStopped(CfdRunError):
    """A solver asked from outside its run (:func:`stop_running_solvers`) to write its
    fields and stop: not a failure; a rerun resumes where it stopped."""


#: solvers this process runs with ``write_on_stop``, for :func:`stop_running_solvers`
_solvers: set[subprocess.Popen] = set()
#: process ids of those asked to write and stop by :func:`stop_running_solvers`
_stop_requested: set[int] = set()
#: threads inside :func:`stoppable`, and whether :func:`stop_running_solvers` stopped them
_stoppable: dict[int, bool] = {}
_solvers_guard = threading.Lock()


@contextmanager
def stoppable() -> Iterator[None]:
    """Make the block (a campaign case's run with its retries) stop as a whole on
    :func:`stop_running_solvers`: once that was called, no OpenFOAM application starts in
    this thread before the block ends (:func:`run_application` raises :class:`RunStopped`).

    A worker of a cluster that outlives the campaign (an external scheduler's) goes on
    with the task it runs when the campaign is stopped; a case still meshing then would
    otherwise start its solver and run to its end unattended.
    """
    me = threading.get_ident()
    with _solvers_guard:
        _stoppable[me] = False
    try:
        yield
    finally:
        with _solvers_guard:
            _stoppable.pop(me, None)


def _raise_if_stopped(case_dir: Path, application: str) -> None:
    with _solvers_guard:
        stopped = _stoppable.get(threading.get_ident(), False)
    if stopped:
        raise RunStopped(f"{application} not started: the run was asked to stop; a rerun "
                         f"resumes from t = {latest_solution_time(case_dir) or 0} s",
                         case=str(case_dir))


def stop_running_solvers(grace_s: float = 60.0) -> int:
    """Ask every solver this process runs (in any thread) to write its fields and stop, and
    wait up to ``grace_s`` for them; return how many were asked. The runs inside
    :func:`stoppable` blocks start no other application.

    A campaign's dask workers run their solvers in threads of their own; on Ctrl-C the
    campaign calls this on every worker (``Client.run``) before it closes the cluster, so
    that the cases in flight resume where they stopped. Their runs raise
    :class:`RunStopped`.
    """
    with _solvers_guard:
        running = [proc for proc in _solvers if proc.poll() is None]
        _stop_requested.update(proc.pid for proc in running)
        _stoppable.update(dict.fromkeys(_stoppable, True))
    for proc in running:
        proc.send_signal(WRITE_AND_STOP_SIGNAL)
    deadline = time.monotonic() + grace_s
    for proc in running:
        try:
            proc.wait(timeout=max(0.0, deadline - time.monotonic()))
        except subprocess.TimeoutExpired:
            pass
    return len(running)


def _tail(path: Path, n: int = 20) -> str:
    if not path.exists():
        return ""
    return "\n".join(path.read_text(errors="replace").splitlines()[-n:])


def _collapsed(application: str, time_steps: TimeStepWatch, case_dir: Path, log: Path,
               exited: bool = False) -> SolverDiverged:
    """The error of a run whose time step collapsed (:attr:`TimeStepWatch.collapse`);
    ``exited``: read after the solver exited, which ran on past it."""
    time_step_s, time_s = time_steps.collapse
    after = ""
    if exited:
        roots = [case_dir, *processor_folders(case_dir)[:1]]
        later = sorted({p.name for root in roots for p in root.iterdir()
                        if p.is_dir() and is_time_folder(p.name) and float(p.name) >= time_s},
                       key=float)
        after = ("; the solver ran on past it to its end, so what it wrote after that time is "
                 f"not to be trusted (its time folders {', '.join(later)}): rerun it from a time "
                 f"written before (`mfflap cfd run --rewind-before {time_s:.10g}`)" if later
                 else "; the solver ran on past it to its end")
    return SolverDiverged(f"{application} diverged: the time step collapsed to "
                          f"{time_step_s:.3g} s at t = {time_s:.10g} s (an instability held "
                          f"at the Courant limit){after}", case=str(case_dir),
                          log_tail=_tail(log), kind=TIME_STEP_COLLAPSED, time_s=float(time_s))


def _exploded(application: str, time_steps: TimeStepWatch, case_dir: Path,
              log: Path) -> SolverDiverged:
    """The error of a run whose Courant number exploded
    (:attr:`TimeStepWatch.largest_courant`)."""
    courant, time_s = time_steps.largest_courant
    return SolverDiverged(f"{application} diverged: the Courant number exploded to "
                          f"{courant:g} in the step from t = {time_s:.10g} s",
                          case=str(case_dir), log_tail=_tail(log), kind=COURANT_EXPLODED,
                          time_s=float(time_s))


#: the largest Courant number a run may reach before it counts as diverged
MAX_COURANT_ABORT = 100.0


def _diverged(application: str, time_steps: TimeStepWatch, case_dir: Path, log: Path,
              max_courant_abort: float, exited: bool = False) -> CfdRunError | None:
    """The error of a run whose steps read so far (``time_steps``) hold a collapsed time
    step or a Courant number above ``max_courant_abort``, else None; ``exited``: read after
    the solver exited."""
    if time_steps.collapse is not None:
        return _collapsed(application, time_steps, case_dir, log, exited)
    if time_steps.largest_courant[0] > max_courant_abort:
        return _exploded(application, time_steps, case_dir, log)
    return None


def _last_run_diverged(case_dir: Path, min_time_step: float) -> CfdRunError | None:
    """The error of the case's last pimpleFoam run (its log from the last "Starting time
    loop" on) if its time step collapsed below ``min_time_step`` or its Courant number
    passed :data:`MAX_COURANT_ABORT` anywhere, else None: a run that reached its end time
    is judged whole, however its judging was cut short (its caller killed as it ended, or a
    runner that read only the last time step)."""
    log = case_dir / "log.pimpleFoam"
    start = log.read_bytes().rfind(b"Starting time loop") if log.is_file() else -1
    steps = TimeStepWatch(log, min_time_step, start_byte=max(start, 0))
    steps.read(to_end=True)
    return _diverged("pimpleFoam", steps, case_dir, log, MAX_COURANT_ABORT, exited=True)


def _check_time_limit(timeout_s: float, application: str) -> None:
    """Refuse a time limit that is not a finite time > 0 s (ConfigError, key timeout_s)."""
    if not (math.isfinite(timeout_s) and timeout_s > 0):
        raise ConfigError(f"the time limit of {application} must be a finite time > 0 s, "
                          f"got {timeout_s!r}", key="timeout_s")


def run_application(case_dir: str | Path, application: str, timeout_s: float = 3600.0,
                    max_courant_abort: float = MAX_COURANT_ABORT, n_procs: int = 1,
                    extra_args: tuple[str, ...] = (), min_time_step: float = 1e-7,
                    poll_s: float = 2.0, watch: Callable[[], object | None] | None = None,
                    watch_every_s: float = 60.0, progress: Callable[[], None] | None = None,
                    progress_every_s: float = 10.0, write_on_stop: bool = False,
                    write_grace_s: float = 120.0) -> Path:
    """Run one OpenFOAM application in a case; return the log path.

    The log is watched while the solver runs: a time step that collapses below
    ``min_time_step`` (an instability that the adaptive time step hides: the Courant number
    stays bounded while dt goes to zero and the run never ends) stops the run at once, and
    so does one that collapsed for a moment only and recovered (its forces there are
    spoiled): every line the run writes is read (:class:`TimeStepWatch`). So does a maximum
    Courant number above ``max_courant_abort`` anywhere in the run. A collapse or a Courant
    number beyond the limit in the seconds before the solver exited fails the run after it.
    ``watch``, called every ``watch_every_s`` seconds while it runs, stops it too when it
    returns a reason (e.g. forces beyond what the motion can drive:
    :func:`mfflap.cfd.openfoam.run_motion.run_motion`). ``progress`` is called every
    ``progress_every_s`` seconds while it runs (e.g.
    :class:`mfflap.cfd.openfoam.run_progress.RunProgress`).

    The log is appended to (a restart's log follows the run it restarts); only what this
    run writes is judged, so an earlier run's divergence in the same log does not fail it.

    With ``write_on_stop`` (a solver) a run stopped on purpose loses nothing: on a timeout or
    Ctrl-C (KeyboardInterrupt) the solver is asked to write its fields at the end of its
    time step and stop (:data:`WRITE_AND_STOP_SIGNAL`), so that a restart resumes where it
    stopped, not from its last regular write. It gets ``write_grace_s`` seconds, then is
    stopped as any other (a second Ctrl-C stops it at once). It runs in a process group of
    its own, so that a Ctrl-C in the terminal reaches this process and not the solver
    directly. A run stopped because it diverged or was stopped by ``watch`` is not written.
    If this process is killed outright (SIGKILL, the out-of-memory killer), the kernel sends
    the solver that signal too (:func:`dies_with_caller`), and the solver, which shares the
    case's run lock when this thread holds it, keeps the case locked until it has written
    and stopped.

    Raises
    ------
    ConfigError
        Before it starts, if the case's path holds characters OpenFOAM strips
        (:func:`~mfflap.cfd.openfoam.case_path.check_case_path`), or ``timeout_s`` is not a
        finite time > 0 s.
    CfdRunError
        Before it starts, if the OpenFOAM on PATH is of the openfoam.org line, whose cases
        differ from the ones mfflap writes (:mod:`mfflap.cfd.openfoam.release`). On a
        non-zero exit, a timeout, NaNs or a floating-point exception in the log, a
        collapsed time step, or a Courant number above ``max_courant_abort``, with the
        log's tail.
    """
    case_dir = check_case_path(case_dir)
    _check_time_limit(timeout_s, application)
    _raise_if_stopped(case_dir, application)
    require_supported_release(str(case_dir))  # openfoam.com's line, not openfoam.org's
    if not openfoam_available():
        raise CfdRunError("OpenFOAM is not installed (apt-get install openfoam)",
                          case=str(case_dir))
    log = case_dir / f"log.{application}"
    command = [application, "-case", str(case_dir), *extra_args]
    if write_on_stop:
        command += ["-opt-switch", f"stopAtWriteNowSignal={int(WRITE_AND_STOP_SIGNAL)}"]
    if n_procs > 1:
        command = ["mpirun", "-np", str(n_procs), "--allow-run-as-root", "--oversubscribe",
                   *command, "-parallel"]
    started = time.monotonic()
    watched = reported = started
    own_start = log.stat().st_size if log.is_file() else 0  # where this run's lines begin
    time_steps = TimeStepWatch(log, min_time_step, start_byte=own_start)
    # a solver that writes on a stop shares the case's lock: killed, its caller leaves the
    # case locked until the solver has written the step it reached and stopped
    lock_fd = held_descriptor(case_dir) if write_on_stop else None
    death_signal = WRITE_AND_STOP_SIGNAL.name.removeprefix("SIG") if write_on_stop else "TERM"
    with open(log, "a") as fh:
        proc = subprocess.Popen(dies_with_caller(command, death_signal), stdout=fh,
                                stderr=subprocess.STDOUT, env=_env(),
                                process_group=0 if write_on_stop else None,
                                pass_fds=() if lock_fd is None else (lock_fd,))
        if write_on_stop:
            with _solvers_guard:
                _solvers.add(proc)
        try:
            while True:
                try:
                    proc.wait(timeout=poll_s)
                    break
                except subprocess.TimeoutExpired:
                    pass
                if time.monotonic() - started > timeout_s:
                    kept = ""
                    if write_on_stop and write_and_stop(proc, write_grace_s) and (
                            written := written_where_stopped(case_dir)) is not None:
                        kept = f"; it wrote its fields at t = {written} s, where a rerun resumes"
                    raise CfdRunError(f"{application} timed out after {timeout_s} s{kept}",
                                      case=str(case_dir), log_tail=_tail(log))
                fh.flush()
                time_steps.read()
                if (diverged := _diverged(application, time_steps, case_dir, log,
                                          max_courant_abort)) is not None:
                    raise diverged
                if progress is not None and time.monotonic() - reported >= progress_every_s:
                    reported = time.monotonic()
                    progress()
                if watch is not None and time.monotonic() - watched >= watch_every_s:
                    watched = time.monotonic()
                    reason = watch()
                    if reason is not None:
                        raise RunStoppedByWatch(f"{application} stopped: {reason}",
                                                case=str(case_dir), log_tail=_tail(log),
                                                reason=reason)
        except KeyboardInterrupt:
            if write_on_stop and proc.poll() is None:
                write_and_stop(proc, write_grace_s)  # a second Ctrl-C: stopped below
            raise
        finally:
            if proc.poll() is None:
                stop(proc)
            with _solvers_guard:
                _solvers.discard(proc)
                asked_to_stop = proc.pid in _stop_requested
                _stop_requested.discard(proc.pid)
    if asked_to_stop:
        raise RunStopped(f"{application} was asked to write its fields and stop; the last time "
                         f"written whole is {latest_solution_time(case_dir)} s, where a rerun "
                         "resumes", case=str(case_dir), log_tail=_tail(log))
    own_tail = read_tail(log, 200_000, start=own_start)
    if proc.returncode != 0 or DIVERGED.search(own_tail[-50_000:]):
        raise CfdRunError(f"{application} failed (exit code {proc.returncode}): "
                          f"{failure_reason(own_tail[-50_000:], proc.returncode)}",
                          case=str(case_dir), log_tail=_tail(log))
    time_steps.read(to_end=True)  # what it wrote in its last poll's seconds
    if (diverged := _diverged(application, time_steps, case_dir, log, max_courant_abort,
                              exited=True)) is not None:
        raise diverged
    return log


def _last_check(case_dir: str | Path) -> str | None:
    """The output of the last checkMesh run in the case (``log.checkMesh`` holds every run,
    each from its ``Exec`` line), or None if it has not run."""
    log = Path(case_dir) / "log.checkMesh"
    if not log.is_file():
        return None
    text = log.read_text(errors="replace")
    return text[max(text.rfind("\nExec "), 0):]


def mesh_checked(case_dir: str | Path) -> bool:
    """True if the last checkMesh of the case (its ``log.checkMesh``, written by
    :func:`run_application`) passed its mesh ("Mesh OK"). A mesh made without mfflap, or
    one whose check failed, is not."""
    last = _last_check(case_dir)
    return last is not None and "Mesh OK" in last


def ran_to_end(case_dir: str | Path) -> bool:
    """True if the case's last pimpleFoam run ended normally at its end time: its log's last
    time step within one step of endTime (OpenFOAM runs while t < endTime - deltaT / 2),
    then "End"."""
    log = Path(case_dir) / "log.pimpleFoam"
    final = end_time(case_dir)
    text = read_tail(log) if log.is_file() else ""
    times = [float(t) for t in TIME_LINE.findall(text)]
    if not times or final is None:
        return False
    steps = DELTA_T_LINE.findall(text)  # a fixed time step prints none: the last two times
    step = (float(steps[-1]) if steps else times[-1] - times[-2] if len(times) > 1 else 0.0)
    if times[-1] < final - step - 1e-9 * abs(final):
        return False
    last_lines = [line.strip() for line in text[-2_000:].splitlines() if line.strip()]
    return "End" in last_lines[-10:]  # "Finalising parallel run", MPI notes may follow


def written_where_stopped(case_dir: str | Path) -> str | None:
    """The latest time written whole if it is the time step the solver's log reached (the
    solver wrote its fields where it stopped), else None."""
    reached, written = solver_progress(case_dir), latest_solution_time(case_dir)
    if reached is None or written is None or math.isnan(reached[1]):
        return None
    return written if abs(float(written) - reached[0]) <= 0.5 * reached[1] else None


def _later(a: str | None, b: str | None) -> bool:
    """Whether time name ``a`` is later than ``b`` (None: no time)."""
    return a is not None and (b is None or float(a) > float(b))


def _check_layout(case_dir: Path, n_procs: int) -> None:
    """Refuse a run whose layout (serial, or decomposed on ``n_procs`` ranks) would not
    resume where the case's last run stopped.

    OpenFOAM 1912's decomposePar and reconstructPar carry a time's fields but not the
    moving mesh's points (written under ``<time>/polyMesh``), so a run cannot switch
    between serial and decomposed, or between rank counts, part-way: decomposed, a serial
    run's progress was ignored and the run began again at t = 0; reconstructed, the serial
    solver stopped on a missing field, or restarted its mesh from rest and its time step
    collapsed.

    Raises
    ------
    CfdRunError
        Naming the layout that holds the latest time and how to continue.
    """
    processors = processor_folders(case_dir)
    serial = latest_solution_time(case_dir, "serial")
    decomposed = latest_solution_time(case_dir, "decomposed") if processors else None
    how = ("OpenFOAM 1912's decomposePar and reconstructPar do not carry the moving mesh's "
           "points between the two, so a run continues in the layout it stopped in")
    if n_procs > 1 and _later(serial, decomposed) and float(serial) > 0:
        raise CfdRunError(f"the case was run serial to t = {serial} s; decomposed on {n_procs} "
                          f"processes it would start again from t = {decomposed or 0} s "
                          f"({how}): continue it serial (without --procs), or write it "
                          "again (--overwrite) to run it decomposed from the start",
                          case=str(case_dir))
    if processors and _later(decomposed, serial) and float(decomposed) > 0 \
            and len(processors) != n_procs:
        layout = "serial" if n_procs == 1 else f"on {n_procs} processes"
        raise CfdRunError(f"the case was run decomposed on {len(processors)} processes to "
                          f"t = {decomposed} s; {layout} it cannot resume there ({how}): "
                          f"continue it with --procs {len(processors)}", case=str(case_dir))


def run_case(case_dir: str | Path, timeout_s: float = 3600.0, n_procs: int = 1,
             min_time_step: float = 1e-7, watch: Callable[[], object | None] | None = None,
             watch_every_s: float = 60.0, progress: Callable[[str], None] | None = None,
             progress_every_s: float = 10.0) -> None:
    """blockMesh (once), checkMesh (once), then pimpleFoam from the latest written time
    (none if the case has run to its end time; unless that run diverged somewhere, which
    fails the call as it failed the run: :func:`run_application`).

    The latest written time is the latest folder holding every field
    (:func:`~mfflap.cfd.openfoam.time_folders.latest_solution_time`), not merely the latest
    folder: controlDict is set to start there. With ``n_procs`` > 1 the case is decomposed
    once (``method simple``: scotch and metis are stubs in Debian's package) and pimpleFoam
    runs under mpirun; a restart continues from the processor folders' latest time. The
    forces function object writes from the master. ``progress``, if given, is told what is
    being done and, every ``progress_every_s`` seconds while pimpleFoam runs, how far it has
    got (:class:`mfflap.cfd.openfoam.run_progress.RunProgress`).

    Raises
    ------
    ConfigError
        Before anything runs, if the case's path holds characters OpenFOAM strips
        (:func:`~mfflap.cfd.openfoam.case_path.check_case_path`) or ``timeout_s`` is not a
        finite time > 0 s.
    CfdRunError
        If the folder is not a case, if another process is running it
        (:func:`mfflap.cfd.openfoam.case_lock.case_lock`), if pimpleFoam ended without an
        error before the case's end time (a stop signal sent to it directly: it wrote its
        fields, and a rerun resumes there), or as :func:`run_application`.
    """
    case_dir = check_case_path(case_dir)  # before "meshing" is said
    _check_time_limit(timeout_s, "pimpleFoam")
    meshed = (case_dir / "constant" / "polyMesh" / "points").exists()
    checked = meshed and mesh_checked(case_dir)  # a mesh made by hand, or failed, is checked
    needed = ("system/controlDict",) if meshed else ("system/controlDict", "system/blockMeshDict")
    missing = [name for name in needed if not (case_dir / name).is_file()]
    if missing:
        raise CfdRunError(f"not an OpenFOAM case: no {' or '.join(missing)} (write one with "
                          "`mfflap cfd write`)", case=str(case_dir))
    require_supported_release(str(case_dir))  # before the lock file is written
    with case_lock(case_dir):  # one run at a time in a case
        _check_layout(case_dir, n_procs)
        if not checked:
            if progress is not None:
                progress(f"meshing {case_dir} (blockMesh, checkMesh)" if not meshed else
                         f"checking the mesh of {case_dir} (checkMesh)")
            if not meshed:
                run_application(case_dir, "blockMesh", timeout_s=300)
            log = run_application(case_dir, "checkMesh", timeout_s=300)
            last = _last_check(case_dir) or ""
            if "Mesh OK" not in last:  # as mesh_checked, from the log read once
                failed = [" ".join(line.strip().lstrip("*").rstrip(".").split())
                          for line in last.splitlines() if line.lstrip().startswith("***")]
                raise CfdRunError(
                    "checkMesh did not report 'Mesh OK'"
                    + (f": {'; '.join(failed)}" if failed else "")
                    + "; pimpleFoam is not started on this mesh (a rerun checks it again)",
                    case=str(case_dir), log_tail=_tail(log))
        if n_procs > 1:
            decomposition = foam_file(case_dir / "system" / "decomposeParDict")
            with decomposition:  # n_procs slabs along x, by the simple method
                decomposition["numberOfSubdomains"] = n_procs
                for coeffs in ("coeffs", "simpleCoeffs"):
                    if coeffs in decomposition:
                        decomposition[coeffs]["n"] = [n_procs, 1, 1]
            if len(processor_folders(case_dir)) != n_procs:  # none, or only t = 0 of another
                run_application(case_dir, "decomposePar", timeout_s=300, extra_args=("-force",))
        start = latest_solution_time(case_dir, "decomposed" if n_procs > 1 else "serial") or "0"
        final = end_time(case_dir)
        if (final is not None and float(start) >= final - 1e-9 * abs(final)
                and ran_to_end(case_dir)):
            if (diverged := _last_run_diverged(case_dir, min_time_step)) is not None:
                raise diverged
            if progress is not None:
                progress(f"{case_dir} has run to its end time ({final:g} s) already: nothing to "
                         "run")
            return
        set_start_time(case_dir, start)
        aligned = align_writes_to_end(case_dir, float(start))
        if aligned is not None and progress is not None:
            progress(f"write interval {aligned:.6g} s from t = {start} s, so that the run "
                     "still writes at its end time")
        reporter = None
        if progress is not None:
            progress(f"pimpleFoam {'from t = ' + start + ' s' if start != '0' else 'started'}"
                     f"{f' on {n_procs} processes' if n_procs > 1 else ''}; log: "
                     f"{case_dir / 'log.pimpleFoam'}")
            reporter = RunProgress(case_dir, progress)
        log = run_application(case_dir, "pimpleFoam", timeout_s=timeout_s, n_procs=n_procs,
                              min_time_step=min_time_step, watch=watch,
                              watch_every_s=watch_every_s, progress=reporter,
                              progress_every_s=progress_every_s, write_on_stop=True)
        reached = solver_progress(case_dir)
        if reached is not None and not ran_to_end(case_dir):
            raise CfdRunError(  # sent a stop signal by someone else: not a finished run
                f"pimpleFoam stopped without an error at t = {reached[0]:.6g} s, before its "
                f"end time {end_time(case_dir):g} s (a stop signal sent to the solver "
                f"itself?); a rerun resumes from t = {latest_solution_time(case_dir)} s",
                case=str(case_dir),
                log_tail=_tail(log))
