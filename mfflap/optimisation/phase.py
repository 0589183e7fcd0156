"""The phase of a periodic motion, and the condition that fixes it in the optimisation.

A periodic motion shifted in time is the same motion to the flow: its cycle means, and so J,
do not change (on the discrete grid, to the scheme's error only). Nothing in the
problem of docs/theory.md fixes the phase, so a flat direction runs through
every optimum. Where the objective is flat along other directions too (beta = 1's least
power), round-off steers the optimum along it: a start changed in its 12th digit, or
OpenBLAS's kernels of another CPU, moved beta = 1's optimum up to 1.4 s along its 10 s
cycle. The phase condition removes that direction: the pitch's first harmonic keeps the
phase of sin(2 pi t / T), the sinusoids' convention (:func:`~mfflap.kinematics.convert.
harmonic_to_discrete`), one linear equation in the pitch accelerations.

The pitch angles of the half cycle are theta_k = dt^2 (R a)_k (semi-implicit Euler with the
antisymmetric closure, :func:`~mfflap.kinematics.discrete.integrate`, R independent of dt),
at t_k = (k - 1) dt, and the full cycle is the half cycle with the sign flipped, so the
first harmonic of the full cycle is 2 dt^2 a . w with w = R e^{-i pi (k - 1) / N}. Its
cosine part vanishes, Re(a . w) = 0, for every motion whose first harmonic is
c sin(2 pi t / T) (c of either sign: a half period apart).
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np

from mfflap.errors import ConfigError
from mfflap.kinematics.discrete import DiscreteMotion, integrate

#: a start whose pitch first harmonic is below this share of its pitch range has no phase
MIN_HARMONIC_SHARE = 1e-6


@lru_cache(maxsize=16)
def _harmonic_weights(n_steps: int) -> np.ndarray:
    response = integrate(np.eye(n_steps), np.ones(n_steps))[1][:, :n_steps]
    weights = response @ np.exp(-1j * np.pi * np.arange(n_steps) / n_steps)
    weights.flags.writeable = False
    return weights


def harmonic_weights(n_steps: int) -> np.ndarray:
    """w, shape (N,) complex: the first harmonic of a half cycle's positions over a full
    cycle is 2 dt^2 (a . w) for accelerations a (the same map serves pitch and heave)."""
    return _harmonic_weights(int(n_steps))


def phase_condition_row(n_steps: int) -> np.ndarray:
    """The phase condition's row r, shape (N,), unit norm: r . pitch_acceleration = 0."""
    row = np.real(harmonic_weights(n_steps))
    return row / np.linalg.norm(row)


def first_harmonic(motion: DiscreteMotion, signal: str = "pitch") -> complex:
    """The complex first harmonic of a single motion's ``"pitch"`` (rad) or ``"heave"``
    (m): the signal's Fourier coefficient c_1 over the full cycle, so that the harmonic is
    2 Re(c_1 e^{i 2 pi t / T}) (c sin(2 pi t / T) has c_1 = -i c / 2)."""
    acceleration = {"pitch": motion.pitch_acceleration,
                    "heave": motion.heave_acceleration}[signal]
    n = motion.n_steps
    dt = float(np.real(motion.time_step))
    return complex(2 * dt ** 2 * (np.real(acceleration) @ harmonic_weights(n)) / (2 * n))


def pitch_phase_rad(motion: DiscreteMotion) -> float:
    """The phase of the pitch's first harmonic against sin(2 pi t / T), rad in (-pi, pi]:
    0 for theta_a sin(2 pi t / T), pi for its negative, pi / 2 for theta_a cos(...)."""
    return float(np.angle(first_harmonic(motion, "pitch") * 1j))


def check_phase_can_be_fixed(start: DiscreteMotion, label: str = "the start") -> None:
    """Refuse a start whose pitch has no first harmonic: the condition would not fix its
    phase (and would pin a pitch it does not have).

    Raises
    ------
    ConfigError
        Naming ``optimisation.phase`` and the start.
    """
    _, pitch, _ = start.full_cycle_positions()
    spread = float(np.ptp(np.real(pitch)))
    amplitude = 2 * abs(first_harmonic(start, "pitch"))
    if spread == 0.0 or amplitude < MIN_HARMONIC_SHARE * spread:
        raise ConfigError(
            f"optimisation.phase = 'fixed' keeps the phase of the pitch's first harmonic, "
            f"and {label} has none (first-harmonic amplitude {amplitude:.3g} rad over a pitch "
            f"range of {spread:.3g} rad): use phase = 'free'", key="optimisation.phase")


__all__ = ["MIN_HARMONIC_SHARE", "check_phase_can_be_fixed", "first_harmonic",
           "harmonic_weights", "phase_condition_row", "pitch_phase_rad"]
