"""``mfflap identify`` and ``mfflap report identification``."""

from __future__ import annotations

from pathlib import Path

import click
import numpy as np

from mfflap.cli.json_output import echo_json
from mfflap.cli.options import FloatList, NameList, ResultsOutput, residual_scaling_option


def _strategies(names: tuple[str, ...], weights: list[float] | None, case) -> list:
    chosen: list = list(names) or ["uniform", "low", "high"]
    if weights:
        chosen.append(list(weights))
    elif case.identification.frequency_weights is not None and not names:
        chosen.append(list(case.identification.frequency_weights))
    return chosen


def _check_weights(weights: list[float], cases: list) -> None:
    """Refuse ``--weights`` that are not one weight per distinct frequency of the records,
    naming the option (the fit would name only the case file's key)."""
    from mfflap.errors import ConfigError
    from mfflap.identification.weights import frequency_weights

    try:
        frequency_weights([c.frequency for c in cases], weights)
    except ConfigError as exc:
        distinct = sorted({float(c.frequency) for c in cases})
        raise click.BadParameter(
            f"{len(weights)} weights {weights} for the {len(distinct)} frequencies of the "
            f"records, {', '.join(f'{f:g}' for f in distinct)} Hz: give one finite weight >= "
            "0 per frequency, in ascending frequency, with a positive sum",
            param_hint="--weights") from exc


def _fitted_components() -> tuple[str, ...]:
    """The load components an identification can fit."""
    from mfflap.identification.data import COMPONENTS

    return tuple(COMPONENTS)


@click.command()
@click.argument("case_file", type=click.Path(dir_okay=False, exists=True, path_type=Path))
@click.option("--fixtures", "folders", multiple=True,
              type=click.Path(exists=True, path_type=Path),
              help="Folder of CFD records or one record file, DIR/CASE.h5 (default: the "
                   "shipped fixtures); repeat to pool several (a case may have a record in "
                   "one of them only).")
@click.option("--exclude", "left_out", multiple=True, metavar="CASE",
              help="Leave this case out of the fit (e.g. the one a coefficient rests on "
                   "most); repeat for several.")
@click.option("--strategy", "strategies", multiple=True,
              type=click.Choice(["uniform", "low", "high"]),
              help="Weighting strategy; repeat for several (default: all three).")
@click.option("--weights", type=FloatList(unique=False), default=None,
              help="User weights per frequency, ascending frequency, comma-separated.")
@click.option("--components", type=NameList(_fitted_components), default=None,
              help="Fitted components, comma-separated, each once (default normal_force,"
                   "tangential_force,moment).")
@residual_scaling_option
@click.option("--bootstrap", "n_bootstrap", default=200, show_default=True,
              type=click.IntRange(min=0),
              help="Case-bootstrap replicates.")
@click.option("--output", type=ResultsOutput("identification"),
              default=Path("identification.h5"), show_default=True, help="HDF5 results.")
