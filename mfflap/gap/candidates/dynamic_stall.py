"""Dynamic stall: the attached lift lost as the flow separates, with a lagged separation state
(Goman-Khrabrov)."""

from __future__ import annotations

import numpy as np

from mfflap.gap.candidates.base import CandidateEffect, register

#: incidence at which half the chord is separated in steady flow, rad
BREAK_INCIDENCE_RAD = np.radians(15.0)
#: steepness of the steady separation curve, 1/rad (it falls from 0.9 to 0.1 over 4.4 deg)
SEPARATION_STEEPNESS = 57.0
#: relaxation time of the separation state, in convective times c / V of the relative flow
RELAXATION_CONVECTIVE = 2.0
#: delay of the separation behind the incidence, in convective times c / V
DELAY_CONVECTIVE = 0.5


def static_separation(incidence_rad: np.ndarray) -> np.ndarray:
    """Goman and Khrabrov's steady attachment x0 = 1 / (1 + exp(sigma (|alpha| - alpha*))):
    1 for attached flow, 0 for flow separated from the leading edge."""
    arg = np.clip(SEPARATION_STEEPNESS * (np.abs(incidence_rad) - BREAK_INCIDENCE_RAD),
                  -700.0, 700.0)
    return 1.0 / (1.0 + np.exp(arg))


def separation_state(time: np.ndarray, incidence_rad: np.ndarray,
                     incidence_rate: np.ndarray, speed: np.ndarray, chord: float) -> np.ndarray:
    """The attachment x(t) of tau1 dx/dt + x = x0(alpha - tau2 alphadot), tau_i = k_i c / V.

    Integrated exactly over each step with the forcing and the time constant of the step's
    start held, from the steady value of the first sample.
    """
    speed = np.maximum(speed, 1e-9)
    forcing = static_separation(incidence_rad - DELAY_CONVECTIVE * chord / speed
                                * incidence_rate)
    tau = RELAXATION_CONVECTIVE * chord / speed
    decay = np.exp(-np.diff(time) / tau[:-1])
    x = np.empty_like(forcing)
    x[0] = forcing[0]
    for i in range(1, len(x)):
        x[i] = forcing[i - 1] + (x[i - 1] - forcing[i - 1]) * decay[i - 1]
    return x


@register
class DynamicStall(CandidateEffect):
    """The normal force separation takes from the attached lift, with a lagged separation
    state: F_n = -1/2 rho S a V^2 sin(alpha) [((1 + sqrt x) / 2)^2 - 1], at c/4.

    Kirchhoff's flow: a plate whose flow separates at a share ``x`` of the chord from the
    trailing edge keeps ((1 + sqrt x)/2)^2 of its attached normal force a sin(alpha) (a:
    lift slope; the rest, including fully separated flow at x = 0, is left to the strip
    model's cross-flow drag). The attachment x follows Goman and Khrabrov's state equation
    (J. Aircraft 31(5), 1994): tau1 dx/dt + x = x0(alpha - tau2 alphadot), with the steady
    curve x0 a logistic step at 15 deg and the time constants tau1 = 2 c/V and
    tau2 = c/(2V) in convective times of the relative flow (V the speed at three-quarter
    chord): at the optima's heave rates the plate travels several chords of flow per chord
    of stream. The incidence is that of the three-quarter chord, as for the circulatory
    lift. Coefficient: the lift slope a (thin-aerofoil theory: 2 pi); it is zero in
    attached flow.
    """

    name = "dynamic_stall"
    physical_name = "dynamic stall (Goman-Khrabrov separation state, Kirchhoff lift loss)"
    coefficient_name = "lift slope a = dC_L/dalpha of the attached lift lost (2 pi)"
    plausible = (1.0, 8.0)
    typical = 2 * np.pi

    def regressor(self, state):
        c, rho, area = self.context.plate.chord, self.context.fluid.density, self.context.area
        f = self.flow(state)
        vn = f.normal_velocity + 0.75 * c * state.pitch_rate
        vn_rate = f.normal_acceleration + 0.75 * c * state.pitch_acceleration
        along = np.abs(f.tangential_velocity)
        along_rate = np.sign(f.tangential_velocity) * f.tangential_acceleration
        speed2 = np.maximum(vn**2 + along**2, 1e-18)
        incidence = np.arctan2(vn, along)
        incidence_rate = (along * vn_rate - vn * along_rate) / speed2
        x = separation_state(np.asarray(state.time, dtype=float), incidence, incidence_rate,
                             np.sqrt(speed2), c)
        lost = ((1.0 + np.sqrt(x)) / 2.0) ** 2 - 1.0
        fn = -0.5 * rho * area * speed2 * np.sin(incidence) * lost
        return self.loads(state, normal=fn, moment=fn * 0.25 * c)
