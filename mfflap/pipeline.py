"""The main job, ``mfflap run``: identification -> sinusoid sweep -> optimisation for each
beta -> where the motions lie against the identification data -> back-test against CFD ->
gap diagnosis (its effect checked on the back-tests) -> coefficient sensitivity -> one HTML
report and one HDF5 file with every number and the inputs.

Each stage ends in a :class:`StageOutcome` (done, failed with an mfflap error, or
interrupted). A stage that fails with an mfflap error (bad input, a CFD run that failed, a
fit that cannot be made) is reported and the run goes on with the rest; the report says what
is missing and why. Any other exception is a fault in mfflap, not in the input: it ends the
run with its traceback.
"""

from __future__ import annotations

import json
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path

import numpy as np

from mfflap.backtest.baseline import CfdBaseline, cfd_baseline
from mfflap.backtest.store import safe_label, write_backtests
from mfflap.backtest.workflow import backtest_all
from mfflap.cfd.openfoam.case_path import check_case_path
from mfflap.cfd.openfoam.setups import case_mesh_and_solver
from mfflap.cfd.openfoam.writer import SolverSettings
from mfflap.config import CaseConfig
from mfflap.errors import ConfigError, MfflapError
from mfflap.gap.store import write_diagnosis
from mfflap.gap.transfer import held_out_motions
from mfflap.gap.workflow import diagnose_cases
from mfflap.identification.coverage import CoverageReference
from mfflap.identification.error_growth import scaling_advice
from mfflap.identification.store import write_identification
from mfflap.identification.workflow import identify_strategies, load_cases
from mfflap.kinematics.convert import to_spline
from mfflap.optimisation.gradcheck import gradient_checks
from mfflap.optimisation.optimise import optimise_sqp
from mfflap.optimisation.output_correction import OutputCorrection, check_gain
from mfflap.optimisation.store import (
    beta_key,
    beta_label,
    polished_label,
    write_polish,
    write_result,
)
from mfflap.optimisation.study import (
    StudyInterrupted,
    beta_study,
    gain_table,
    problem_for,
    sinusoid_motion,
)
from mfflap.optimisation.workflow import write_study
from mfflap.records.inputs import input_mismatches
from mfflap.records.record import (
    backtest_fixture_dirs,
    fixture_dir,
    identification_fixture_dirs,
    read_records,
)
from mfflap.results import ResultsFile

Progress = Callable[[str], None]

#: how a stage ended
DONE, FAILED, INTERRUPTED = "done", "failed", "interrupted"


@dataclass(frozen=True)
class StageOutcome:
    """How one stage of the main job ended.

    Attributes
    ----------
    name : str
        The stage ("identification", "optimisation", "back-test", ...).
    status : str
        :data:`DONE`, :data:`FAILED` (an mfflap error, ``problem`` says which) or
        :data:`INTERRUPTED` (Ctrl-C).
    seconds : float
        Wall time it took, s.
    problem : str
        What failed, '' when it did not.
    """

    name: str
    status: str
    seconds: float
    problem: str = ""

#: the frequency weightings the main job identifies, one coefficient set each
RUN_STRATEGIES = ("uniform", "low", "high")


#: the folder of a run's output that holds its live back-tests' records (fixtures that
#: ``--backtest-fixtures`` reads back)
BACKTEST_RECORDS = "backtest_records"


#: N per half cycle of the main job's gradient check (half a second; `mfflap gradcheck`
#: checks at any N)
GRADIENT_CHECK_STEPS = 20


