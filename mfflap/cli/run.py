"""``mfflap run``: the whole pipeline of a study file."""

from __future__ import annotations

from pathlib import Path

import click

from mfflap.cli.json_output import echo_json
from mfflap.cli.options import fix_phase_option, retries_from_start_option, with_phase_fixed


@click.command("run")
@click.argument("case_file", type=click.Path(dir_okay=False, exists=True, path_type=Path))
@click.option("--out", "out_dir", type=click.Path(file_okay=False, path_type=Path),
              default=None, help="Output folder (default: <study name>_run).")
@click.option("--fixtures", multiple=True,
              type=click.Path(exists=True, path_type=Path),
              help="Identification CFD records, a folder or one record file (default: "
                   "shipped fixtures); repeat to pool several.")
@click.option("--backtest-fixtures", multiple=True,
              type=click.Path(file_okay=False, exists=True, path_type=Path),
              help="Back-test CFD records (default: shipped fixtures).")
@click.option("--live", is_flag=True, help="Run the back-test CFD live with OpenFOAM.")
@click.option("--coefficients", default="case", show_default=True,
              help="Model coefficients for the optimisation: 'case' or "
                   "'identified:<uniform|low|high>'.")
@click.option("--starts", default=3, show_default=True, type=click.IntRange(min=1),
              help="Multi-start points per beta.")
@click.option("--gain-table/--no-gain-table", default=True, show_default=True,
              help="Tabulate the beta = 0 gain against N and the smoothing weights.")
@click.option("--no-ipopt", is_flag=True, help="Skip the hard-constrained IPOPT comparison.")
@click.option("--within-data", is_flag=True,
              help="Keep the optimised motions within the identification data: the pitch "
                   "amplitude, peak pitch rate and acceleration, frequency and heave amplitude "
                   "its CFD cases reach bound the sweep, the refinement and the optimisers "
                   "(each the tighter of the case file's and the data's).")
@click.option("--rounds", default=1, show_default=True, type=click.IntRange(min=1),
              help="CFD in the loop: run the whole job up to this many times, each round "
                   "identifying the model with the back-test CFD of the rounds before "
                   "pooled in, until the model predicts its back-tested motions' mean thrust "
                   "and power within --loop-tolerance (needs --coefficients identified:... "
                   "or --correct-outputs; "
                   "each round in <out>/round_<k>, the rounds in <out>/rounds.html, .h5, "
                   ".png).")
@click.option("--loop-tolerance", default=0.1, show_default=True, type=float,
              help="With --rounds: the relative error of the model's mean thrust and power "
                   "against CFD at which the rounds stop.")
@click.option("--correct-outputs", is_flag=True,
              help="With --rounds: from round 2 on, optimise each beta with the model's "
                   "thrust and power scaled to predict the CFD means of the previous round's "
                   "optimum of that beta (output space mapping), and check those corrected "
                   "predictions against the new back-tests.")
@click.option("--correction-gain", default=1.0, show_default=True, type=float,
              help="With --correct-outputs: K in (0, 1] of a first-order filter of the "
                   "scales, each round moving them only this fraction of the way from "
                   "those the previous optimum was optimised with to the measured ones "
                   "(damps the rounds' oscillation; 1: no filter).")
@click.option("--refit/--no-refit", default=True, show_default=True,
              help="With --rounds and identified coefficients: refit the model on the "
                   "back-tests of the rounds before; --no-refit keeps round 1's "
                   "coefficients, so that only --correct-outputs learns from the CFD.")
@click.option("--trust-region", "trust_radius", default=None, type=float,
              help="With --rounds: from round 2 on, keep each beta's optimum within this "
                   "fraction (the first radius, e.g. 0.25) of the accelerations and time "
                   "step of the last optimum CFD confirmed, halving or doubling it as the "
                   "back-tests confirm the predicted gains (trust-region modifier "
                   "adaptation).")
@click.option("--first-order", is_flag=True, default=False,
              help="With --correct-outputs and --trust-region: give each beta's corrected "
                   "objective a slope too, so that it is CFD's objective at the earlier "
                   "back-tested motions of that beta near the centre, not only at the "
                   "centre (a minimum-norm secant slope: a first-order modifier without CFD "
                   "gradients).")
@click.option("--cfd-repeatability", "cfd_repeatability", default=None, type=float,
              help="With --trust-region: the share by which two CFD runs of one motion differ "
                   "in their mean thrust and power (e.g. 0.03, the copies' spread in their "
                   "third cycle, docs/findings/optimised_motions.md 'First-order corrections'; one "
                   "cycle's scatter in longer runs is 0.02-0.09, "
                   "docs/findings/optimised_motions.md "
                   "'How long a back-test runs', which mfflap backtest --average-cycles "
                   "prints). Each step's ratio is relaxed by the noise it makes in the "
                   "objective, and a step predicted to gain less than that noise counts as "
                   "settled.")
