"""Refinement of the best feasible sinusoid: a continuous search over (f, h_amp, theta_amp,
phi) from the best grid point, under the same instantaneous power limit at the N samples.

The baseline of the paper's gain is the best feasible *sinusoid*; a grid point is only an
approximation of it, so the optimised motion is compared with the refined one too.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import minimize

from mfflap.kinematics.convert import harmonic_to_discrete
from mfflap.performance import evaluate_discrete
from mfflap.sweep import SweepResult


@dataclass
class RefinedSinusoid:
    """The refined best feasible sinusoid."""

    frequency: float  # Hz
    heave_amplitude: float  # m
    pitch_amplitude: float  # rad
    phase: float  # rad
    mean_thrust: float  # N
    max_power: float  # W
    grid_thrust: float  # N, the grid point it started from
    success: bool
    message: str


def sinusoid_pitch_margins(frequency, pitch_amplitude, max_pitch: float = np.inf,
                           max_pitch_rate: float = np.inf,
                           max_pitch_acceleration: float = np.inf) -> np.ndarray:
    """1 - peak / limit of sinusoids theta = theta_a sin(2 pi f t) for their amplitude
    |theta_a|, peak rate w |theta_a| and peak acceleration w^2 |theta_a| (w = 2 pi f), shape
    (3, ...): >= 0 within the pitch envelope (rad, rad/s, rad/s^2; inf: no limit, margin 1).
    """
    w = 2 * np.pi * np.asarray(frequency, dtype=float)
    a = np.abs(np.asarray(pitch_amplitude, dtype=float))
    return np.stack([1.0 - peak / limit for peak, limit in (
        (a, max_pitch), (w * a, max_pitch_rate), (w**2 * a, max_pitch_acceleration))])


def refine_best_sinusoid(model, sweep: SweepResult, n_steps: int, max_power: float,
                         max_heave: float, min_period: float, max_period: float,
                         scheme: str = "paper",
                         pitch_envelope: dict[str, float] | None = None) -> RefinedSinusoid:
    """Maximise mean thrust over (f, h, theta, phi) subject to max_j P_j <= P_max, the
    heave and period bounds and the pitch envelope (``max_pitch`` rad, ``max_pitch_rate``
    rad/s, ``max_pitch_acceleration`` rad/s^2 on the sinusoid's amplitude, peak rate and
    peak acceleration; inf or left out: none) (SLSQP, from the best feasible grid point)."""
    i = sweep.best_feasible()
    x0 = np.array([sweep.frequency[i], sweep.heave_amplitude[i], sweep.pitch_amplitude[i],
                   sweep.phase[i]])
    scale = np.array([1.0, 0.1, 0.1, 1.0])

    evaluated: dict[bytes, tuple[float, np.ndarray]] = {}

    def evaluate(xs):
        # SLSQP asks for the objective and the power constraints at the same points: each
        # point is evaluated once
        key = np.asarray(xs, dtype=float).tobytes()
        if key not in evaluated:
            f, h, th, ph = xs * scale
            ev = evaluate_discrete(model, harmonic_to_discrete(f, h, th, ph, n_steps),
                                   scheme)  # type: ignore[arg-type]
            evaluated[key] = (float(ev.summary.mean_thrust),
                              np.real(np.asarray(ev.input_power, dtype=float)))
        return evaluated[key]

    bounds = [(1 / max_period / scale[0], 1 / min_period / scale[0]),
              (0.0, max_heave / scale[1]), (0.0, np.pi / 2 / scale[2]),
              (-np.pi / scale[3], 2 * np.pi / scale[3])]
    def pitch_margins(xs):  # >= 0 within the envelope
        f, _, th, _ = xs * scale
        return sinusoid_pitch_margins(f, th, **(pitch_envelope or {}))

    # the limit at every sample, not on their maximum: the maximum has a kink wherever
    # the peak moves from one sample to another, on which SLSQP stalls (200 iterations,
    # 2,500 evaluations, where one constraint per sample converges in a few dozen)
    res = minimize(lambda xs: -evaluate(xs)[0], x0 / scale, method="SLSQP", bounds=bounds,
                   constraints=[{"type": "ineq",
                                 "fun": lambda xs: (max_power - evaluate(xs)[1]) / max_power},
                                {"type": "ineq", "fun": pitch_margins}],
                   options={"maxiter": 200, "ftol": 1e-10})
    thrust, power = evaluate(res.x)
    peak = float(power.max())
    f, h, th, ph = res.x * scale
    if (peak > max_power * (1 + 1e-6) or thrust < sweep.mean_thrust[i]
            or pitch_margins(res.x).min() < -1e-6):
        f, h, th, ph = x0  # keep the grid point when the refinement did not improve on it
        thrust, peak = float(sweep.mean_thrust[i]), float(sweep.max_power[i])
    return RefinedSinusoid(float(f), float(h), float(th), float(ph), thrust, peak,
                           float(sweep.mean_thrust[i]), bool(res.success), str(res.message))
