"""Cost of the discrete-vortex model's exact gradient against its forward run, and how far
back in time its sensitivity reaches.

Run: python benchmarks/vortex_gradient.py
The paper's sinusoid (f = 1 Hz, h = 0.3 m, 20 deg pitch), three cycles of 200 steps from
rest; the objective is the last cycle's mean of F_n + F_t + M. For each wake cut-off, with
and without leading-edge shedding: the forward run, the gradient (forward with its tape and
the reverse sweep) and their ratio, measured in the same process; then the largest
|dJ/d(pitch rate)| in each cycle, as a factor on the last cycle's: a factor far above 1
means the exact gradient of the last cycle is dominated by the wake's sensitivity to the
start.
"""

from __future__ import annotations

import numpy as np
from timing import best_of

from mfflap.hydro.discrete_vortex import (
    ATTACHED_FLOW,
    VortexModelSettings,
    simulate_vortex_model,
)
from mfflap.hydro.discrete_vortex_adjoint import vortex_loads_vjp
from mfflap.kinematics.continuous import HarmonicMotion


def main() -> None:
    n_per, cycles = 200, 3
    time_s = 0.0013 + np.arange(n_per * cycles) / n_per
    state = HarmonicMotion(frequency=1.0, heave_amplitude=0.3,
                           pitch_amplitude=np.radians(20)).sample(time_s)
    weight = np.zeros(time_s.size)
    weight[-n_per:] = 1.0 / n_per
    print("shedding    wake [chords]  forward [s]  gradient [s]  ratio   "
          "max |dJ/dtheta'| per cycle / last cycle's")
    for lesp, label in ((ATTACHED_FLOW, "attached"), (0.2, "LESP 0.2")):
        for wake in (0.5, 1.0, 3.0):
            settings = VortexModelSettings(wake_chords=wake, critical_lesp=lesp)
            grad = vortex_loads_vjp(state, weight, weight, weight, settings=settings)
            forward = best_of(lambda s=settings: simulate_vortex_model(state, settings=s),
                              repeat=3)
            reverse = best_of(lambda s=settings: vortex_loads_vjp(
                state, weight, weight, weight, settings=s), repeat=3)
            peaks = np.abs(grad.pitch_rate).reshape(cycles, n_per).max(axis=1)
            growth = "  ".join(f"{p / peaks[-1]:8.1e}" for p in peaks)
            print(f"{label:10s}  {wake:13.1f}  {forward:11.3f}  {reverse:12.3f}  "
                  f"{reverse / forward:5.1f}   {growth}")


if __name__ == "__main__":
    main()
