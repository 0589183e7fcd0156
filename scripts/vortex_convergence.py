"""Time-step convergence of the discrete-vortex model on large harmonic motions.

    python scripts/vortex_convergence.py            # the default model and its variants
    python scripts/vortex_convergence.py --quick    # 100 and 200 steps a period only

For each motion and each step count n (steps a period) the model runs eight periods from
rest on the paper's plate and stream; it prints the mean thrust, the mean input power and
the peak input power over the last four periods, and beside each the spread of the four
periods' figures (largest minus smallest over their mean): how far a single period's figure
moves from one period to the next. Three variants separate what decides the convergence:

- ``default``: the model's defaults (leading-edge shedding above the critical LESP, core
  0.02 c);
- ``attached``: no leading-edge shedding (the critical LESP infinite), core 0.02 c;
- ``core 0.4 c``: leading-edge shedding with a core of 0.4 chords, where the wake stops
  being chaotic and each period repeats the last.

A model converged in time step gives figures that move by less than the goal (2 % on the
means, 5 % on the peak) from n to 2n; the period-to-period spread says whether a mean over
a few periods can be converged at all.
"""

from __future__ import annotations

import argparse
import math
import time

import numpy as np

from mfflap.hydro.discrete_vortex import VortexModelSettings, simulate_vortex_model
from mfflap.kinematics.continuous import HarmonicMotion
from mfflap.performance import thrust_and_power

#: (frequency Hz, heave amplitude m, pitch amplitude deg, phase deg): the main job's best
#: sinusoid and a larger harmonic
MOTIONS = {"best sinusoid": (0.892, 0.35, 60.0, 112.0),
           "large harmonic": (1.12, 0.5, 64.0, 100.0)}
VARIANTS = {"default": VortexModelSettings(),
            "attached": VortexModelSettings(critical_lesp=math.inf),
            "core 0.4 c": VortexModelSettings(core_radius_chords=0.4)}
PERIODS, KEPT = 8, 4


def period_figures(motion: tuple[float, float, float, float], steps_per_period: int,
                   settings: VortexModelSettings) -> tuple[np.ndarray, float]:
    """Mean thrust (N), mean power (W) and peak power (W) of each of the last KEPT periods,
    shape (3, KEPT), and the run's wall time (s)."""
    frequency, heave, pitch_deg, phase_deg = motion
    harmonic = HarmonicMotion(frequency, heave, math.radians(pitch_deg),
                              math.radians(phase_deg))
    state = harmonic.sample(np.arange(PERIODS * steps_per_period)
                            / (steps_per_period * frequency))
    start = time.perf_counter()
    run = simulate_vortex_model(state, settings=settings)
    wall_s = time.perf_counter() - start
    thrust, power = thrust_and_power(run.loads, state)
    shape = (PERIODS, steps_per_period)
    kept = slice(PERIODS - KEPT, PERIODS)
    return np.array([thrust.reshape(shape).mean(axis=1)[kept],
                     power.reshape(shape).mean(axis=1)[kept],
                     power.reshape(shape).max(axis=1)[kept]]), wall_s


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="100 and 200 steps only")
    steps = (100, 200) if parser.parse_args().quick else (100, 200, 400)
    print(f"means over the last {KEPT} of {PERIODS} periods; (spread) = largest minus "
          "smallest period over their mean")
    print(f"{'motion':15s} {'variant':11s} {'n':>4s}  {'thrust N':>15s}  {'mean power W':>15s}"
          f"  {'peak power W':>15s}  {'wall s':>6s}")
    for name, motion in MOTIONS.items():
        for variant, settings in VARIANTS.items():
            for n in steps:
                figures, wall_s = period_figures(motion, n, settings)
                mean = figures.mean(axis=1)
                spread = np.ptp(figures, axis=1) / np.abs(mean)
                cells = "  ".join(f"{m:7.1f} ({100 * s:3.0f} %)"
                                  for m, s in zip(mean, spread, strict=True))
                print(f"{name:15s} {variant:11s} {n:4d}  {cells}  {wall_s:6.1f}", flush=True)


if __name__ == "__main__":
    main()
