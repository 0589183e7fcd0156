"""One run at a time in a case folder.

Two solvers writing into the same case (a second ``mfflap cfd run`` of a case still running,
two campaigns given the same ``--out``, a back-test resumed by hand while its study runs)
interleave their time folders and force logs, and a restart then resumes from fields neither
run wrote whole. :func:`case_lock` holds an exclusive ``flock(2)`` on ``<case>/.mfflap-run.lock``
while a case is written to, and refuses a second holder with the first one's process id and
start time. The kernel drops the lock when its process dies, however it dies, so a killed run
never leaves a stale lock behind (the file stays, unlocked). On a file system without
flock(2) runs go unguarded, as they did before the lock. The lock is re-entrant within a
thread, so :func:`mfflap.campaign.openfoam_run.run_motion` can hold it around writing the
case and its retries while :func:`mfflap.cfd.openfoam.runner.run_case` takes it again. A
refusal is a :class:`CaseBusyError`, so that a campaign tells a case another process is
running from one that failed; :func:`lock_holder` says who runs a case without taking it.
"""

from __future__ import annotations

import datetime as _dt
import fcntl
import os
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


def _acquire(case: Path, shown: str | Path) -> int:
    case.mkdir(parents=True, exist_ok=True)
    fd = os.open(case / LOCK_FILE, os.O_RDWR | os.O_CREAT | os.O_CLOEXEC, 0o644)
    try:
        _flock_or_wait(fd)
    except BlockingIOError:
        holder = os.pread(fd, 200, 0).decode(errors="replace").strip() or "unknown"
        os.close(fd)
        raise CaseBusyError(f"the case is being run by another process ({holder}); wait for "
                            "it to finish or stop it first", case=str(shown)) from None
    except OSError:  # a file system without flock(2): run unguarded, as before the lock
        return fd
    started = _dt.datetime.now().astimezone().isoformat(timespec="seconds")
    os.ftruncate(fd, 0)
    os.pwrite(fd, f"pid {os.getpid()} since {started}".encode(), 0)
    return fd


#: tries to take a lock found held, and the pause between them, s: a :func:`lock_holder`
#: probe holds it for microseconds, a run for minutes
_TRIES, _PAUSE_S = 5, 0.05


def _flock_or_wait(fd: int) -> None:
    """Take the exclusive lock, trying again for a moment if it is held (raises
    BlockingIOError if it still is)."""
    for attempt in range(_TRIES):
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            return
        except BlockingIOError:
            if attempt == _TRIES - 1:
                raise
            time.sleep(_PAUSE_S)


def lock_holder(case_dir: str | Path) -> str | None:
    """Who holds the run lock of ``case_dir`` ("pid N since <ISO time>"), or None if nobody
    does (no lock file, a file system without flock(2), or the lock free). A lock held by
    this process counts as held. The lock is only tested, never kept, and the lock file is
    not created."""
    path = Path(case_dir) / LOCK_FILE
    try:
        fd = os.open(path, os.O_RDONLY | os.O_CLOEXEC)
    except OSError:
        return None
    try:
        try:
            fcntl.flock(fd, fcntl.LOCK_SH | fcntl.LOCK_NB)
        except BlockingIOError:
            return os.pread(fd, 200, 0).decode(errors="replace").strip() or "unknown"
        except OSError:
            return None
        return None  # free (closing the descriptor drops the shared lock just taken)
    finally:
        os.close(fd)
