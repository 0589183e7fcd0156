"""The paper's optimisation study: best feasible sinusoid, beta sweep of optimised motions
(multi-start SQP, IPOPT comparison), the thrust gain and its dependence on N and smoothing."""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field, replace

import numpy as np

from mfflap.config import CaseConfig, OptimisationSettings
from mfflap.errors import ConfigError
from mfflap.kinematics.convert import harmonic_to_discrete, resample
from mfflap.kinematics.discrete import DiscreteMotion
from mfflap.optimisation.optimise import (
    OptimisationResult,
    multistart,
    optimise_ipopt,
    optimise_sqp,
    peak_power_flag,
)
from mfflap.optimisation.output_correction import OutputCorrection
from mfflap.optimisation.problem import FlappingProblem
from mfflap.optimisation.refine import (
    RefinedSinusoid,
    refine_best_sinusoid,
    sinusoid_pitch_margins,
)
from mfflap.optimisation.trust_region import TrustRegion
from mfflap.performance import no_thrust_gain_reason, thrust_gain
from mfflap.sweep import SweepResult, pareto_front, sinusoid_sweep

Progress = Callable[[str], None]


def problem_for(config: CaseConfig, beta: float, model=None,
                settings: OptimisationSettings | None = None) -> FlappingProblem:
    """The penalised problem of a case at one beta."""
    o = settings or config.optimisation
    return FlappingProblem(model or config.morison_model(), beta, o.max_power, o.max_heave,
                           o.penalty_power, o.penalty_heave, o.smoothing_pitch,
                           o.smoothing_heave, o.scheme, **o.pitch_envelope(),
                           penalty_pitch=o.penalty_pitch)


def default_sweep(config: CaseConfig, model=None, progress: Progress | None = None
                  ) -> SweepResult:
    """Sinusoids over f (within the period bounds, at most 3 Hz), h_amp up to h_max, pitch
    amplitude 0-60 deg and phase 0-180 deg, at the optimiser's N."""
    o = config.optimisation
    f_hi = min(1.0 / o.min_period, 3.0)
    f_lo = max(1.0 / o.max_period, 0.05)
    freqs = np.geomspace(f_lo, f_hi, 28)
    heaves = np.linspace(0.05, o.max_heave, 10)
    pitches = np.deg2rad(np.linspace(0.0, 60.0, 13))
    phases = np.deg2rad(np.linspace(0.0, 180.0, 9))

    def report(done, total):
        if progress is not None and (done == total or done % 20000 == 0):
            progress(f"sinusoid sweep {done}/{total}")

    sweep = sinusoid_sweep(model or config.morison_model(), freqs, heaves, pitches, phases,
                           n_steps=o.n_steps, max_power=o.max_power, scheme=o.scheme,
                           progress=report)
    inside = within_pitch_envelope(sweep.frequency, sweep.pitch_amplitude,
                                   **o.pitch_envelope())
    return sweep if inside.all() else replace(sweep, feasible=sweep.feasible & inside)


def within_pitch_envelope(frequency, pitch_amplitude, max_pitch: float = np.inf,
                          max_pitch_rate: float = np.inf,
                          max_pitch_acceleration: float = np.inf) -> np.ndarray:
    """Whether sinusoids theta = theta_a sin(2 pi f t) keep within the pitch envelope: their
    amplitude theta_a, peak rate w theta_a and peak acceleration w^2 theta_a (w = 2 pi f)
    at most the limits (rad, rad/s, rad/s^2; inf: none)."""
    return np.all(sinusoid_pitch_margins(frequency, pitch_amplitude, max_pitch, max_pitch_rate,
                                         max_pitch_acceleration) >= 0, axis=0)


def sinusoid_motion(sweep: SweepResult, index: int, n_steps: int) -> DiscreteMotion:
    """The discrete motion of one swept sinusoid."""
    return harmonic_to_discrete(sweep.frequency[index], sweep.heave_amplitude[index],
                                sweep.pitch_amplitude[index], sweep.phase[index], n_steps)


