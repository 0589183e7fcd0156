"""CFD in the loop: rounds of the main job (``mfflap run --rounds N``).

The model optimises its motions where it has never been checked (three of the four shipped
optima lie outside the identification data, :mod:`mfflap.identification.coverage`), and
the back-test says by how much it is wrong there. Each round here feeds that CFD back: it
runs the whole main job (:func:`mfflap.pipeline.run_study`) with the identification data
pooled with the back-test records of every round before, so the model is refitted on the
motions it optimised, optimises again, and is back-tested on the new optima, which its fit
has not seen. The rounds stop when

- the model predicts the CFD mean thrust and mean input power of every back-tested motion
  of the round within the tolerance (converged),
- the round's optimised motions are those of an earlier round (a fixed point: the next round
  would fit the same data; with filtered output corrections, not a stop: the filter still
  moves the scales),
- a motion could not be back-tested, or the identification or optimisation failed (the next
  round would learn nothing new), or Ctrl-C stopped the round,
- or the rounds asked for are done.

The back-test records of every round are kept in ``<out>/loop_records`` (one per motion);
they are looked up before the shipped fixtures and, live, before a new OpenFOAM run, so a
motion repeated from an earlier round is not run again and the same command run again (after
a Ctrl-C) finds the CFD done before.

With ``refit`` False (``--no-refit``) or the case file's coefficients, the back-tests are
not pooled into the fits: every round optimises with round 1's coefficients, and only the
output correction learns from the CFD (the classical modifier adaptation of a fixed model).

With ``correct_outputs`` (``--correct-outputs``), round k >= 2 also corrects the model's
outputs: each beta is optimised with the model's mean thrust and power scaled to predict
the CFD means of round k - 1's optimum of that beta, measured with round k's refitted model
(:mod:`mfflap.optimisation.output_correction`), and the error counted is that of the
corrected prediction, the one the optimiser relied on. If the rounds reach a fixed point,
the corrected model predicts CFD's means there. With ``correction_gain`` K < 1
(``--correction-gain``), the scales move only that fraction of the way from those the last
optimum was optimised with to the measured ones (a first-order filter, the usual cure for
the oscillation of the undamped correction).

The prediction checked is made of the model's means as the optimiser saw them (at the
motion's N samples of its scheme, :func:`mfflap.performance.discrete_means`), the ones the
correction's scales are measured with, so that at a fixed point it is CFD's exactly; the
back-test reports keep the model on the kinematics CFD imposed, which differs by the
scheme's discretisation.

With ``trust_radius`` (``--trust-region``), each round's optimum of a beta is kept near the
last one CFD confirmed (:mod:`mfflap.optimisation.trust_region`); the rounds then converge
only where no optimum is on its region's boundary and no step was refused, and stop when a
region collapses. With ``first_order`` (``--first-order``) the corrected objective also gets
a slope through the earlier back-tested motions of the beta near the centre, so that it is
CFD's objective there too
(:meth:`~mfflap.optimisation.output_correction.OutputCorrection.with_slopes`); the predicted
means stay the scaled ones.

Only motions whose CFD the round's fit has not seen count (a motion repeated from an earlier
round is in the fit). A motion's mean thrust error counts only where its CFD mean thrust is at least
:data:`THRUST_FLOOR` of the largest CFD mean thrust among the round's motions: a motion of
almost no net thrust (beta = 1) has a relative thrust error of no meaning. Its power error
counts.
"""

from __future__ import annotations

import json
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from mfflap.config import CaseConfig
from mfflap.errors import ConfigError
from mfflap.optimisation.trust_region import MIN_RADIUS

Progress = Callable[[str], None]

#: a motion's relative mean thrust error counts where its CFD mean thrust is at least this
#: fraction of the largest CFD mean thrust among the round's back-tested motions
THRUST_FLOOR = 0.05

#: the folder (inside the output folder) holding the back-test records the rounds pool
RECORDS_FOLDER = "loop_records"


