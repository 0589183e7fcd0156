"""Quasi-steady circulatory lift of a thin plate, acting at the quarter chord."""

from __future__ import annotations

import numpy as np

from mfflap.gap.candidates.base import CandidateEffect, register


def quasi_steady_normal_force(effect: CandidateEffect, state) -> np.ndarray:
    """-1/2 rho S |v_t| v_n(3c/4) per unit lift slope: the small-angle flat-plate normal
    force of thin-aerofoil theory, its incidence the normal velocity at three quarters of
    the chord (the leading edge's plus the pitch rate's 3/4 c thetadot)."""
    f = effect.flow(state)
    rho, area = effect.context.fluid.density, effect.context.area
    downwash = f.normal_velocity + 0.75 * effect.context.plate.chord * state.pitch_rate
    return -0.5 * rho * area * np.abs(f.tangential_velocity) * downwash


@register
class CirculatoryLift(CandidateEffect):
    """Quasi-steady circulatory lift F_n = -1/2 rho S a |v_t| v_n(3c/4) at c/4 (a: lift
    slope; thin-aerofoil theory: the incidence seen at three-quarter chord, the lift at the
    quarter chord)."""

    name = "circulatory_lift"
    physical_name = "quasi-steady circulatory lift"
    coefficient_name = "lift slope a = dC_L/dalpha (thin-aerofoil theory: 2 pi)"
    plausible = (1.0, 8.0)
    typical = 2 * np.pi
    family = "circulatory lift"

    def regressor(self, state):
        fn = quasi_steady_normal_force(self, state)
        return self.loads(state, normal=fn, moment=fn * 0.25 * self.context.plate.chord)