def starting_points(sweep: SweepResult, n_steps: int, n_starts: int
                    ) -> list[tuple[str, DiscreteMotion]]:
    """The best feasible sinusoid and up to n_starts - 1 others spread along the feasible
    Pareto front."""
    best = sweep.best_feasible()
    feas = np.flatnonzero(sweep.feasible)
    front = feas[pareto_front(sweep.mean_thrust[feas], sweep.mean_power[feas])]
    picks = [best]
    if n_starts > 1 and len(front):
        for i in front[np.unique(np.linspace(0, len(front) - 1, n_starts - 1).round()
                                 .astype(int))]:
            if i not in picks:
                picks.append(int(i))
    labels = []
    for i in picks[:n_starts]:
        tag = "best sinusoid" if i == best else "Pareto sinusoid"
        labels.append((f"{tag} f={sweep.frequency[i]:.3g} Hz h={sweep.heave_amplitude[i]:.3g}"
                       f" m th={np.rad2deg(sweep.pitch_amplitude[i]):.0f} deg "
                       f"phi={np.rad2deg(sweep.phase[i]):.0f} deg",
                       sinusoid_motion(sweep, i, n_steps)))
    return labels


@dataclass
class BetaStudy:
    """Optimised motions for each beta, with the sinusoid baseline."""

    sweep: SweepResult
    best_sinusoid: int
    sqp: dict[float, OptimisationResult]
    sqp_all: dict[float, list[OptimisationResult]]
    ipopt: dict[float, OptimisationResult] = field(default_factory=dict)
    refined: RefinedSinusoid | None = None
    #: the beta whose optimisation a Ctrl-C (or SIGTERM) stopped, or None
    interrupted_beta: float | None = None
    #: the betas asked for but not optimised because of that interrupt (the stopped one
    #: first); their partial results are not kept
    betas_not_optimised: tuple[float, ...] = ()
    #: beta -> the output correction its optimisation used
    #: (:class:`~mfflap.optimisation.output_correction.OutputCorrection`); none: the model's
    corrections: dict = field(default_factory=dict)
    #: beta -> the trust region its optimum was kept in
    #: (:class:`~mfflap.optimisation.trust_region.TrustRegion`); none: unbounded
    trust_regions: dict = field(default_factory=dict)

    @property
    def interruption(self) -> str | None:
        """What an interrupt left out, in words (None when the study ran to its end)."""
        if self.interrupted_beta is None:
            return None
        done = ", ".join(f"{b:g}" for b in self.sqp) or "none"
        return (f"interrupted during beta = {self.interrupted_beta:g}: beta "
                f"{', '.join(f'{b:g}' for b in self.betas_not_optimised)} not optimised "
                f"(optimised: {done})")

    @property
    def thrust_gain(self) -> float | None:
        """beta = 0 mean-thrust gain over the best feasible sinusoid of the grid (fraction);
        None when beta = 0 was not optimised or that sinusoid makes no thrust
        (:attr:`no_thrust_gain_reason` says which)."""
        if 0.0 not in self.sqp:
            return None
        return thrust_gain(float(self.sqp[0.0].summary.mean_thrust),
                           float(self.sweep.mean_thrust[self.best_sinusoid]))

    @property
    def thrust_gain_refined(self) -> float | None:
        """beta = 0 gain over the refined best feasible sinusoid (fraction); None as
        :attr:`thrust_gain`, or without a refined sinusoid."""
        if 0.0 not in self.sqp or self.refined is None:
            return None
        return thrust_gain(float(self.sqp[0.0].summary.mean_thrust), self.refined.mean_thrust)

    @property
    def no_thrust_gain_reason(self) -> str | None:
        """Why :attr:`thrust_gain` is None (None when it is a number)."""
        if 0.0 not in self.sqp:
            return "beta = 0 was not optimised"
        base = float(self.sweep.mean_thrust[self.best_sinusoid])
        if self.thrust_gain is None:
            return no_thrust_gain_reason(base, "the best feasible sinusoid")
        return None

    @property
    def thrust_gain_caveat(self) -> str | None:
        """Why :attr:`thrust_gain`, a number, is in doubt: the beta = 0 optimum it is
        computed from did not converge or was flagged (None when neither, or when there is
        no gain)."""
        if self.thrust_gain is None:
            return None
        result = self.sqp[0.0]
        doubts = ([] if result.converged else ["did not converge"]) + \
            ([f"is flagged ({len(result.flags)} flag{'s' if len(result.flags) > 1 else ''})"]
             if result.flags else [])
        if 0.0 in self.corrections:
            doubts.append("was optimised with the model's outputs corrected from CFD (its "
                          "power limit is not the best sinusoid's)")
        if 0.0 in self.trust_regions:
            doubts.append("was kept in a trust region about an earlier optimum")
        if not doubts:
            return None
        return (f"the beta = 0 optimum it is computed from {' and '.join(doubts)}: the gain "
                "inherits that doubt")