@dataclass
class MotionCheck:
    """The model against CFD on one back-tested motion of a round.

    Attributes
    ----------
    cfd_mean_thrust, model_mean_thrust : N (the model's own on the kinematics CFD imposed,
        as the back-test compares them)
    cfd_mean_power, model_mean_power : W (likewise)
    thrust_error, power_error : (prediction - CFD) / |CFD| of the means
    thrust_counted : whether the thrust error counts (:data:`THRUST_FLOOR`)
    in_fit : whether the fit of this round had already seen this motion's CFD
    thrust_scale, power_scale : the output correction the motion was optimised with (1: none);
        the prediction is the optimiser's mean times it
    optimised_mean_thrust, optimised_mean_power : N, W, the model's means as the optimiser
        saw them (:func:`~mfflap.performance.discrete_means`: at the motion's N samples, the
        ones the correction's scales are measured with); NaN where not known, the
        back-test's model means then stand in
    cfd_record : the name of the CFD record compared ("": not known); another motion's
        (:attr:`cfd_of_neighbour`) where the back-test look-up found one within its tolerance
    """

    label: str
    key: str
    cfd_mean_thrust: float
    model_mean_thrust: float
    cfd_mean_power: float
    model_mean_power: float
    thrust_error: float
    power_error: float
    thrust_counted: bool
    in_fit: bool
    thrust_scale: float = 1.0
    power_scale: float = 1.0
    optimised_mean_thrust: float = float("nan")
    optimised_mean_power: float = float("nan")
    cfd_record: str = ""

    @property
    def cfd_of_neighbour(self) -> bool:
        """Whether the CFD compared is that of a motion within the look-up's tolerance, not of
        this motion itself (its record is named for another key)."""
        return bool(self.cfd_record) and self.cfd_record != f"backtest_{self.key}"

    @property
    def predicted_thrust(self) -> float:
        """N: the mean thrust the optimisation relied on (corrected model)."""
        own = self.optimised_mean_thrust
        return self.thrust_scale * (own if np.isfinite(own) else self.model_mean_thrust)

    @property
    def predicted_power(self) -> float:
        """W: the mean input power the optimisation relied on (corrected model)."""
        own = self.optimised_mean_power
        return self.power_scale * (own if np.isfinite(own) else self.model_mean_power)

    @property
    def error(self) -> float:
        """The largest counted relative error of the means."""
        return max(abs(self.power_error), abs(self.thrust_error) if self.thrust_counted else 0)

    def as_dict(self) -> dict:
        """JSON-friendly."""
        return {"label": self.label, "key": self.key, "cfd_mean_thrust": self.cfd_mean_thrust,
                "model_mean_thrust": self.model_mean_thrust,
                "cfd_mean_power": self.cfd_mean_power,
                "model_mean_power": self.model_mean_power, "thrust_error": self.thrust_error,
                "power_error": self.power_error, "thrust_counted": self.thrust_counted,
                "in_fit": self.in_fit, "error": self.error,
                "thrust_scale": self.thrust_scale, "power_scale": self.power_scale,
                "predicted_thrust": self.predicted_thrust,
                "predicted_power": self.predicted_power,
                "optimised_mean_thrust": _finite_or_none(self.optimised_mean_thrust),
                "optimised_mean_power": _finite_or_none(self.optimised_mean_power),
                "cfd_record": self.cfd_record, "cfd_of_neighbour": self.cfd_of_neighbour}


@dataclass
class RoundSummary:
    """What one round fitted, optimised and found in CFD.

    Attributes
    ----------
    index : 1, 2, ...
    out_dir : the round's report.html and results.h5
    n_cases : CFD runs the round's identification used
    loop_records_in_fit : the earlier rounds' back-test records among them
    coefficients : the coefficients the round optimised with (name -> value)
    checks : per back-tested motion
    not_backtested : label -> why
    corrections : beta -> the output correction the round optimised it with (as a dict)
    trust_steps : beta -> the round's step in that beta's trust region, judged by its CFD
        (:class:`~mfflap.optimisation.trust_region.TrustStep`)
    """

    index: int
    out_dir: Path
    n_cases: int
    loop_records_in_fit: int
    coefficients: dict[str, float]
    checks: dict[str, MotionCheck] = field(default_factory=dict)
    not_backtested: dict[str, str] = field(default_factory=dict)
    corrections: dict[float, dict] = field(default_factory=dict)
    trust_steps: dict = field(default_factory=dict)

    @property
    def largest_error(self) -> float | None:
        """The largest counted error over the back-tested motions whose CFD the round's fit
        had not seen (None: none such)."""
        return max((c.error for c in self.checks.values() if not c.in_fit), default=None)

    def as_dict(self) -> dict:
        """JSON-friendly."""
        return {"round": self.index, "out_dir": str(self.out_dir), "n_cases": self.n_cases,
                "loop_records_in_fit": self.loop_records_in_fit,
                "coefficients": self.coefficients, "largest_error": self.largest_error,
                "checks": {k: c.as_dict() for k, c in self.checks.items()},
                "not_backtested": self.not_backtested,
                "corrections": {f"{b:g}": c for b, c in self.corrections.items()},
                "trust_steps": {f"{b:g}": t.as_dict() for b, t in self.trust_steps.items()}}


@dataclass
class LoopResult:
    """The rounds run and why they stopped."""

    rounds: list[RoundSummary]
    tolerance: float
    converged: bool
    stopped_because: str
    correct_outputs: bool = False
    correction_gain: float = 1.0
    refit: bool = True
    #: the trust region's first radius (None: none)
    trust_radius: float | None = None
    #: with a trust region, beta -> the rounds' answer: the last motion of that beta CFD
    #: confirmed (its region's centre when the rounds stopped), in words with its CFD means
    answers: dict = field(default_factory=dict)
    #: whether the output corrections had slopes through the earlier motions (first order)
    first_order: bool = False
    #: the share by which two CFD runs of one motion differ, as given (None: not known)
    cfd_repeatability: float | None = None

    def as_dict(self) -> dict:
        """JSON-friendly."""
        return {"tolerance": self.tolerance, "converged": self.converged,
                "stopped_because": self.stopped_because,
                "correct_outputs": self.correct_outputs,
                "correction_gain": self.correction_gain, "refit": self.refit,
                "trust_radius": self.trust_radius, "first_order": self.first_order,
                "cfd_repeatability": self.cfd_repeatability,
                "answers": {f"{b:g}": a for b, a in self.answers.items()},
                "rounds": [r.as_dict() for r in self.rounds]}


