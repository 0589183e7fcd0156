"""One beta optimisation from the best sinusoid to convergence (target < 0.5 s at N = 50),
free and with the phase fixed (optimisation.phase = "fixed"),
and identification over the whole 125-case grid (target < 2 s), also with the residual
scaling chosen by the errors ("auto").

It also times one SQP optimisation beside a busy core on one BLAS thread (the optimisers'
own limit) and on the BLAS library's own thread count.

Run: python benchmarks/optimiser_and_identification.py
Each time is also printed as a ratio against a baseline measured in the same process (one
objective + adjoint gradient evaluation; one model evaluation of the grid), so the numbers
can be compared between machines.
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np

from mfflap.campaign.cases import grid_cases
from mfflap.config import IdentificationGrid, load_case
from mfflap.hydro.loads import Loads
from mfflap.identification import identify, prepare_cases
from mfflap.kinematics.convert import harmonic_to_discrete
from mfflap.optimisation.optimise import optimise_ipopt, optimise_sqp
from mfflap.optimisation.study import problem_for
from mfflap.records.record import CfdRecord

CASE = Path(__file__).parents[1] / "cases" / "paper2026.toml"


def optimiser() -> None:
    case = load_case(CASE)
    o = case.optimisation
    start = harmonic_to_discrete(2.1, 0.05, np.deg2rad(50), np.deg2rad(112.5), o.n_steps)
    print(f"one optimisation from a sinusoid, N = {o.n_steps} (target < 0.5 s)")
    print("beta  method            iterations  time [s]  time / (J + grad) eval   target met")
    for beta in o.betas:
        problem = problem_for(case, beta)
        if beta == o.betas[0]:  # one-off costs (imports, loading the compiled kernels)
            t0 = time.perf_counter()
            optimise_sqp(problem, start, min_period=o.min_period, max_period=o.max_period)
            print(f"      (first SQP run in the process, with one-off imports and kernel "
                  f"loading: {time.perf_counter() - t0:.2f} s)")
        t0 = time.perf_counter()
        for _ in range(20):
            problem.objective(start)
            problem.gradient(start)
        eval_time = (time.perf_counter() - t0) / 20
        if beta == o.betas[0]:
            for fixed in (False, True):
                t0 = time.perf_counter()
                optimise_ipopt(problem, start, min_period=o.min_period,
                               max_period=o.max_period, fix_phase=fixed)
                print(f"      (IPOPT NLP build with CasADi's exact Hessian, once per N and "
                      f"model{', phase fixed' if fixed else ''}: "
                      f"{time.perf_counter() - t0:.2f} s including the first solve)")
        # the phase fixed (optimisation.phase = "fixed"): one linear equality more
        for name, fn, fixed in (("SQP (adjoint)", optimise_sqp, False),
                                ("SQP, phase fixed", optimise_sqp, True),
                                ("IPOPT (cached)", optimise_ipopt, False),
                                ("IPOPT, ph. fixed", optimise_ipopt, True)):
            t0 = time.perf_counter()
            r = fn(problem, start, min_period=o.min_period, max_period=o.max_period,
                   fix_phase=fixed)
            dt = time.perf_counter() - t0
            print(f"{beta:4.2f}  {name:16s}  {r.n_iterations:10d}  {dt:8.3f}  "
                  f"{dt / eval_time:10.0f}              {'yes' if dt < 0.5 else 'NO'}")


def optimiser_beside_a_busy_core() -> None:
    """One SQP optimisation while another process keeps a core busy (as a CFD run does),
    on one BLAS thread (what the optimisers limit themselves to) and on the library's own
    count; the ratio says what the limit saves."""
    import statistics
    import subprocess
    import sys

    from threadpoolctl import threadpool_info

    from mfflap.optimisation import blas_threads

    case = load_case(CASE)
    o = case.optimisation
    start = harmonic_to_discrete(2.1, 0.05, np.deg2rad(50), np.deg2rad(112.5), o.n_steps)
    problem = problem_for(case, 0.0)
    optimise_sqp(problem, start, min_period=o.min_period, max_period=o.max_period)  # warm
    own = max((lib["num_threads"] for lib in threadpool_info()
               if lib["user_api"] == "blas"), default=1)
    busy = subprocess.Popen([sys.executable, "-c", "while True: pass"])
    times: dict[str, list[float]] = {"one BLAS thread": [], f"{own} BLAS threads": []}
    try:
        for _ in range(5):
            for label, threads in (("one BLAS thread", 1), (f"{own} BLAS threads", None)):
                blas_threads.OPTIMISER_BLAS_THREADS = threads
                t0 = time.perf_counter()
                optimise_sqp(problem, start, min_period=o.min_period,
                             max_period=o.max_period)
                times[label].append(time.perf_counter() - t0)
    finally:
        blas_threads.OPTIMISER_BLAS_THREADS = 1
        busy.kill()
        busy.wait()
    one, lib = (statistics.median(v) for v in times.values())
    print(f"\none SQP optimisation (beta = 0) beside a busy core, median of 5: one BLAS "
          f"thread {one:.3f} s, the library's {own} thread(s) {lib:.3f} s; "
          f"ratio {lib / one:.2f}")


def identification() -> None:
    rng = np.random.default_rng(0)
    case = load_case(CASE)
    model = case.morison_model()
    records = []
    t0 = time.perf_counter()
    for c in grid_cases(IdentificationGrid()):
        t = np.linspace(0, c.duration, 1500)
        s = c.motion().sample(t)
        ld = model.loads(s)
        noisy = [getattr(ld, k) * (1 + 0.05 * rng.standard_normal(len(t)))
                 for k in ("normal_force", "tangential_force", "moment")]
        records.append(CfdRecord(c.case_id, s, Loads(t, *noisy), c.as_dict()))
    baseline = time.perf_counter() - t0
    t0 = time.perf_counter()
    cases, _ = prepare_cases(records)
    prep = time.perf_counter() - t0
    t0 = time.perf_counter()
    identify(cases, model, "uniform", n_bootstrap=200)
    fit = time.perf_counter() - t0
    total = prep + fit
    print(f"\nidentification over {len(cases)} cases (target < 2 s): preparation {prep:.3f} s, "
          f"fit + 200 bootstrap replicates + scoring {fit:.3f} s, total {total:.3f} s "
          f"({total / baseline:.2f} x the time to evaluate the model on the grid); "
          f"target met: {'yes' if total < 2 else 'NO'}")
    t0 = time.perf_counter()
    auto = identify(cases, model, "uniform", n_bootstrap=200, residual_scaling="auto")
    auto_fit = time.perf_counter() - t0
    print(f"the same with residual_scaling = \"auto\" (a fit on the grid's scale, the error "
          f"growth measured, and here, the noise being a share of the loads, a refit with "
          f"\"{auto.residual_scaling}\"): {auto_fit:.3f} s, {auto_fit / fit:.2f} x the fit "
          f"above; total {prep + auto_fit:.3f} s, target met: "
          f"{'yes' if prep + auto_fit < 2 else 'NO'}")


if __name__ == "__main__":
    optimiser()
    optimiser_beside_a_busy_core()
    identification()
