"""Added-mass coupling terms the strip model leaves out (rotating-frame terms, Munk moment)."""

from __future__ import annotations

import numpy as np

from mfflap.gap.candidates.base import CandidateEffect, register


@register
class AddedMassCoupling(CandidateEffect):
    """F_n = -m_a v_t thetadot (at c/2) and the Munk moment M = -m_a v_n v_t, with the plate's
    normal added mass m_a = rho pi (c/2)^2 s; coefficient: their weight (potential flow: 1)."""

    name = "added_mass_coupling"
    physical_name = "added-mass coupling (rotating-frame force and Munk moment)"
    coefficient_name = "weight of the coupling terms (potential flow: 1)"
    plausible = (0.3, 2.0)
    typical = 1.0

    def regressor(self, state):
        f = self.flow(state)
        ctx = self.context
        c = ctx.plate.chord
        mass = ctx.fluid.density * np.pi * (c / 2) ** 2 * ctx.plate.span
        vt, vn = f.tangential_velocity, f.normal_velocity
        fn = -mass * vt * state.pitch_rate
        munk = -mass * vn * vt
        return self.loads(state, normal=fn, moment=fn * 0.5 * c + munk)