@dataclass
class RunOptions:
    """Options of the main job."""

    fixtures: tuple[Path, ...] = ()  # identification record folders (default: table1_coarse)
    backtest_fixtures: tuple[Path, ...] = ()  # default: shipped backtest folder
    live: bool = False  # run the back-test CFD with OpenFOAM
    work_dir: Path = Path("mfflap_run_cases")
    #: where a live back-test's record is written, as ``backtest_<key>.h5`` (None: kept in
    #: the results only)
    save_to: Path | None = None
    coefficients: str = "case"  # "case" or "identified:<strategy>"
    n_starts: int = 3
    with_ipopt: bool = True
    gain_table: bool = False
    sensitivity: bool = True
    vtk_dir: Path | None = None
    #: mesh and solver settings of a live back-test (None: the case's ``[cfd]`` set-up,
    #: :func:`~mfflap.cfd.openfoam.setups.case_mesh_and_solver`)
    mesh: str | None = None
    solver: SolverSettings | None = None
    #: periods a live back-test runs (:func:`~mfflap.backtest.run.backtest_motion`)
    backtest_cycles: float = 3.0
    #: whole cycles the back-test's CFD and model means are taken over (1: the last)
    average_cycles: int = 1
    #: a live back-test's retries rerun it from t = 0 s: one set-up throughout
    #: (:func:`~mfflap.cfd.openfoam.run_motion.run_motion`)
    retries_from_start: bool = False
    #: keep the optimisation within what the identification cases reach
    #: (:func:`within_data_config`)
    within_data: bool = False
    #: live, back-test records run before on this set-up, taken instead of a new run (the
    #: rounds' own records, :mod:`mfflap.rounds`)
    done_backtests: tuple[Path, ...] = ()
    #: beta -> a motion with its CFD means: that beta is optimised with the model's outputs
    #: corrected to predict them (:mod:`mfflap.optimisation.output_correction`; the rounds'
    #: ``rounds.correct_outputs``)
    correct_at: dict = field(default_factory=dict)
    #: polish each optimum on the discrete-vortex model and back-test the polish (the
    #: rounds do not: their CFD corrects the model itself each round)
    polish: bool = True
    #: K of the first-order filter from each point's scales to the measured ones (1: none;
    #: :meth:`~mfflap.optimisation.output_correction.OutputCorrection.filtered`)
    correction_gain: float = 1.0
    #: beta -> earlier motions of that beta with their CFD means
    #: (:class:`~mfflap.optimisation.output_correction.CorrectionPoint`): its corrected
    #: objective (``correct_at``) gets a slope that makes it CFD's there too
    #: (:meth:`~mfflap.optimisation.output_correction.OutputCorrection.with_slopes`; the
    #: rounds' ``first_order``)
    secant_at: dict = field(default_factory=dict)
    #: beta -> the trust region that beta's optimum is kept in
    #: (:class:`~mfflap.optimisation.trust_region.TrustRegion`; the rounds' ``trust_radius``)
    trust_at: dict = field(default_factory=dict)

    @classmethod
    def for_case(cls, config: CaseConfig, out_dir: Path, *,
                 fixtures: tuple[Path, ...] = (), backtest_fixtures: tuple[Path, ...] = (),
                 live: bool = False) -> RunOptions:
        """The options of the main job as ``config``'s [optimisation] and [backtest] tables
        say, writing under ``out_dir``.

        Examples
        --------
        >>> from mfflap.config import CaseConfig
        >>> options = RunOptions.for_case(CaseConfig(), Path("demo_run"))
        >>> options.coefficients, options.average_cycles, options.backtest_cycles
        ('identified:uniform', 2, 3.5)
        """
        opt, backtest = config.optimisation, config.backtest
        spec, solver = case_mesh_and_solver(config.cfd, config.source)
        return cls(fixtures=fixtures, backtest_fixtures=backtest_fixtures, live=live,
                   mesh=spec.name, solver=solver,
                   work_dir=out_dir / "cfd_cases", vtk_dir=out_dir / "vtk",
                   # rounds keep their records in their own folder (mfflap.rounds)
                   save_to=(out_dir / BACKTEST_RECORDS if live and config.rounds.count == 1
                            else None),
                   coefficients=("case" if opt.coefficients == "case"
                                 else f"identified:{opt.coefficients}"),
                   n_starts=opt.starts, with_ipopt=opt.ipopt, gain_table=opt.gain_table,
                   within_data=opt.within_data, backtest_cycles=backtest.simulated_periods,
                   average_cycles=backtest.average_cycles,
                   retries_from_start=config.cfd.retries_from_start)

    def __post_init__(self) -> None:
        allowed = ["case", *(f"identified:{s}" for s in RUN_STRATEGIES)]
        if self.coefficients not in allowed:
            raise ConfigError(f"{self.coefficients!r} is not a coefficient set of the run; "
                              f"use one of {', '.join(allowed)}", key="coefficients")
        if self.n_starts < 1:
            raise ConfigError(f"n_starts must be >= 1, got {self.n_starts!r}", key="n_starts")

        check_gain(self.correction_gain)
        if self.live:  # the live back-test's cases go there: refused before the first stage

            check_case_path(self.work_dir)