class StudyInterrupted(KeyboardInterrupt):
    """A Ctrl-C (or a stop signal) during a beta study's optimisations.

    It is a KeyboardInterrupt, so whatever does not know it stops as on Ctrl-C; a caller
    that does finds the betas finished before it in :attr:`study` (with the sweep and the
    refined sinusoid), to write them before it stops.

    Attributes
    ----------
    study : BetaStudy
        The betas whose SQP (and IPOPT, when asked) finished;
        :attr:`BetaStudy.interrupted_beta` and :attr:`BetaStudy.betas_not_optimised` say
        what was left out.
    """

    def __init__(self, study: BetaStudy) -> None:
        super().__init__(study.interruption)
        self.study = study


def beta_study(config: CaseConfig, betas: Sequence[float] | None = None, n_starts: int = 3,
               with_ipopt: bool = True, model=None, sweep: SweepResult | None = None,
               progress: Progress | None = None,
               corrections: Mapping[float, OutputCorrection] | None = None,
               trust_regions: Mapping[float, TrustRegion] | None = None) -> BetaStudy:
    """Best feasible sinusoid, then multi-start SQP (and IPOPT) for each beta.

    ``corrections`` (beta -> :class:`OutputCorrection`) optimise those betas with the
    model's thrust and power scaled as CFD measured them; the sweep and the best sinusoid
    stay the model's own. ``trust_regions`` (beta -> :class:`TrustRegion`) keep those betas'
    optima within their boxes, SQP and IPOPT started from the centre alone.

    Raises
    ------
    ConfigError
        Before any work, if a beta is outside [0, 1] or ``n_starts`` is below 1.
    StudyInterrupted
        On a Ctrl-C (or a stop signal) during the optimisations, holding the betas
        finished before it; during the sweep, a plain KeyboardInterrupt.
    """
    o = config.optimisation
    model = model or config.morison_model()
    if n_starts < 1:
        raise ConfigError(f"n_starts must be >= 1 (the best sinusoid is the first start), got "
                          f"{n_starts!r}", key="n_starts")
    corrections = dict(corrections or {})
    trust_regions = dict(trust_regions or {})
    problems = {beta: problem_for(config, beta, model)
                for beta in (betas if betas is not None else o.betas)}
    for what, key, given in (("output corrections", "corrections", corrections),
                             ("trust regions", "trust_regions", trust_regions)):
        unknown = sorted(set(given) - set(problems))
        if unknown:
            raise ConfigError(f"{what} for beta {unknown} that are not optimised "
                              f"(betas {list(problems)})", key=key)
    for beta, corr in corrections.items():
        problems[beta] = corr.problem(problems[beta])
        if progress is not None:
            progress(f"beta {beta:g} optimised with the model's outputs corrected: "
                     f"{corr.describe()}")
    sweep = sweep if sweep is not None else default_sweep(config, model, progress)
    best = sweep.best_feasible()
    starts = starting_points(sweep, o.n_steps, n_starts)
    refined = refine_best_sinusoid(model, sweep, o.n_steps, o.max_power, o.max_heave,
                                   o.min_period, o.max_period, o.scheme,
                                   pitch_envelope=o.pitch_envelope())
    if progress is not None:
        progress(f"refined best feasible sinusoid: f = {refined.frequency:.4g} Hz, h = "
                 f"{refined.heave_amplitude:.4g} m, mean thrust {refined.mean_thrust:.4g} N "
                 f"(grid {refined.grid_thrust:.4g} N)")
    sqp, sqp_all, ipopt = {}, {}, {}
    for beta, problem in problems.items():
        region = trust_regions.get(beta)
        own_starts = starts if region is None else [
            (f"trust-region centre ({region.source or 'given'}, radius {region.radius:.3g})",
             region.centre)]
        try:
            found, found_all = multistart(
                problem, own_starts, min_period=o.min_period, max_period=o.max_period,
                progress=progress, trust_region=region, fix_phase=o.fix_phase,
                label=f"beta {beta:g}" + (
                    " (outputs corrected; J over c)" if beta in corrections else "")
                + ("" if region is None else f" (trust region {region.radius:.3g})"))
            found_ipopt = optimise_ipopt(problem, own_starts[0][1], min_period=o.min_period,
                                         max_period=o.max_period,
                                         start_label=own_starts[0][0], trust_region=region,
                                         fix_phase=o.fix_phase) if with_ipopt else None
            if beta in corrections:  # the case's beta, the corrected J (not J / c)
                corr = corrections[beta]
                found, found_ipopt = (_corrected(r, beta, corr, problem)
                                      for r in (found, found_ipopt))
                found_all = [_corrected(r, beta, corr, problem) for r in found_all]
        except KeyboardInterrupt as exc:  # keep the betas finished; this one is dropped
            left = tuple(list(problems)[list(problems).index(beta):])
            raise StudyInterrupted(BetaStudy(sweep, best, sqp, sqp_all, ipopt, refined,
                                             interrupted_beta=beta,
                                             betas_not_optimised=left,
                                             corrections=corrections,
                                             trust_regions=trust_regions)) from exc
        sqp[beta], sqp_all[beta] = found, found_all
        if found_ipopt is not None:
            ipopt[beta] = found_ipopt
            if progress is not None:
                progress(f"beta {beta:g} IPOPT (hard constraints): thrust "
                         f"{float(found_ipopt.summary.mean_thrust):.3g} N, {found_ipopt.message}")
    return BetaStudy(sweep, best, sqp, sqp_all, ipopt, refined, corrections=corrections,
                     trust_regions=trust_regions)


