"""Files written whole or not at all: a new file beside the target, flushed to disk and
renamed over it.

A results file or CFD record is never edited where it lies: a kill or a full disk in the
middle of an edit would leave it unreadable. Every write goes to a temporary file in the
target's folder, created exclusively under an unpredictable name (so that no symlink planted
under a predictable name is followed), and is renamed over the target once it is complete
and on disk; the rename replaces a symlink at the target rather than writing through it.
Each temporary name carries the id of the process writing it, so that a clean-up removes
only the temporary files of processes that are gone, never those of a writer still at work.

Examples
--------
>>> import tempfile
>>> from pathlib import Path
>>> target = Path(tempfile.mkdtemp()) / "results.h5"
>>> tmp = temporary_beside(target)
>>> tmp.parent == target.parent and tmp.name.startswith(".results.h5.")
True
>>> _ = tmp.write_bytes(b"whole")
>>> commit(tmp, target)
>>> target.read_bytes(), tmp.exists()
(b'whole', False)
>>> stale_temporaries(target.parent)
[]
"""

from __future__ import annotations

import os
import re
import shutil
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import h5py

from mfflap.errors import MfflapError

#: a temporary file's name: .<target name>.<8 random characters>.<pid>.tmp (tempfile's
#: names), or without the random part
_TEMPORARY = re.compile(r"\.(?P<target>.+?)(?:\.[a-z0-9_]{8})?\.(?P<pid>\d+)\.tmp")


def temporary_beside(path: str | Path) -> Path:
    """A new, empty file in ``path``'s folder to write ``path``'s next content into, created
    exclusively (``O_EXCL``) under an unpredictable name that carries this process's id."""
    path = Path(path)
    fd, name = tempfile.mkstemp(prefix=f".{path.name}.", suffix=f".{os.getpid()}.tmp",
                                dir=path.parent)
    os.close(fd)
    return Path(name)


def _fsync(path: Path) -> None:
    fd = os.open(path, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


def commit(temporary: str | Path, path: str | Path) -> None:
    """Put the complete ``temporary`` (from :func:`temporary_beside`) in ``path``'s place:
    flushed to disk, renamed, and the folder's entry flushed too.

    Raises
    ------
    MfflapError
        Naming ``path``, if the temporary file is gone (another process removed it) or the
        disk refused the write; ``path`` keeps what it held.
    """
    temporary, path = Path(temporary), Path(path)
    if not temporary.is_file():
        raise MfflapError(f"{path}: its new content ({temporary.name}) was removed before it "
                          "could take the file's place; nothing was written")
    try:
        _fsync(temporary)
        os.replace(temporary, path)
        _fsync(path.parent)
    except OSError as exc:
        temporary.unlink(missing_ok=True)
        raise MfflapError(f"{path}: cannot be written ({exc.strerror or exc}); it keeps what "
                          "it held") from exc


def _process_alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # another user's process: alive
        return True
    return True


def stale_temporaries(folder: str | Path, target_suffix: str = "") -> list[Path]:
    """The temporary files in ``folder`` (of targets ending in ``target_suffix``) whose
    writing process is gone: what a kill left behind, safe to remove."""
    out = []
    for p in sorted(Path(folder).glob(".*.tmp")):
        m = _TEMPORARY.fullmatch(p.name)
        if m and m["target"].endswith(target_suffix) and not _process_alive(int(m["pid"])):
            out.append(p)
    return out


@contextmanager
def edited_copy(path: str | Path) -> Iterator[h5py.File]:
    """An HDF5 file's copy opened for appending, which takes the file's place when the
    block ends without an error; on an error (or a kill) the file is as it was.

    Raises
    ------
    MfflapError
        Naming the file, if it cannot be copied, opened or written.
    """
    path = Path(path)
    temporary = temporary_beside(path)
    try:
        shutil.copyfile(path, temporary)
        with h5py.File(temporary, "a") as h5:
            yield h5
    except BaseException as exc:
        temporary.unlink(missing_ok=True)
        if isinstance(exc, OSError):
            raise MfflapError(f"{path}: cannot be edited ({exc})") from exc
        raise
    commit(temporary, path)


__all__ = ["commit", "edited_copy", "stale_temporaries", "temporary_beside"]
