"""Case folders: paths OpenFOAM can run in, and folders a new case may be written into.

OpenFOAM strips whitespace and quotes from every file name it reads, the ``-case`` argument
included, so a case in ``/tmp/a b/case`` runs as ``/tmp/ab/case`` and fails ("cannot open
root directory"), or runs a case of that other name if one exists. Checked here on Debian's
openfoam (v1912) with blockMesh: a space, ``"`` and ``'`` are stripped; ``$ ~ # ; ( { * , @
= :`` and non-ASCII letters are kept.

A case written over another mixes with it: a run resumes from the times written there and
keeps the mesh made there, and the files of another frame or mesh type stay (a plate-frame
case's MRFProperties would turn an inertial case's mesh). :func:`prepare_case_folder` lets a
case be written only into a new or empty folder, or over a case mfflap wrote when asked to
overwrite it.
"""

from __future__ import annotations

import shutil
from pathlib import Path

from mfflap.cfd.openfoam.case_lock import LOCK_FILE, case_lock
from mfflap.errors import ConfigError

#: the characters OpenFOAM strips from a file name besides whitespace
STRIPPED_QUOTES = "\"'"


def stripped_characters(path: str | Path) -> list[str]:
    """The characters of ``path`` (made absolute, as OpenFOAM sees it from the working
    folder) that OpenFOAM strips from a file name, each once, in order."""
    found: list[str] = []
    for char in str(Path(path).absolute()):
        if (char.isspace() or char in STRIPPED_QUOTES) and char not in found:
            found.append(char)
    return found


def check_case_path(path: str | Path) -> Path:
    """``path`` if OpenFOAM can run a case in it (or in a folder below it).

    Raises
    ------
    ConfigError
        Naming the path and the characters OpenFOAM would strip from it, before anything is
        written or run.
    """
    path = Path(path)
    bad = stripped_characters(path)
    if bad:
        absolute = str(path.absolute())
        seen_as = "".join(c for c in absolute if c not in bad)
        raise ConfigError(
            f"OpenFOAM cannot run a case in {absolute!r}: it strips whitespace and quotes "
            f"from file names ({', '.join(repr(c) for c in bad)} here) and would look in "
            f"{seen_as!r} instead; choose a folder whose path has none")
    return path


def _listed(names: list[str], shown: int = 6) -> str:
    more = len(names) - shown
    return ", ".join(names[:shown]) + (f" and {more} more" if more > 0 else "")


def prepare_case_folder(case_dir: str | Path, marker: str, overwrite: bool = False) -> Path:
    """``case_dir`` ready for a new case: a new or empty folder, or one holding a case
    mfflap wrote (its ``marker`` file, e.g. mfflap_case.toml) whose contents are deleted
    when ``overwrite`` is set. Call it once every setting has been checked: an overwritten
    case is gone.

    Raises
    ------
    ConfigError
        For a path OpenFOAM cannot read (:func:`check_case_path`), a file, a folder with
        files of something other than a case mfflap wrote (never deleted), or a case
        written before without ``overwrite``, naming what the folder holds.
    CaseBusyError
        If a run is going in the case to be overwritten.
    """
    case_dir = check_case_path(case_dir)
    if not case_dir.exists():
        return case_dir
    if not case_dir.is_dir():
        raise ConfigError(f"{case_dir} is a file; a case is written into a folder")
    held = sorted(p.name for p in case_dir.iterdir() if p.name != LOCK_FILE)
    if not held:
        return case_dir
    if not (case_dir / marker).is_file():
        raise ConfigError(f"{case_dir} is not empty ({_listed(held)}) and holds no case "
                          f"mfflap wrote (no {marker}): write the case into a new or empty "
                          "folder")
    if not overwrite:
        raise ConfigError(f"{case_dir} holds a case written before ({_listed(held)}); a case "
                          "written over it would mix with it (a run resumes from the times "
                          "written there and keeps its mesh, and files of another frame or "
                          "mesh stay): write into a new folder, or overwrite it "
                          "(--overwrite), which deletes what it holds")
    with case_lock(case_dir):  # no run going in it while its files go
        empty_case_folder(case_dir)
    return case_dir


def empty_case_folder(case_dir: Path) -> None:
    """Delete everything in ``case_dir`` but its run lock file (whose holder, the caller,
    keeps it); a symbolic link goes, not what it points to."""
    for entry in case_dir.iterdir():
        if entry.name == LOCK_FILE:
            continue
        if entry.is_dir() and not entry.is_symlink():
            shutil.rmtree(entry)
        else:
            entry.unlink()


__all__ = ["STRIPPED_QUOTES", "check_case_path", "empty_case_folder", "prepare_case_folder",
           "stripped_characters"]
