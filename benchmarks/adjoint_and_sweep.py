"""Gradient cost over forward cost at several N, and sinusoidal-sweep throughput.

Run: python benchmarks/adjoint_and_sweep.py
Every number is a ratio against a baseline measured in the same process.
"""

from __future__ import annotations

import time

import numpy as np
from timing import best_of

from mfflap.hydro import MorisonModel
from mfflap.kinematics import harmonic_to_discrete
from mfflap.optimisation import FlappingProblem
from mfflap.sweep import sinusoid_sweep


def main() -> None:
    model = MorisonModel()
    problem = FlappingProblem(model, beta=0.5, max_power=50.0)
    print("N        forward [s]   gradient [s]   gradient/forward")
    base = None
    for n in (50, 500, 5000, 50000):
        d = harmonic_to_discrete(1.0, 0.3, 0.35, np.pi / 2, n)
        fwd = best_of(lambda d=d: problem.objective(d))
        grad = best_of(lambda d=d: problem.gradient(d))
        base = base or grad
        print(f"{n:<8d} {fwd:12.3e}  {grad:12.3e}   {grad / fwd:6.2f}   "
              f"(gradient time / N=50 gradient time: {grad / base:8.1f})")
    from mfflap.optimisation.casadi_objective import build_objective

    for n in (50, 500):
        d = harmonic_to_discrete(1.0, 0.3, 0.35, np.pi / 2, n)
        _, grad = build_objective(problem, n)
        z = np.concatenate([d.pitch_acceleration, d.heave_acceleration, [d.time_step]])
        t_ca = best_of(lambda grad=grad, z=z: grad(z))
        t_adj = best_of(lambda d=d: problem.gradient(d))
        print(f"N={n}: CasADi reverse-mode gradient / adjoint gradient = {t_ca / t_adj:.2f} "
              "(target >= 2)")
    small = np.linspace(0.1, 2, 20), np.linspace(0.05, 0.5, 10), np.linspace(0, 1, 10), \
        np.linspace(0, np.pi, 10)
    t0 = time.perf_counter()
    res = sinusoid_sweep(model, *small, n_steps=50, compiled=False)
    array_rate = res.mean_thrust.size / (time.perf_counter() - t0)
    sinusoid_sweep(model, *small, n_steps=50)  # load (or compile) the kernel once
    big = np.linspace(0.1, 2, 100), np.linspace(0.05, 0.5, 40), np.linspace(0, 1, 25), \
        np.linspace(0, np.pi, 10)
    t0 = time.perf_counter()
    res = sinusoid_sweep(model, *big, n_steps=50)
    elapsed = time.perf_counter() - t0
    rate = res.mean_thrust.size / elapsed
    print(f"sweep: {res.mean_thrust.size:,} sinusoids at N=50 in {elapsed:.2f} s = "
          f"{rate:,.0f} motions/s with the compiled kernel ({rate / array_rate:.0f}x the "
          f"array version's {array_rate:,.0f}/s; target 1e6/s: ratio {rate / 1e6:.2f})")


if __name__ == "__main__":
    main()