def check_rounds(n_rounds: int, tolerance: float, coefficients: str,
                 correct_outputs: bool = False, refit: bool = True,
                 trust_radius: float | None = None, first_order: bool = False,
                 correction_gain: float = 1.0, cfd_repeatability: float | None = None
                 ) -> None:
    """Refuse rounds that cannot learn from their CFD.

    Rounds learn by the refit of identified coefficients on the back-tests, by the output
    correction (``correct_outputs``), or both.

    Raises
    ------
    ConfigError
        ``n_rounds`` < 1, ``tolerance`` not in (0, 1), or more than one round where nothing
        learns: neither a refit (the case file's coefficients, or ``refit`` False) nor an
        output correction, so that every round would optimise the same motions; a trust
        region's radius not in (0, :data:`~mfflap.optimisation.trust_region.MAX_RADIUS`], or
        a trust region for one round (it bounds the rounds after the first); slopes
        (``first_order``) without the output correction, its measured scales (gain 1) and a
        trust region; a CFD repeatability not in (0, 1) or without a trust region.
    """
    if n_rounds < 1:
        raise ConfigError(f"--rounds must be >= 1, got {n_rounds}", key="rounds")
    if not (np.isfinite(tolerance) and 0 < tolerance < 1):
        raise ConfigError(f"--loop-tolerance must be a fraction in (0, 1), got {tolerance}",
                          key="loop_tolerance")
    if n_rounds > 1 and not correct_outputs:
        if not coefficients.startswith("identified:"):
            raise ConfigError(
                "--rounds > 1 refits the model on each round's back-tests, which only "
                f"identified coefficients take up; with --coefficients {coefficients} every "
                "round would optimise the same motions: add --coefficients identified:uniform "
                "(or low, high), or --correct-outputs", key="rounds")
        if not refit:
            raise ConfigError("--no-refit keeps the coefficients of round 1, so without "
                              "--correct-outputs every round would optimise the same motions",
                              key="refit")
    if trust_radius is not None:
        from mfflap.optimisation.trust_region import check_radius

        check_radius(trust_radius)
        if n_rounds < 2:
            raise ConfigError("--trust-region bounds each round's optimum about the last one "
                              "CFD confirmed, so it needs --rounds 2 or more", key="trust_region")
    if cfd_repeatability is not None:
        from mfflap.optimisation.trust_region import check_repeatability

        check_repeatability(cfd_repeatability)
        if trust_radius is None:
            raise ConfigError("--cfd-repeatability relaxes the trust region's judgement of "
                              "each step by CFD's noise, so it needs --trust-region",
                              key="cfd_repeatability")
    if first_order:
        missing = [flag for flag, given in (("--correct-outputs", correct_outputs),
                                            ("--trust-region", trust_radius is not None))
                   if not given]
        if missing:
            raise ConfigError("--first-order gives the corrected objective a slope, which "
                              "without a trust region would lead the optimiser off along a "
                              f"secant; it needs {' and '.join(missing)}", key="first_order")
        if correction_gain != 1.0:
            raise ConfigError("--first-order meets CFD at the centre with the measured "
                              f"scales; --correction-gain {correction_gain:g} filters them",
                              key="first_order")


def motion_checks(backtests: dict, in_fit: set[str],
                  scales: dict[str, tuple[float, float]] | None = None,
                  optimised: dict[str, tuple[float, float]] | None = None
                  ) -> dict[str, MotionCheck]:
    """Per back-tested motion: the mean thrust and power predicted for it against CFD's.

    ``in_fit``: the names of the cases the round's fit used (a record's name is its case's);
    ``scales``: label -> (thrust, power) scale of the output correction the motion was
    optimised with (a motion not in it: the model's own means); ``optimised``: label ->
    (thrust N, power W) the optimiser's own means of the motion, which the prediction is
    made of (a motion not in it: the back-test's model means).
    """
    done = {k: o for k, o in backtests.items() if o.comparison is not None}
    largest = max((abs(o.comparison.cfd_mean_thrust) for o in done.values()), default=0.0)
    out = {}
    for label, o in done.items():
        c = o.comparison
        k_t, k_p = (scales or {}).get(label, (1.0, 1.0))
        own = (optimised or {}).get(label)
        own_t, own_p = own if own is not None else (c.model_mean_thrust, c.model_mean_power)
        out[label] = MotionCheck(
            label, o.key, c.cfd_mean_thrust, c.model_mean_thrust, c.cfd_mean_power,
            c.model_mean_power, _relative(k_t * own_t, c.cfd_mean_thrust),
            _relative(k_p * own_p, c.cfd_mean_power),
            thrust_counted=bool(abs(c.cfd_mean_thrust) >= THRUST_FLOOR * largest > 0),
            in_fit=o.record is not None and o.record.name in in_fit,
            thrust_scale=k_t, power_scale=k_p,
            optimised_mean_thrust=np.nan if own is None else float(own_t),
            optimised_mean_power=np.nan if own is None else float(own_p),
            cfd_record="" if o.record is None else str(o.record.name))
    return out


def _finite_or_none(value: float) -> float | None:
    """A number for JSON: None where it is NaN (not known)."""
    return float(value) if np.isfinite(value) else None


def optimised_means(outcome, config: CaseConfig) -> dict[str, tuple[float, float]]:
    """label -> (mean thrust N, mean power W) of each back-tested motion of a round as its
    optimiser saw them (:func:`~mfflap.performance.discrete_means`, the round's model and
    scheme); empty without a model."""
    from mfflap.performance import discrete_means

    if outcome.model is None:
        return {}
    scheme = (outcome.config or config).optimisation.scheme
    return {label: discrete_means(outcome.model, motion, scheme)
            for label, motion in outcome.backtest_motions.items()}


def _relative(predicted: float, cfd: float) -> float:
    """(predicted - CFD) / |CFD|, as the back-test's comparison gives it."""
    return (predicted - cfd) / max(abs(cfd), 1e-12)


