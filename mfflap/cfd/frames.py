"""The one place where the model's frame meets the CFD case's frame.

Model: X0 = heave direction, Y0 = free stream (water moves at +U along Y0); chord unit vector
e_t = (sin theta, cos theta) in (X0, Y0).
CFD case: x = stream direction (inflow +x), y = heave direction, z out of the 2D plane; the
plate lies along +x at theta = 0, its pivot at the origin.
So (x, y) = (Y0, X0), e_t = (cos theta, sin theta) in (x, y): theta is the case's rotation
about +z (anticlockwise positive), and the heave is the case's y displacement.
"""

from __future__ import annotations

import numpy as np

#: The two formulations of the plate's motion in a CFD case: "inertial" (the whole mesh moves
#: with the plate) and "plate" (a static mesh in the plate's frame, below)
FRAMES = ("inertial", "plate")


def case_displacement(heave_position: np.ndarray) -> np.ndarray:
    """Translation (dx, dy, dz) in the case frame for a heave h, shape (..., 3), m."""
    h = np.asarray(heave_position, dtype=float)
    z = np.zeros_like(h)
    return np.stack([z, h, z], axis=-1)


def case_rotation_deg(pitch_angle: np.ndarray) -> np.ndarray:
    """Rotation (rx, ry, rz) in degrees for a pitch angle theta (rad), shape (..., 3)."""
    th = np.degrees(np.asarray(pitch_angle, dtype=float))
    z = np.zeros_like(th)
    return np.stack([z, z, th], axis=-1)


def case_force_to_model(force_x: np.ndarray, force_y: np.ndarray
                        ) -> tuple[np.ndarray, np.ndarray]:
    """(F_X0, F_Y0) in the model frame from the case's (F_x, F_y)."""
    return np.asarray(force_y), np.asarray(force_x)


def case_moment_to_model(moment_z: np.ndarray) -> np.ndarray:
    """Moment about the pivot in the model's sign (M = sum F_nk l_k).

    The model's M is the moment of normal forces (along e_n = (cos, -sin) in (X0, Y0), i.e.
    (-sin, cos) in (x, y), which is e_t rotated +90 deg) at arm l along e_t: r x F = l F_n e_z.
    So the model's M equals the case's M_z about the pivot.
    """
    return np.asarray(moment_z)


# The plate's frame (SolverSettings.frame = "plate"): a static mesh whose axes are the case
# axes of the plate at theta = 0, rotating with the plate about its pivot (the origin)
# and translating with its heave. Velocities there are relative to the translating frame,
# with components along the rotating axes: w = R(theta)^T (U_abs - (0, h')).


def plate_frame_inflow(pitch_angle: np.ndarray, heave_velocity: np.ndarray,
                       stream_velocity: float) -> np.ndarray:
    """Velocity of the undisturbed stream in the plate's frame, shape (..., 3), m/s.

    The stream (U, 0) minus the heave velocity (0, h'), along the plate's axes:
    R(theta)^T (U, -h') = (U cos theta - h' sin theta, -U sin theta - h' cos theta).
    """
    th = np.asarray(pitch_angle, dtype=float)
    hd = np.asarray(heave_velocity, dtype=float)
    c, s = np.cos(th), np.sin(th)
    return np.stack([stream_velocity * c - hd * s, -stream_velocity * s - hd * c,
                     np.zeros_like(th)], axis=-1)


def plate_frame_acceleration(pitch_angle: np.ndarray, heave_acceleration: np.ndarray
                             ) -> np.ndarray:
    """The pivot's acceleration (0, h'') along the plate's axes, shape (..., 3), m/s^2.

    R(theta)^T (0, h'') = (h'' sin theta, h'' cos theta); the fluid in the plate's frame
    feels minus this as a body force.
    """
    th = np.asarray(pitch_angle, dtype=float)
    hdd = np.asarray(heave_acceleration, dtype=float)
    return np.stack([hdd * np.sin(th), hdd * np.cos(th), np.zeros_like(th)], axis=-1)


def plate_frame_force_to_model(force_x: np.ndarray, force_y: np.ndarray
                               ) -> tuple[np.ndarray, np.ndarray]:
    """(F_n, F_t) from forces along the plate's axes.

    e_t = (cos theta, sin theta) and e_n = (-sin theta, cos theta) in the case's (x, y)
    are the plate frame's x and y axes, so F_n = F_y and F_t = F_x there.
    """
    return np.asarray(force_y), np.asarray(force_x)
