"""Skin friction on both faces of the plate, for any flat-plate friction law."""

from __future__ import annotations

import numpy as np

from mfflap.gap.candidates.base import CandidateEffect

#: the smallest chord Reynolds number a friction law is evaluated at (a plate at rest in
#: the relative flow would otherwise divide by zero)
MIN_REYNOLDS = 1e3


class FlatPlateFriction(CandidateEffect):
    """F_t = -1/2 rho (2 S) k C_f(Re) |v_t| v_t, Re = |v_t| c / nu, with the law C_f(Re) of
    the subclass (:meth:`friction_coefficient`); coefficient k (flat plate: 1)."""

    plausible = (0.3, 3.0)
    typical = 1.0
    family = "skin friction"

    def friction_coefficient(self, reynolds: np.ndarray) -> np.ndarray:
        """C_f of a flat plate at chord Reynolds number ``reynolds``."""
        raise NotImplementedError

    def regressor(self, state):
        ctx = self.context
        vt = self.flow(state).tangential_velocity
        re = np.maximum(np.abs(vt) * ctx.plate.chord / ctx.fluid.kinematic_viscosity,
                        MIN_REYNOLDS)
        ft = (-0.5 * ctx.fluid.density * 2 * ctx.area * self.friction_coefficient(re)
              * np.abs(vt) * vt)
        return self.loads(state, tangential=ft)