def correction_points(outcome, checks: dict[str, MotionCheck], index: int) -> dict:
    """beta -> :class:`~mfflap.optimisation.output_correction.CorrectionPoint`: each
    back-tested optimum of round ``index`` with its CFD means, for the next round's output
    correction."""
    from mfflap.optimisation.output_correction import CorrectionPoint
    from mfflap.optimisation.store import beta_label

    points = {}
    for beta, result in (outcome.study.sqp.items() if outcome.study is not None else ()):
        label = beta_label(beta)
        if label in checks:
            c = checks[label]
            points[beta] = CorrectionPoint(
                result.motion, c.cfd_mean_thrust, c.cfd_mean_power,
                f"round {index}'s beta = {beta:g} (back-test {c.key})",
                thrust_usable=c.thrust_counted, scales=(c.thrust_scale, c.power_scale))
    return points


def trust_steps(outcome, checks: dict[str, MotionCheck], regions: dict, centres: dict,
                config: CaseConfig, repeatability: float | None = None) -> dict:
    """beta -> :class:`~mfflap.optimisation.trust_region.TrustStep`: each back-tested
    optimum of a round with trust ``regions`` (beta -> region) judged against its centre
    (``centres``: beta -> the centre's
    :class:`~mfflap.optimisation.output_correction.CorrectionPoint`).

    The predicted objective is the one the round optimised (``config``'s problem with the
    round's model, its outputs corrected as they were); CFD's is the same problem with the
    model's outputs scaled to each motion's own CFD means. ``repeatability``: the share by
    which two CFD runs of one motion differ, which relaxes the ratio by the noise of J at the
    centre (:func:`~mfflap.optimisation.trust_region.noise_of_objective`; None: not known).
    """
    from mfflap.optimisation.output_correction import (
        CorrectionPoint,
        OutputCorrection,
        cfd_objective,
    )
    from mfflap.optimisation.store import beta_label
    from mfflap.optimisation.study import problem_for
    from mfflap.optimisation.trust_region import TrustStep, noise_of_objective

    steps = {}
    sqp = outcome.study.sqp if outcome.study is not None else {}
    cfg = outcome.config or config
    for beta, region in regions.items():
        label = beta_label(beta)
        if beta not in sqp or label not in checks or outcome.model is None:
            continue
        c, centre, optimum = checks[label], centres[beta], sqp[beta].motion
        base = problem_for(cfg, beta, outcome.model)

        def corrected(correction: OutputCorrection | None, motion, base=base) -> float:
            if correction is None:
                return float(base.objective(motion))
            return correction.objective_factor(base.beta) * float(
                correction.problem(base).objective(motion))

        own = outcome.corrections.get(beta)
        steps[beta] = TrustStep.judged(
            region, beta, optimum, cfd_objective(centre, base),
            cfd_objective(CorrectionPoint(optimum, c.cfd_mean_thrust, c.cfd_mean_power, label,
                                          thrust_usable=c.thrust_counted), base),
            corrected(own, centre.motion), corrected(own, optimum),
            0.0 if repeatability is None else noise_of_objective(
                repeatability, beta, centre.cfd_mean_thrust, centre.cfd_mean_power))
    return steps


def _run_of(outcome, beta: float):
    """The CFD record of this round's back-test of ``beta``'s optimum, or None."""
    from mfflap.optimisation.store import beta_label

    found = outcome.backtests.get(beta_label(beta))
    return None if found is None else found.record


def _mixed_set_up(outcome, beta: float, whose: str) -> list[str]:
    """``whose`` run's compared cycles mixing two set-ups (a retry resumed it part-way
    through them), said for a trust step's ``ran_otherwise``; empty if not."""
    from mfflap.optimisation.store import beta_label

    found = outcome.backtests.get(beta_label(beta))
    c = None if found is None else found.comparison
    if c is None or not c.compared_cycles_mixed_set_up:
        return []
    return [f"{whose}'s compared cycles mix two set-ups (its settings changed at t = "
            f"{c.cfd_settings_since_s:.4g} s, after t = {c.compared_from_s:.4g} s)"]


def _keep_records(backtests: dict, folder: Path) -> None:
    """Write each back-tested motion's CFD record into ``folder`` under its own name (a
    fixture found within the look-up's tolerance keeps the name of the motion it ran)."""
    from mfflap.campaign.records import write_record

    folder.mkdir(parents=True, exist_ok=True)
    for o in backtests.values():
        if o.record is not None and not (folder / f"{o.record.name}.h5").exists():
            write_record(folder / f"{o.record.name}.h5", o.record, single_precision=True)


def _coefficients(outcome) -> dict[str, float]:
    """The coefficients the round optimised with (term name -> value)."""
    return {} if outcome.model is None else {
        k: float(v) for k, v in outcome.model.coefficients.items()}


