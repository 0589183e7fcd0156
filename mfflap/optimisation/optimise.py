"""Optimisers of the discrete motion: SQP on the penalised objective (exact adjoint gradient,
sigma_P continuation, multi-start) and a hard-constrained IPOPT formulation through CasADi.

Design variables: the N pitch and N heave accelerations of the half cycle and the time step,
scaled by the starting point's magnitudes so that the SQP sees numbers of order one. The time
step is bounded by the period bounds (T = 2 N dt).
"""

from __future__ import annotations

import time
import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import minimize

from mfflap.errors import ConfigError
from mfflap.kinematics.convert import resample
from mfflap.kinematics.discrete import DiscreteMotion
from mfflap.optimisation.bandwidth import band_limited, bandwidth_rows
from mfflap.optimisation.blas_threads import optimiser_blas_threads
from mfflap.optimisation.casadi_objective import symbolic_stages
from mfflap.optimisation.interrupts import interrupts_kept
from mfflap.optimisation.phase import check_phase_can_be_fixed, phase_condition_row
from mfflap.optimisation.problem import FlappingProblem
from mfflap.optimisation.trust_region import TrustRegion
from mfflap.performance import CycleSummary, evaluate_discrete

#: An optimum is flagged when |mean energy residual| exceeds this share of its mean power.
ENERGY_RESIDUAL_SHARE = 0.1
#: ... or when its peak power after resampling to 10 N exceeds P_max by more than this.
RESAMPLED_POWER_MARGIN = 0.05


@dataclass
class OptimisationResult:
    """One optimised motion with how it was found and what it achieves.

    Attributes
    ----------
    motion : DiscreteMotion
        The optimum, or the last iterate when ``converged`` is False.
    method : str
        ``"sqp-penalty"`` or ``"ipopt-constrained"``.
    start : str
        Which starting point led to it.
    converged : bool
    message : str
        The optimiser's own message.
    objective : float
        J of the final motion under the *final* settings.
    history : ndarray
        Objective after each iteration (all continuation stages).
    summary : CycleSummary
        Cycle means at the N samples.
    resampled_max_power : float, W
        Peak input power after resampling the motion to 10 N steps.
    flags : list of str
        Model artefacts the optimum may exploit (empty when none).
    n_iterations : int
    wall_time_s : float
    """

    beta: float
    motion: DiscreteMotion
    method: str
    start: str
    converged: bool
    message: str
    objective: float
    history: np.ndarray
    summary: CycleSummary
    resampled_max_power: float
    flags: list[str] = field(default_factory=list)
    n_iterations: int = 0
    wall_time_s: float = 0.0


def time_step_bounds(n_steps: int, min_period: float, max_period: float) -> tuple[float, float]:
    """dt bounds from period bounds, T = 2 N dt."""
    return min_period / (2 * n_steps), max_period / (2 * n_steps)


def assess(problem: FlappingProblem, motion: DiscreteMotion
           ) -> tuple[CycleSummary, float, list[str]]:
    """Cycle summary, peak power after resampling to 10 N, and artefact flags."""
    ev = evaluate_discrete(problem.model, motion, problem.scheme)  # type: ignore[arg-type]
    s = ev.summary
    fine = resample(motion, 10 * motion.n_steps)
    fine_ev = evaluate_discrete(problem.model, fine, problem.scheme)  # type: ignore[arg-type]
    peak = float(np.max(fine_ev.input_power))
    flags = []
    share = abs(float(s.energy_residual)) / max(abs(float(s.mean_power)), 1e-12)
    if share > ENERGY_RESIDUAL_SHARE:
        flags.append(f"energy residual {float(s.energy_residual):.3g} W is {share:.0%} of the "
                     f"mean power {float(s.mean_power):.3g} W: the scheme's energy error may "
                     "carry the optimum (try scheme = 'midpoint')")
    flag = peak_power_flag(peak, 10 * motion.n_steps, problem.max_power)
    return s, peak, flags + ([flag] if flag else [])


def peak_power_flag(peak: float, n_resampled: int, max_power: float,
                    what: str = "peak power") -> str | None:
    """The artefact flag of a peak power (W, after resampling to ``n_resampled`` steps) over
    ``max_power`` (W) by more than :data:`RESAMPLED_POWER_MARGIN`; None when it is not."""
    if peak <= (1 + RESAMPLED_POWER_MARGIN) * max_power:
        return None
    return (f"{what} {peak:.3g} W after resampling to {n_resampled} steps exceeds P_max "
            f"{max_power:g} W by more than {RESAMPLED_POWER_MARGIN:.0%}: the optimum exploits "
            "the sampling")


