"""Parse OpenFOAM ``forces`` function-object logs and turn them into body-frame Loads.

The layout of a file is read from its rows, whatever the file is called:

- ``v1912``: openfoam.com's ``force.dat``/``moment.dat``, rows
  ``t (tx ty tz) (px py pz) (vx vy vz)``: total, pressure, viscous;
- ``com-bare``: later openfoam.com releases, the same nine numbers without parentheses;
- ``foundation``: the Foundation line's ``forces.dat``, rows ``t ((px py pz) (vx vy vz))
  ((mpx ...) (mvx ...))``: force and moment, each as pressure and viscous (no total);
- ``foundation-porous``: the same with a third, porous, triple in each
  (``forces(pressure viscous porous)``).

The Foundation layouts are also read without their parentheses (12 or 18 numbers after
the time). Whether a file of the openfoam.com layouts holds forces or moments is read from
its header (``# Force`` or ``# Moment``), else from its name. The centre of rotation of
the moments is read from the header's ``# CofR : (x y z)`` line.

Several time folders (restarts) are merged, later folders winning on overlap. A last line
cut short by a killed run is dropped; any other malformed line is an error naming the file
and the line. OpenFOAM ends every row with a newline, so a last line without one is a row
cut short unless it shows it is whole: its parentheses close. A bare row cut inside its
last number still holds all its numbers, one of them wrong, so a bare last line without a
newline is always dropped.
"""

from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np

from mfflap.cfd.force_history import ForceHistory, read_solver_text
from mfflap.errors import ParseError, RepeatedTimes, shown