def run_rounds(config: CaseConfig, options, n_rounds: int, tolerance: float, out_dir: Path,
               progress: Progress = print, source: str = "", correct_outputs: bool = False,
               correction_gain: float = 1.0, refit: bool = True,
               trust_radius: float | None = None, first_order: bool = False,
               cfd_repeatability: float | None = None):
    """Run the main job in rounds (module docstring) into ``out_dir/round_<k>``.

    ``correct_outputs``: from round 2 on, each beta is optimised with the model's thrust and
    power scaled to predict the CFD means of the previous round's optimum of that beta
    (:mod:`mfflap.optimisation.output_correction`), and it is those corrected predictions
    that are checked against the new back-tests. ``correction_gain``: K of the filter from
    the scales that optimum was optimised with to the measured ones (1: the measured ones).
    ``refit`` False: every round identifies from the identification data alone (round 1's
    coefficients), so only the output correction learns from the back-tests (the classical
    modifier adaptation of a fixed model). ``first_order`` (with ``trust_radius``): the
    corrected objective gets a slope that makes it CFD's at the earlier back-tested motions
    of the beta (:meth:`~mfflap.optimisation.output_correction.OutputCorrection.with_slopes`)
    within :data:`~mfflap.optimisation.output_correction.SECANT_REACH` radii of the centre;
    a motion whose CFD is a neighbour's (found within the look-up's tolerance) is left out.
    ``cfd_repeatability`` (with ``trust_radius``): the share by which two CFD runs of one
    motion differ; the trust regions' ratios are relaxed by the noise it makes in J, and a
    step predicted to gain less than that noise counts as settled.

    The back-test records of every round are kept in ``out_dir/loop_records`` (one per
    motion), pooled with the identification data of the later rounds and looked up as
    back-test fixtures first, so the same command run again finds the CFD already done.

    Returns
    -------
    (LoopResult, RunOutcome)
        The rounds and the last round's outcome.
    """
    from mfflap.backtest.as_run import as_run_differences
    from mfflap.campaign.records import backtest_fixture_dirs, fixture_dir
    from mfflap.optimisation.output_correction import SECANT_REACH, secants_within
    from mfflap.optimisation.store import beta_label
    from mfflap.optimisation.trust_region import TrustRegion
    from mfflap.pipeline import run_study, write_outputs

    check_rounds(n_rounds, tolerance, options.coefficients, correct_outputs, refit,
                 trust_radius, first_order, correction_gain, cfd_repeatability)
    refit = refit and options.coefficients.startswith("identified:")  # case: none to refit
    records = out_dir / RECORDS_FOLDER
    base_fixtures = tuple(options.fixtures) or (fixture_dir(),)
    base_backtests = tuple(options.backtest_fixtures) or tuple(backtest_fixture_dirs())
    rounds: list[RoundSummary] = []
    seen: set[str] = set()  # motion keys back-tested in earlier rounds
    outcome = None
    points: dict = {}  # beta -> the last round's optimum with its CFD (correct_outputs)
    centres: dict = {}  # beta -> the trust region's centre with its CFD (trust_radius)
    radii: dict[float, float] = {}  # beta -> the trust region's radius
    centre_runs: dict = {}  # beta -> the centre's CFD record (how it ran: as_run_differences)
    centre_mixed: dict = {}  # beta -> what mixes two set-ups in the centre's compared cycles
    visited: dict = {}  # beta -> every back-tested optimum with its own CFD (first_order)
    converged, why = False, f"ran the {n_rounds} round(s) asked for"
    for k in range(1, n_rounds + 1):
        round_dir = out_dir / f"round_{k}"
        pooled = sorted(records.glob("backtest_*.h5")) if refit and records.is_dir() else []
        regions = {b: TrustRegion(p.motion, radii[b], p.source) for b, p in centres.items()}
        opts = replace(options, fixtures=base_fixtures + tuple(pooled),
                       backtest_fixtures=(records, *base_backtests),
                       done_backtests=(records,),
                       correct_at=(centres if trust_radius is not None else points)
                       if correct_outputs else {},
                       trust_at=regions,
                       secant_at={b: tuple(secants_within(
                           c.motion, [p for p in visited.get(b, ()) if p is not c],
                           SECANT_REACH * radii[b])) for b, c in centres.items()}
                       if first_order else {},
                       correction_gain=correction_gain,
                       work_dir=round_dir / "cfd_cases",
                       vtk_dir=None if options.vtk_dir is None else round_dir / "vtk")
        progress(f"[round {k} of {n_rounds}] identification from {len(pooled)} back-test "
                 "record(s) of earlier rounds beside the identification data"
                 + ("" if refit else " (nothing refitted: the coefficients of round 1)"))

        def told(message: str, k: int = k) -> None:
            progress(f"[round {k}] {message}")

        outcome = run_study(config, opts, progress=told)
        round_dir.mkdir(parents=True, exist_ok=True)
        write_outputs(outcome.config or config, outcome, round_dir / "results.h5",
                      round_dir / "report.html", source)
        in_fit = {c.name for c in outcome.cases}
        scales = {beta_label(b): (c.thrust_scale, c.power_scale)
                  for b, c in outcome.corrections.items()}
        summary = RoundSummary(
            k, round_dir, len(outcome.cases),
            sum(1 for p in pooled if p.stem in in_fit), _coefficients(outcome),
            motion_checks(outcome.backtests, in_fit, scales, optimised_means(outcome, config)),
            {lbl: o.source for lbl, o in outcome.backtests.items() if o.comparison is None},
            {b: c.as_dict() for b, c in outcome.corrections.items()})
        points = correction_points(outcome, summary.checks, k)
        for beta, point in points.items():
            if not summary.checks[beta_label(beta)].cfd_of_neighbour:
                visited.setdefault(beta, []).append(point)
        if trust_radius is not None:
            summary.trust_steps = trust_steps(outcome, summary.checks, regions, centres,
                                              config, cfd_repeatability)
            for beta, step in list(summary.trust_steps.items()):
                run = _run_of(outcome, beta)
                mixed = _mixed_set_up(outcome, beta, "the optimum")
                if centre_runs.get(beta) is not None and run is not None:
                    step = summary.trust_steps[beta] = replace(step, ran_otherwise=tuple(
                        as_run_differences(centre_runs[beta], run)
                        + centre_mixed.get(beta, []) + mixed))
                radii[beta] = step.next_radius
                if step.accepted and beta in points:
                    centres[beta] = points[beta]
                    centre_runs[beta] = run
                    centre_mixed[beta] = _mixed_set_up(outcome, beta, "the centre")
            if k == 1:
                centres, radii = dict(points), {b: float(trust_radius) for b in points}
                centre_runs = {b: _run_of(outcome, b) for b in points}
                centre_mixed = {b: _mixed_set_up(outcome, b, "the centre") for b in points}
        rounds.append(summary)
        _keep_records(outcome.backtests, records)
        progress(describe_round(summary, tolerance))
        keys = {o.key for o in outcome.backtests.values()}
        stop = stop_reason(summary, outcome, keys, seen, tolerance, live=options.live,
                           corrected=correct_outputs,
                           filtered=correct_outputs and correction_gain < 1,
                           bounded=trust_radius is not None)
        if stop is not None:
            converged, why = stop
            break
        seen |= keys
    answers = {b: f"{p.source}: CFD mean thrust {p.cfd_mean_thrust:.4g} N, mean power "
                  f"{p.cfd_mean_power:.4g} W" for b, p in centres.items()}
    result = LoopResult(rounds, tolerance, converged, why, correct_outputs, correction_gain,
                        refit, trust_radius, answers, first_order, cfd_repeatability)
    progress(f"rounds: {why}")
    for beta, answer in answers.items():
        progress(f"rounds: beta {beta:g}'s last motion CFD confirmed: {answer}")
    write_rounds(result, config, out_dir)
    return result, outcome