@dataclass
class RunOutcome:
    """What the main job produced, and what it could not."""

    identification: dict = field(default_factory=dict)
    study: object | None = None
    gain: dict | None = None
    backtests: dict = field(default_factory=dict)
    sensitivity: dict = field(default_factory=dict)
    #: beta -> the adjoint gradient's check at the case's sinusoid
    #: (:func:`~mfflap.optimisation.gradcheck.gradient_checks`; the paper's Fig. 6)
    gradient_checks: dict = field(default_factory=dict)
    problems: list[str] = field(default_factory=list)
    timings: dict[str, float] = field(default_factory=dict)
    cases: list = field(default_factory=list)
    model: object | None = None
    gap: tuple | None = None
    #: per optimised motion (and the best sinusoid): where it lies against the
    #: identification data (:class:`~mfflap.identification.coverage.Coverage`)
    coverage: dict = field(default_factory=dict)
    #: the case as the stages ran it (with ``within_data``, its optimisation limited to the
    #: identification data); None before the identification
    config: CaseConfig | None = None
    #: the limits ``within_data`` set: setting -> value
    within_data_limits: dict = field(default_factory=dict)
    #: the stage a Ctrl-C stopped (the later ones did not run), or None
    interrupted: str | None = None
    #: beta -> the output correction measured for it (``RunOptions.correct_at``)
    corrections: dict = field(default_factory=dict)
    #: label -> the discrete motion back-tested under it (the best sinusoid, each beta's)
    backtest_motions: dict = field(default_factory=dict)
    #: every stage that ran, in order, with how it ended
    stages: list[StageOutcome] = field(default_factory=list)
    #: label -> CFD, Morison and the discrete-vortex model on its back-test
    #: (:class:`~mfflap.backtest.model_ladder.LadderComparison`)
    ladder: dict = field(default_factory=dict)
    #: beta -> its optimum polished on the discrete-vortex model
    #: (:class:`~mfflap.optimisation.vortex_polish.PolishResult`)
    polished: dict = field(default_factory=dict)
    #: the weighting whose identified coefficients the optimisation used, or None when it
    #: used the case file's
    optimised_with: str | None = None
    #: the best sinusoid within P_max in CFD, from the shipped runs of this case's plate,
    #: fluid and stream (:mod:`mfflap.backtest.baseline`); None where none was run for them
    cfd_baseline: CfdBaseline | None = None


def _stage(outcome: RunOutcome, name: str, progress: Progress, fn):
    """Run one stage, keeping how it ended in ``outcome.stages``; its result, or None when it
    failed with an mfflap error. Any other exception propagates: a fault, not bad input."""
    t0 = time.perf_counter()
    progress(f"[{name}] started")

    def ended(status: str, problem: str = "") -> None:
        seconds = time.perf_counter() - t0
        outcome.stages.append(StageOutcome(name, status, seconds, problem))
        outcome.timings[name] = seconds
        if problem:
            outcome.problems.append(f"{name}: {problem}")

    try:
        result = fn()
    except KeyboardInterrupt:  # run_study ends the run with the stages so far
        outcome.interrupted = name
        ended(INTERRUPTED, f"interrupted (Ctrl-C) after {time.perf_counter() - t0:.1f} s; "
                           "the later stages did not run")
        raise
    except MfflapError as exc:
        ended(FAILED, str(exc))
        progress(f"[{name}] FAILED: {exc}")
        return None
    ended(DONE)
    progress(f"[{name}] done in {outcome.timings[name]:.1f} s")
    return result


