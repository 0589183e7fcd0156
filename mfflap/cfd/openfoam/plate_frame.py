"""The tables of a case in the plate's frame (``SolverSettings.frame = "plate"``).

The mesh stays still; the frame turns with the pitch about the pivot (an MRF zone
whose rate is ``constant/pitchRate.dat``), and translates with the heave: the far field's
inflow is the stream minus the heave velocity (``constant/farFieldVelocity.dat``, a
uniformInletOutlet table) and the fluid feels minus the heave acceleration as a uniform body
force (``constant/acceleration.dat``, tabulatedAccelerationSource). All along the plate's
axes (:mod:`mfflap.cfd.frames`).
"""

from __future__ import annotations

import numpy as np

from mfflap.cfd.frames import plate_frame_acceleration, plate_frame_inflow
from mfflap.cfd.imposed_motion import imposed_state
from mfflap.kinematics.continuous import Motion


def plate_frame_tables(motion: Motion, times: np.ndarray, stream_velocity: float,
                       ramp_time: float = 0.0) -> dict[str, np.ndarray]:
    """The plate's frame's tables at ``times`` (s) for the kinematics the case imposes
    (:func:`~mfflap.cfd.imposed_motion.imposed_state`).

    Returns
    -------
    dict
        ``"pitch_rate"``: rows (t, theta') of the MRF rate, rad/s; ``"inflow"``: rows
        (t, wx, wy, wz) of the far field's inflow velocity, m/s; ``"acceleration"``: rows
        (t, ax, ay, az) of the frame's acceleration, m/s^2; all along the plate's axes.
    """
    t = np.asarray(times, dtype=float)
    s = imposed_state(motion, t, ramp_time).check_finite("plate frame tables")
    col = t[:, None]
    return {
        "pitch_rate": np.column_stack([t, s.pitch_rate]),
        "inflow": np.hstack([col, plate_frame_inflow(s.pitch_angle, s.heave_velocity,
                                                     stream_velocity)]),
        "acceleration": np.hstack([col, plate_frame_acceleration(s.pitch_angle,
                                                                 s.heave_acceleration)]),
    }


def format_function1_table(rows: np.ndarray) -> str:
    """OpenFOAM text of a Function1 table file: ``( (t v) ... )`` or ``( (t (x y z)) ... )``."""
    lines = ["("]
    for r in rows:
        value = f"{r[1]:.9g}" if len(r) == 2 else "(" + " ".join(f"{v:.9g}" for v in r[1:]) + ")"
        lines.append(f"({r[0]:.9g} {value})")
    lines.append(")")
    return "\n".join(lines) + "\n"


def format_acceleration_table(rows: np.ndarray) -> str:
    """tabulatedAccelerationSource's table: ``N ( (t ((ax ay az) (0 0 0) (0 0 0))) ... )``.

    The angular velocity and acceleration columns stay zero: the MRF zone turns the frame.
    """
    lines = [f"{len(rows)}", "("]
    for r in rows:
        lines.append(f"({r[0]:.9g} (({r[1]:.9g} {r[2]:.9g} {r[3]:.9g}) (0 0 0) (0 0 0)))")
    lines.append(")")
    return "\n".join(lines) + "\n"