def stop_reason(summary: RoundSummary, outcome, keys: set[str], seen: set[str],
                tolerance: float, *, live: bool = False, corrected: bool = False,
                filtered: bool = False, bounded: bool = False) -> tuple[bool, str] | None:
    """Whether the rounds stop after ``summary``'s round (module docstring), and why.

    Parameters
    ----------
    summary, outcome : the round's summary and run outcome
    keys : the motion keys the round back-tested; ``seen``: those of the rounds before
    live : whether the back-tests run OpenFOAM (said where a motion had no CFD)
    corrected, filtered : output corrections, filtered (gain < 1): a repeated motion is then
        no fixed point, the filter still moves the scales
    bounded : trust regions (``summary.trust_steps``): a repeated motion is a fixed point
        only where no optimum left its centre (else the radius still moves), the rounds
        converge only where every optimum is inside its region and no step was rejected
        (a rejected optimum is not the rounds' answer: its centre is), and stop when a
        radius collapses

    Returns
    -------
    (converged, why), or None to go on.
    """
    k = summary.index
    if outcome.interrupted is not None:
        return False, f"round {k} was stopped (Ctrl-C) in its {outcome.interrupted} stage"
    if not outcome.identification or outcome.study is None:
        return False, f"round {k}'s identification or optimisation failed (its report says why)"
    if summary.not_backtested:
        label, reason = next(iter(summary.not_backtested.items()))
        return False, (f"round {k}: {label} was not back-tested ({reason}); the next round "
                       "would not learn where the model is wrong"
                       + ("" if live else " (--live runs its CFD in OpenFOAM)"))
    unsettled = [t for t in summary.trust_steps.values()
                 if not t.within_noise and (t.on_boundary or not t.accepted)]
    if (summary.largest_error is not None and summary.largest_error <= tolerance
            and not unsettled):
        who = "the corrected model" if summary.corrections else "the model"
        inside = (" with every optimum inside its trust region and its step confirmed by CFD"
                  if summary.trust_steps else "")
        if any(t.within_noise for t in summary.trust_steps.values()):
            inside = (" with every step confirmed by CFD, its optimum inside its trust region, "
                      "or predicted to gain less than CFD's noise")
        return True, (f"round {k}: {who} predicts every back-tested motion's CFD mean thrust "
                      f"and power within {tolerance:.0%} (largest {summary.largest_error:.1%})"
                      + inside)
    collapsed = sorted(b for b, t in summary.trust_steps.items()
                       if t.next_radius < MIN_RADIUS)
    if collapsed:
        return False, (f"round {k}: the trust region of beta "
                       f"{', '.join(f'{b:g}' for b in collapsed)} collapsed (radius below "
                       f"{MIN_RADIUS:g}): CFD confirms no step of the model there")
    still = bool(summary.trust_steps) and not any(t.moved for t in summary.trust_steps.values())
    if keys and keys <= seen and not filtered and (not bounded or still):
        return False, (f"round {k} optimised the motions of an earlier round (a fixed point): "
                       "a further round would fit the same data"
                       + (" and measure the same corrections" if corrected else ""))
    return None