def optimise_sqp(problem: FlappingProblem, start: DiscreteMotion, *, min_period: float,
                 max_period: float, continuation: Sequence[float] = (0.01, 0.1, 1.0),
                 max_iterations: int = 400, tolerance: float = 1e-9, start_label: str = "start",
                 callback: Callable[[int, float], None] | None = None,
                 trust_region: TrustRegion | None = None,
                 fix_phase: bool = False,
                 bandwidth_harmonics: int | None = None) -> OptimisationResult:
    """SLSQP on the penalised objective with the exact adjoint gradient.

    The power penalty is raised through ``continuation`` (multipliers of the problem's
    sigma_P, ending at 1): early stages explore, the last one enforces P_max.
    Non-convergence is reported in the result (``converged`` False, the last iterate kept).
    ``trust_region`` bounds every variable to its box
    (:class:`~mfflap.optimisation.trust_region.TrustRegion`); the start is moved into it.
    ``fix_phase`` keeps the pitch's first harmonic at the phase of sin(2 pi t / T), a linear
    equality (:mod:`mfflap.optimisation.phase`): without it the motion's phase is free,
    and where J is flat round-off decides it. ``bandwidth_harmonics`` keeps every iterate
    free of the harmonics above it (linear equalities,
    :mod:`mfflap.optimisation.bandwidth`); the start is projected onto the band first.
    """
    if not continuation or continuation[-1] != 1.0 or any(c <= 0 for c in continuation):
        raise ConfigError(f"continuation {list(continuation)} must be positive multipliers "
                          "ending at 1.0", key="optimisation.continuation")
    n = start.n_steps
    lo, hi = time_step_bounds(n, min_period, max_period)
    dt0 = float(np.clip(start.time_step, lo, hi))
    start = DiscreteMotion(start.pitch_acceleration, start.heave_acceleration, dt0)
    if bandwidth_harmonics is not None:
        start = band_limited(start, bandwidth_harmonics)
    scale = start.control_scales()
    bounds = [(None, None)] * (2 * n) + [(lo / scale[-1], hi / scale[-1])]
    x = np.real(start.controls()) / scale
    if trust_region is not None:
        lower, upper = trust_region.bounds(n, (lo, hi))
        bounds = list(zip(lower / scale, upper / scale, strict=True))
        x = np.clip(x, lower / scale, upper / scale)
    constraints = list(_phase_constraints(start, start_label) if fix_phase else ())
    if bandwidth_harmonics is not None:
        rows = bandwidth_rows(n, bandwidth_harmonics) * scale  # on the scaled variables
        if rows.size:
            constraints.append({"type": "eq", "fun": lambda xs, rows=rows: rows @ xs,
                                "jac": lambda xs, rows=rows: rows})
    history: list[float] = []
    t0 = time.perf_counter()
    converged, message, iterations = False, "not run", 0
    for mult in continuation:
        stage = replace_problem(problem, penalty_power=problem.penalty_power * mult)

        def fun(xs, stage=stage):
            j, g = stage.packed_value_and_gradient(xs * scale)
            return j, g * scale

        def record(xs, stage=stage):
            history.append(stage.packed_value_and_gradient(xs * scale, False)[0])
            if callback is not None:
                callback(len(history), history[-1])

        with warnings.catch_warnings(), optimiser_blas_threads():
            warnings.simplefilter("ignore", RuntimeWarning)
            res = minimize(fun, x, jac=True, method="SLSQP", bounds=bounds, callback=record,
                           constraints=constraints,
                           options={"maxiter": max_iterations, "ftol": tolerance})
        x = res.x
        converged, message = bool(res.success), str(res.message)
        iterations += int(res.nit)
    motion = DiscreteMotion.from_controls(x * scale)
    summary, peak, flags = assess(problem, motion)
    return OptimisationResult(problem.beta, motion, "sqp-penalty", start_label, converged,
                              message, float(problem.objective(motion)), np.array(history),
                              summary, peak, flags, iterations, time.perf_counter() - t0)


def _phase_constraints(start: DiscreteMotion, start_label: str) -> list[dict]:
    """SLSQP's form of the phase condition on the packed, scaled variables (the pitch
    accelerations share one scale, so the row holds for the scaled ones alike)."""
    check_phase_can_be_fixed(start, start_label)
    n = start.n_steps
    row = np.concatenate([phase_condition_row(n), np.zeros(n + 1)])
    return [{"type": "eq", "fun": lambda xs: np.array([row @ xs]),
             "jac": lambda xs: row[None, :]}]


