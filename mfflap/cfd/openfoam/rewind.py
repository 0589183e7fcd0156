"""Rewind an OpenFOAM case to a time it wrote, so that a rerun resumes there and its output
is the only one from there on (after a run whose time step collapsed, or whose forces left
what its motion can drive, at a later time)."""

from __future__ import annotations

import shutil
from pathlib import Path

from mfflap.cfd.openfoam.time_folders import is_time_folder, latest_solution_time
from mfflap.errors import CfdRunError


def rewind_case(case_dir: str | Path, before_s: float) -> str:
    """Make a case resume from its last written time before ``before_s``; return that time.

    Later solution folders (the case's and its processor folders') go, and so does the
    function-object output that began after it (``postProcessing/*/<time>/`` folders and
    ``<stem>_<time>.dat`` restart files), so that the rerun's output is the only one from
    there on (:func:`mfflap.cfd.openfoam.forces.merge_restart_segments`). mfflap's cases
    keep their last two writes (``purgeWrite 2``), so a breach before those resumes from 0.

    Raises
    ------
    CfdRunError
        If no complete solution folder is older than ``before_s`` (not even ``0/``).
    """
    case = Path(case_dir)
    roots = [case, *sorted(case.glob("processor*"))]

    def times(root: Path) -> list[Path]:
        return [p for p in root.iterdir() if p.is_dir() and is_time_folder(p.name)]

    while (latest := latest_solution_time(case)) is not None and float(latest) >= before_s:
        if float(latest) == 0.0:
            break
        for root in roots:
            for folder in times(root):
                if float(folder.name) >= float(latest):
                    shutil.rmtree(folder)
    if latest is None or (float(latest) >= before_s and float(latest) != 0.0):
        raise CfdRunError(f"no written time before t = {before_s:g} s to resume from",
                          case=str(case))
    resume = float(latest)
    for root in roots:  # partial or newer folders (e.g. yPlus output) after the resume time
        for folder in times(root):
            if float(folder.name) > resume:
                shutil.rmtree(folder)
    for output in (case / "postProcessing").glob("*"):
        if not output.is_dir():
            continue
        for folder in times(output):
            if float(folder.name) > resume:
                shutil.rmtree(folder)
                continue
            for restart in folder.glob("*_*.dat"):
                try:
                    if float(restart.stem.rsplit("_", 1)[1]) > resume:
                        restart.unlink()
                except ValueError:
                    continue
    return latest