def describe_round(summary: RoundSummary, tolerance: float) -> str:
    """One line per motion: model against CFD mean thrust and power."""
    from mfflap.optimisation.output_correction import describe_correction

    lines = [f"round {summary.index}: {summary.n_cases} CFD runs in the fit "
             f"({summary.loop_records_in_fit} from earlier rounds); "
             + ", ".join(f"{k} {v:.3g}" for k, v in summary.coefficients.items())]
    for beta, corr in summary.corrections.items():
        lines.append(f"  beta {beta:g} optimised with the outputs corrected: "
                     + describe_correction(corr))
    for beta, step in summary.trust_steps.items():
        lines.append(f"  beta {beta:g}: {step.describe()}")
    for c in summary.checks.values():
        thrust = (f"{c.thrust_error:+.1%}" if c.thrust_counted
                  else f"{c.thrust_error:+.1%} (not counted: small thrust)")
        who = "model" if (c.thrust_scale, c.power_scale) == (1.0, 1.0) else "corrected model"
        lines.append(f"  {c.label}: thrust {who} {c.predicted_thrust:.3g} N / CFD "
                     f"{c.cfd_mean_thrust:.3g} N ({thrust}); power {who} "
                     f"{c.predicted_power:.3g} W / CFD {c.cfd_mean_power:.3g} W "
                     f"({c.power_error:+.1%})" + ("; its CFD was in the fit (not counted)"
                                                   if c.in_fit else "")
                     + (f"; the CFD of {c.cfd_record}, a motion within the back-test "
                        "look-up's tolerance" if c.cfd_of_neighbour else ""))
    for label, reason in summary.not_backtested.items():
        lines.append(f"  {label}: not back-tested: {reason.splitlines()[0]}")
    largest = summary.largest_error
    if largest is not None:
        lines.append(f"  largest counted error {largest:.1%} "
                     f"({'within' if largest <= tolerance else 'beyond'} {tolerance:.0%})")
    return "\n".join(lines)


def write_rounds(result: LoopResult, config: CaseConfig, out_dir: Path) -> None:
    """``out_dir/rounds.h5`` (every round's numbers, the case file beside them),
    ``rounds.png`` (model against CFD per motion over the rounds) and ``rounds.html``."""
    from mfflap.optimisation.output_correction import describe_correction
    from mfflap.reports.html import Report, figure_html, table_html, text_html
    from mfflap.results import ResultsFile

    with ResultsFile(out_dir / "rounds.h5", "w", kind="rounds",
                     config_toml=config.to_toml()) as rf:
        rf.h5.attrs["tolerance"] = result.tolerance
        rf.h5.attrs["converged"] = result.converged
        rf.h5.attrs["stopped_because"] = result.stopped_because
        rf.h5.attrs["correct_outputs"] = result.correct_outputs
        rf.h5.attrs["correction_gain"] = result.correction_gain
        rf.h5.attrs["refit"] = result.refit
        rf.h5.attrs["trust_radius"] = np.nan if result.trust_radius is None else \
            result.trust_radius
        rf.h5.attrs["first_order"] = result.first_order
        rf.h5.attrs["cfd_repeatability"] = np.nan if result.cfd_repeatability is None else \
            result.cfd_repeatability
        for r in result.rounds:
            labels = list(r.checks)
            arrays = {name: np.array([getattr(r.checks[lbl], name) for lbl in labels])
                      for name in ("cfd_mean_thrust", "model_mean_thrust", "predicted_thrust",
                                   "cfd_mean_power", "model_mean_power", "predicted_power",
                                   "thrust_scale", "power_scale", "optimised_mean_thrust",
                                   "optimised_mean_power")}
            units = {name: "1" if "scale" in name else "N" if "thrust" in name else "W"
                     for name in arrays}
            rf.write_group(f"rounds/round_{r.index}", arrays, units, {
                "labels": json.dumps(labels), "summary": json.dumps(r.as_dict())})
    fig = rounds_figure(result)
    fig.savefig(out_dir / "rounds.png", dpi=110)
    learns = ("refits the model with the back-tests of the rounds before" if result.refit
              else "keeps round 1's coefficients")
    if result.correct_outputs:
        learns += ", corrects its outputs to the CFD of the round before"
    if result.trust_radius is not None:
        learns += (f", keeps each optimum in a trust region (first radius "
                   f"{result.trust_radius:g}) about the last one CFD confirmed")
    if result.cfd_repeatability is not None:
        learns += (f", counts CFD's noise ({result.cfd_repeatability:.1%} of the means "
                   "between two runs) in judging each step")
    if result.first_order:
        learns += (", and gives the corrected objective a slope that makes it CFD's at the "
                   "earlier motions near the centre")
    rep = Report("mfflap run: rounds of CFD in the loop",
                 f"{config.study.name}: each round {learns}, optimises and back-tests again")
    s = rep.section("Rounds")
    s.blocks.append(text_html(f"{'Converged' if result.converged else 'Not converged'}: "
                              f"{result.stopped_because}.", warn=not result.converged))
    rows = []
    for r in result.rounds:
        for c in r.checks.values():
            shown = c.label + (f" (CFD of {c.cfd_record}, within the look-up's tolerance)"
                               if c.cfd_of_neighbour else "")
            rows.append([r.index, shown, f"{c.predicted_thrust:.3g}",
                         f"{c.cfd_mean_thrust:.3g}",
                         f"{c.thrust_error:+.1%}" + ("" if c.thrust_counted else " (n.c.)"),
                         f"{c.predicted_power:.3g}", f"{c.cfd_mean_power:.3g}",
                         f"{c.power_error:+.1%}", "yes" if c.in_fit else "no",
                         _scales_text(c)])
        for label, reason in r.not_backtested.items():
            rows.append([r.index, label, "", "", "not back-tested: " + reason.splitlines()[0],
                         "", "", "", "", ""])
    s.blocks.append(table_html(["round", "motion", "thrust predicted N", "CFD N", "error",
                                "power predicted W", "CFD W", "error", "CFD in the fit",
                                "output correction (thrust, power)"], rows))
    if result.answers:
        s.blocks.append(text_html(
            "The last motion of each β that CFD confirmed (its trust region's centre when the "
            "rounds stopped; each round's own report holds it): " + "; ".join(
                f"β = {b:g}: {a}" for b, a in result.answers.items()) + "."))
    corrected = [f"round {r.index}, beta {b:g}: {describe_correction(c)}"
                 for r in result.rounds for b, c in r.corrections.items()]
    if corrected:
        s.blocks.append(text_html(
            "Output corrections (" + ("measured scales" if result.correction_gain == 1.0
                                      else f"filtered, gain {result.correction_gain:g}")
            + "): " + "; ".join(corrected) + "."))
    steps = [[r.index, f"{b:g}", f"{t.radius:.3g}", t.centre, f"{t.step_fraction:.2f}",
              "yes" if t.on_boundary else "no", f"{t.cfd_decrease:.4g}",
              f"{t.predicted_decrease:.4g}", f"{t.ratio:.3g}" if t.moved else "–",
              ("accepted" if t.accepted else "rejected") if t.moved else "no step",
              f"{t.next_radius:.3g}", "; ".join(t.ran_otherwise) or "alike"]
             for r in result.rounds for b, t in r.trust_steps.items()]
    if steps:
        s.blocks.append(text_html(
            "Trust-region steps: the ratio is CFD's decrease of the objective J from the "
            "centre to the optimum over the decrease the round's optimisation predicted (J "
            "with the model's thrust and power scaled to each motion's own CFD means, against "
            "J as the round optimised it); a step of ratio below 0.1 is rejected (the centre "
            "stays), below 0.25 the radius halves, above 0.75 on the boundary it doubles."))
        s.blocks.append(table_html(["round", "beta", "radius", "centre", "step / radius",
                                    "on the boundary", "CFD decrease of J",
                                    "predicted decrease", "ratio", "step", "next radius",
                                    "CFD runs (centre against optimum)"],
                                   steps))
        if any(t.ran_otherwise for r in result.rounds for t in r.trust_steps.values()):
            s.blocks.append(text_html(
                "Some steps compare CFD runs that did not run alike: a retry of a run whose "
                "time step collapsed changed its far field or Courant limit, and its CFD "
                "decrease holds that change as well as the motion's (at the trust series' "
                "beta = 0.5 optimum, max Co 2 instead of 4 moves the mean thrust by 7 %); "
                "a run resumed part-way by a retry may mix two set-ups in the cycles "
                "compared. --retries-from-start reruns a retried run from t = 0 s.",
                warn=True))
    s.blocks.append(table_html(["round", "CFD runs in the fit", "of them from rounds before",
                                *(result.rounds[0].coefficients if result.rounds else [])],
                               [[r.index, r.n_cases, r.loop_records_in_fit,
                                 *(f"{v:.3g}" for v in r.coefficients.values())]
                                for r in result.rounds]))
    s.blocks.append(figure_html(fig, "Mean thrust and input power of each back-tested "
                                     "motion, predicted (open: the model's, or the corrected "
                                     "model's where the motion was optimised with corrected "
                                     "outputs) and CFD (filled), by round, and the "
                                     "prediction's largest counted error of the two (grey: "
                                     "its CFD was in the round's fit, not counted); each "
                                     "round's own report: round_<k>/report.html"))
    rep.write(out_dir / "rounds.html")