def replace_problem(problem: FlappingProblem, **changes) -> FlappingProblem:
    """A copy of ``problem`` with some settings changed (validated again)."""
    kw = {k: getattr(problem, k) for k in ("beta", "max_power", "max_heave", "penalty_power",
                                           "penalty_heave", "smoothing_pitch",
                                           "smoothing_heave", "scheme", "compiled",
                                           "max_pitch", "max_pitch_rate",
                                           "max_pitch_acceleration", "penalty_pitch",
                                           "linear_modifier", "sample_offsets")}
    kw.update(changes)
    return FlappingProblem(problem.model, **kw)


_IPOPT_CACHE: dict[tuple, object] = {}


def _ipopt_solver(problem: FlappingProblem, n: int, max_iterations: int, tolerance: float,
                  fix_phase: bool = False):
    """The IPOPT NLP for N steps of this model and scheme, built once and cached.

    The scaling, beta, P_max, h_max, the smoothing weights and the linear modifier's
    gradient (:class:`~mfflap.optimisation.problem.LinearModifier`) are NLP parameters, so one
    build (the expensive part: CasADi's exact Hessian graph) serves a whole beta sweep and
    every multi-start. With a pitch envelope the pitch angle and rate are constrained too
    (their limits are bounds given at the solve); with ``fix_phase`` the phase condition is
    the last constraint (:mod:`mfflap.optimisation.phase`).
    """
    # CasADi loads its compiled libraries: only the IPOPT path needs it
    import casadi as ca

    m = problem.model
    envelope = _has_state_envelope(problem)
    key = (n, problem.scheme, tuple(sorted(m.coefficients.items())), m.geometry,
           m.fluid, m.stream, max_iterations, tolerance, envelope, fix_phase)
    if key in _IPOPT_CACHE:
        return _IPOPT_CACHE[key]
    e = symbolic_stages(problem, n)
    xs = ca.SX.sym("x", 2 * n + 1)
    par = ca.SX.sym("p", 4 * n + 7)
    scale, beta, eps_p, eps_h = par[: 2 * n + 1], par[2 * n + 1], par[2 * n + 4], par[2 * n + 5]
    modifier = par[2 * n + 6:]  # g of the linear modifier (its constant does not move x)
    sub = ca.Function("sub", [e["z"]], [e["thrust"], e["power"], e["heave_position"],
                                        e["pitch_acceleration"], e["heave_acceleration"],
                                        e["pitch_angle"], e["pitch_rate"]])
    thrust, power, hp, tdd, hdd, th, td = sub(xs * scale)
    smooth = 0
    for eps, acc in ((eps_p, tdd), (eps_h, hdd)):
        d = acc[1:] - acc[:-1]
        smooth = smooth + 0.5 * eps * (ca.sumsqr(d) + (acc[0] + acc[n - 1]) ** 2)
    f = (ca.sum1(-(1 - beta) * thrust + beta * power) / n + smooth
         + ca.dot(modifier, xs * scale))
    g = ca.vertcat(power - par[2 * n + 2], hp, *((th, td) if envelope else ()),
                   *((ca.dot(ca.DM(phase_condition_row(n)), xs[:n]),) if fix_phase else ()))
    solver = ca.nlpsol("mfflap_ipopt", "ipopt", {"x": xs, "f": f, "g": g, "p": par},
                       {"ipopt.print_level": 0, "print_time": False, "ipopt.sb": "yes",
                        "ipopt.max_iter": max_iterations, "ipopt.tol": tolerance})
    _IPOPT_CACHE[key] = solver
    return solver


def _has_state_envelope(problem: FlappingProblem) -> bool:
    """Whether the pitch angle or rate is limited (IPOPT then constrains both)."""
    return bool(np.isfinite(problem.max_pitch) or np.isfinite(problem.max_pitch_rate))


