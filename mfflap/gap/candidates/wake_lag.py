"""Circulatory lift delayed by the wake: Wagner's function, R.T. Jones' approximation."""

from __future__ import annotations

import numpy as np

from mfflap.gap.candidates.base import CandidateEffect, register
from mfflap.hydro.thin_aerofoil import wagner_filter


@register
class WakeLag(CandidateEffect):
    """Circulatory lift with the wake's lag (Wagner/Jones) of the 3/4-chord normal velocity,
    F_n = -1/2 rho S a |v_t| (v_n + 3/4 c thetadot) lagged, at c/4; coefficient: lift slope.

    The normal velocity is taken at three quarters of the chord, Theodorsen's downwash
    point, as in :mod:`mfflap.hydro.thin_aerofoil`: small-motion CFD follows that theory
    (docs/findings/linear_theory.md), and a point at the leading edge leaves out
    the pitch rate's share of the circulation.
    """

    name = "wake_lag"
    physical_name = "wake-lagged circulatory lift (Wagner function, Jones approximation)"
    coefficient_name = "lift slope a = dC_L/dalpha (thin-aerofoil theory: 2 pi)"
    plausible = (1.0, 8.0)
    typical = 2 * np.pi
    family = "circulatory lift"

    def regressor(self, state):
        f = self.flow(state)
        ctx = self.context
        c = ctx.plate.chord
        downwash = f.normal_velocity + 0.75 * c * state.pitch_rate
        qs = -0.5 * ctx.fluid.density * ctx.area * np.abs(f.tangential_velocity) * downwash
        # the wake is laid down at the flow's speed along the chord, not the stream's: at
        # large heave rates the plate travels several chords of its own wake per chord of
        # stream
        fn = wagner_filter(qs, state.time, np.abs(f.tangential_velocity), c)
        return self.loads(state, normal=fn, moment=fn * 0.25 * c)
