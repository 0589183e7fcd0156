"""Continuous motions: functions of time that can be sampled anywhere.

Every class here has ``sample(times) -> KinematicState`` with exact derivatives. Parameters
may be arrays (broadcast together); the state then has shape ``params.shape + (n_times,)``,
which is how sweeps evaluate many motions at once.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol, runtime_checkable

import numpy as np
from scipy.interpolate import CubicHermiteSpline, CubicSpline

from mfflap.errors import MotionError
from mfflap.kinematics.state import KinematicState

#: the pitch at which the plate stands across the stream, rad; a flapping plate stays within
#: it (the case file's pitch amplitude, and the pitch its ramp reaches, are bounded by it)
UPRIGHT_PITCH = np.pi / 2


def check_times(times: np.ndarray | float, what: str = "time array") -> np.ndarray:
    """Return ``times`` as a 1-D float array, refusing NaN and non-increasing values.

    Raises
    ------
    MotionError
        If a time is not finite or the array is not strictly increasing.
    """
    t = np.atleast_1d(np.asarray(times, dtype=float))
    if t.ndim != 1:
        raise MotionError(f"{what} must be one-dimensional, got shape {t.shape}")
    if not np.all(np.isfinite(t)):
        bad = int(np.argmin(np.isfinite(t)))
        raise MotionError(f"{what} has a non-finite value at index {bad}")
    if t.size > 1 and np.any(np.diff(t) <= 0):
        i = int(np.argmax(np.diff(t) <= 0))
        raise MotionError(
            f"{what} is not strictly increasing: t[{i}] = {t[i]!r} s, t[{i + 1}] = {t[i + 1]!r} s"
        )
    return t


@runtime_checkable
class Motion(Protocol):
    """Anything that can be sampled in time."""

    def sample(self, times: np.ndarray) -> KinematicState:
        """Kinematic state at ``times`` (s)."""
        ...


def _positive_array(value, name: str) -> np.ndarray:
    a = np.asarray(value, dtype=float)
    if not np.all(np.isfinite(a)) or np.any(a <= 0):
        raise MotionError(f"{name} must be finite and > 0, got {value!r}")
    return a


def _finite_array(value, name: str) -> np.ndarray:
    a = np.asarray(value, dtype=float)
    if not np.all(np.isfinite(a)):
        raise MotionError(f"{name} must be finite, got {value!r}")
    return a


def _carrier(times, frequency, heave_amplitude, pitch_parameter, phase):
    """Broadcast parameters against the time axis and sample the heave sinusoid.

    Returns (t, w, pitch_parameter, heave dict, time array for the state), with parameters
    shaped (..., 1) so that they broadcast against ``t``.
    """
    t = check_times(times)
    f, ha, pp, ph = np.broadcast_arrays(
        *(np.asarray(v, dtype=float) for v in (frequency, heave_amplitude, pitch_parameter,
                                               phase))
    )
    w = (2 * np.pi * f)[..., None]
    ha, pp, ph = ha[..., None], pp[..., None], ph[..., None]
    arg_h = w * t + ph
    heave = {
        "heave_position": ha * np.sin(arg_h),
        "heave_velocity": ha * w * np.cos(arg_h),
        "heave_acceleration": -ha * w**2 * np.sin(arg_h),
    }
    time = t if f.ndim == 0 else np.array(np.broadcast_to(t, arg_h.shape))
    return t, w, pp, heave, time


def _check_carrier(frequency, heave_amplitude, pitch_parameter, phase, pitch_name) -> None:
    _positive_array(frequency, "frequency")
    _finite_array(heave_amplitude, "heave_amplitude")
    _finite_array(pitch_parameter, pitch_name)
    _finite_array(phase, "phase")


@dataclass(frozen=True)
class HarmonicMotion:
    """Sinusoidal heave and pitch: theta = theta_a sin(2 pi f t), h = h_a sin(2 pi f t + phi).

    Parameters
    ----------
    frequency : float or ndarray, Hz
    heave_amplitude : float or ndarray, m
    pitch_amplitude : float or ndarray, rad
    phase : float or ndarray, rad
        Phase by which heave leads pitch.
    """

    frequency: float | np.ndarray
    heave_amplitude: float | np.ndarray
    pitch_amplitude: float | np.ndarray
    phase: float | np.ndarray = np.pi / 2

    def __post_init__(self) -> None:
        _check_carrier(self.frequency, self.heave_amplitude, self.pitch_amplitude, self.phase,
                       "pitch_amplitude")

    @property
    def period(self) -> np.ndarray | float:
        """Period 1/f, s."""
        return 1.0 / np.asarray(self.frequency, dtype=float)

    def sample(self, times: np.ndarray) -> KinematicState:
        """Exact state at ``times``; shape ``broadcast(params).shape + (n_times,)``."""
        t, w, ta, heave, time = _carrier(times, self.frequency, self.heave_amplitude,
                                         self.pitch_amplitude, self.phase)
        arg_p = w * t
        return KinematicState(
            time=time,
            pitch_angle=ta * np.sin(arg_p),
            pitch_rate=ta * w * np.cos(arg_p),
            pitch_acceleration=-ta * w**2 * np.sin(arg_p),
            **heave,
        )


@dataclass(frozen=True)
class RampHarmonicMotion:
    """The identification motion: theta = k t sin(2 pi f t), h = h_a sin(2 pi f t + phi).

    The pitch amplitude grows linearly in time at ``pitch_ramp_rate`` (the paper's theta_kamp)
    so that one CFD run explores many pitch amplitudes.

    Parameters
    ----------
    frequency : float or ndarray, Hz
    heave_amplitude : float or ndarray, m
    pitch_ramp_rate : float or ndarray, rad/s
    phase : float or ndarray, rad
    """

    frequency: float | np.ndarray
    heave_amplitude: float | np.ndarray
    pitch_ramp_rate: float | np.ndarray
    phase: float | np.ndarray = np.pi / 2

    def __post_init__(self) -> None:
        _check_carrier(self.frequency, self.heave_amplitude, self.pitch_ramp_rate, self.phase,
                       "pitch_ramp_rate")

    @property
    def period(self) -> np.ndarray | float:
        """Period of the carrier 1/f, s (the motion itself is not periodic)."""
        return 1.0 / np.asarray(self.frequency, dtype=float)

    def sample(self, times: np.ndarray) -> KinematicState:
        """Exact state at ``times``; shape ``broadcast(params).shape + (n_times,)``."""
        t, w, k, heave, time = _carrier(times, self.frequency, self.heave_amplitude,
                                        self.pitch_ramp_rate, self.phase)
        s, c = np.sin(w * t), np.cos(w * t)
        return KinematicState(
            time=time,
            pitch_angle=k * t * s,
            pitch_rate=k * s + k * t * w * c,
            pitch_acceleration=2 * k * w * c - k * t * w**2 * s,
            **heave,
        )

    def largest_pitch(self, end_time: float,
                      samples_per_period: int = 720) -> tuple[float, float]:
        """The largest pitch in magnitude from 0 to ``end_time``, and its time.

        The envelope k t grows, so this is the last peak of the carrier before
        ``end_time`` or ``end_time`` itself. Sampled at ``samples_per_period`` times per
        carrier period and at ``end_time``: at 720 a peak is missed by less than 1e-5 of
        its value. Scalar parameters only.

        Returns
        -------
        tuple
            The pitch (rad, with its sign) and its time (s).
        """
        n = max(2, int(np.ceil(float(end_time) * float(self.frequency) * samples_per_period)))
        times = np.linspace(0.0, float(end_time), n + 1)
        pitch = self.sample(times).pitch_angle
        worst = int(np.argmax(np.abs(pitch)))
        return float(pitch[worst]), float(times[worst])


class PeriodicSplineMotion:
    """Periodic cubic spline through one period of pitch and heave samples.

    Parameters
    ----------
    period : float, s
    pitch_angle : ndarray, rad, shape (n,)
        Samples at ``t_i = i * period / n``, i = 0..n-1 (the end point is implied).
    heave_position : ndarray, m, shape (n,)
    """

    def __init__(self, period: float, pitch_angle: np.ndarray, heave_position: np.ndarray):
        self.period = float(_positive_array(period, "period"))
        th = _finite_array(pitch_angle, "pitch_angle")
        hp = _finite_array(heave_position, "heave_position")
        if th.ndim != 1 or th.shape != hp.shape or th.size < 4:
            raise MotionError(
                "pitch_angle and heave_position must be 1-D arrays of the same length >= 4, "
                f"got shapes {th.shape} and {hp.shape}"
            )
        n = th.size
        knots = np.arange(n + 1) * self.period / n
        self._pitch = CubicSpline(knots, np.append(th, th[0]), bc_type="periodic")
        self._heave = CubicSpline(knots, np.append(hp, hp[0]), bc_type="periodic")
        self.sample_pitch = th
        self.sample_heave = hp

    def sample(self, times: np.ndarray) -> KinematicState:
        """State at ``times`` (wrapped into one period), shape ``(n_times,)``."""
        t = check_times(times)
        tw = np.mod(t, self.period)
        p, h = self._pitch, self._heave
        return KinematicState(
            time=t,
            pitch_angle=p(tw),
            pitch_rate=p(tw, 1),
            pitch_acceleration=p(tw, 2),
            heave_position=h(tw),
            heave_velocity=h(tw, 1),
            heave_acceleration=h(tw, 2),
        )


class TabulatedMotion:
    """A user's table of pitch and heave against time, interpolated by cubic splines.

    Parameters
    ----------
    time : ndarray, s, shape (n,)
        Strictly increasing.
    pitch_angle : ndarray, rad, shape (n,)
    heave_position : ndarray, m, shape (n,)
    hold_after_end : bool
        Past the last row, hold the last position at rest instead of refusing. A solver's
        motion table runs past the simulated end time (OpenFOAM's interpolation needs rows
        there); a run of a user's table ends at or before its last row, so those rows are
        never simulated.
    pitch_rate, heave_velocity : ndarray, rad/s and m/s, shape (n,), optional
        Rates at the rows, used as given: the position between rows is then the cubic
        Hermite spline through the positions with these slopes.
    pitch_acceleration, heave_acceleration : ndarray, rad/s^2 and m/s^2, optional
        Accelerations at the rows, used as given with their rates: the rate between rows is
        the cubic Hermite spline through the rates with these slopes.
    """

    def __init__(self, time: np.ndarray, pitch_angle: np.ndarray, heave_position: np.ndarray,
                 hold_after_end: bool = False, *, pitch_rate: np.ndarray | None = None,
                 heave_velocity: np.ndarray | None = None,
                 pitch_acceleration: np.ndarray | None = None,
                 heave_acceleration: np.ndarray | None = None):
        t = check_times(time, "table time column")
        given = {"pitch_angle": pitch_angle, "heave_position": heave_position,
                 "pitch_rate": pitch_rate, "heave_velocity": heave_velocity,
                 "pitch_acceleration": pitch_acceleration,
                 "heave_acceleration": heave_acceleration}
        cols = {k: _finite_array(v, k) for k, v in given.items() if v is not None}
        if t.size < 4 or any(c.shape != t.shape for c in cols.values()):
            raise MotionError("a motion table needs >= 4 rows and equal-length columns")
        for acc, rate in (("pitch_acceleration", "pitch_rate"),
                          ("heave_acceleration", "heave_velocity")):
            if acc in cols and rate not in cols:
                raise MotionError(f"{acc} is used with {rate}: give both, or neither")
        self.table_time = t
        self.hold_after_end = hold_after_end
        self._pitch, self._pitch_rate = self._splines(t, cols, "pitch_angle", "pitch_rate",
                                                      "pitch_acceleration")
        self._heave, self._heave_rate = self._splines(t, cols, "heave_position",
                                                      "heave_velocity", "heave_acceleration")

    @staticmethod
    def _splines(t, cols, position, rate, acceleration):
        """(position spline, rate spline or None): cubic through the positions alone, else
        Hermite with the given rates (and the rates Hermite with the given accelerations)."""
        if rate not in cols:
            return CubicSpline(t, cols[position]), None
        rates = (CubicHermiteSpline(t, cols[rate], cols[acceleration])
                 if acceleration in cols else None)
        return CubicHermiteSpline(t, cols[position], cols[rate]), rates

    def sample(self, times: np.ndarray) -> KinematicState:
        """State at ``times`` inside the table's range (or past it, if held)."""
        t = check_times(times)
        end = self.table_time[-1]
        if t[0] < self.table_time[0] - 1e-12 or (t[-1] > end + 1e-12
                                                 and not self.hold_after_end):
            raise MotionError(
                f"times [{t[0]}, {t[-1]}] s leave the table's range "
                f"[{self.table_time[0]}, {end}] s"
            )
        p, h = self._pitch, self._heave
        inside = t <= end
        tc = np.minimum(t, end)

        def moving(values: np.ndarray) -> np.ndarray:  # rates and accelerations: 0 when held
            return np.where(inside, values, 0.0)

        pr, hr = self._pitch_rate, self._heave_rate
        return KinematicState(
            time=t, pitch_angle=p(tc),
            pitch_rate=moving(p(tc, 1) if pr is None else pr(tc)),
            pitch_acceleration=moving(p(tc, 2) if pr is None else pr(tc, 1)),
            heave_position=h(tc),
            heave_velocity=moving(h(tc, 1) if hr is None else hr(tc)),
            heave_acceleration=moving(h(tc, 2) if hr is None else hr(tc, 1)),
        )
