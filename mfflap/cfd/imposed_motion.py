"""The motion a CFD case imposes: the start-up ramp, the start and end times it allows,
and the kinematic state it imposes at given times (the same for every solver)."""

from __future__ import annotations

import numpy as np

from mfflap.errors import ConfigError, MotionError
from mfflap.kinematics.continuous import Motion
from mfflap.kinematics.state import KinematicState


def check_ramp_time(ramp_time: float, end_time: float | None = None) -> float:
    """``ramp_time`` as a float, s.

    Parameters
    ----------
    ramp_time : s
    end_time : s, optional
        The run's simulated time: the ramp must end before it.

    Raises
    ------
    ConfigError
        If it is negative or not a finite number (0 is no ramp), or lasts the whole run
        (the motion would never reach its amplitude).
    """
    value = float(ramp_time)
    if not (np.isfinite(value) and value >= 0):
        raise ConfigError(f"the start-up ramp must be a finite time >= 0 s (0: none), got "
                          f"{ramp_time!r}", key="ramp_time")
    if end_time is not None and value > 0 and value >= float(end_time):
        raise ConfigError(f"the start-up ramp ({value:g} s) lasts the whole run "
                          f"({float(end_time):g} s): the motion would never reach its "
                          "amplitude; end it well before the run does (a quarter to half a "
                          "period is usual)", key="ramp_time")
    return value


def check_end_time(end_time: float) -> float:
    """``end_time``, the simulated time of a CFD run, as a float, s.

    Raises
    ------
    MotionError
        If it is not a finite time > 0 s (a run of zero, negative or endless length).
    """
    value = float(end_time)
    if not (np.isfinite(value) and value > 0):
        raise MotionError(f"end_time must be a finite time > 0 s, got {end_time!r}")
    return value


def smooth_ramp(t: np.ndarray, ramp_time: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """C^2 smoothstep r(t) over ``ramp_time`` and its first two derivatives.

    Raises
    ------
    ConfigError
        For a negative or non-finite ``ramp_time`` (:func:`check_ramp_time`).
    """
    if check_ramp_time(ramp_time) == 0:
        one = np.ones_like(t)
        return one, 0 * one, 0 * one
    x = np.clip(t / ramp_time, 0, 1)
    inside = (t > 0) & (t < ramp_time)
    r = x**3 * (10 - 15 * x + 6 * x**2)
    dr = np.where(inside, 30 * x**2 * (1 - x) ** 2 / ramp_time, 0)
    ddr = np.where(inside, 60 * x * (1 - x) * (1 - 2 * x) / ramp_time**2, 0)
    return r, dr, ddr


def imposed_state(motion: Motion, times: np.ndarray, ramp_time: float = 0.0) -> KinematicState:
    """The kinematics the CFD case actually imposes: heave from zero, times the start-up ramp."""
    s = motion.sample(times)
    h0 = motion.sample(np.array([0.0])).heave_position[0]
    r, dr, ddr = smooth_ramp(np.asarray(times, dtype=float), ramp_time)
    h = s.heave_position - h0
    return KinematicState(
        time=s.time,
        pitch_angle=r * s.pitch_angle,
        pitch_rate=dr * s.pitch_angle + r * s.pitch_rate,
        pitch_acceleration=ddr * s.pitch_angle + 2 * dr * s.pitch_rate + r * s.pitch_acceleration,
        heave_position=r * h,
        heave_velocity=dr * h + r * s.heave_velocity,
        heave_acceleration=ddr * h + 2 * dr * s.heave_velocity + r * s.heave_acceleration,
    )


#: a pitch at t = 0 within this of zero, rad, is the mesh's own (round-off of a table)
START_PITCH_TOLERANCE = 1.0e-9
#: rates at t = 0 within these of zero are a start at rest (rad/s, m/s)
START_RATE_TOLERANCE = 1.0e-9


def check_start_at_mesh(motion: Motion, ramp_time: float) -> None:
    """Refuse a motion that every solver cannot impose the same way from its first step.

    Meshes are drawn with the plate at zero pitch. OpenFOAM's table imposes positions, so a
    motion that starts pitched would jump there in the first step; Fluent's UDF imposes
    rates, which it integrates from the mesh, so it would pitch by that much less
    throughout. With a start-up ramp (``ramp_time`` > 0) both start at the mesh and at rest
    and impose one motion; without one, the pitch at t = 0 must be zero. A heave offset is
    no problem: the heave is imposed from zero in both.

    Raises
    ------
    MotionError
        Naming the pitch at t = 0 and the remedy.

    Examples
    --------
    >>> from mfflap.kinematics.continuous import HarmonicMotion
    >>> check_start_at_mesh(HarmonicMotion(1.0, 0.3, 0.3, 1.5), 0.0)  # theta(0) = 0
    >>> check_start_at_mesh(HarmonicMotion(1.0, 0.3, 0.3, 1.5), 0.25)  # any motion, ramped
    """
    if ramp_time > 0:
        return
    pitch = float(motion.sample(np.array([0.0])).pitch_angle[0])
    if abs(pitch) > START_PITCH_TOLERANCE:
        raise MotionError(
            f"the motion starts pitched at {np.degrees(pitch):.6g} deg, where the mesh is "
            "drawn at 0 deg: OpenFOAM would jump there in its first step and Fluent (which "
            "imposes rates) would pitch that much less throughout. Give a start-up ramp "
            "(ramp_time > 0, --ramp-time), which starts both at the mesh and at rest")


#: a rate at t = 0 below this share of its largest magnitude over the run is a start at rest
#: (a table's spline leaves a trace of a rate at its ends)
START_RATE_SHARE = 0.01


def not_at_rest(motion: Motion, ramp_time: float, end_time: float) -> dict[str, tuple[float, str]]:
    """The rates of the imposed motion at t = 0 that are not zero (an impulsive start),
    by name with their value and unit; empty with a start-up ramp or a start at rest.

    A rate counts when it is above :data:`START_RATE_SHARE` of its largest magnitude over
    ``[0, end_time]``.

    Examples
    --------
    >>> from mfflap.kinematics.continuous import HarmonicMotion
    >>> sorted(not_at_rest(HarmonicMotion(1.0, 0.3, 0.3, 0.0), 0.0, 1.0))
    ['heave velocity', 'pitch rate']
    >>> not_at_rest(HarmonicMotion(1.0, 0.3, 0.3, 0.0), 0.25, 1.0)
    {}
    """
    s = imposed_state(motion, np.linspace(0.0, end_time, 2001), ramp_time)
    said = {}
    for name, rate, unit, scale in (("pitch rate", s.pitch_rate, "deg/s", np.degrees(1.0)),
                                    ("heave velocity", s.heave_velocity, "m/s", 1.0)):
        peak = float(np.max(np.abs(rate)))
        if abs(rate[0]) > max(START_RATE_SHARE * peak, START_RATE_TOLERANCE):
            said[name] = (float(rate[0] * scale), unit)
    return said
