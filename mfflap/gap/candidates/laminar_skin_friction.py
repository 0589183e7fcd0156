"""Laminar skin friction on both faces of the plate (Blasius)."""

from __future__ import annotations

import numpy as np

from mfflap.gap.candidates.base import CandidateEffect, register


@register
class LaminarSkinFriction(CandidateEffect):
    """F_t = -1/2 rho (2 S) k C_f(Re) |v_t| v_t with Blasius' laminar flat-plate law
    C_f = 1.328 Re^-1/2, Re = |v_t| c / nu; coefficient k (flat plate: 1).

    The paper's plate runs at chord Reynolds numbers of 5e4-2e5, below a flat plate's
    transition (about 5e5), where the laminar law holds; :mod:`.turbulent_skin_friction` is the
    turbulent one, for a tripped or rough plate. The two differ only in the Reynolds
    exponent and are grouped as one family.
    """

    name = "laminar_skin_friction"
    physical_name = "laminar skin friction (Blasius)"
    coefficient_name = "multiplier k of C_f = 1.328 Re^-0.5 (flat plate: 1)"
    plausible = (0.3, 3.0)
    typical = 1.0
    family = "skin friction"

    def regressor(self, state):
        f = self.flow(state)
        ctx = self.context
        vt = f.tangential_velocity
        re = np.maximum(np.abs(vt) * ctx.plate.chord / ctx.fluid.kinematic_viscosity, 1e3)
        cf = 1.328 / np.sqrt(re)
        ft = -0.5 * ctx.fluid.density * 2 * ctx.area * cf * np.abs(vt) * vt
        return self.loads(state, tangential=ft)
