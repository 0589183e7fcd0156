"""Edits of a case's system/controlDict for a resumed run: its start time (at a precision
that names the folder), its end time, and write times that fall on the end.

The dictionary is read and written through foamlib's parser (:class:`foamlib.FoamFile`),
so an edit changes the entry it means, wherever and however it is written.
"""

from __future__ import annotations

import math
import re
from pathlib import Path

from mfflap.cfd.openfoam.foam_files import decode_error, foam_file
from mfflap.errors import CfdRunError

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
    control = foam_file(path)
    if "startFrom" not in control or "startTime" not in control:
        raise CfdRunError(f"{path} has no startFrom or startTime entry", case=str(case_dir))
    digits = significant_digits(time_name)
    precision = control.get("timePrecision", OPENFOAM_TIME_PRECISION)
    with control:  # one write of every change
        control["startFrom"] = "startTime"
        control["startTime"] = float(time_name)
        if int(precision) < digits:
            control["timePrecision"] = digits


def significant_digits(time_name: str) -> int:
    """The significant digits of a time folder's name (``2.20850674``: 9; ``0.015``: 2;
    ``1e-05``: 1), the ``timePrecision`` that names it."""
    mantissa = re.split(r"[eE]", time_name.strip().lstrip("+-"))[0]
    return max(len(mantissa.replace(".", "").lstrip("0")), 1)


def end_time(case_dir: str | Path) -> float | None:
    """The ``endTime`` of a case's system/controlDict, s; None if it has none that is a
    number."""
    path = Path(case_dir) / "system" / "controlDict"
    if not path.is_file():
        return None
    try:
        value = foam_file(path).get("endTime")
    except decode_error():  # a controlDict foamlib cannot parse has no endTime to give
        return None
    return float(value) if isinstance(value, int | float) else None


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
    control_dict = foam_file(path)
    control, interval = control_dict.get("writeControl"), control_dict.get("writeInterval")
    final = end_time(case_dir)
    if (control not in ("adjustableRunTime", "runTime") or not isinstance(interval, int | float)
            or final is None or final <= start_s):
        return None
    step = float(interval)
    n_writes, n_before = (final - start_s) / step, start_s / step

    def whole(count: float) -> bool:
        return abs(count - round(count)) <= 1e-6 * max(count, 1.0)

    if whole(n_writes) or whole(n_before):  # ends on the grid, or starts on the case's own
        return None
    aligned = float(f"{(final - start_s) / math.ceil(n_writes):.12g}")
    control_dict["writeInterval"] = aligned
    return aligned
