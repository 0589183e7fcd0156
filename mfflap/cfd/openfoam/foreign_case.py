"""An OpenFOAM case that mfflap did not write: the motion it imposes, the depth of its mesh,
the forces function object that logged its loads and the point its moments are about.

mfflap's model is a rigid plate that heaves across the stream and pitches about a pivot that
heaves with it. A case imposes such a motion when its whole mesh moves as a solid body
(``motionSolver solidBody`` in ``constant/dynamicMeshDict``) with one of

- ``tabulated6DoFMotion``: a table of ``(t ((dx dy dz) (rx ry rz)))`` rows, rotations in
  degrees about ``CofG`` (a point moves as x' = CofG + d + R(x - CofG));
- ``oscillatingRotatingMotion`` (``origin``, ``amplitude`` in degrees, ``omega`` in rad/s)
  and ``oscillatingLinearMotion`` (``amplitude`` in m, ``omega``), alone or together under
  ``multiMotion``. OpenFOAM applies the functions of a ``multiMotion`` from the last listed
  to the first (checked against the mesh points pimpleFoam writes): to pitch about a pivot
  that heaves, list the heave first and the pitch after it.

Each function's settings may sit in its own dictionary or in a ``<type>Coeffs`` dictionary
inside it, as OpenFOAM reads them. The pivot is the rotation's centre at rest; the case's
y displacement of it is the heave and its rotation about z the pitch. A motion that moves
the pivot along the stream or out of the plane, or turns the plate about another axis, is
not one the model has and is refused, naming the file.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from mfflap.cfd.force_history import ForceHistory
from mfflap.cfd.openfoam.foam_files import decode_error, foam_file
from mfflap.cfd.openfoam.forces import read_forces
from mfflap.errors import ConfigError, ParseError
from mfflap.kinematics.continuous import Motion, TabulatedMotion
from mfflap.kinematics.table_file import read_motion_table

#: samples per period of the analytic motion functions when they are tabulated
SAMPLES_PER_PERIOD = 400
#: a displacement or rotation below this share of the motion's own counts as none
STILL_SHARE = 1e-9

_MESH_DICT = Path("constant") / "dynamicMeshDict"


@dataclass(frozen=True)
class CaseMotion:
    """The heave and pitch an OpenFOAM case imposes on its plate.

    Attributes
    ----------
    motion : TabulatedMotion
        Heave (the pivot's y displacement, m) and pitch (rotation about +z, rad) against
        time.
    pivot_m : tuple of float
        The pivot at rest in the case's axes (x along the stream, y across it), m.
    source : str
        What the motion was read from, in words.
    """

    motion: TabulatedMotion
    pivot_m: tuple[float, float]
    source: str


def _read_foam(path: Path, headerless: bool = False) -> Any:
    """A dictionary file read whole by foamlib, or (``headerless``) the list a file without
    entries holds, such as a mesh's points.

    Raises
    ------
    ParseError
        Naming the file, for one foamlib cannot parse.
    """
    try:
        data = foam_file(path)
        return data[None] if headerless else data.as_dict()
    except decode_error() as exc:
        first = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise ParseError(f"not an OpenFOAM dictionary foamlib can read ({first[:200]})",
                         path=str(path)) from None


def _as_dict(entry: Any, path: Path, key: str) -> Mapping[str, Any]:
    if not isinstance(entry, Mapping):
        raise ConfigError(f"{key} is not a dictionary", key=key, source=str(path))
    return entry


def _coefficients(entry: Mapping[str, Any], kind: str) -> Mapping[str, Any]:
    """A motion function's settings: its ``<kind>Coeffs`` dictionary, else the entry."""
    inner = entry.get(f"{kind}Coeffs")
    return inner if isinstance(inner, Mapping) else entry


def _vector(coeffs: Mapping[str, Any], key: str, path: Path, default=None) -> np.ndarray:
    value = coeffs.get(key, default)
    try:
        out = np.asarray(value, dtype=float).reshape(3)
    except (TypeError, ValueError):
        raise ConfigError(f"{key} must be a vector (x y z), got {value!r}", key=key,
                          source=str(path)) from None
    if not np.all(np.isfinite(out)):
        raise ConfigError(f"{key} must be finite, got {value!r}", key=key,
                          source=str(path))
    return out


def _scalar(coeffs: Mapping[str, Any], key: str, path: Path) -> float:
    value = coeffs.get(key)
    if not isinstance(value, int | float) or not math.isfinite(value):
        raise ConfigError(f"{key} must be a number, got {value!r}", key=key,
                          source=str(path))
    return float(value)


def _rotation_z(angle_rad: np.ndarray) -> np.ndarray:
    """Rotation matrices about +z, shape (n, 3, 3)."""
    c, s = np.cos(angle_rad), np.sin(angle_rad)
    out = np.zeros((len(angle_rad), 3, 3))
    out[:, 0, 0], out[:, 0, 1], out[:, 1, 0], out[:, 1, 1], out[:, 2, 2] = c, -s, s, c, 1.0
    return out


@dataclass(frozen=True)
class _Part:
    """One analytic motion function: how it moves a point, its rotation's centre (None for
    a translation) and its angular frequency."""

    move: Callable[[np.ndarray, np.ndarray], np.ndarray]  # (times (n,), points (n, 3)) -> (n, 3)
    origin: np.ndarray | None
    omega: float
    rotation_deg: Callable[[np.ndarray], np.ndarray]  # times -> (n, 3) degrees


def _part(entry: Mapping[str, Any], path: Path, name: str) -> _Part:
    kind = entry.get("solidBodyMotionFunction")
    coeffs = _coefficients(entry, str(kind))
    if kind == "oscillatingLinearMotion":
        amplitude = _vector(coeffs, "amplitude", path)
        omega = _scalar(coeffs, "omega", path)
        return _Part(lambda t, x: x + np.sin(omega * t)[:, None] * amplitude, None, omega,
                     lambda t: np.zeros((len(t), 3)))
    if kind == "oscillatingRotatingMotion":
        origin = _vector(coeffs, "origin", path)
        amplitude = _vector(coeffs, "amplitude", path)
        omega = _scalar(coeffs, "omega", path)
        if np.any(np.abs(amplitude[:2]) > STILL_SHARE * max(abs(amplitude[2]), 1.0)):
            raise ConfigError(f"{name} turns the plate about x or y (amplitude "
                              f"{tuple(amplitude)} deg): mfflap's plate pitches about z only",
                              key="amplitude", source=str(path))

        def move(t: np.ndarray, x: np.ndarray) -> np.ndarray:
            rot = _rotation_z(np.radians(amplitude[2] * np.sin(omega * t)))
            return origin + np.einsum("nij,nj->ni", rot, x - origin)

        return _Part(move, origin, omega,
                     lambda t: np.sin(omega * t)[:, None] * amplitude)
    raise ConfigError(f"solidBodyMotionFunction {kind!r} ({name}) is not one mfflap "
                      "reads; use tabulated6DoFMotion, oscillatingLinearMotion or "
                      "oscillatingRotatingMotion (alone or under multiMotion), or give the "
                      "motion as a CSV table", key="solidBodyMotionFunction", source=str(path))


def read_six_dof_table(path: str | Path) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The rows of a tabulated6DoFMotion table: times (n,) s, displacements (n, 3) m and
    rotations (n, 3) degrees.

    Raises
    ------
    ParseError
        Naming the file (and the line, for a value that is not a number) for a table that is
        not ``N ( (t ((dx dy dz) (rx ry rz))) ... )``.
    """
    path = Path(path)
    try:
        text = path.read_text()
    except OSError as exc:
        raise ParseError(f"cannot read the motion table ({exc.strerror})", path=str(path)) \
            from None
    numbers: list[float] = []
    for lineno, line in enumerate(text.splitlines(), start=1):
        for token in line.split("//", 1)[0].replace("(", " ").replace(")", " ").split():
            try:
                value = float(token)
            except ValueError:
                raise ParseError(f"not a number: {token[:40]!r}", path=str(path),
                                 line=lineno) from None
            if not math.isfinite(value):
                raise ParseError(f"non-finite value {token!r}", path=str(path), line=lineno)
            numbers.append(value)
    if not numbers:
        raise ParseError("an empty motion table", path=str(path))
    count = numbers[0]
    rows = np.asarray(numbers[1:])
    if count != int(count) or rows.size != 7 * int(count):
        raise ParseError(f"the table says {count:g} rows but holds {rows.size / 7:g} of "
                         "(t ((dx dy dz) (rx ry rz)))", path=str(path))
    rows = rows.reshape(int(count), 7)
    if rows.shape[0] < 4 or np.any(np.diff(rows[:, 0]) <= 0):
        raise ParseError("a motion table needs at least 4 rows at increasing times",
                         path=str(path))
    return rows[:, 0], rows[:, 1:4], rows[:, 4:7]


def _check_in_plane(path: Path, displacement: np.ndarray, rotation_deg: np.ndarray) -> None:
    """Refuse a motion that surges, moves out of the plane or turns about x or y."""
    heave = max(float(np.abs(displacement[:, 1]).max()), 1e-3)
    pitch = max(float(np.abs(rotation_deg[:, 2]).max()), 1.0)
    surge = float(np.abs(displacement[:, [0, 2]]).max())
    if surge > STILL_SHARE * heave + 1e-12:
        raise ConfigError(
            f"the pivot moves along the stream or out of the plane by up to "
            f"{surge:.3g} m: mfflap's plate only heaves (under multiMotion, list the heave "
            "before the pitch: OpenFOAM applies the last one first)", source=str(path))
    turn = float(np.abs(rotation_deg[:, :2]).max())
    if turn > STILL_SHARE * pitch:
        raise ConfigError(f"the plate turns about x or y by up to {turn:.3g} deg: "
                          "mfflap's plate pitches about z only", source=str(path))


def read_case_motion(case_dir: str | Path, end_time_s: float) -> CaseMotion:
    """The motion a case imposes, read from its ``constant/dynamicMeshDict`` (module notes),
    over [0, ``end_time_s``] s.

    Raises
    ------
    ConfigError
        Naming the file, for a case whose mesh does not move as a solid body, a motion
        function mfflap does not read, or a motion that is not a heave and a pitch.
    ParseError
        For a tabulated motion whose table cannot be read, or ends before ``end_time_s``.

    Examples
    --------
    >>> from pathlib import Path
    >>> case = Path("tests/data/hand_written_openfoam_case")
    >>> m = read_case_motion(case, 0.25)                     # doctest: +SKIP
    >>> m.pivot_m                                            # doctest: +SKIP
    (0.02, 0.0)
    """
    case_dir = Path(case_dir)
    path = case_dir / _MESH_DICT
    if not path.is_file():
        raise ConfigError(f"{case_dir}: no {_MESH_DICT}, so nothing says how its mesh moves; "
                          "give the motion as a CSV table", source=str(case_dir))
    mesh_dict = _read_foam(path)
    solver = mesh_dict.get("motionSolver", mesh_dict.get("solver"))
    if solver != "solidBody":
        raise ConfigError(f"motionSolver {solver!r}: mfflap reads the motion of a mesh "
                          "that moves as a solid body (motionSolver solidBody); give the "
                          "motion as a CSV table", key="motionSolver", source=str(path))
    solid = _coefficients(mesh_dict, "solidBody")
    kind = solid.get("solidBodyMotionFunction")
    if kind == "tabulated6DoFMotion":
        coeffs = _coefficients(solid, kind)
        pivot = _vector(coeffs, "CofG", path, default=(0.0, 0.0, 0.0))
        name = str(coeffs.get("timeDataFileName", "")).strip('"')
        table = Path(name.replace("<constant>", str(case_dir / "constant"))
                     .replace("$FOAM_CASE", str(case_dir)))
        if not table.is_absolute():
            table = case_dir / table
        t, displacement, rotation_deg = read_six_dof_table(table)
        if t[-1] < end_time_s - 1e-9:
            raise ParseError(f"the motion table ends at t = {t[-1]:g} s, before the forces "
                             f"do (t = {end_time_s:g} s)", path=str(table))
        _check_in_plane(table, displacement, rotation_deg)
        keep = t <= end_time_s + (t[-1] - t[0]) / max(len(t) - 1, 1) * 4
        source = f"{path}: tabulated6DoFMotion ({table})"
        return CaseMotion(TabulatedMotion(t[keep], np.radians(rotation_deg[keep, 2]),
                                          displacement[keep, 1]),
                          (float(pivot[0]), float(pivot[1])), source)
    if kind == "multiMotion":
        coeffs = _coefficients(solid, kind)
        names = [k for k, v in coeffs.items() if isinstance(v, Mapping)]
        parts = [_part(_as_dict(coeffs[k], path, k), path, k) for k in names]
    else:
        names, parts = [str(kind)], [_part(solid, path, str(kind))]
    if not parts:
        raise ConfigError("multiMotion lists no motion functions",
                          key="multiMotion", source=str(path))
    rotating = [p for p in parts if p.origin is not None]
    if len(rotating) > 1:
        raise ConfigError(f"{len(rotating)} rotating motions: mfflap reads one pitch",
                          source=str(path))
    pivot = rotating[0].origin if rotating else np.zeros(3)
    period = 2.0 * math.pi / max(abs(p.omega) for p in parts)
    n = max(math.ceil(end_time_s / period * SAMPLES_PER_PERIOD), 8) + 1
    t = np.linspace(0.0, end_time_s, n)
    place = np.broadcast_to(pivot, (n, 3)).copy()
    angle = np.zeros(n)
    for p in reversed(parts):  # OpenFOAM applies the last function listed first
        place = p.move(t, place)
        angle += np.radians(p.rotation_deg(t)[:, 2])
    displacement = place - pivot
    rotation = np.zeros((n, 3))
    rotation[:, 2] = np.degrees(angle)
    _check_in_plane(path, displacement, rotation)
    source = f"{path}: " + (f"multiMotion ({', '.join(names)})" if kind == "multiMotion"
                            else str(kind))
    return CaseMotion(TabulatedMotion(t, angle, displacement[:, 1]),
                      (float(pivot[0]), float(pivot[1])), source)


def mesh_depth(case_dir: str | Path) -> float:
    """The depth of a case's 2-D mesh (the z extent of ``constant/polyMesh/points``), m: its
    forces are per that depth.

    Raises
    ------
    ParseError
        For a mesh that is missing (run blockMesh first) or has no depth.
    """
    path = Path(case_dir) / "constant" / "polyMesh" / "points"
    if not path.is_file():
        raise ParseError("no mesh points: mesh the case (blockMesh) or give --depth",
                         path=str(path))
    points = np.asarray(_read_foam(path, headerless=True), dtype=float)
    depth = float(points[:, 2].max() - points[:, 2].min()) if points.ndim == 2 else 0.0
    if not depth > 0.0:
        raise ParseError("the mesh has no depth along z", path=str(path))
    return depth


def forces_function(case_dir: str | Path) -> str:
    """The name of the case's forces function object: the postProcessing folder that holds
    force files (``forces`` first, when there are several).

    Raises
    ------
    ParseError
        For a case with no such folder.
    """
    base = Path(case_dir) / "postProcessing"
    found = sorted(p.name for p in base.glob("*") if p.is_dir()
                   and any(any(q.glob("*orce*.dat")) for q in p.iterdir() if q.is_dir()))
    if not found:
        raise ParseError("no forces output (postProcessing/<name>/<time>/force*.dat): has the "
                         "case run with a forces function object?", path=str(base))
    return "forces" if "forces" in found else found[0]


def forces_centre(case_dir: str | Path, function_name: str) -> np.ndarray | None:
    """The point the case's forces function object takes moments about (its ``CofR``, else
    its ``origin``), m, from ``system/controlDict``; None where it does not say."""
    path = Path(case_dir) / "system" / "controlDict"
    if not path.is_file():
        return None
    functions = _read_foam(path).get("functions")
    entry = functions.get(function_name) if isinstance(functions, Mapping) else None
    if not isinstance(entry, Mapping):
        return None
    for key in ("CofR", "origin"):
        if key in entry:
            return _vector(entry, key, path)
    return None


@dataclass(frozen=True)
class ForeignCase:
    """What :func:`read_foreign_case` reads of a case mfflap did not write.

    Attributes
    ----------
    history : ForceHistory
        Its forces function object's loads, the moments about the point it names.
    motion : Motion
        The heave and pitch it imposes.
    motion_from : str
        Where the motion was read from.
    depth_m : float
        The depth its forces are for, m.
    pivot_m : tuple of float
        The pivot at rest in the case's axes, m.
    forces_function : str
        The name of its forces function object.
    """

    history: ForceHistory
    motion: Motion
    motion_from: str
    depth_m: float
    pivot_m: tuple[float, float]
    forces_function: str


def read_foreign_case(case_dir: str | Path, motion_table: str | Path | None = None,
                      depth_m: float | None = None) -> ForeignCase:
    """Read an OpenFOAM case that mfflap did not write, for comparison with the model.

    The loads are those of its forces function object (:func:`forces_function`), in any
    dialect (:mod:`mfflap.cfd.openfoam.forces`), their moments about the ``CofR`` of the
    file's header, else of the function object's entry in controlDict
    (:func:`forces_centre`), else the origin. The motion is ``motion_table`` (a CSV table,
    :mod:`mfflap.kinematics.table_file`; the pivot at rest at the origin), else the one its
    dynamicMeshDict imposes (:func:`read_case_motion`, whose rotation's centre is the
    pivot). The depth is ``depth_m``, else the z extent of its mesh (:func:`mesh_depth`).

    Raises
    ------
    ParseError, ConfigError
        Naming the file (and line) that cannot be read as what it should hold.
    """
    case_dir = Path(case_dir)
    name = forces_function(case_dir)
    history = read_forces(case_dir, name)
    if history.centre_of_rotation is None:
        history = dataclasses.replace(history,
                                      centre_of_rotation=forces_centre(case_dir, name))
    if motion_table is not None:
        motion: Motion = read_motion_table(motion_table)
        motion_from, pivot = str(motion_table), (0.0, 0.0)
    else:
        read = read_case_motion(case_dir, float(history.time[-1]))
        motion, motion_from, pivot = read.motion, read.source, read.pivot_m
    depth = mesh_depth(case_dir) if depth_m is None else float(depth_m)
    return ForeignCase(history, motion, motion_from, depth, pivot, name)


__all__ = [
    "CaseMotion",
    "ForeignCase",
    "forces_centre",
    "forces_function",
    "mesh_depth",
    "read_case_motion",
    "read_foreign_case",
    "read_six_dof_table",
]
