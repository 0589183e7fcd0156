"""``mfflap run``: the whole pipeline of a study file."""

from __future__ import annotations

from pathlib import Path

import click

from mfflap.cli.json_output import echo_json
from mfflap.cli.options import set_option


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
@click.option("--live", is_flag=True,
              help="Run the back-test CFD live with OpenFOAM (the case file's [backtest]).")
@click.option("--overwrite", is_flag=True,
              help="Replace the outputs of an earlier run in --out (its report, results, "
                   "VTK files and rounds); without it such a folder is refused. The earlier "
                   "run's CFD records and case folders are kept and reused.")
@set_option()
@click.option("--json", "as_json", is_flag=True, help="Print the key numbers as JSON.")
def run_cmd(case_file: Path, out_dir: Path | None, fixtures: tuple[Path, ...],
            backtest_fixtures: tuple[Path, ...], live: bool, overwrite: bool,
            settings: tuple[str, ...], as_json: bool) -> None:
    """Identification, sweep, optimisation, back-test and reports for CASE_FILE.

    Optimises with the coefficients it identifies ([optimisation] coefficients), back-tests
    every optimum in CFD ([backtest]) and, with [rounds] count above 1, runs CFD in the
    loop. Writes <out>/report.html (every figure), <out>/results.h5 (every number and the
    inputs), <out>/vtk/*.pvd (the motions for ParaView) and, with --live, each back-test's
    CFD record in <out>/backtest_records (which --backtest-fixtures reads back). A stage
    that fails is reported and the run goes on. Ctrl-C stops the run and writes the report
    and results of the stages finished before it.
    """
    from mfflap.config import load_case
    from mfflap.identification.workflow import sources_shown
    from mfflap.pipeline import RunOptions, run_study
    from mfflap.reports.run import write_run_outputs
    from mfflap.reports.run_folder import prepare_run_folder

    case = load_case(case_file, settings)
    out_dir = out_dir or Path(f"{case.study.name}_run")
    options = RunOptions.for_case(case, out_dir, fixtures=fixtures,
                                  backtest_fixtures=backtest_fixtures, live=live)
    prepare_run_folder(out_dir, overwrite=overwrite)
    weighting = case.optimisation.coefficients
    click.echo("optimising with " + ("the case file's [model.coefficients]" if weighting == "case"
                                     else f"the coefficients it identifies from the CFD records "
                                          f"with the {weighting} weighting") +
               " ([optimisation] coefficients; the report's summary gives their values)",
               err=True)
    if case.rounds.count > 1:
        _run_rounds(case, options, out_dir, sources_shown(fixtures), as_json)
        return
    outcome = run_study(case, options, progress=lambda m: click.echo(m, err=True))
    write_run_outputs(outcome.config or case, outcome, out_dir / "results.h5",
                      out_dir / "report.html", sources_shown(fixtures))
    if outcome.interrupted is not None:
        click.echo(f"interrupted ({outcome.interrupted}): {out_dir / 'report.html'} and "
                   f"{out_dir / 'results.h5'} hold the stages finished before; the same command "
                   "with --overwrite runs the whole study again"
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


def _run_rounds(case, options, out_dir: Path, source: str, as_json: bool) -> None:
    """[rounds] count > 1: :func:`mfflap.rounds.run_rounds` and what it wrote."""
    from mfflap.reports.rounds import write_rounds
    from mfflap.reports.run import write_round_outputs
    from mfflap.rounds import run_rounds

    r = case.rounds
    result, outcome = run_rounds(case, options, r.count, r.tolerance, out_dir,
                                 progress=lambda m: click.echo(m, err=True), source=source,
                                 correct_outputs=r.correct_outputs,
                                 correction_gain=r.correction_gain, refit=r.refit,
                                 trust_radius=r.trust_radius, first_order=r.first_order,
                                 cfd_repeatability=r.cfd_repeatability,
                                 write_round=write_round_outputs, write_summary=write_rounds)
    if outcome is not None and outcome.interrupted is not None:
        click.echo(f"interrupted in round {len(result.rounds)} ({outcome.interrupted}): "
                   f"{out_dir / 'rounds.html'} holds the rounds so far; the same command with "
                   "--overwrite runs them again, finding the back-test CFD done before in "
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
    # the coefficients the optimisation used: a weighting's identified ones, or the case's
    out["optimised_with"] = outcome.optimised_with or "case"
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
