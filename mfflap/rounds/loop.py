"""The rounds themselves: run the main job round by round (:func:`run_rounds`) until
:func:`stop_reason` says why not to go on."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace
from pathlib import Path

from mfflap.config import CaseConfig
from mfflap.optimisation.output_correction import SECANT_REACH, secants_within
from mfflap.optimisation.store import beta_label
from mfflap.optimisation.trust_region import MIN_RADIUS, TrustRegion
from mfflap.pipeline import RunOutcome, run_study, write_results
from mfflap.records.as_run import as_run_differences
from mfflap.records.record import backtest_fixture_dirs, identification_fixture_dirs, write_record
from mfflap.rounds.checks import motion_checks, optimised_means
from mfflap.rounds.output import write_rounds_results
from mfflap.rounds.refusals import check_rounds
from mfflap.rounds.state import BetaState, with_centres
from mfflap.rounds.steps import (
    backtest_record_of,
    correction_points,
    mixed_set_up_notes,
    secant_points,
    trust_steps,
)
from mfflap.rounds.summary import LoopResult, RoundSummary, describe_round

Progress = Callable[[str], None]
#: writes a round's outputs into its folder: (the case as run, its outcome, the folder,
#: where its CFD came from)
WriteRound = Callable[[CaseConfig, RunOutcome, Path, str], None]
#: writes the rounds' own outputs into the output folder
WriteSummary = Callable[[LoopResult, CaseConfig, Path], None]


def write_round_results(config: CaseConfig, outcome: RunOutcome, round_dir: Path,
                        source: str) -> None:
    """A round's ``results.h5`` (:func:`mfflap.pipeline.write_results`), no report."""
    write_results(config, outcome, round_dir / "results.h5")


#: the folder (inside the output folder) holding the back-test records the rounds pool
RECORDS_FOLDER = "loop_records"



def _keep_records(backtests: dict, folder: Path) -> None:
    """Write each back-tested motion's CFD record into ``folder`` under its own name (a
    fixture found within the look-up's tolerance keeps the name of the motion it ran)."""
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
               cfd_repeatability: float | None = None,
               write_round: WriteRound = write_round_results,
               write_summary: WriteSummary = write_rounds_results):
    """Run the main job in rounds (:mod:`mfflap.rounds`) into ``out_dir/round_<k>``.

    ``write_round`` writes each round's outputs into its folder (by default its
    ``results.h5``; :func:`mfflap.reports.run.write_round_outputs` adds its report), and
    ``write_summary`` the rounds' own (by default ``rounds.h5``;
    :func:`mfflap.reports.rounds.write_rounds` adds ``rounds.png`` and ``rounds.html``).

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
    a motion whose CFD is a neighbour's (found within the look-up's tolerance or shifted in
    time) counts only where that record gave the beta no point before
    (:func:`~mfflap.rounds.steps.secant_points`).
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
    check_rounds(n_rounds, tolerance, options.coefficients, correct_outputs, refit,
                 trust_radius, first_order, correction_gain, cfd_repeatability)
    refit = refit and options.coefficients.startswith("identified:")  # case: none to refit
    records = out_dir / RECORDS_FOLDER
    base_fixtures = tuple(options.fixtures) or identification_fixture_dirs()
    base_backtests = tuple(options.backtest_fixtures) or tuple(backtest_fixture_dirs())
    rounds: list[RoundSummary] = []
    seen: set[str] = set()  # motion keys back-tested in earlier rounds
    outcome = None
    states: dict[float, BetaState] = {}  # beta -> what the rounds carry for it
    converged, why = False, f"ran the {n_rounds} round(s) asked for"
    for k in range(1, n_rounds + 1):
        round_dir = out_dir / f"round_{k}"
        pooled = sorted(records.glob("backtest_*.h5")) if refit and records.is_dir() else []
        centred = with_centres(states)
        centres = {b: st.centre for b, st in centred.items()}
        points = {b: st.last_point for b, st in states.items() if st.last_point is not None}
        regions = {b: TrustRegion(st.centre.motion, st.radius, st.centre.source)
                   for b, st in centred.items()}
        opts = replace(options, polish=False, fixtures=base_fixtures + tuple(pooled),
                       backtest_fixtures=(records, *base_backtests),
                       done_backtests=(records,),
                       correct_at=(centres if trust_radius is not None else points)
                       if correct_outputs else {},
                       trust_at=regions,
                       secant_at={b: tuple(secants_within(
                           st.centre.motion, [p for p in st.visited if p is not st.centre],
                           SECANT_REACH * st.radius)) for b, st in centred.items()}
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
        write_round(outcome.config or config, outcome, round_dir, source)
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
        for beta in states.keys() - points.keys():  # no point this round: none to correct to
            states[beta].last_point = None
        for beta, point in points.items():
            states.setdefault(beta, BetaState()).last_point = point
        used = {b: states[b].records_used for b in points}
        for beta, point in secant_points(points, summary.checks, used).items():
            states[beta].visited.append(point)
        if trust_radius is not None:
            summary.trust_steps = trust_steps(outcome, summary.checks, regions, centres,
                                              config, cfd_repeatability)
            for beta, step in list(summary.trust_steps.items()):
                state = states.setdefault(beta, BetaState())
                run = backtest_record_of(outcome, beta)
                mixed = mixed_set_up_notes(outcome, beta, "the optimum")
                if state.centre_run is not None and run is not None:
                    step = summary.trust_steps[beta] = replace(step, ran_otherwise=tuple(
                        as_run_differences(state.centre_run, run)
                        + state.centre_mixed + mixed))
                state.radius = step.next_radius
                if step.accepted and beta in points:
                    state.centre, state.centre_run = points[beta], run
                    state.centre_mixed = mixed_set_up_notes(outcome, beta, "the centre")
            if k == 1:
                for beta, state in states.items():  # the first round's optima are the centres
                    if beta in points:
                        state.centre, state.radius = points[beta], float(trust_radius)
                        state.centre_run = backtest_record_of(outcome, beta)
                        state.centre_mixed = mixed_set_up_notes(outcome, beta, "the centre")
                    else:
                        state.centre = state.radius = state.centre_run = None
                        state.centre_mixed = []
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
    answers = {b: f"{st.centre.source}: CFD mean thrust {st.centre.cfd_mean_thrust:.4g} N, "
                  f"mean power {st.centre.cfd_mean_power:.4g} W"
               for b, st in with_centres(states).items()}
    result = LoopResult(rounds, tolerance, converged, why, correct_outputs, correction_gain,
                        refit, trust_radius, answers, first_order, cfd_repeatability)
    progress(f"rounds: {why}")
    for beta, answer in answers.items():
        progress(f"rounds: beta {beta:g}'s last motion CFD confirmed: {answer}")
    write_summary(result, config, out_dir)
    return result, outcome


def stop_reason(summary: RoundSummary, outcome, keys: set[str], seen: set[str],
                tolerance: float, *, live: bool = False, corrected: bool = False,
                filtered: bool = False, bounded: bool = False) -> tuple[bool, str] | None:
    """Whether the rounds stop after ``summary``'s round (:mod:`mfflap.rounds`), and why.

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


__all__ = ["RECORDS_FOLDER", "run_rounds", "stop_reason"]
