"""``mfflap optimise``: the beta sweep of optimised motions with sweep, IPOPT and report."""

from __future__ import annotations

from pathlib import Path

import click

from mfflap.cli.json_output import echo_json
from mfflap.cli.options import FloatList, ResultsOutput, set_option


@click.command()
@click.argument("case_file", type=click.Path(dir_okay=False, exists=True, path_type=Path))
@click.option("--betas", type=FloatList(), default=None,
              help="Comma-separated betas (default: the case's).")
@click.option("--output", type=ResultsOutput("optimisation"),
              default=Path("optimisation.h5"), show_default=True)
@click.option("--report", "report_path", type=click.Path(dir_okay=False, path_type=Path),
              default=None, help="HTML report (default: <output>.html).")
@set_option()
@click.option("--json", "as_json", is_flag=True, help="Print the optimised means as JSON.")
def optimise(case_file: Path, betas: list[float] | None, output: Path,
             report_path: Path | None, settings: tuple[str, ...], as_json: bool) -> None:
    """Optimise the motion of CASE_FILE for each beta with the discrete adjoint and its
    [optimisation] table (multi-starts, the IPOPT comparison, the gain table), with the
    coefficients [optimisation] coefficients names, as `mfflap run` does: identified from
    the shipped CFD records with that frequency weighting (default uniform), or the case
    file's [model.coefficients] (coefficients = "case"). The first line says which.

    Ctrl-C (or SIGTERM, SIGUSR1) stops it and writes the betas optimised before it.
    """
    from mfflap.config import load_case
    from mfflap.optimisation.study import StudyInterrupted, beta_study
    from mfflap.optimisation.study import gain_table as make_gain_table

    case = load_case(case_file, settings)
    opt = case.optimisation

    def progress(msg: str) -> None:
        if not as_json:
            click.echo(msg, err=True)

    if opt.coefficients == "case":
        model = case.morison_model()
        said = "the case file's [model.coefficients]"
    else:
        from mfflap.api import Study

        identified = Study(case)
        identified.identify(weighting=opt.coefficients, bootstrap=0)
        model = identified.model
        said = (f"the coefficients identified from the shipped CFD records with the "
                f"{opt.coefficients} weighting, as mfflap run does ([optimisation] "
                "coefficients)")
    values = ", ".join(f"{k} = {v:.4g}" for k, v in model.coefficients.items())
    click.echo(f"optimising with {said}: {values}", err=True)
    try:
        study = beta_study(case, betas, n_starts=opt.starts, with_ipopt=opt.ipopt, model=model,
                           progress=progress)
    except StudyInterrupted as exc:  # write the betas finished before it, then stop
        html = _write(case, exc.study, None, model, output, report_path)
        click.echo(f"{exc.study.interruption}; wrote those optimised to {output} and {html}",
                   err=True)
        raise click.Abort() from None
    try:
        gain = make_gain_table(case, model=model, sweep=study.sweep, progress=progress) \
            if opt.gain_table else None
    except KeyboardInterrupt:  # the beta study is finished: write it without the table
        html = _write(case, study, None, model, output, report_path)
        click.echo(f"interrupted during the gain table; wrote the beta study without it to "
                   f"{output} and {html}", err=True)
        raise click.Abort() from None
    html = _write(case, study, gain, model, output, report_path)
    out = {f"{b:g}": {**r.summary.as_dict(), "period": float(r.motion.period),
                      "converged": r.converged, "flags": r.flags}
           for b, r in study.sqp.items()}
    if as_json:
        echo_json({"optimised": out, "thrust_gain_beta0": study.thrust_gain,
                   "thrust_gain_beta0_refined": study.thrust_gain_refined,
                   "thrust_gain_beta0_missing": study.no_thrust_gain_reason,
                   "thrust_gain_beta0_caveat": study.thrust_gain_caveat})
        return
    for b, r in study.sqp.items():
        s = r.summary
        click.echo(f"beta {b:4g}: thrust {float(s.mean_thrust):8.3f} N  power "
                   f"{float(s.mean_power):8.3f} W  St {float(s.strouhal_number):5.2f}  "
                   f"{'converged' if r.converged else 'NOT CONVERGED'}"
                   f"{'  FLAGGED' if r.flags else ''}")
        if not r.converged:
            click.echo(f"    not converged after {r.n_iterations} iterations: {r.message}")
        for flag in r.flags:
            click.echo(f"    flagged: {flag}")
    if study.thrust_gain is None:
        click.echo(f"beta = 0 thrust gain: not given: {study.no_thrust_gain_reason}")
    else:
        refined = study.thrust_gain_refined
        click.echo(f"beta = 0 thrust gain over the best feasible sinusoid: "
                   f"{study.thrust_gain:+.1%}"
                   + ("" if refined is None else f" (over the refined one: {refined:+.1%})")
                   + (f"; caution: {study.thrust_gain_caveat}" if study.thrust_gain_caveat
                      else ""))
    click.echo(f"wrote {output} and {html}")


def _write(case, study, gain, model, output: Path, report_path: Path | None) -> Path:
    """Write the study's results file and HTML report; return the report's path."""
    from mfflap.optimisation.workflow import write_study
    from mfflap.reports.html import Report
    from mfflap.reports.optimisation import add_optimisation_sections
    from mfflap.results import ResultsFile

    with ResultsFile(output, "w", kind="optimisation", config_toml=case.to_toml()) as rf:
        write_study(rf, case, study, gain, model)
    rep = Report(f"Optimisation study: {case.study.name}", case.study.description)
    add_optimisation_sections(rep, study, model, case.optimisation.scheme,
                              case.optimisation.max_power, gain, case.optimisation.phase)
    return rep.write(report_path or output.with_suffix(".html"))
