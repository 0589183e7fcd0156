"""The discrete-vortex model on the oscillating-foil experiments of Read, Hover and
Triantafyllou (2003, J. Fluids Struct. 17, 163-183): heave amplitude 0.75 chords, pitch about
the third chord, heave leading pitch by 90 deg, Re 40,000; thrust coefficient and efficiency
against the Strouhal number at a maximum angle of attack of 15 and 35 deg.

    python scripts/oscillating_foil_experiments.py

Prints one line per motion: St = 2 f h0 / U, the pitch amplitude that gives the maximum
angle of attack at mid-stroke (theta0 = atan(pi St) - alpha_max), the thrust coefficient
C_T = T / (rho U^2 c s / 2) and the efficiency T U / P, means over the last two of six
periods at 200 steps a period, the model's defaults otherwise.
"""

from __future__ import annotations

import numpy as np

from mfflap.hydro.discrete_vortex import VortexModelSettings, simulate_vortex_model
from mfflap.kinematics.continuous import HarmonicMotion
from mfflap.metrics import time_mean
from mfflap.parameters import Fluid, FreeStream, Plate
from mfflap.performance import thrust_and_power

#: chord (m), span (m) and stream speed (m/s): Re = U c / nu = 40,000 in water
CHORD, SPAN, SPEED = 0.1, 1.0, 0.4
#: heave amplitude over the chord and the pivot's place on the chord (the experiments')
HEAVE_CHORDS, PIVOT = 0.75, 1.0 / 3.0
#: what the experiments report: the largest efficiency at alpha_max 15 deg and the largest
#: thrust coefficient at alpha_max 35 deg (Read et al. 2003, abstract)
MEASURED_BEST_EFFICIENCY_15, MEASURED_BEST_THRUST_COEFFICIENT_35 = 0.715, 2.4


def foil_figures(strouhal: float, max_angle_deg: float, periods: int = 6,
                 steps_per_period: int = 200) -> tuple[float, float, float]:
    """Pitch amplitude (deg), thrust coefficient and efficiency of one motion on the
    vortex model (module docstring); NaN figures when the angle needs no pitch."""
    pitch = float(np.arctan(np.pi * strouhal) - np.radians(max_angle_deg))
    if pitch <= 0:
        return float(np.degrees(pitch)), float("nan"), float("nan")
    heave = HEAVE_CHORDS * CHORD
    frequency = strouhal * SPEED / (2 * heave)
    period = 1.0 / frequency
    t = np.arange(periods * steps_per_period) * period / steps_per_period
    state = HarmonicMotion(frequency, heave, pitch, np.pi / 2).sample(t)
    plate = Plate(chord=CHORD, span=SPAN, thickness=0.001, pivot_chord_fraction=PIVOT)
    loads = simulate_vortex_model(state, plate, Fluid(), FreeStream(velocity=SPEED),
                                  VortexModelSettings()).loads
    thrust, power = thrust_and_power(loads, state)
    last = t >= t[-1] - 2 * period
    mean_thrust, mean_power = time_mean(t[last], thrust[last]), time_mean(t[last], power[last])
    dynamic = 0.5 * Fluid().density * SPEED**2 * CHORD * SPAN
    return (float(np.degrees(pitch)), mean_thrust / dynamic,
            mean_thrust * SPEED / mean_power)


def main() -> None:
    print("alpha_max [deg]  St    theta0 [deg]  C_T    efficiency")
    for max_angle in (15.0, 35.0):
        for strouhal in np.arange(0.10, 0.501, 0.05):
            pitch, ct, eta = foil_figures(float(strouhal), max_angle)
            if np.isfinite(ct):
                print(f"{max_angle:15.0f}  {strouhal:.2f}  {pitch:12.1f}  {ct:5.2f}  {eta:10.2f}")
    print(f"measured: best efficiency at 15 deg {MEASURED_BEST_EFFICIENCY_15:.3f}, best C_T at "
          f"35 deg {MEASURED_BEST_THRUST_COEFFICIENT_35:.1f}")


if __name__ == "__main__":
    main()
