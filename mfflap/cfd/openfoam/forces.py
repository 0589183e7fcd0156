"""Parse OpenFOAM ``forces`` function-object logs and turn them into body-frame Loads.

Three dialects are recognised from the header and the rows:

- ``v1912``: ``force.dat``/``moment.dat``, rows ``t (tx ty tz) (px py pz) (vx vy vz)``;
- ``com-bare``: later openfoam.com releases, the same nine columns without parentheses;
- ``foundation``: the Foundation line's ``forces.dat``, rows ``t ((px py pz) (vx vy vz))
  ((mpx ...) (mvx ...))`` whose first triple is pressure, not total.

Several time folders (restarts) are merged, later folders winning on overlap. A last line
cut short by a killed run is dropped; any other malformed line is an error naming the file
and the line. OpenFOAM ends every row with a newline, so a last line without one is a row
cut short unless it shows it is whole: its parentheses close (v1912, Foundation). A bare
row (com-bare) cut inside its last number still holds nine numbers, one of them wrong, so a
bare last line without a newline is always dropped.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from mfflap.errors import ParseError

_NUMBER = re.compile(r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?|[-+]?(?:nan|inf)", re.I)


@dataclass(frozen=True)
class ForceHistory:
    """Total force (and optionally moment) in the case frame, N and N*m, per unit of mesh depth
    as OpenFOAM wrote it (i.e. for the mesh's depth)."""

    time: np.ndarray
    force: np.ndarray  # (n, 3) total force
    moment: np.ndarray | None  # (n, 3) about CofR, or None
    dialect: str


def _numbers(line: str, path: str, lineno: int) -> list[float]:
    cleaned = line.replace("(", " ").replace(")", " ")
    toks = cleaned.split()
    out = []
    for tok in toks:
        if not _NUMBER.fullmatch(tok):
            raise ParseError(f"not a number: {tok!r}", path=path, line=lineno)
        v = float(tok)
        if not math.isfinite(v):
            raise ParseError(f"non-finite value {tok!r} (a diverged run?)", path=path,
                             line=lineno)
        out.append(v)
    return out


def detect_dialect(text: str, name: str = "") -> str:
    """``"v1912"``, ``"com-bare"`` or ``"foundation"`` from a file's text and name."""
    for line in text.splitlines():
        s = line.strip()
        if not s or s.startswith("#"):
            continue
        if "((" in s:
            return "foundation"
        return "v1912" if "(" in s else "com-bare"
    if name == "forces.dat":
        return "foundation"
    raise ParseError("no data rows", path=name or None)


def _whole_row(row: str, dialect: str) -> bool:
    """Whether a row without a final newline shows that it was written whole."""
    return dialect != "com-bare" and row.endswith(")") and row.count("(") == row.count(")")


def parse_table(text: str, path: str = "<text>", columns: int = 9,
                check_increasing: bool = True) -> tuple[np.ndarray, str]:
    """Rows of a force or moment file as an array (n, 1 + columns) and the dialect.

    ``check_increasing`` False leaves the time check to the caller (a segment that a restart
    supersedes may end in a collapsed run whose times repeat at the written precision).
    """
    dialect = detect_dialect(text, Path(path).name)
    ncol = 1 + (12 if dialect == "foundation" else columns)
    lines = text.splitlines()
    complete_last = text.endswith(("\n", "\r"))
    rows = []
    for i, line in enumerate(lines, start=1):
        s = line.strip()
        if not s or s.startswith("#"):
            continue
        if i == len(lines) and not complete_last and not _whole_row(s, dialect):
            break  # cut short by a killed run
        try:
            vals = _numbers(s, path, i)
        except ParseError:
            if i == len(lines) and not complete_last:
                break  # truncated last line of a killed run
            raise
        if dialect != "foundation" and ("(" in s) != (dialect == "v1912"):
            raise ParseError("row format differs from the file's first row", path=path, line=i)
        if len(vals) != ncol:
            if i == len(lines) and not complete_last:
                break
            raise ParseError(f"expected {ncol} numbers, found {len(vals)}", path=path, line=i)
        rows.append(vals)
    if not rows:
        raise ParseError("no complete data rows", path=path)
    arr = np.asarray(rows)
    if check_increasing:
        _check_increasing(arr, path)
    return arr, dialect


def _check_increasing(arr: np.ndarray, path: str) -> None:
    if np.any(np.diff(arr[:, 0]) <= 0):
        i = int(np.argmax(np.diff(arr[:, 0]) <= 0))
        raise ParseError(f"time does not increase after t = {float(arr[i, 0])!r}", path=path)


def restart_segments(folder: Path, stem: str) -> list[Path]:
    """``<stem>.dat`` then the restart files ``<stem>_<time>.dat`` (``force_0.dat``,
    ``force_0.75.dat``) that v1912 writes when a run restarts into a time folder whose
    ``<stem>.dat`` already exists; later restarts come later."""
    numbered = []
    for p in folder.glob(f"{stem}_*.dat"):
        try:
            restart_time = float(p.stem[len(stem) + 1:])
        except ValueError:
            continue
        numbered.append((restart_time, p.stat().st_mtime_ns, p))
    first = [folder / f"{stem}.dat"] if (folder / f"{stem}.dat").is_file() else []
    return first + [p for *_, p in sorted(numbered)]


def merge_restart_segments(parts: list[np.ndarray]) -> np.ndarray:
    """Merge restart segments (arrays whose first column is time) in order; a later
    segment replaces everything from its first time on."""
    out = parts[0]
    for nxt in parts[1:]:
        out = np.concatenate([out[out[:, 0] < nxt[0, 0]], nxt])
    return out


def time_folders(base: Path) -> list[Path]:
    """The start-time folders of a function object's output folder, earliest first.

    Raises
    ------
    ParseError
        If a folder there is not named by a time (naming it).
    """
    folders = [p for p in base.iterdir() if p.is_dir()]
    for folder in folders:
        if not _NUMBER.fullmatch(folder.name) or not math.isfinite(float(folder.name)):
            raise ParseError("not a time folder (its name is not a start time)",
                             path=str(folder))
    return sorted(folders, key=lambda p: float(p.name))


def read_forces(case_dir: str | Path, function_name: str = "forces") -> ForceHistory:
    """Read every time folder of ``postProcessing/<function_name>`` of a case."""
    base = Path(case_dir) / "postProcessing" / function_name
    if not base.is_dir():
        ran = (Path(case_dir) / "postProcessing").is_dir() or any(
            Path(case_dir).glob("log.*"))
        raise ParseError("no forces output folder" + (
            "" if ran else f": the case has not run yet (mfflap cfd run {case_dir})"),
            path=str(base))
    folders = time_folders(base)
    if not folders:
        raise ParseError("no time folders", path=str(base))
    f_parts, m_parts, dialect = [], [], ""
    for folder in folders:
        forces = restart_segments(folder, "force")
        if forces:
            moments = restart_segments(folder, "moment")
            for k, path in enumerate(forces):
                arr, dialect = parse_table(path.read_text(), str(path), check_increasing=False)
                f_parts.append(arr[:, :4])
                if k < len(moments):
                    marr, _ = parse_table(moments[k].read_text(), str(moments[k]),
                                          check_increasing=False)
                    m_parts.append(marr[:, :4])
        elif restart_segments(folder, "forces"):
            for path in restart_segments(folder, "forces"):
                arr, dialect = parse_table(path.read_text(), str(path), check_increasing=False)
                # pressure + viscous = total; moments likewise
                f_parts.append(np.column_stack([arr[:, 0], arr[:, 1:4] + arr[:, 4:7]]))
                m_parts.append(np.column_stack([arr[:, 0], arr[:, 7:10] + arr[:, 10:13]]))
        else:
            raise ParseError("neither force.dat nor forces.dat", path=str(folder))
    force = merge_restart_segments(f_parts)
    _check_increasing(force, str(base))
    moment = merge_restart_segments(m_parts) if len(m_parts) == len(f_parts) else None
    if moment is not None:
        n = min(len(force), len(moment))
        force, moment = force[:n], moment[:n]
        if not np.allclose(force[:, 0], moment[:, 0], rtol=0, atol=1e-9):
            raise ParseError("force and moment files have different time bases", path=str(base))
    return ForceHistory(force[:, 0], force[:, 1:4], None if moment is None else moment[:, 1:4],
                        dialect)