@click.option("--json", "as_json", is_flag=True, help="Print coefficients as JSON.")
def identify(case_file: Path, folders: tuple[Path, ...], left_out: tuple[str, ...],
             strategies: tuple[str, ...], weights: list[float] | None,
             components: list[str] | None, residual_scaling: str | None, n_bootstrap: int,
             output: Path, as_json: bool) -> None:
    """Fit the Morison coefficients of CASE_FILE's model to CFD records."""
    from mfflap.config import load_case
    from mfflap.errors import MfflapError
    from mfflap.identification.data import SET_UP_NOTE
    from mfflap.identification.error_growth import scaling_advice
    from mfflap.identification.fit import HELD_AT_ZERO, most_influential, scalings_said
    from mfflap.identification.workflow import (
        identify_strategies,
        leave_out,
        load_cases,
        save_identification,
        source_text,
        sources_shown,
    )
    from mfflap.records.record import identification_fixture_dirs

    case = load_case(case_file)
    folders = folders or identification_fixture_dirs()
    cases, excluded = load_cases(case, folders)
    if left_out:
        try:
            cases, excluded = leave_out(cases, excluded, left_out)
        except MfflapError as exc:
            raise click.BadParameter(str(exc), param_hint="--exclude") from exc
    if weights:
        _check_weights(weights, cases)
    results = identify_strategies(case, cases, excluded, _strategies(strategies, weights, case),
                                  components, n_bootstrap, residual_scaling)
    save_identification(output, case, results, source_text(folders))
    influence = {label: most_influential(r) for label, r in results.items()}
    # fitted across two set-ups: a retry resumed the run with other settings in its window
    mixed = [c.name for c in cases if any(n.startswith(SET_UP_NOTE) for n in c.notes)]
    summary = {
        label: {"coefficients": r.coefficients, "standard_error": r.standard_error,
                "median_nrmse_normal_force": float(
                    sorted(r.metrics["normal_force"]["nrmse"])[len(r.case_names) // 2]),
                "at_lower_bound": list(r.at_lower_bound),
                "n_cases": len(r.case_names), "excluded": r.excluded,
                "residual_scaling": r.residual_scaling,
                "residual_scaling_asked": r.scaling_asked,
                "error_growth": {k: g.summary() for k, g in r.error_growth.items()},
                "most_influential": {
                    i.term: {"case": i.case, "value_without": i.value_without,
                             "relative_change": i.relative_change,
                             "change_in_standard_errors": i.in_standard_errors}
                    for i in influence[label]},
                "mixed_set_up": mixed}
        for label, r in results.items()
    }
    if as_json:
        echo_json(summary)
        return
    first = next(iter(results.values()))  # the strategies' fits err alike
    click.echo(f"{len(cases)} cases from {sources_shown(folders)}; {len(excluded)} left out; "
               f"residuals scaled {scalings_said(results)}")
    for label, r in results.items():
        coeffs = "  ".join(f"{n} = {v:.3f}" + (f" ± {r.standard_error[n]:.3f}"
                                                 if np.isfinite(r.standard_error[n]) else "")
                           + (" (held at 0)" if n in r.at_lower_bound else "")
                           for n, v in r.coefficients.items())
        click.echo(f"{label:8s} {coeffs}")
        if influence[label]:
            click.echo(f"{'':8s} left out, moves most: "
                       + "; ".join(map(str, influence[label])))
    if any(r.at_lower_bound for r in results.values()):
        click.echo(f"held at 0: {HELD_AT_ZERO}")
    if mixed:
        click.echo(f"{len(mixed)} case(s) fitted across two set-ups (a retry resumed the run "
                   f"with other settings within its fitted window): {', '.join(mixed)}; "
                   "`mfflap campaign run --rerun-mixed` reruns them as one set-up")
    click.echo(f"{scaling_advice(first.error_growth, first.residual_scaling)} "
               f"({first.strategy} weighting)")
    click.echo(f"wrote {output}")


@click.group()
def report() -> None:
    """HTML reports from mfflap's HDF5 results."""


@report.command("identification")
@click.argument("results_file", type=click.Path(dir_okay=False, exists=True, path_type=Path))
@click.option("--fixtures", "folders", multiple=True,
              type=click.Path(exists=True, path_type=Path),
              help="The record folders or files; repeat for several (default: the ones the "
                   "results name).")
@click.option("--out", "out_path", type=click.Path(dir_okay=False, path_type=Path),
              default=None, help="HTML file (default: <results>.html).")
def report_identification(results_file: Path, folders: tuple[Path, ...],
                          out_path: Path | None) -> None:
    """Maps of Pearson and NRMSE, overlays, applicability region, weighting sensitivity."""
    from mfflap.config import stored_case
    from mfflap.errors import MfflapError
    from mfflap.identification.store import read_identification, strategies_in
    from mfflap.identification.workflow import load_cases, sources_shown
    from mfflap.reports.identification import identification_report
    from mfflap.results import ResultsFile

    with ResultsFile(results_file, "r", kinds=("identification", "run")) as rf:
        case = stored_case(rf.config_toml, source=f"{results_file}:/inputs")
        results = {s: read_identification(rf, f"identification/{s}") for s in strategies_in(rf)}
        if not results:
            raise MfflapError(f"{results_file}: no identification results (its groups: "
                              f"{', '.join(sorted(rf.h5)) or 'none'}); write them with "
                              "`mfflap identify` or `mfflap run`")
        source = str(rf.h5["identification"].attrs.get("source", ""))
    cases, _ = load_cases(case, folders or source)
    fitted = set(next(iter(results.values())).case_names)
    missing = sorted(fitted - {c.name for c in cases})
    if missing:  # maps and overlays of other records beside these coefficients' metrics
        raise MfflapError(f"{sources_shown(folders or source)} lacks {len(missing)} of the "
                          f"{len(fitted)} records {results_file} was fitted to (e.g. "
                          f"{', '.join(missing[:3])}); give the folders it was fitted from "
                          "with --fixtures")
    out_path = out_path or results_file.with_suffix(".html")
    identification_report(out_path, results, cases, case.morison_model(), case.flow.velocity,
                          sources_shown(folders or source))
    click.echo(f"wrote {out_path}")