def coefficient_sensitivity(config: CaseConfig, identification: dict, sweep,
                            progress: Progress) -> dict:
    """Re-optimise beta = 0 with each weighting strategy's coefficients (Figure 5)."""
    o = config.optimisation
    out = {}
    base = config.morison_model()
    for label, res in identification.items():
        model = res.model(base)
        start = sinusoid_motion(sweep, sweep.best_feasible(), o.n_steps)
        r = optimise_sqp(problem_for(config, 0.0, model), start, min_period=o.min_period,
                         max_period=o.max_period, start_label="best sinusoid",
                         fix_phase=o.fix_phase)
        out[label] = (model, r)
        progress(f"sensitivity {label}: thrust {float(r.summary.mean_thrust):.3g} N, "
                 f"period {float(r.motion.period):.3g} s")
    return out


def within_data_config(config: CaseConfig, cases: list, reference=None
                       ) -> tuple[CaseConfig, dict]:
    """The case with its optimisation limited to what ``cases`` reach: the pitch amplitude,
    peak pitch rate and acceleration of the pitch envelope, the period bounds and the
    heave limit (each the tighter of the case's own and the data's; the case's period
    bounds where the data's frequencies lie outside them); and those settings."""
    reference = reference or CoverageReference.from_cases(cases, config.morison_model(),
                                                          config.flow.velocity)
    ranges = reference.ranges
    o = config.optimisation

    def tighter(current, data):
        return data if current is None else min(current, data)

    limits = {"max_pitch_deg": tighter(o.max_pitch_deg, ranges["pitch amplitude"][1]),
              "max_pitch_rate": tighter(o.max_pitch_rate, ranges["peak |pitch rate|"][1]),
              "max_pitch_acceleration": tighter(o.max_pitch_acceleration,
                                                ranges["peak |pitch acceleration|"][1]),
              "max_heave": min(o.max_heave, ranges["heave amplitude"][1])}
    if "frequency" in ranges:
        lo, hi = ranges["frequency"]
        limits["min_period"] = max(o.min_period, 1.0 / hi)
        limits["max_period"] = min(o.max_period, 1.0 / lo)
        if limits["min_period"] >= limits["max_period"]:  # the data's and the case's apart
            limits["min_period"], limits["max_period"] = o.min_period, o.max_period
    return replace(config, optimisation=replace(o, **limits)), limits


def motion_coverage(config: CaseConfig, cases: list, motions: dict, reference=None) -> dict:
    """Where each motion, as CFD imposes it (the periodic spline through its cycle), lies
    against the identification cases (:mod:`mfflap.identification.coverage`; ``reference``
    their :class:`~mfflap.identification.coverage.CoverageReference`, built if not given)."""
    reference = reference or CoverageReference.from_cases(cases, config.morison_model(),
                                                          config.flow.velocity)
    out = {}
    for label, motion in motions.items():
        spline = to_spline(motion)
        t = np.linspace(0.0, spline.period, 400, endpoint=False)
        out[label] = reference.check(spline.sample(t), 1.0 / spline.period)
    return out


def gap_diagnosis(config: CaseConfig, cases: list, backtests: dict | None = None) -> tuple:
    """Diagnosis and residual decomposition of the case's model on the identification CFD;
    with back-tests, whether its effect carries over to their CFD runs (the motions the fits
    never saw)."""
    records = [o.record for o in (backtests or {}).values() if o.record is not None]
    held_out, excluded = (held_out_motions(records, config.identification.discard_time,
                                           plate=config.plate, fluid=config.fluid,
                                           stream=config.flow) if records else (None, None))
    diag, where, _ = diagnose_cases(config, cases, held_out=held_out,
                                    held_out_excluded=excluded)
    return diag, where