def optimise_ipopt(problem: FlappingProblem, start: DiscreteMotion, *, min_period: float,
                   max_period: float, max_iterations: int = 1000, tolerance: float = 1e-8,
                   start_label: str = "start", trust_region: TrustRegion | None = None,
                   fix_phase: bool = False) -> OptimisationResult:
    """Hard constraints P_in,j <= P_max and |h_j| <= h_max, and the pitch envelope's
    |theta_j| <= theta_max, |thetadot_j| <= thetadot_max, |thetaddot_j| <= thetaddot_max
    where it is given, solved by IPOPT (CasADi).

    The objective is the same beta-weighted mean with the smoothness term (and the linear
    modifier) and no penalties.
    ``trust_region`` bounds the variables to its box, and ``fix_phase`` fixes the phase,
    as in :func:`optimise_sqp`.
    """
    n = start.n_steps
    if problem.sample_offsets is not None:
        raise ConfigError("IPOPT's constrained problem does not take sample offsets; "
                          "optimise a problem with them by optimise_sqp",
                          key="optimisation.solver")
    if fix_phase:
        check_phase_can_be_fixed(start, start_label)
    lo, hi = time_step_bounds(n, min_period, max_period)
    dt0 = float(np.clip(start.time_step, lo, hi))
    start = DiscreteMotion(start.pitch_acceleration, start.heave_acceleration, dt0)
    scale = start.control_scales()
    t0 = time.perf_counter()
    solver = _ipopt_solver(problem, n, max_iterations, tolerance, fix_phase)
    modifier = problem.linear_modifier
    if modifier is not None and modifier.n_steps != n:
        raise ConfigError(f"the objective's linear modifier is for N = {modifier.n_steps} "
                          f"steps, the start has {n}", key="linear_modifier")
    par = np.concatenate([scale, [problem.beta, problem.max_power, problem.max_heave,
                                  problem.smoothing_pitch, problem.smoothing_heave],
                          np.zeros(2 * n + 1) if modifier is None else modifier.gradient])
    bounds_g = [(np.full(n, -np.inf), np.zeros(n)),
                (np.full(n, -problem.max_heave), np.full(n, problem.max_heave))]
    if _has_state_envelope(problem):
        bounds_g += [(np.full(n, -limit), np.full(n, limit))
                     for limit in (problem.max_pitch, problem.max_pitch_rate)]
    if fix_phase:
        bounds_g.append((np.zeros(1), np.zeros(1)))
    lbg = np.concatenate([b[0] for b in bounds_g])
    ubg = np.concatenate([b[1] for b in bounds_g])
    lbx = np.full(2 * n + 1, -np.inf)
    ubx = np.full(2 * n + 1, np.inf)
    lbx[-1], ubx[-1] = lo / scale[-1], hi / scale[-1]
    # the pitch accelerations are the controls: their limit is a bound
    lbx[:n] = -problem.max_pitch_acceleration / scale[:n]
    ubx[:n] = problem.max_pitch_acceleration / scale[:n]
    if trust_region is not None:
        lower, upper = trust_region.bounds(n, (lo, hi))
        lbx, ubx = np.maximum(lbx, lower / scale), np.minimum(ubx, upper / scale)
        if np.any(lbx > ubx):
            raise ConfigError(f"the trust region about {trust_region.source or 'its centre'} "
                              "lies outside the pitch acceleration limit "
                              f"{problem.max_pitch_acceleration:g} rad/s^2",
                              key="trust_region")
    x0 = np.clip(np.real(start.controls()) / scale, lbx, ubx)
    # a Ctrl-C stops the solve and the caller, not only IPOPT
    with interrupts_kept(), optimiser_blas_threads():
        sol = solver(x0=x0, p=par, lbx=lbx, ubx=ubx, lbg=lbg, ubg=ubg)
    stats = solver.stats()
    motion = DiscreteMotion.from_controls(np.asarray(sol["x"]).ravel() * scale)
    summary, peak, flags = assess(problem, motion)
    hard = replace_problem(problem, penalty_power=0.0, penalty_heave=0.0, penalty_pitch=0.0)
    return OptimisationResult(problem.beta, motion, "ipopt-constrained", start_label,
                              bool(stats.get("success", False)),
                              str(stats.get("return_status", "")),
                              float(hard.objective(motion)), np.array([float(sol["f"])]),
                              summary, peak, flags, int(stats.get("iter_count", 0)),
                              time.perf_counter() - t0)


def multistart(problem: FlappingProblem, starts: Sequence[tuple[str, DiscreteMotion]], *,
               min_period: float, max_period: float,
               progress: Callable[[str], None] | None = None, label: str | None = None,
               **kwargs) -> tuple[OptimisationResult, list[OptimisationResult]]:
    """SQP from each start; the best result (lowest J, converged first) and all of them.

    ``label`` names the problem in the progress lines (default ``beta <beta>``).
    """
    if not starts:
        raise ConfigError("multistart needs at least one starting motion")
    results = []
    name = label or f"beta {problem.beta:g}"
    for start_label, motion in starts:
        res = optimise_sqp(problem, motion, min_period=min_period, max_period=max_period,
                           start_label=start_label, **kwargs)
        results.append(res)
        if progress is not None:
            progress(f"{name} from {start_label}: J = {res.objective:.4g}, "
                     f"thrust {float(res.summary.mean_thrust):.3g} N, "
                     f"{'converged' if res.converged else 'NOT converged'}")
    best = min(results, key=lambda r: (not r.converged, r.objective))
    return best, results


__all__ = ["OptimisationResult", "assess", "multistart", "optimise_ipopt", "optimise_sqp",
           "peak_power_flag", "replace_problem", "time_step_bounds"]
