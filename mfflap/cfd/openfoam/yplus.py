"""The yPlus function object's output (postProcessing/yPlus/<time>/yPlus.dat)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from mfflap.cfd.openfoam.forces import merge_restart_segments, restart_segments, time_folders
from mfflap.errors import ParseError


@dataclass
class YPlusHistory:
    """y+ on one patch over time: min, max and area average."""

    time: np.ndarray
    minimum: np.ndarray
    maximum: np.ndarray
    average: np.ndarray


def read_y_plus(case_dir: str | Path, patch: str = "plate") -> YPlusHistory:
    """y+ of ``patch``, merged over restart folders and restart files like the forces
    (:func:`~mfflap.cfd.openfoam.forces.merge_restart_segments`: a restart replaces
    everything from its first time on, so the rows of a run that was stopped and restarted
    from an earlier written time do not interleave with the restart's).

    Raises
    ------
    ParseError
        If there is no yPlus output, or a row cannot be read or holds NaN or inf (naming
        file and line).
    """
    root = Path(case_dir) / "postProcessing" / "yPlus"
    folders = time_folders(root) if root.is_dir() else []
    if not folders:
        raise ParseError("no yPlus output (write the case with y_plus=True)", path=str(root))
    parts = []
    for folder in folders:
        for path in restart_segments(folder, "yPlus"):
            rows = _patch_rows(path, patch)
            if rows:
                parts.append(np.array(rows))
    if not parts:
        raise ParseError(f"no y+ rows for patch {patch!r}", path=str(root))
    v = merge_restart_segments(parts)
    return YPlusHistory(v[:, 0], v[:, 1], v[:, 2], v[:, 3])


def _patch_rows(path: Path, patch: str) -> list[tuple[float, float, float, float]]:
    """(time, min, max, average) of ``patch`` in one yPlus.dat.

    OpenFOAM ends every row with a newline: a last line without one was cut short by a killed
    run (its last number may be cut) and is dropped.
    """
    rows = []
    text = path.read_text()
    lines = text.splitlines()
    if lines and not text.endswith(("\n", "\r")):
        lines = lines[:-1]
    for i, line in enumerate(lines, start=1):
        if not line.strip() or line.lstrip().startswith("#"):
            continue
        parts = line.split()
        if len(parts) != 5:
            raise ParseError(f"expected 5 columns (time patch min max average), got "
                             f"{len(parts)}", path=str(path), line=i)
        if parts[1] != patch:
            continue
        try:
            row = tuple(float(parts[k]) for k in (0, 2, 3, 4))
        except ValueError as exc:
            raise ParseError(f"unreadable number in {line.strip()!r}", path=str(path),
                             line=i) from exc
        if not all(math.isfinite(v) for v in row):
            raise ParseError(f"non-finite value in {line.strip()!r} (a diverged run?)",
                             path=str(path), line=i)
        rows.append(row)
    return rows


#: the log-law range of y+ that wall functions are made for (the first cell's centre in the
#: log layer); OpenFOAM's nutkWallFunction treats a cell below y+ of about 11 as laminar
WALL_FUNCTION_RANGE = (30.0, 300.0)


def y_plus_summary(history: YPlusHistory) -> dict[str, float]:
    """The plate's y+ over a run: the time mean of its area average, the smallest and the
    largest value anywhere on it, and the share of the run's output times whose area average
    lies below and above :data:`WALL_FUNCTION_RANGE`."""
    low, high = WALL_FUNCTION_RANGE
    return {"y_plus_mean": float(np.mean(history.average)),
            "y_plus_min": float(np.min(history.minimum)),
            "y_plus_max": float(np.max(history.maximum)),
            "y_plus_share_below_log_law": float(np.mean(history.average < low)),
            "y_plus_share_above_log_law": float(np.mean(history.average > high))}


def wall_function_note(summary: dict[str, float],
                       wall_treatment: str = "log_law") -> str | None:
    """What the y+ of a run means for its wall conditions, or None if they hold throughout.

    Parameters
    ----------
    summary
        :func:`y_plus_summary` of the run.
    wall_treatment
        The case's wall treatment (:func:`~mfflap.cfd.openfoam.writer.written_wall_treatment`):
        "all_y_plus" holds at any y+ below the top of :data:`WALL_FUNCTION_RANGE` (the log
        layer's end), the sublayer and buffer layer too; "log_law" (or another) wall
        functions only while the area average stays within that range.
    """
    low, high = WALL_FUNCTION_RANGE
    all_y_plus = wall_treatment == "all_y_plus"
    below = 0.0 if all_y_plus else summary["y_plus_share_below_log_law"]
    above = summary["y_plus_share_above_log_law"]
    if not below and not above:
        return None
    parts = []
    if below:
        parts.append(f"below {low:g} for {below:.0%} of the output times (the first cells in "
                     "the buffer layer or viscous sublayer, where the wall functions' log law "
                     "does not hold; nutkWallFunction takes a cell below y+ of about 11 as "
                     "laminar; cfd.wall_treatment = \"all_y_plus\" holds there)")
    if above:
        parts.append(f"above {high:g} for {above:.0%} of {'them' if below else 'the output times'}"
                     " (the first cells past the log layer)")
    where = (f"above the log layer's end ({high:g}), where its all_y_plus wall treatment "
             "does not hold" if all_y_plus else
             f"outside the wall functions' log-law range ({low:g}-{high:g})")
    return (f"the plate's average y+ lies {where}: {'; '.join(parts)}; its wall shear, and "
            "so F_t, is the least certain of the forces")