@click.option("--backtest-cycles", type=float, default=None,
              help="With --live: the periods each back-test runs after its start-up ramp of "
                   "half a period [default: 3] (mfflap backtest --cycles).")
@click.option("--average-cycles", type=int, default=1, show_default=True,
              help="Compare the back-tests' CFD and model means over their last this many "
                   "whole cycles, with the CFD's standard errors (mfflap backtest "
                   "--average-cycles); with --rounds, the rounds judge those means.")
@retries_from_start_option()
@fix_phase_option()
@click.option("--json", "as_json", is_flag=True, help="Print the key numbers as JSON.")
def run_cmd(case_file: Path, out_dir: Path | None, fixtures: tuple[Path, ...],
            backtest_fixtures: tuple[Path, ...], live: bool, coefficients: str, starts: int,
            gain_table: bool, no_ipopt: bool, within_data: bool, rounds: int,
            loop_tolerance: float, correct_outputs: bool, correction_gain: float,
            refit: bool, trust_radius: float | None, first_order: bool,
            cfd_repeatability: float | None, backtest_cycles: float | None,
            average_cycles: int, retries_from_start: bool, fix_phase: bool,
            as_json: bool) -> None:
    """Identification, sweep, optimisation, back-test and reports for CASE_FILE.

    Writes <out>/report.html (every figure), <out>/results.h5 (every number and the inputs)
    and <out>/vtk/*.pvd (the motions for ParaView). A stage that fails is reported and the
    run goes on. Ctrl-C stops the run and writes the report and results of the stages
    finished before it.
    """
    from mfflap.cli.backtest import check_cycles
    from mfflap.cli.options import refuse_given
    from mfflap.config import load_case
    from mfflap.identification.workflow import sources_shown
    from mfflap.optimisation.output_correction import check_gain
    from mfflap.pipeline import RunOptions, run_study
    from mfflap.reports.run import write_run_outputs
    from mfflap.rounds import check_rounds

    if rounds == 1:
        refuse_given(("loop_tolerance", "correct_outputs", "correction_gain", "refit",
                      "trust_radius", "first_order", "cfd_repeatability"),
                     "rounds of CFD in the loop (--rounds 2 or more)")
    if not correct_outputs:
        refuse_given(("correction_gain",), "corrected outputs (--correct-outputs)")
    if not coefficients.startswith("identified:"):
        refuse_given(("refit",), "identified coefficients (--coefficients identified:...)")
    check_rounds(rounds, loop_tolerance, coefficients, correct_outputs, refit, trust_radius,
                 first_order, correction_gain, cfd_repeatability)
    check_gain(correction_gain)
    if not live:
        refuse_given(("backtest_cycles", "retries_from_start"),
                     "live back-tests (--live); without it the back-test reads CFD records, "
                     "run for as many periods as they were, with the retries they made")
    n_cycles = check_cycles(backtest_cycles, average_cycles, option="--backtest-cycles")
    case = with_phase_fixed(load_case(case_file), fix_phase)
    out_dir = out_dir or Path(f"{case.study.name}_run")
    options = RunOptions(fixtures=fixtures, backtest_fixtures=backtest_fixtures, live=live,
                         work_dir=out_dir / "cfd_cases", coefficients=coefficients,
                         n_starts=starts, with_ipopt=not no_ipopt, gain_table=gain_table,
                         vtk_dir=out_dir / "vtk",  # checked before the folder is made
                         within_data=within_data, backtest_cycles=n_cycles,
                         average_cycles=average_cycles,
                         retries_from_start=retries_from_start)
    out_dir.mkdir(parents=True, exist_ok=True)
    if rounds > 1:
        _run_rounds(case, options, rounds, loop_tolerance, out_dir, sources_shown(fixtures),
                    as_json, correct_outputs, correction_gain, refit, trust_radius,
                    first_order, cfd_repeatability)
        return
    outcome = run_study(case, options, progress=lambda m: click.echo(m, err=True))
    write_run_outputs(outcome.config or case, outcome, out_dir / "results.h5",
                  out_dir / "report.html",
                  sources_shown(fixtures))
    if outcome.interrupted is not None:
        click.echo(f"interrupted ({outcome.interrupted}): {out_dir / 'report.html'} and "
                   f"{out_dir / 'results.h5'} hold the stages finished before; the same command "
                   "runs the whole study again"
                   + (f", and live back-test cases in {options.work_dir} resume from their last "
                      "written times" if live else ""), err=True)
        raise click.Abort()
    if as_json:
        echo_json(run_summary(outcome))
        return
    click.echo(f"wrote {out_dir / 'report.html'} and {out_dir / 'results.h5'}")
    if outcome.problems:
        click.echo(f"{len(outcome.problems)} problem(s), listed in the report:")
        for p in outcome.problems:
            click.echo(f"  - {p.splitlines()[0]}")


