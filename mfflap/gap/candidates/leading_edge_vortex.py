"""Leading-edge vortex lift (Polhamus' suction analogy)."""

from __future__ import annotations

import numpy as np

from mfflap.gap.candidates.base import CandidateEffect, register


@register
class LeadingEdgeVortex(CandidateEffect):
    """Polhamus vortex normal force C_N,v = K_v sin^2(alpha) sign(alpha), at 0.4 c.

    Polhamus' suction analogy gives the vortex lift K_v cos(alpha) sin^2(alpha), whose
    normal component is K_v sin^2(alpha): it grows with the incidence up to 90 deg. With
    v_n = V sin(alpha) at the leading edge: F_n = -1/2 rho S K_v |v_n| v_n.
    """

    name = "leading_edge_vortex"
    physical_name = "leading-edge vortex lift (Polhamus suction analogy)"
    coefficient_name = "vortex-lift factor K_v (flat plate: about pi)"
    plausible = (0.5, 6.0)
    typical = np.pi

    def regressor(self, state):
        f = self.flow(state)
        ctx = self.context
        vn = f.normal_velocity
        fn = -0.5 * ctx.fluid.density * ctx.area * np.abs(vn) * vn
        return self.loads(state, normal=fn, moment=fn * 0.4 * ctx.plate.chord)