def run_study(config: CaseConfig, options: RunOptions, progress: Progress = print
              ) -> RunOutcome:
    """Run every stage; failures are collected in ``outcome.problems``.

    A Ctrl-C (KeyboardInterrupt) ends the run: the outcome holds the stages finished before
    it, names the stage it stopped in ``outcome.interrupted`` and is returned, so that they
    can still be written (live back-test cases resume from their last written times when
    run again).
    """
    outcome = RunOutcome()
    try:
        _run_stages(config, options, progress, outcome)
    except KeyboardInterrupt:
        if outcome.interrupted is None:  # between two stages
            outcome.interrupted = "between stages"
            outcome.problems.append("interrupted (Ctrl-C) between stages; the later stages "
                                    "did not run")
    return outcome


@dataclass
class RunContext:
    """What the stages of one run share: its inputs, the outcome they fill, and what one
    stage hands the next (the model the optimisation uses, the identification data's
    coverage)."""

    config: CaseConfig
    options: RunOptions
    progress: Progress
    outcome: RunOutcome
    #: the model the optimisation uses: the case's coefficients, or identified ones
    model: object = None
    #: the identification data's coverage, built once by its stage (None before it)
    reference: CoverageReference | None = None


@dataclass(frozen=True)
class Stage:
    """One stage of the main job: its name (as progress lines and the results file give
    it), what it does with the run's context, and whether it runs in this one."""

    name: str
    run: Callable[[RunContext], None]
    runs_when: Callable[[RunContext], bool] = lambda ctx: True


def _identify(ctx: RunContext) -> None:
    folders = ctx.options.fixtures or identification_fixture_dirs()
    cases, excluded = load_cases(ctx.config, folders)
    for name, why in excluded.items():
        ctx.outcome.problems.append(f"identification: case {name} left out: {why}")
    ctx.outcome.cases = cases
    ctx.outcome.identification = identify_strategies(ctx.config, cases, excluded,
                                                     list(RUN_STRATEGIES))


def _choose_model(ctx: RunContext) -> None:
    """The optimisation's model: the case's coefficients, or the identified ones asked for
    (a problem said when the identification did not give them)."""
    outcome, options = ctx.outcome, ctx.options
    if outcome.identification:  # whether the fit weighs the runs as their errors say
        first = next(iter(outcome.identification.values()))
        ctx.progress(f"identification ({first.strategy} weighting): "
                     f"{scaling_advice(first.error_growth, first.residual_scaling)}")
    ctx.model = ctx.config.morison_model()
    if options.coefficients.startswith("identified:"):
        strategy = options.coefficients.split(":", 1)[1]
        if strategy in outcome.identification:
            ctx.model = outcome.identification[strategy].model(ctx.model)
            outcome.optimised_with = strategy
        else:
            outcome.problems.append(f"optimisation: no identified coefficients for strategy "
                                    f"{strategy!r}; used the case's coefficients")
    outcome.model = ctx.model
    outcome.config = ctx.config


def _coverage_reference(ctx: RunContext) -> None:
    ctx.reference = CoverageReference.from_cases(ctx.outcome.cases, ctx.config.morison_model(),
                                                 ctx.config.flow.velocity)


def _keep_within_data(ctx: RunContext) -> None:
    """With ``within_data``, the optimisation limited to the identification data's reach."""
    if not ctx.options.within_data:
        return
    outcome = ctx.outcome
    if ctx.reference is not None:
        ctx.config, outcome.within_data_limits = within_data_config(ctx.config, outcome.cases,
                                                                    ctx.reference)
        outcome.config = ctx.config
        ctx.progress("optimisation kept within the identification data: " + ", ".join(
            f"{k} = {v:.4g}" for k, v in outcome.within_data_limits.items()))
    else:
        why = ("the identification data's coverage failed (above)" if outcome.cases
               else "there are no identification cases")
        outcome.problems.append("optimisation: not kept within the identification data "
                                f"(asked): {why}")


