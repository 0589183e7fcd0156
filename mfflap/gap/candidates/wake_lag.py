"""Circulatory lift delayed by the wake: Wagner's function, R.T. Jones' approximation."""

from __future__ import annotations

import numpy as np

from mfflap.gap.candidates.base import CandidateEffect, register
from mfflap.gap.candidates.circulatory_lift import quasi_steady_normal_force
from mfflap.hydro.thin_aerofoil import wagner_filter


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
