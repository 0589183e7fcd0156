"""A CFD run's total force and moment history, whichever solver wrote it, and its turn
into body-frame loads on the whole span."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from mfflap.cfd.frames import (
    FRAMES,
    case_force_to_model,
    case_moment_to_model,
    plate_frame_force_to_model,
)
from mfflap.errors import ConfigError, ParseError, shown
from mfflap.hydro.loads import Loads
from mfflap.kinematics.state import KinematicState


def read_solver_text(path: str | Path) -> str:
    """A solver's output file as text (UTF-8, which covers ASCII), or a ParseError naming the
    file, the line and the byte that is not text (a file damaged on disk, or not a log).

    Examples
    --------
    >>> import tempfile
    >>> from pathlib import Path
    >>> log = Path(tempfile.mkdtemp()) / "force.dat"
    >>> _ = log.write_bytes(b"# Force\\n0.1 (1 2 3)\\n0.2 (1 \\xff 3)\\n")
    >>> read_solver_text(log)  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    mfflap.errors.ParseError: ...force.dat, line 3: byte 0xff at column 8 is not text ...
    """
    path = Path(path)
    data = path.read_bytes()
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as exc:
        line = data.count(b"\n", 0, exc.start) + 1
        column = exc.start - (data.rfind(b"\n", 0, exc.start) + 1) + 1
        raise ParseError(f"byte 0x{data[exc.start]:02x} at column {column} is not text "
                         "(UTF-8): a file damaged on disk, or not a solver's output?",
                         path=str(path), line=line) from None


@dataclass(frozen=True)
class ForceHistory:
    """Total force (and optionally moment) in the case frame, N and N*m, per unit of mesh depth
    as OpenFOAM wrote it (i.e. for the mesh's depth).

    Attributes
    ----------
    time : (n,) s
    force : (n, 3) N, total force
    moment : (n, 3) N*m about ``centre_of_rotation``, or None
    dialect : the row layout it was read from
    centre_of_rotation : (3,) m, the point the moments are taken about as the file's header
        gives it, or None where no header gives one (the origin)
    """

    time: np.ndarray
    force: np.ndarray
    moment: np.ndarray | None
    dialect: str
    centre_of_rotation: np.ndarray | None = None


def to_loads(history: ForceHistory, state: KinematicState, span: float, depth: float,
             source: str, frame: str = "inertial",
             pivot_m: tuple[float, float] = (0.0, 0.0)) -> Loads:
    """Body-frame loads on the whole span from a force history on the state's time base.

    The forces are scaled by span/depth. ``frame`` is the case's
    (:attr:`~mfflap.cfd.openfoam.writer.SolverSettings.frame`): "inertial" (the mesh
    moves; forces along the case axes, moment about the origin, taken here about the
    *moving* pivot: M_P = M_O - r_P x F with r_P = (x_P, y_P + h, 0)) or "plate" (static
    mesh in the plate's frame; forces along the plate's axes, moment about the pivot at the
    origin). Moments taken about another point than the origin (the forces function
    object's CofR, :attr:`ForceHistory.centre_of_rotation`) are first moved to the origin:
    M_O = M_C + r_C x F. ``pivot_m`` is the pivot (the point the plate pitches about, whose
    heave is h) at rest in the case's axes, m; mfflap's own cases have it at the origin.
    """
    if history.moment is None:
        raise ParseError("the force history has no moments; need moment.dat or forces.dat")
    if len(history.time) != len(state.time) or not np.allclose(history.time, state.time):
        raise ParseError("the state is not sampled on the force history's time base")
    scale = span / depth
    fx, fy = history.force[:, 0] * scale, history.force[:, 1] * scale
    mz = history.moment[:, 2] * scale
    if history.centre_of_rotation is not None:
        xc, yc = float(history.centre_of_rotation[0]), float(history.centre_of_rotation[1])
        mz = mz + xc * fy - yc * fx  # about the origin: M_O = M_C + r_C x F
    if frame not in FRAMES:
        raise ConfigError(f"unknown frame {shown(frame)}; allowed: {', '.join(FRAMES)}",
                          key="frame")
    if frame == "plate":
        if tuple(pivot_m) != (0.0, 0.0):
            raise ConfigError("a case in the plate's frame has its pivot at the origin",
                              key="pivot")
        normal, tangential = plate_frame_force_to_model(fx, fy)
        return Loads(state.time, normal, tangential, case_moment_to_model(mz), source=source)
    x_p, y_p = pivot_m[0], pivot_m[1] + state.heave_position
    mz_p = mz - (x_p * fy - y_p * fx)  # M_P = M_O - r_P x F
    f_x0, f_y0 = case_force_to_model(fx, fy)
    th = state.pitch_angle
    s, c = np.sin(th), np.cos(th)
    # e_n = (cos, -sin), e_t = (sin, cos) in (X0, Y0)
    normal = f_x0 * c - f_y0 * s
    tangential = f_x0 * s + f_y0 * c
    return Loads(state.time, normal, tangential, case_moment_to_model(mz_p), source=source)