def _measure_corrections(ctx: RunContext) -> None:
    options, scheme = ctx.options, ctx.config.optimisation.scheme
    out = {}
    for beta, point in options.correct_at.items():
        corr = OutputCorrection.measured(point, ctx.model, scheme).filtered(
            point.scales, options.correction_gain)
        if beta in options.secant_at:
            corr = corr.with_slopes(point.motion, options.secant_at[beta],
                                    problem_for(ctx.config, beta, ctx.model))
        out[beta] = corr
    ctx.outcome.corrections = out


def _optimise(ctx: RunContext) -> None:
    options, outcome = ctx.options, ctx.outcome
    try:
        outcome.study = beta_study(ctx.config, n_starts=options.n_starts,
                                   with_ipopt=options.with_ipopt, model=ctx.model,
                                   progress=ctx.progress, corrections=outcome.corrections,
                                   trust_regions=options.trust_at)
    except StudyInterrupted as exc:  # the betas finished before it are written
        outcome.study = exc.study
        outcome.problems.append(f"optimisation: {exc.study.interruption}")
        raise


def _polish(ctx: RunContext) -> None:
    # the discrete-vortex model loads its compiled kernel (numba) when it first runs
    from mfflap.optimisation.vortex_polish_study import polish_optima

    ctx.outcome.polished = polish_optima(ctx.config, ctx.outcome.study.sqp, ctx.model,
                                         ctx.progress)


def _gain_table(ctx: RunContext) -> None:
    ctx.outcome.gain = gain_table(ctx.config, model=ctx.model, sweep=ctx.outcome.study.sweep,
                                  progress=ctx.progress)


def _motions_to_backtest(ctx: RunContext) -> None:
    """The motions to back-test once the optimisation gave them: the best sinusoid, each
    beta's optimum and its polish on the discrete-vortex model."""
    study = ctx.outcome.study
    if study is None:
        return
    n = ctx.config.optimisation.n_steps
    motions = {"best sinusoid": sinusoid_motion(study.sweep, study.best_sinusoid, n)}
    motions.update({beta_label(b): r.motion for b, r in study.sqp.items()})
    motions.update({polished_label(b): r.motion for b, r in ctx.outcome.polished.items()
                    if r.moved_from(study.sqp[b].motion)})
    ctx.outcome.backtest_motions = motions


def _motion_coverage(ctx: RunContext) -> None:
    outcome = ctx.outcome
    outcome.coverage = motion_coverage(ctx.config, outcome.cases, outcome.backtest_motions,
                                       ctx.reference)
    for label, cov in outcome.coverage.items():
        ctx.progress(f"{label}: {cov.describe()}")


def _backtest(ctx: RunContext) -> None:
    options = ctx.options
    folders = list(options.backtest_fixtures) or backtest_fixture_dirs()
    mesh, solver = options.mesh, options.solver
    if mesh is None or solver is None:  # the case's [cfd] set-up for what is not given
        spec, case_solver = case_mesh_and_solver(ctx.config.cfd, ctx.config.source)
        mesh, solver = mesh or spec.name, solver or case_solver
    backtest_all(ctx.config, ctx.outcome.backtest_motions, ctx.model, fixture_folders=folders,
                 live=options.live, work_dir=options.work_dir, mesh=mesh, solver=solver,
                 progress=ctx.progress,
                 # those done before a failure or Ctrl-C are kept in outcome.backtests
                 into=ctx.outcome.backtests, done_folders=options.done_backtests,
                 n_cycles=options.backtest_cycles, average_cycles=options.average_cycles,
                 retries_from_start=options.retries_from_start, save_to=options.save_to)


#: the shipped CFD runs of sinusoids near the power limit (the CFD baseline's)
BASELINE_FIXTURES = "baseline_sinusoids"


def _cfd_baseline(ctx: RunContext) -> None:
    config = ctx.config
    records = [r for r in read_records(fixture_dir(BASELINE_FIXTURES))
               if not input_mismatches(r, config.plate, config.fluid, config.flow)]
    if not records:
        ctx.progress("CFD baseline: no shipped sinusoid was run for this case's plate, fluid "
                     "and stream")
        return
    baseline = cfd_baseline(records, config.optimisation.max_power)
    ctx.outcome.cfd_baseline = baseline
    best = baseline.best
    ctx.progress(f"CFD baseline: {len(records)} sinusoid(s) in CFD; best within P_max: "
                 + (best.said() if best is not None else "none holds it"))