_NUMBER = re.compile(r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?|[-+]?(?:nan|inf)", re.I)


def _numbers(line: str, path: str, lineno: int) -> list[float]:
    cleaned = line.replace("(", " ").replace(")", " ")
    toks = cleaned.split()
    out = []
    for tok in toks:
        if not _NUMBER.fullmatch(tok):
            raise ParseError(f"not a number: {shown(tok)}", path=path, line=lineno)
        v = float(tok)
        if not math.isfinite(v):
            raise ParseError(f"non-finite value {shown(tok)} (a diverged run?)", path=path,
                             line=lineno)
        out.append(v)
    return out


#: numbers after the time in a row of each layout
LAYOUT_NUMBERS = {"v1912": 9, "com-bare": 9, "foundation": 12, "foundation-porous": 18}
#: layouts whose rows hold forces and moments together
BOTH_LAYOUTS = ("foundation", "foundation-porous")


def _first_row(text: str) -> tuple[int, str] | None:
    for i, line in enumerate(text.splitlines(), start=1):
        s = line.strip()
        if s and not s.startswith("#"):
            return i, s
    return None


def detect_dialect(text: str, path: str = "<text>") -> str:
    """``"v1912"``, ``"com-bare"``, ``"foundation"`` or ``"foundation-porous"`` from the
    shape of a file's first row (nesting of parentheses, count of numbers).

    Raises
    ------
    ParseError
        Naming the file (and the line): no data rows, or a row of none of these shapes.

    Examples
    --------
    >>> detect_dialect("0.1 (1 2 3) (1 2 3) (0 0 0)\\n")
    'v1912'
    >>> detect_dialect("0.1 ((1 2 3) (0 0 0)) ((4 5 6) (0 0 0))\\n")
    'foundation'
    """
    first = _first_row(text)
    if first is None:
        raise ParseError("no data rows (an empty file)", path=path)
    lineno, row = first
    count = len(row.replace("(", " ").replace(")", " ").split()) - 1
    if "((" in row.replace(" ", ""):
        found = {12: "foundation", 18: "foundation-porous"}.get(count)
    elif "(" in row:
        found = "v1912" if count == 9 else None
    else:
        found = {9: "com-bare", 12: "foundation", 18: "foundation-porous"}.get(count)
    if found is None:
        raise ParseError(
            f"a row of {count} numbers after the time is no forces layout: openfoam.com's "
            "force.dat/moment.dat hold 9 (total, pressure, viscous), the Foundation's "
            "forces.dat 12 (force and moment, pressure and viscous) or 18 (with porous)",
            path=path, line=lineno)
    return found


def header_quantity(text: str) -> str | None:
    """``"force"`` or ``"moment"`` as the header's first line says (``# Force``,
    ``# Moment``), else None."""
    for line in text.splitlines():
        s = line.strip()
        if not s:
            continue
        if not s.startswith("#"):
            return None
        word = s.lstrip("#").strip().lower()
        return "force" if word.startswith("force") else (
            "moment" if word.startswith("moment") else None)
    return None


def header_centre_of_rotation(text: str, path: str = "<text>") -> np.ndarray | None:
    """The ``# CofR : (x y z)`` of a file's header, m, or None without one."""
    for i, line in enumerate(text.splitlines(), start=1):
        s = line.strip()
        if s and not s.startswith("#"):
            return None
        body = s.lstrip("#").strip()
        if body.lower().startswith("cofr"):
            values = body.split(":", 1)[-1].replace("(", " ").replace(")", " ").split()
            try:
                point = np.array([float(v) for v in values])
            except ValueError:
                point = np.array([])
            if point.shape != (3,) or not np.all(np.isfinite(point)):
                raise ParseError(f"the CofR line does not give three numbers: {body[:80]!r}",
                                 path=path, line=i)
            return point
    return None


def header_layout(text: str) -> str | None:
    """What a file's column line (``# Time ...``) says its rows hold: ``"both"`` (forces
    and moments in each row: the Foundation's ``forces(...) moment(...)``), ``"one"`` (one
    quantity's total, pressure and viscous: openfoam.com's ``(total_x ...)``), or None
    without such a line."""
    for line in text.splitlines():
        s = line.strip()
        if s and not s.startswith("#"):
            return None
        body = s.lstrip("#").strip().lower()
        if body.startswith("time") and len(body) > 4:
            if "moment" in body and "force" in body:
                return "both"
            if "total" in body or "pressure_x" in body:
                return "one"
    return None


def _check_layout_agrees(text: str, dialect: str, path: str) -> None:
    """Refuse rows of one layout under a column line of the other: which columns hold
    what would be guessed, and the loads read wrong without bound."""
    said = header_layout(text)
    rows = "both" if dialect in BOTH_LAYOUTS else "one"
    if said is not None and said != rows:
        what = {"both": "forces and moments in each row (the Foundation's forces.dat)",
                "one": "one quantity's total, pressure and viscous parts (openfoam.com's "
                       "force.dat or moment.dat)"}
        raise ParseError(f"its header says the rows hold {what[said]}, but its rows are "
                         f"{dialect} rows of {LAYOUT_NUMBERS[dialect]} numbers, which hold "
                         f"{what[rows]}: the header and the rows disagree", path=path)


def _whole_row(row: str, dialect: str) -> bool:
    """Whether a row without a final newline shows that it was written whole."""
    return "(" in row and row.endswith(")") and row.count("(") == row.count(")")


def parse_table(text: str, path: str = "<text>", columns: int = 9,
                check_increasing: bool = True) -> tuple[np.ndarray, str]:
    """Rows of a force or moment file as an array (n, 1 + numbers) and the dialect.

    ``columns`` is the count of numbers after the time that a one-quantity layout holds.
    ``check_increasing`` False leaves the time check to the caller (a segment that a restart
    supersedes may end in a collapsed run whose times repeat at the written precision).
    """
    lines = text.splitlines()
    complete_last = text.endswith(("\n", "\r"))
    try:
        dialect = detect_dialect(text, path)
    except ParseError as exc:
        first = _first_row(text)
        if first is not None and first[0] == len(lines) and not complete_last:
            # the only row is the last, cut short by a killed run
            raise ParseError("no complete data rows", path=path) from exc
        raise
    _check_layout_agrees(text, dialect, path)
    ncol = 1 + (LAYOUT_NUMBERS[dialect] if dialect in BOTH_LAYOUTS else columns)
    nested = "(" in _first_row(text)[1]  # type: ignore[index]
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
        if ("(" in s) != nested:
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
        raise RepeatedTimes(f"time does not increase after t = {float(arr[i, 0])!r}",
                            path=path, time_s=float(arr[i, 0]))


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
    centre: np.ndarray | None = None
    centre_from = ""
    for folder in folders:
        stems = _stems(folder)
        if not stems:
            raise ParseError("no force or moment files (*.dat)", path=str(folder))
        forces_here, moments_here = [], []
        for stem in stems:
            for path in restart_segments(folder, stem):
                text = read_solver_text(path)
                arr, dialect = parse_table(text, str(path), check_increasing=False)
                point = header_centre_of_rotation(text, str(path))
                if point is not None:
                    if centre is not None and not np.allclose(point, centre):
                        raise ParseError(f"CofR {tuple(point)} differs from {tuple(centre)} "
                                         f"in {centre_from}: moments about two points",
                                         path=str(path))
                    centre, centre_from = point, str(path)
                if dialect in BOTH_LAYOUTS:
                    k = 3 if dialect == "foundation-porous" else 2
                    triples = arr[:, 1:].reshape(len(arr), 2, k, 3).sum(axis=2)
                    forces_here.append(np.column_stack([arr[:, 0], triples[:, 0]]))
                    moments_here.append(np.column_stack([arr[:, 0], triples[:, 1]]))
                    continue
                quantity = header_quantity(text) or _quantity_by_name(stem)
                if quantity is None:
                    raise ParseError(
                        "neither its header (# Force, # Moment) nor its name says whether it "
                        "holds forces or moments", path=str(path))
                (forces_here if quantity == "force" else moments_here).append(arr[:, :4])
        if not forces_here:
            raise ParseError("moments but no forces", path=str(folder))
        f_parts += forces_here
        m_parts += moments_here
    force = merge_restart_segments(f_parts)
    _check_increasing(force, str(base))
    moment = merge_restart_segments(m_parts) if len(m_parts) == len(f_parts) else None
    if moment is not None:
        n = min(len(force), len(moment))
        force, moment = force[:n], moment[:n]
        if not np.allclose(force[:, 0], moment[:, 0], rtol=0, atol=1e-9):
            raise ParseError("force and moment files have different time bases", path=str(base))
    return ForceHistory(force[:, 0], force[:, 1:4], None if moment is None else moment[:, 1:4],
                        dialect, centre)


def _stems(folder: Path) -> list[str]:
    """The files of a time folder by stem, a restart's ``<stem>_<time>.dat`` under its
    ``<stem>``: ``force``, ``moment``, ``forces``, or whatever a user's case calls them."""
    stems = set()
    for p in folder.glob("*.dat"):
        stem, _, suffix = p.stem.rpartition("_")
        try:
            float(suffix)
            restart = bool(stem)
        except ValueError:
            restart = False
        stems.add(stem if restart else p.stem)
    return sorted(stems, key=lambda name: (not name.startswith("force"), name))


def _quantity_by_name(stem: str) -> str | None:
    name = stem.lower()
    return "moment" if "moment" in name else ("force" if "force" in name else None)
