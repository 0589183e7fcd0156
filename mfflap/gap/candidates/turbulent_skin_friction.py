"""Turbulent skin friction on both faces of the plate."""

from __future__ import annotations

import numpy as np

from mfflap.gap.candidates.base import CandidateEffect, register


@register
class TurbulentSkinFriction(CandidateEffect):
    """F_t = -1/2 rho (2 S) k C_f(Re) |v_t| v_t with the turbulent flat-plate law
    C_f = 0.074 Re^-1/5, Re = |v_t| c / nu; coefficient k (flat plate: 1)."""

    name = "turbulent_skin_friction"
    physical_name = "turbulent skin friction (flat-plate 1/5-power law)"
    coefficient_name = "multiplier k of C_f = 0.074 Re^-0.2 (flat plate: 1)"
    plausible = (0.3, 3.0)
    typical = 1.0
    family = "skin friction"

    def regressor(self, state):
        f = self.flow(state)
        ctx = self.context
        vt = f.tangential_velocity
        re = np.maximum(np.abs(vt) * ctx.plate.chord / ctx.fluid.kinematic_viscosity, 1e3)
        cf = 0.074 * re**-0.2
        ft = -0.5 * ctx.fluid.density * 2 * ctx.area * cf * np.abs(vt) * vt
        return self.loads(state, tangential=ft)
