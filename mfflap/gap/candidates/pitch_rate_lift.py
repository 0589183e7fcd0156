"""Rotational (pitch-rate) lift: the 3/4-chord downwash of a pitching plate."""

from __future__ import annotations

import numpy as np

from mfflap.gap.candidates.base import CandidateEffect, register


@register
class PitchRateLift(CandidateEffect):
    """F_n = -1/2 rho S a |v_t| thetadot c/2 at c/4 (pitch rate seen at the 3/4 chord)."""

    name = "pitch_rate_lift"
    physical_name = "rotational (pitch-rate) lift"
    coefficient_name = "lift slope a of the pitch-rate term (thin-aerofoil theory: 2 pi)"
    plausible = (1.0, 8.0)
    typical = 2 * np.pi

    def regressor(self, state):
        f = self.flow(state)
        ctx = self.context
        c = ctx.plate.chord
        fn = (-0.5 * ctx.fluid.density * ctx.area * np.abs(f.tangential_velocity)
              * state.pitch_rate * 0.5 * c)
        return self.loads(state, normal=fn, moment=fn * 0.25 * c)