def _say_what_was_not_backtested(ctx: RunContext) -> None:
    for label, o in ctx.outcome.backtests.items():
        if o.status != "back-tested":
            ctx.outcome.problems.append(f"back-test: {label} not back-tested: {o.source}")


def _model_ladder(ctx: RunContext) -> None:
    # the discrete-vortex model loads its compiled kernel (numba) when it first runs
    from mfflap.backtest.model_ladder import compare_model_ladder

    config = ctx.config
    for label, o in ctx.outcome.backtests.items():
        if o.record is None or o.comparison is None:
            continue
        ladder = compare_model_ladder(o.record, ctx.model, config.vortex, plate=config.plate,
                                      fluid=config.fluid, stream=config.flow)
        ctx.outcome.ladder[label] = ladder
        ctx.progress(f"model ladder, {label}: peak power CFD {ladder.cfd.peak_power:.3g} W, "
                     f"Morison {ladder.morison.peak_power:.3g} W, discrete-vortex model "
                     f"{ladder.vortex.peak_power:.3g} W")


def _diagnose(ctx: RunContext) -> None:
    outcome = ctx.outcome
    outcome.gap = gap_diagnosis(ctx.config, outcome.cases, outcome.backtests)
    ctx.progress(f"gap diagnosis: {outcome.gap[0].verdict}")
    if outcome.gap[0].transfer is not None:
        ctx.progress(f"gap diagnosis, on the back-tested motions: "
                     f"{outcome.gap[0].transfer.verdict}")


def _check_gradient(ctx: RunContext) -> None:
    ctx.outcome.gradient_checks = gradient_checks(ctx.config, GRADIENT_CHECK_STEPS)
    worst = max(max(c.controls_error_complex_step, c.time_step_error_complex_step)
                for c in ctx.outcome.gradient_checks.values())
    ctx.progress(f"gradient check: largest relative error against complex step {worst:.1e}")


def _sensitivity(ctx: RunContext) -> None:
    ctx.outcome.sensitivity = coefficient_sensitivity(ctx.config, ctx.outcome.identification,
                                                      ctx.outcome.study.sweep, ctx.progress)


def _export_vtk(ctx: RunContext) -> None:
    # pyvista takes seconds to load: only a VTK export needs it
    from mfflap.export.vtk import export_motion

    for label, m in ctx.outcome.backtest_motions.items():
        safe = label.replace(" ", "_").replace("=", "").replace("β", "beta")
        export_motion(ctx.options.vtk_dir, m, ctx.model, ctx.config.optimisation.scheme, safe)


def _optimised(ctx: RunContext) -> bool:
    return ctx.outcome.study is not None


#: the main job in order: its stages (each timed, ending in a :class:`StageOutcome`) and
#: the bookkeeping between them (plain functions of the run's context)
STAGES: tuple[Stage | Callable[[RunContext], None], ...] = (
    Stage("identification", _identify),
    _choose_model,
    Stage("identification coverage", _coverage_reference,
          lambda ctx: bool(ctx.outcome.cases)),
    _keep_within_data,
    Stage("output correction", _measure_corrections,
          lambda ctx: bool(ctx.options.correct_at)),
    Stage("optimisation", _optimise),
    Stage("vortex polish", _polish, lambda ctx: _optimised(ctx) and ctx.options.polish),
    Stage("gradient check", _check_gradient),
    Stage("gain table", _gain_table, lambda ctx: _optimised(ctx) and ctx.options.gain_table),
    _motions_to_backtest,
    Stage("motions against the identification data", _motion_coverage,
          lambda ctx: _optimised(ctx) and ctx.reference is not None),
    Stage("back-test", _backtest, _optimised),
    _say_what_was_not_backtested,
    Stage("CFD baseline", _cfd_baseline),
    Stage("model ladder", _model_ladder,
          lambda ctx: any(o.record is not None for o in ctx.outcome.backtests.values())),
    # after the back-test: its runs are the ones the fits never saw
    Stage("gap diagnosis", _diagnose, lambda ctx: bool(ctx.outcome.cases)),
    Stage("coefficient sensitivity", _sensitivity,
          lambda ctx: (_optimised(ctx) and ctx.options.sensitivity
                       and bool(ctx.outcome.identification))),
    Stage("VTK export", _export_vtk,
          lambda ctx: _optimised(ctx) and ctx.options.vtk_dir is not None),
)