def _run_rounds(case, options, rounds: int, tolerance: float, out_dir: Path, source: str,
                as_json: bool, correct_outputs: bool = False,
                correction_gain: float = 1.0, refit: bool = True,
                trust_radius: float | None = None, first_order: bool = False,
                cfd_repeatability: float | None = None) -> None:
    """``--rounds`` > 1: :func:`mfflap.rounds.run_rounds` and what it wrote."""
    from mfflap.reports.rounds import write_rounds
    from mfflap.reports.run import write_round_outputs
    from mfflap.rounds import run_rounds

    result, outcome = run_rounds(case, options, rounds, tolerance, out_dir,
                                 progress=lambda m: click.echo(m, err=True), source=source,
                                 correct_outputs=correct_outputs,
                                 correction_gain=correction_gain, refit=refit,
                                 trust_radius=trust_radius, first_order=first_order,
                                 cfd_repeatability=cfd_repeatability,
                                 write_round=write_round_outputs, write_summary=write_rounds)
    if outcome is not None and outcome.interrupted is not None:
        click.echo(f"interrupted in round {len(result.rounds)} ({outcome.interrupted}): "
                   f"{out_dir / 'rounds.html'} holds the rounds so far; the same command runs "
                   "them again, finding the back-test CFD done before in "
                   f"{out_dir / 'loop_records'}", err=True)
        raise click.Abort()
    if as_json:
        echo_json({"rounds": result.as_dict(),
                   "last_round": None if outcome is None else run_summary(outcome)})
        return
    click.echo(f"wrote {out_dir / 'rounds.html'}, {out_dir / 'rounds.h5'} and "
               f"{out_dir / 'rounds.png'}; each round's report and results in "
               f"{out_dir}/round_<k>")
    click.echo(f"{'converged' if result.converged else 'not converged'}: "
               f"{result.stopped_because}")
    n_problems = sum(1 for r in result.rounds for _ in r.not_backtested)
    if n_problems:
        click.echo(f"{n_problems} motion(s) not back-tested, listed in the rounds' reports")


def run_summary(outcome) -> dict:
    """The key numbers of a run (JSON-friendly)."""
    from mfflap.identification.fit import most_influential

    out: dict = {"problems": [p.splitlines()[0] for p in outcome.problems]}
    out["coefficients"] = {k: r.coefficients for k, r in outcome.identification.items()}
    out["most_influential_case"] = {  # per strategy and coefficient: the case it rests on most
        k: {i.term: i.case for i in most_influential(r)}
        for k, r in outcome.identification.items()}
    if outcome.study is not None:
        out["optimised"] = {f"{b:g}": {**r.summary.as_dict(), "period": float(r.motion.period),
                                       "converged": r.converged, "flags": r.flags}
                            for b, r in outcome.study.sqp.items()}
        out["thrust_gain_beta0"] = outcome.study.thrust_gain
        out["thrust_gain_beta0_refined"] = outcome.study.thrust_gain_refined
        out["thrust_gain_beta0_caveat"] = outcome.study.thrust_gain_caveat
    out["output_corrections"] = {f"{b:g}": c.as_dict() for b, c in outcome.corrections.items()}
    out["backtest"] = {k: {"status": o.status, "source": o.source,
                           **(o.comparison.as_dict() if o.comparison else {})}
                       for k, o in outcome.backtests.items()}
    # per strategy: the scaling the fit was made with, and the one its errors ask for
    out["residual_scaling"] = {
        k: {"used": r.residual_scaling, "asked": r.scaling_asked,
            "errors_ask_for": sorted({g.matching_scaling for g in r.error_growth.values()})}
        for k, r in outcome.identification.items()}
    out["coverage"] = {k: c.as_dict() for k, c in outcome.coverage.items()}
    out["within_data_limits"] = outcome.within_data_limits or None
    if outcome.gap is not None:
        out["gap_verdict"] = outcome.gap[0].verdict
        out["gap_residual_scaling"] = outcome.gap[0].residual_scaling
        transfer = outcome.gap[0].transfer
        out["gap_transfer"] = None if transfer is None else {
            "effect": list(transfer.effect), "claimed": transfer.claimed,
            "carries_over": transfer.carries_over, "gain": transfer.gain,
            "verdict": transfer.verdict}
    return out
