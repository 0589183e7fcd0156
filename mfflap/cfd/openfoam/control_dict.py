"""Edits of a case's system/controlDict for a resumed run: its start time (at a precision
that names the folder), its end time, and write times that fall on the end."""

from __future__ import annotations

import math
import re
from pathlib import Path

from mfflap.errors import CfdRunError

_TIME_PRECISION = re.compile(r"^timePrecision\s+(\d+)\s*;", re.M)

#: OpenFOAM's timePrecision where controlDict gives none
OPENFOAM_TIME_PRECISION = 6


def set_start_time(case_dir: str | Path, time_name: str) -> None:
    """Make pimpleFoam start from the time folder ``time_name`` (``startFrom startTime``).

    OpenFOAM names the start time with the case's ``timePrecision`` significant digits. A
    folder written where the time steps had collapsed can carry more (OpenFOAM raises the
    precision while it runs to tell two times apart, and does not write that down), and at
    the case's precision the name may be that of another folder, one the yPlus function
    object wrote a step earlier: the run then starts from that folder and stops for want of
    p. So ``timePrecision`` is raised to the digits of ``time_name`` (never lowered).

    Raises
    ------
    CfdRunError
        If system/controlDict has no ``startFrom`` or ``startTime`` entry.
    """
    path = Path(case_dir) / "system" / "controlDict"
    text = path.read_text()
    new, n_from = re.subn(r"^startFrom\s+[^;]*;", "startFrom       startTime;", text, flags=re.M)
    new, n_time = re.subn(r"^startTime\s+[^;]*;", f"startTime       {time_name};", new,
                          flags=re.M)
    if not (n_from and n_time):
        raise CfdRunError(f"{path} has no startFrom or startTime entry at the start of a line",
                          case=str(case_dir))
    digits = significant_digits(time_name)
    found = _TIME_PRECISION.search(new)
    if found is None and digits > OPENFOAM_TIME_PRECISION:  # OpenFOAM's default
        new = re.sub(r"^(startTime\s+[^;]*;)", rf"\1\ntimePrecision   {digits};", new,
                     flags=re.M)
    elif found is not None and int(found.group(1)) < digits:
        new = _TIME_PRECISION.sub(f"timePrecision   {digits};", new)
    if new != text:
        path.write_text(new)


def significant_digits(time_name: str) -> int:
    """The significant digits of a time folder's name (``2.20850674``: 9; ``0.015``: 2;
    ``1e-05``: 1), the ``timePrecision`` that names it."""
    mantissa = re.split(r"[eE]", time_name.strip().lstrip("+-"))[0]
    return max(len(mantissa.replace(".", "").lstrip("0")), 1)


_END_TIME = re.compile(r"^endTime\s+([^;\s]+)\s*;", re.M)


def end_time(case_dir: str | Path) -> float | None:
    """The ``endTime`` of a case's system/controlDict, s; None if it has none that is a
    number."""
    path = Path(case_dir) / "system" / "controlDict"
    match = _END_TIME.search(path.read_text()) if path.is_file() else None
    try:
        return float(match.group(1)) if match else None
    except ValueError:
        return None


_WRITE_CONTROL = re.compile(r"^writeControl\s+(\w+);", re.M)
_WRITE_INTERVAL = re.compile(r"^(writeInterval\s+)([^;\s]+)(;)", re.M)


def align_writes_to_end(case_dir: str | Path, start_s: float) -> float | None:
    """Make a run from ``start_s`` write at its end time; return the new write interval, s,
    or None if it already does (or writes by time step).

    OpenFOAM counts a run's write times (``adjustableRunTime``) from the time it starts and
    runs while t < endTime - deltaT / 2. A run resumed between two writes (one stopped by
    :data:`~mfflap.cfd.openfoam.runner.WRITE_AND_STOP_SIGNAL`) would write on a shifted
    grid, its last write before the end, and stop short of it unwritten; a rerun would then
    recompute that stretch. The interval becomes the largest one not above the case's that
    divides the time left. A run that starts on the grid of the case's own interval (from 0,
    or from one of its writes) keeps the interval it was given.
    """
    path = Path(case_dir) / "system" / "controlDict"
    text = path.read_text()
    control, interval = _WRITE_CONTROL.search(text), _WRITE_INTERVAL.search(text)
    final = end_time(case_dir)
    if (control is None or control.group(1) not in ("adjustableRunTime", "runTime")
            or interval is None or final is None or final <= start_s):
        return None
    step = float(interval.group(2))
    n_writes, n_before = (final - start_s) / step, start_s / step

    def whole(count: float) -> bool:
        return abs(count - round(count)) <= 1e-6 * max(count, 1.0)

    if whole(n_writes) or whole(n_before):  # ends on the grid, or starts on the case's own
        return None
    aligned = (final - start_s) / math.ceil(n_writes)
    path.write_text(_WRITE_INTERVAL.sub(lambda m: f"{m.group(1)}{aligned:.12g}{m.group(3)}",
                                        text, count=1))
    return aligned