def _scales_text(check: MotionCheck) -> str:
    """The output correction of a motion in a table cell ("none": the model's own)."""
    if (check.thrust_scale, check.power_scale) == (1.0, 1.0):
        return "none"
    return f"x {check.thrust_scale:.3f}, x {check.power_scale:.3f}"


def rounds_figure(result: LoopResult):
    """Predicted (open; the corrected model's where a motion was optimised with corrected
    outputs) and CFD (filled) mean thrust and power of each motion over the rounds, and each
    motion's counted error against the tolerance (a motion whose CFD was in the
    round's fit is drawn grey there)."""
    from matplotlib.figure import Figure

    fig = Figure(figsize=(12, 3.6), layout="constrained")
    axes = fig.subplots(1, 3)
    labels = sorted({lbl for r in result.rounds for lbl in r.checks})
    for i, label in enumerate(labels):
        colour = f"C{i % 10}"
        pts = [(r.index, r.checks[label]) for r in result.rounds if label in r.checks]
        x = [p[0] for p in pts]
        for ax, cfd, mod in ((axes[0], "cfd_mean_thrust", "predicted_thrust"),
                             (axes[1], "cfd_mean_power", "predicted_power")):
            ax.plot(x, [getattr(c, cfd) for _, c in pts], "o-", color=colour, label=label)
            ax.plot(x, [getattr(c, mod) for _, c in pts], "o--", color=colour,
                    markerfacecolor="none")
        axes[2].plot(x, [100 * c.error for _, c in pts], "o-", color=colour, label=label)
        seen = [(k, c) for k, c in pts if c.in_fit]
        if seen:
            axes[2].plot([k for k, _ in seen], [100 * c.error for _, c in seen], "o",
                         color="0.6")
    axes[2].axhline(100 * result.tolerance, color="k", ls=":", label="tolerance")
    axes[0].set_ylabel("mean thrust (N)")
    axes[1].set_ylabel("mean input power (W)")
    axes[2].set_ylabel("prediction's error of the means (%)")
    for ax in axes:
        ax.set_xlabel("round")
        ax.set_xticks([r.index for r in result.rounds])
    if labels:
        axes[0].legend(fontsize=8)
    return fig


__all__ = [
    "THRUST_FLOOR",
    "LoopResult",
    "MotionCheck",
    "RoundSummary",
    "check_rounds",
    "motion_checks",
    "run_rounds",
    "write_rounds",
]
