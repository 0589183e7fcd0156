"""Circulatory lift delayed by the wake: Wagner's function, R.T. Jones' approximation."""

from __future__ import annotations

import numpy as np

from mfflap.gap.candidates.base import CandidateEffect, register
from mfflap.gap.candidates.circulatory_lift import quasi_steady_normal_force

#: Jones' two-exponential approximation of Wagner's function, s = 2 U t / c.
JONES = ((0.165, 0.0455), (0.335, 0.3))


def wagner_filter(values: np.ndarray, time: np.ndarray, velocity: float,
                  chord: float) -> np.ndarray:
    """Response of the Wagner-lag system to ``values`` (last axis is time).

    State-space form of Phi(s) = 1 - sum A_i exp(-b_i s): y = (1 - sum A_i) x +
    sum A_i b_i z_i with dz_i/ds = x - b_i z_i, integrated exactly for a piecewise-constant
    input; the states start in equilibrium (y = x at the first sample).
    """
    x = np.asarray(values, dtype=float)
    s = 2 * velocity * (np.asarray(time, dtype=float) - time[..., :1]) / chord
    ds = np.diff(s, axis=-1)
    y = (1 - sum(a for a, _ in JONES)) * x
    for a, b in JONES:
        z = np.empty_like(x)
        z[..., 0] = x[..., 0] / b
        decay = np.exp(-b * ds)
        for n in range(x.shape[-1] - 1):
            z[..., n + 1] = z[..., n] * decay[..., n] + x[..., n] * (1 - decay[..., n]) / b
        y = y + a * b * z
    return y


@register
class WakeLag(CandidateEffect):
    """Circulatory lift with the wake's lag (Wagner/Jones), at c/4; coefficient: lift slope."""

    name = "wake_lag"
    physical_name = "wake-lagged circulatory lift (Wagner function, Jones approximation)"
    coefficient_name = "lift slope a = dC_L/dalpha (thin-aerofoil theory: 2 pi)"
    plausible = (1.0, 8.0)
    typical = 2 * np.pi

    def regressor(self, state):
        qs = quasi_steady_normal_force(self, state)
        c = self.context.plate.chord
        fn = wagner_filter(qs, state.time, self.context.stream.velocity, c)
        return self.loads(state, normal=fn, moment=fn * 0.25 * c)