def _corrected(result: OptimisationResult | None, beta: float, correction: OutputCorrection,
               problem: FlappingProblem) -> OptimisationResult | None:
    """A result of an output-corrected ``problem`` (the equivalent one) labelled with the
    case's beta, its objective and history the corrected J (c times the equivalent
    problem's), and its peak-power flag in corrected watts against the case's P_max (the
    same test: kappa_P peak > margin kappa_P P_max')."""
    if result is None:
        return None
    c, k_p = correction.objective_factor(beta), correction.power_scale
    n_fine = 10 * result.motion.n_steps
    own = peak_power_flag(result.resampled_max_power, n_fine, problem.max_power)
    flags = [f for f in result.flags if f != own]
    if own is not None and own in result.flags:
        flags.append(str(peak_power_flag(k_p * result.resampled_max_power, n_fine,
                                         k_p * problem.max_power, "corrected peak power")))
    return replace(result, beta=beta, objective=c * result.objective,
                   history=c * np.asarray(result.history), flags=flags)


def gain_table(config: CaseConfig, n_steps: Sequence[int] = (25, 50, 100),
               smoothing_factors: Sequence[float] = (0.1, 1.0, 10.0), model=None,
               sweep: SweepResult | None = None, progress: Progress | None = None
               ) -> dict[str, np.ndarray]:
    """beta = 0 thrust gain over the best feasible sinusoid for several N and smoothing
    weights (both epsilons scaled by the factor), each from the best sinusoid.

    Returns arrays ``gain`` (n_N, n_factors; NaN where the best sinusoid makes no thrust),
    ``thrust`` N, ``strouhal_number``, ``flagged``.
    """
    model = model or config.morison_model()
    sweep = sweep if sweep is not None else default_sweep(config, model, progress)
    best = sweep.best_feasible()
    base = float(sweep.mean_thrust[best])
    shape = (len(n_steps), len(smoothing_factors))
    out = {k: np.full(shape, np.nan) for k in ("gain", "thrust", "strouhal_number")}
    out["flagged"] = np.zeros(shape, dtype=bool)
    o = config.optimisation
    for i, n in enumerate(n_steps):
        start = resample(sinusoid_motion(sweep, best, o.n_steps), n)
        for j, fac in enumerate(smoothing_factors):
            settings = replace(o, n_steps=n, smoothing_pitch=o.smoothing_pitch * fac,
                               smoothing_heave=o.smoothing_heave * fac)
            problem = problem_for(config, 0.0, model, settings)
            r = optimise_sqp(problem, start, min_period=o.min_period, max_period=o.max_period,
                             fix_phase=o.fix_phase)
            out["thrust"][i, j] = float(r.summary.mean_thrust)
            gain = thrust_gain(out["thrust"][i, j], base)
            out["gain"][i, j] = np.nan if gain is None else gain
            out["strouhal_number"][i, j] = float(r.summary.strouhal_number)
            out["flagged"][i, j] = bool(r.flags)
            if progress is not None:
                shown = (f"{gain:+.1%}" if gain is not None
                         else f"thrust {out['thrust'][i, j]:.4g} N (no gain: "
                         f"{no_thrust_gain_reason(base, 'the best feasible sinusoid')})")
                doubt = ([] if r.converged else ["not converged"]) + (["flagged"] if r.flags
                                                                     else [])
                progress(f"gain table N={n} smoothing x{fac:g}: {shown}"
                         + (f" ({', '.join(doubt)})" if doubt else ""))
    out["n_steps"] = np.asarray(n_steps)
    out["smoothing_factors"] = np.asarray(smoothing_factors)
    out["baseline_thrust"] = np.asarray(base)
    return out
