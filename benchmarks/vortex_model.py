"""Cost of the discrete-vortex model per cycle, against the Morison model on the same motion.

Run: python benchmarks/vortex_model.py
One cycle of 200 steps of the paper's sinusoid (f = 1 Hz, h = 0.3 m, 20 deg pitch) after
two cycles from rest, at several wake cut-offs; each time is also given as a ratio to the
Morison model's time on the same 600 samples, measured in the same process.
"""

from __future__ import annotations

import numpy as np
from timing import best_of

from mfflap.hydro import MorisonModel
from mfflap.hydro.discrete_vortex import VortexModelSettings, simulate_vortex_model
from mfflap.kinematics.continuous import HarmonicMotion


def main() -> None:
    n_per, cycles = 200, 3
    time_s = np.arange(n_per * cycles) / n_per
    state = HarmonicMotion(frequency=1.0, heave_amplitude=0.3,
                           pitch_amplitude=np.radians(20)).sample(time_s)
    morison = MorisonModel()
    simulate_vortex_model(state)  # loads the compiled kernel
    base = best_of(lambda: morison.loads(state))
    print(f"Morison, {n_per * cycles} samples: {base:.2e} s")
    print("wake [chords]   3 cycles [s]   per cycle [s]   / Morison")
    for wake in (0.5, 1.0, 3.0, 10.0):
        settings = VortexModelSettings(wake_chords=wake)
        t = best_of(lambda settings=settings: simulate_vortex_model(state, settings=settings),
                    repeat=3)
        print(f"{wake:13.1f}   {t:12.3f}   {t / cycles:13.4f}   {t / base:8.0f}")


if __name__ == "__main__":
    main()
