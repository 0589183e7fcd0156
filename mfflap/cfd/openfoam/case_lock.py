"""One run at a time in a case folder.

Two solvers writing into the same case (a second ``mfflap cfd run`` of a case still running,
two campaigns given the same ``--out``, a back-test resumed by hand while its study runs)
interleave their time folders and force logs, and a restart then resumes from fields neither
run wrote whole. :func:`case_lock` holds an exclusive ``flock(2)`` on ``<case>/.mfflap-run.lock``
while a case is written to, and refuses a second holder with the first one's process id and
start time. The kernel drops the lock when its process dies, however it dies, so a killed run
never leaves a stale lock behind (the file stays, unlocked). On a file system without
flock(2) runs go unguarded, as they did before the lock. The lock is re-entrant within a
thread, so :func:`mfflap.cfd.openfoam.run_motion.run_motion` can hold it around writing the
case and its retries while :func:`mfflap.cfd.openfoam.runner.run_case` takes it again. A
refusal is a :class:`CaseBusyError`, so that a campaign tells a case another process is
running from one that failed; :func:`lock_holder` says who runs a case without taking it.

A solver shares its caller's lock (:func:`held_descriptor`, passed to it by
:func:`mfflap.cfd.openfoam.runner.run_application`): when the caller is killed outright (a
dask worker lost to the out-of-memory killer) the kernel asks the solver to write the time
step it reached and stop, and the case stays locked until it has. A run that meets such a
lock, whose holder named in it is gone from this host, waits for that write
(:data:`ORPHAN_WAIT_S`) instead of refusing at once.
"""

from __future__ import annotations

import datetime as _dt
import fcntl
import os
import random
import re
import socket
import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from mfflap.errors import CfdRunError

#: the lock file in a case folder
LOCK_FILE = ".mfflap-run.lock"


class CaseBusyError(CfdRunError):
    """Another process, or another thread of this one, holds the case's run lock."""


_held: dict[Path, tuple[int, int, int]] = {}  # case -> (fd, owning thread, depth)
_guard = threading.Lock()


@contextmanager
def case_lock(case_dir: str | Path) -> Iterator[None]:
    """Hold the run lock of ``case_dir`` for the duration of the block.

    Raises
    ------
    CaseBusyError
        If another process, or another thread of this one, holds it (naming its process id
        and since when).
    """
    case = Path(case_dir).resolve()
    me = threading.get_ident()
    with _guard:
        held = _held.get(case)
        if held is not None:
            fd, owner, depth = held
            if owner != me:
                raise CaseBusyError("another thread of this process is running the case",
                                    case=str(case_dir))
            _held[case] = (fd, owner, depth + 1)
        else:
            fd = _acquire(case, case_dir)
            _held[case] = (fd, me, 1)
    try:
        yield
    finally:
        with _guard:
            fd, owner, depth = _held[case]
            if depth > 1:
                _held[case] = (fd, owner, depth - 1)
            else:
                del _held[case]
                os.close(fd)  # closing the descriptor releases the flock


def held_descriptor(case_dir: str | Path) -> int | None:
    """The file descriptor of the run lock of ``case_dir`` that this thread holds, or None.

    A process given it (``subprocess.Popen(pass_fds=...)``) holds the lock with this one:
    the kernel drops it only when every holder has closed it or died.
    """
    with _guard:
        held = _held.get(Path(case_dir).resolve())
    return held[0] if held is not None and held[1] == threading.get_ident() else None


#: how long a run waits for a lock whose named holder is gone from this host (its solver
#: writing the step it reached, :data:`mfflap.cfd.openfoam.runner.WRITE_AND_STOP_SIGNAL`),
#: s: the write grace a stopped solver gets
ORPHAN_WAIT_S = 120.0

_HOLDER = re.compile(r"^pid (\d+) since \S+ on (\S+)")


def _holder_gone(holder: str) -> bool:
    """True if the lock text names a process of this host that no longer exists."""
    match = _HOLDER.match(holder)
    if match is None or match.group(2) != socket.gethostname():
        return False
    try:
        os.kill(int(match.group(1)), 0)
    except ProcessLookupError:
        return True
    except OSError:  # exists, another user's
        return False
    return False


def _read_holder(fd: int) -> str:
    return os.pread(fd, 200, 0).decode(errors="replace").strip() or "unknown"


def _acquire(case: Path, shown: str | Path) -> int:
    case.mkdir(parents=True, exist_ok=True)
    fd = os.open(case / LOCK_FILE, os.O_RDWR | os.O_CREAT | os.O_CLOEXEC, 0o644)
    try:
        if not _flock_within(fd, _QUICK_WAIT_S):
            holder = _read_holder(fd)
            gone = _holder_gone(holder)
            if not (gone and _flock_within(fd, ORPHAN_WAIT_S)):
                os.close(fd)
                raise CaseBusyError(
                    f"the case is being run by another process ({holder}); wait for it to "
                    "finish or stop it first" if not gone else
                    f"the case is held by a solver whose caller ({holder}) is gone: asked to "
                    f"write its fields and stop, it still runs after {ORPHAN_WAIT_S:g} s; "
                    f"stop it (pkill -f 'Foam -case {case}')", case=str(shown))
    except OSError:  # a file system without flock(2): run unguarded, as before the lock
        return fd
    started = _dt.datetime.now().astimezone().isoformat(timespec="seconds")
    os.ftruncate(fd, 0)
    os.pwrite(fd, f"pid {os.getpid()} since {started} on {socket.gethostname()}".encode(), 0)
    return fd


#: how long a run tries again to take a lock found held, and the pause between tries, s: a
#: :func:`lock_holder` probe holds it for microseconds, a run for minutes
_QUICK_WAIT_S, _PAUSE_S = 0.2, 0.01

#: the fewest tries before a held lock is given up, however long they took: on a loaded
#: machine one pause can outlast the whole wait, and a probe running in a tight loop holds the
#: lock at about a third of the moments a try is made
_MIN_TRIES = 20


def _flock_within(fd: int, wait_s: float) -> bool:
    """Take the exclusive lock, trying again every :data:`_PAUSE_S` (jittered) while it is
    held, for up to ``wait_s`` seconds and at least :data:`_MIN_TRIES` times; True if it was
    taken (OSError where flock(2) is missing)."""
    deadline = time.monotonic() + wait_s
    tries = 0
    while True:
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            return True
        except BlockingIOError:
            tries += 1
            if tries >= _MIN_TRIES and time.monotonic() >= deadline:
                return False
            time.sleep(_PAUSE_S * random.uniform(0.5, 1.5))  # no lockstep with a poller


def lock_holder(case_dir: str | Path) -> str | None:
    """Who holds the run lock of ``case_dir`` ("pid N since <ISO time> on <host>", and
    whether that process is gone while its solver writes), or None if nobody does (no lock
    file, a file system without flock(2), or the lock free). A lock held by this process
    counts as held. The lock is only tested, never kept, and the lock file is not
    created."""
    path = Path(case_dir) / LOCK_FILE
    try:
        fd = os.open(path, os.O_RDONLY | os.O_CLOEXEC)
    except OSError:
        return None
    try:
        try:
            fcntl.flock(fd, fcntl.LOCK_SH | fcntl.LOCK_NB)
        except BlockingIOError:
            holder = _read_holder(fd)
            return holder + ("; that process is gone, its solver is writing the step it "
                             "reached" if _holder_gone(holder) else "")
        except OSError:
            return None
        return None  # free (closing the descriptor drops the shared lock just taken)
    finally:
        os.close(fd)
