"""Kinematic state of the plate sampled on a time base."""

from __future__ import annotations

from dataclasses import dataclass, fields

import numpy as np

from mfflap.errors import MotionError

#: Names of the six kinematic quantities and their SI units.
KINEMATIC_UNITS: dict[str, str] = {
    "pitch_angle": "rad",
    "pitch_rate": "rad/s",
    "pitch_acceleration": "rad/s^2",
    "heave_position": "m",
    "heave_velocity": "m/s",
    "heave_acceleration": "m/s^2",
}


@dataclass(frozen=True)
class KinematicState:
    """Pitch and heave with their first two time derivatives, sampled at ``time``.

    All arrays share one shape ``(..., n_times)``; leading axes index independent motions
    (vectorised evaluation). ``time`` has shape ``(n_times,)`` or the full shape.

    Attributes
    ----------
    time : ndarray, s
    pitch_angle : ndarray, rad
        theta, positive anticlockwise (chord unit vector e_t = (sin theta, cos theta)).
    pitch_rate : ndarray, rad/s
    pitch_acceleration : ndarray, rad/s^2
    heave_position : ndarray, m
        h, the pivot's displacement along X0 (:attr:`~mfflap.parameters.Plate.pivot_m`).
    heave_velocity : ndarray, m/s
    heave_acceleration : ndarray, m/s^2
    """

    time: np.ndarray
    pitch_angle: np.ndarray
    pitch_rate: np.ndarray
    pitch_acceleration: np.ndarray
    heave_position: np.ndarray
    heave_velocity: np.ndarray
    heave_acceleration: np.ndarray

    def __post_init__(self) -> None:
        shape = np.shape(self.pitch_angle)
        for name in KINEMATIC_UNITS:
            if np.shape(getattr(self, name)) != shape:
                raise MotionError(
                    f"{name} has shape {np.shape(getattr(self, name))}, expected {shape}"
                )

    @property
    def shape(self) -> tuple[int, ...]:
        """Shape ``(..., n_times)`` of every kinematic array."""
        return tuple(np.shape(self.pitch_angle))

    def check_finite(self, what: str = "motion") -> KinematicState:
        """Raise :class:`MotionError` if any sample is NaN or infinite; return self."""
        for name in KINEMATIC_UNITS:
            a = np.asarray(getattr(self, name))
            if np.iscomplexobj(a):
                a = a.real
            if not np.all(np.isfinite(a)):
                idx = np.argwhere(~np.isfinite(a))[0]
                raise MotionError(
                    f"{what}: {name} is not finite at sample index {tuple(int(i) for i in idx)}"
                )
        return self

    def trailing_edge_position(self, chord: float, pivot_m: float = 0.0) -> np.ndarray:
        """Trailing-edge displacement along X0, m: h + (l - x_p) sin(theta), the heave h
        being that of the pivot ``pivot_m`` (x_p) behind the leading edge."""
        return self.heave_position + (chord - pivot_m) * np.sin(self.pitch_angle)

    def take(self, index: tuple | slice | np.ndarray) -> KinematicState:
        """Index the leading (motion) axes, e.g. ``state.take(3)`` for one motion."""
        t = self.time if np.ndim(self.time) == 1 else self.time[index]
        vals = {f.name: getattr(self, f.name)[index] for f in fields(self) if f.name != "time"}
        return KinematicState(time=t, **vals)

    def on_uniform_time(self, time_step: float, start: float | None = None) -> KinematicState:
        """The state linearly interpolated at start, start + dt, ... up to the last sample
        time (one motion on a 1-D time base, e.g. a CFD record's adaptive steps); ``start``
        defaults to the first sample time, and before it the first sample is held.

        Examples
        --------
        >>> import numpy as np
        >>> t = np.array([0.0, 0.1, 0.3])
        >>> state = KinematicState(t, t, t, t, t, t, t).on_uniform_time(0.1)
        >>> state.time.round(12).tolist(), state.pitch_angle.round(12).tolist()
        ([0.0, 0.1, 0.2, 0.3], [0.0, 0.1, 0.2, 0.3])
        """
        t = np.asarray(self.time, dtype=float)
        if t.ndim != 1 or np.shape(self.pitch_angle) != t.shape:
            raise MotionError(f"a uniform time base is for one motion on a 1-D time base, got "
                              f"time {t.shape} and states {np.shape(self.pitch_angle)}")
        if not time_step > 0:
            raise MotionError(f"time_step must be > 0, got {time_step!r}")
        start = t[0] if start is None else float(start)
        n = int(np.floor((t[-1] - start) / time_step + 1e-9)) + 1
        times = start + np.arange(n) * time_step
        return KinematicState(times, **{k: np.interp(times, t, getattr(self, k))
                                        for k in KINEMATIC_UNITS})