def _run_stages(config: CaseConfig, options: RunOptions, progress: Progress,
                outcome: RunOutcome) -> None:
    """The :data:`STAGES` of :func:`run_study`, in order, filling ``outcome``."""
    ctx = RunContext(config, options, progress, outcome)
    for step in STAGES:
        if not isinstance(step, Stage):
            step(ctx)
        elif step.runs_when(ctx):
            _stage(outcome, step.name, progress, lambda step=step: step.run(ctx))


#: the model ladder's figures in the results file, each over (CFD, Morison, vortex model)
LADDER_UNITS = {"mean_thrust": "N", "mean_power": "W", "peak_power": "W",
                "normal_force_nrmse": "1"}


def write_results(config: CaseConfig, outcome: RunOutcome, h5_path: Path) -> None:
    """One HDF5 file with every number of the run and its inputs (the report beside it:
    :func:`mfflap.reports.run.write_run_outputs`)."""
    with ResultsFile(h5_path, "w", kind="run", config_toml=config.to_toml()) as rf:
        for res in outcome.identification.values():
            write_identification(rf, res)
        if outcome.study is not None:
            write_study(rf, config, outcome.study, outcome.gain, outcome.model)
        write_backtests(rf, outcome.backtests)
        for label, cov in outcome.coverage.items():
            rf.write_group(f"coverage/{safe_label(label)}", {}, {}, {"label": label,
                                                        "coverage": json.dumps(cov.as_dict())})
        for label, (_, r) in outcome.sensitivity.items():
            write_result(rf, f"sensitivity/{label}/{beta_key(0.0)}", r)
        for beta, check in outcome.gradient_checks.items():
            rf.write_group(f"gradient_check/{beta_key(beta)}",
                           {"adjoint": check.adjoint, "complex_step": check.complex_step,
                            "finite_difference": check.finite_difference},
                           dict.fromkeys(("adjoint", "complex_step", "finite_difference"),
                                         "dJ/du_j, then dJ/d(dt)"),
                           {"beta": beta, **check.as_dict()})
        for beta, polished in outcome.polished.items():
            write_polish(rf, f"polished/{beta_key(beta)}", polished, beta)
        for label, ladder in outcome.ladder.items():
            levels = ("cfd", "morison", "vortex")
            rf.write_group(f"model_ladder/{safe_label(label)}", {
                f"{figure}": [getattr(getattr(ladder, level), figure) for level in levels]
                for figure in LADDER_UNITS}, LADDER_UNITS,
                {"label": label, "record": ladder.name, "levels": json.dumps(levels),
                 "periods": ladder.periods})
        if outcome.gap is not None:
            write_diagnosis(rf, *outcome.gap)
        if outcome.cfd_baseline is not None:
            rf.write_group("cfd_baseline", {}, {},
                           {"baseline": json.dumps(outcome.cfd_baseline.as_dict())})
        rf.h5.attrs["problems"] = "\n".join(outcome.problems)
        rf.h5.attrs["stage_times_s"] = str(outcome.timings)
        rf.h5.attrs["stages"] = json.dumps([asdict(stage) for stage in outcome.stages])
        rf.h5.attrs["interrupted_stage"] = outcome.interrupted or ""  # "": ran to the end


__all__ = ["DONE", "FAILED", "INTERRUPTED", "RunOptions", "RunOutcome", "StageOutcome", "run_study",
           "write_results"]
