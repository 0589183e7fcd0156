"""The time folders of an OpenFOAM case: which are written whole, and where a run resumes
(serial or decomposed)."""

from __future__ import annotations

import gzip
import re
import zlib
from pathlib import Path

from mfflap.cfd.openfoam.solver_log import read_tail


def is_time_folder(name: str) -> bool:
    """True if ``name`` is a number, as OpenFOAM names its time folders."""
    try:
        float(name)
    except ValueError:
        return False
    return True


#: the line OpenFOAM ends every file it writes with, ASCII or binary
_END_DIVIDER = re.compile(r"// \*{20,} //\s*$")


def written_whole(path: Path) -> bool:
    """True if an OpenFOAM output file ends with its end divider, as every file it writes
    does (ASCII or binary, compressed or not); a write cut short by a kill does not."""
    if path.name.endswith(".gz"):
        try:
            tail = gzip.decompress(path.read_bytes())[-200:].decode(errors="replace")
        except (OSError, EOFError, zlib.error):
            return False
    else:
        tail = read_tail(path, 200)
    return _END_DIVIDER.search(tail) is not None


def processor_folders(case_dir: str | Path) -> list[Path]:
    """The ``processor<N>`` folders of a decomposed case, in rank order (none if serial)."""
    folders = [p for p in Path(case_dir).glob("processor*") if p.is_dir()
               and p.name.removeprefix("processor").isdigit()]
    return sorted(folders, key=lambda p: int(p.name.removeprefix("processor")))


def latest_solution_time(case_dir: str | Path, layout: str = "latest") -> str | None:
    """Name of the latest time folder written whole that holds every field of ``0/``.

    A time folder can hold less: the yPlus function object writes its field into a folder of
    its own every few steps, and a run killed while writing leaves a partial one, or one
    whose last file is cut short (every file OpenFOAM writes ends with its end divider).
    OpenFOAM's ``startFrom latestTime`` would restart from such a folder and stop at once
    for want of p, or on a field it cannot read. A decomposed case needs the folder whole
    in every ``processor*`` folder. None if no folder qualifies (``0/`` missing or empty).

    Parameters
    ----------
    layout
        ``"serial"``: the case folder's own times; ``"decomposed"``: the times every
        ``processor*`` folder holds; ``"latest"``: the later of the two, where
        :func:`~mfflap.cfd.openfoam.runner.run_case` resumes (in the layout that holds it).
    """
    case = Path(case_dir)
    if layout == "latest":
        times = [t for t in (latest_solution_time(case, "serial"),
                             latest_solution_time(case, "decomposed")) if t is not None]
        return max(times, key=float) if times else None
    if layout not in ("serial", "decomposed"):
        raise ValueError(f"layout must be 'serial', 'decomposed' or 'latest', got {layout!r}")
    roots = processor_folders(case) if layout == "decomposed" else [case]
    if not roots:
        return None

    def fields(folder: Path) -> set[str]:
        return {p.name.removesuffix(".gz") for p in folder.iterdir() if p.is_file()}

    initial = roots[0] / "0"
    needed = fields(initial) if initial.is_dir() else set()
    if not needed:
        return None

    def whole(root: Path, name: str) -> bool:
        folder = root / name
        if not folder.is_dir() or not needed <= fields(folder):
            return False
        return name == "0" or all(written_whole(f) for f in folder.rglob("*") if f.is_file())

    names = sorted((p.name for p in roots[0].iterdir() if p.is_dir() and is_time_folder(p.name)),
                   key=float, reverse=True)
    return next((name for name in names if all(whole(root, name) for root in roots)), None)
