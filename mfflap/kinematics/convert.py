"""Conversions between continuous motions and the discrete half-cycle scheme."""

from __future__ import annotations

import numpy as np

from mfflap.errors import MotionError
from mfflap.kinematics.continuous import Motion, PeriodicSplineMotion
from mfflap.kinematics.discrete import DiscreteMotion


def to_discrete(motion: Motion, period: float | np.ndarray, n_steps: int) -> DiscreteMotion:
    """Controls whose discrete trajectory passes through the motion's samples.

    The motion is sampled at t_i = i dt (dt = T / 2N) and the controls are the central second
    differences acc_j = (x_{j+1} - 2 x_j + x_{j-1}) / dt^2, j = 1..N (sample j at t = (j-1) dt).
    For a motion that is half-cycle antisymmetric (a sinusoid), the closed discrete trajectory
    then reproduces the samples to round-off.

    Parameters
    ----------
    motion
        Any continuous motion; batched parameters give batched controls.
    period : float or ndarray, s
        Period T of the motion (broadcast with the motion's parameters).
    n_steps
        N, steps per half cycle.
    """
    if int(n_steps) != n_steps or n_steps < 2:
        raise MotionError(f"n_steps must be a whole number >= 2, got {n_steps!r}")
    period = np.asarray(period, dtype=float)
    if not np.all(np.isfinite(period)) or np.any(period <= 0):
        raise MotionError(f"period must be finite and > 0 s, got {period!r}")
    dt = period / (2 * n_steps)
    k = np.arange(-1, n_steps + 1)  # samples at t = -dt .. N dt
    if period.ndim != 0:
        raise MotionError("to_discrete takes one period; for a batch of sinusoids with their "
                          "own periods use harmonic_to_discrete")
    s = motion.sample(k * float(dt))
    pa, hp = s.pitch_angle, s.heave_position
    acc_p = (pa[..., 2:] - 2 * pa[..., 1:-1] + pa[..., :-2]) / dt**2
    acc_h = (hp[..., 2:] - 2 * hp[..., 1:-1] + hp[..., :-2]) / dt**2
    ts = np.broadcast_to(dt, acc_p.shape[:-1]).copy() if acc_p.ndim > 1 else float(dt)
    return DiscreteMotion(acc_p, acc_h, ts)


def harmonic_to_discrete(frequency, heave_amplitude, pitch_amplitude, phase,
                         n_steps: int) -> DiscreteMotion:
    """Batched exact conversion of sinusoids (any parameter shape) to discrete controls.

    Each sinusoid gets its own time step dt = 1 / (2 N f). Equivalent to
    :func:`to_discrete` on a :class:`HarmonicMotion`, but every motion's own period is used.
    """
    f, ha, ta, ph = np.broadcast_arrays(*(np.asarray(v, dtype=float) for v in
                                          (frequency, heave_amplitude, pitch_amplitude, phase)))
    if np.any(f <= 0) or not np.all(np.isfinite(f)):
        raise MotionError("frequency must be finite and > 0 Hz")
    dt = 1.0 / (2 * n_steps * f)
    j = np.arange(n_steps)  # sample j+1 at t = j dt
    phase_step = (2 * np.pi * f * dt)[..., None]  # = pi / N for all
    arg = phase_step * j
    # second difference of sin(a j + c) is -4 sin^2(a/2) sin(a j + c)
    factor = -4 * np.sin(phase_step / 2) ** 2 / dt[..., None] ** 2
    acc_p = factor * ta[..., None] * np.sin(arg)
    acc_h = factor * ha[..., None] * np.sin(arg + ph[..., None])
    return DiscreteMotion(acc_p, acc_h, dt if dt.ndim else float(dt))


def to_spline(motion: DiscreteMotion) -> PeriodicSplineMotion:
    """Periodic cubic spline through the full-cycle positions of a (single) discrete motion."""
    if motion.pitch_acceleration.ndim != 1:
        raise MotionError("to_spline takes one motion; use DiscreteMotion.take(i) on a batch")
    _, pa, hp = motion.full_cycle_positions()
    return PeriodicSplineMotion(float(np.real(motion.period)), np.real(pa), np.real(hp))


def resample(motion: DiscreteMotion, n_steps: int) -> DiscreteMotion:
    """The same motion on another number of half-cycle steps (same period).

    The positions are interpolated by a periodic cubic spline and converted back to controls,
    so the new trajectory passes through the spline at its own samples.
    """
    spline = to_spline(motion)
    return to_discrete(spline, float(np.real(motion.period)), n_steps)
