"""Entry point of the ``mfflap`` command."""

from __future__ import annotations

import contextlib
import json
import sys
from pathlib import Path

import click

from mfflap.cli.json_output import echo_json
from mfflap.cli.options import FigureFile, ResultsOutput
from mfflap.errors import SHOWN_CHARS, MfflapError


@contextlib.contextmanager
def _config_warnings_as_lines():
    """Show a case file's warnings (:class:`mfflap.config.ConfigWarning`) as one line each,
    ``warning: FILE: KEY ...``, instead of Python's file-and-line form."""
    import warnings

    from mfflap.config import ConfigWarning

    shown = warnings.showwarning

    def show(message, category, filename, lineno, file=None, line=None):
        if issubclass(category, ConfigWarning):
            click.echo(f"warning: {message}", err=True)
        else:
            shown(message, category, filename, lineno, file, line)

    warnings.showwarning = show
    try:
        yield
    finally:
        warnings.showwarning = shown


class MfflapGroup(click.Group):
    """A click group that turns mfflap's own errors into one clear line and exit code 2, and
    SIGTERM and SIGUSR1 into a Ctrl-C (:mod:`mfflap.cli.stop_signals`)."""

    def invoke(self, ctx: click.Context):
        from mfflap.cli.stop_signals import stop_signals_as_interrupt

        try:
            with stop_signals_as_interrupt(), _config_warnings_as_lines():
                return super().invoke(ctx)
        except MfflapError as exc:
            click.echo(f"mfflap: error: {exc}", err=True)
            sys.exit(2)
        except click.UsageError as exc:  # click repeats a bad value whole: cut it short
            exc.message = " ".join(word if len(word) <= 200
                                   else word[:SHOWN_CHARS] + "..."
                                   for word in exc.message.split(" "))
            raise


@click.group(cls=MfflapGroup, context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(package_name="mfflap")
def cli() -> None:
    """Morison reduced-order model of flapping-foil propulsion, its discrete adjoint, and the
    CFD pipeline (OpenFOAM, Fluent) that identifies and checks it."""


def _register_subgroups() -> None:
    from mfflap.cli.backtest import backtest
    from mfflap.cli.campaign import campaign
    from mfflap.cli.case import case, init
    from mfflap.cli.cfd import cfd
    from mfflap.cli.cfd_convergence import convergence
    from mfflap.cli.cfd_cycles import cycles
    from mfflap.cli.cfd_linear_check import linear_check
    from mfflap.cli.cfd_motion_table import motion_table_cmd
    from mfflap.cli.gap import gap
    from mfflap.cli.identify import identify, report
    from mfflap.cli.identify_vortex import identify_vortex
    from mfflap.cli.optimise import optimise
    from mfflap.cli.run import run_cmd

    for command in (convergence, cycles, linear_check, motion_table_cmd):
        cfd.add_command(command)
    cli.add_command(init)
    cli.add_command(case)
    cli.add_command(cfd)
    cli.add_command(campaign)
    cli.add_command(identify)
    cli.add_command(identify_vortex)
    cli.add_command(report)
    cli.add_command(optimise)
    cli.add_command(backtest)
    cli.add_command(run_cmd)
    cli.add_command(gap)


@cli.command()
@click.argument("case_file", type=click.Path(dir_okay=False, path_type=Path))
@click.option("--json", "as_json", is_flag=True, help="Print the cycle means as JSON.")
@click.option("--figure", type=FigureFile(), default=None,
              help="Where to save the one-cycle figure (.png, .pdf or .svg). Default: "
                   "<case name>.cycle.png in the working folder (the case file's own folder "
                   "may be read-only).")
@click.option("--output", type=ResultsOutput("evaluation"), default=None,
              help="Also write the results (HDF5, with the case stored beside them).")
@click.option("--scheme", type=click.Choice(["paper", "midpoint"]), default=None,
              help="Discrete scheme of the Morison model (default: the case's [model] "
                   "scheme).")
@click.option("--model", "model", type=click.Choice(["morison", "vortex"]), default="morison",
              show_default=True,
              help="The Morison model of the case, or the discrete-vortex model.")
@click.option("--motion", "motion_table", default=None,
              type=click.Path(dir_okay=False, exists=True, path_type=Path),
              help="Evaluate this motion table (CSV: t, heave, pitch with their units) "
                   "instead of the case's [motion], over its whole span.")
def evaluate(case_file: Path, as_json: bool, figure: Path | None, output: Path | None,
             scheme: str | None, model: str, motion_table: Path | None) -> None:
    """Evaluate the [motion] of CASE_FILE (or a --motion table) with the Morison model
    over one cycle, or with the discrete-vortex model.

    For the Morison model, a harmonic motion is converted to the discrete half-cycle scheme
    with the case's [discretisation] n_steps; a ramp motion is evaluated continuously over
    its cycles. The discrete-vortex model runs the motion from rest, 200 steps a period,
    and gives a harmonic motion's last period once its start-up wake is 5 chords
    downstream. A --motion table is evaluated continuously over its span, its first row to
    its last, with the case's plate, fluid, stream and model. Prints the cycle means and
    saves a figure of thrust, power, F_n, F_t and M.
    """
    from mfflap.config import load_case
    from mfflap.evaluation import evaluate_case, evaluate_table
    from mfflap.plots import save_figure

    if motion_table is not None:
        if scheme is not None:
            raise click.UsageError("--scheme is a discrete scheme of the case's harmonic "
                                   "[motion]; a --motion table is evaluated continuously")
        result = evaluate_table(load_case(case_file), motion_table, model=model)
    else:
        result = evaluate_case(case_file, scheme=scheme, model=model)
    figure = figure or Path(f"{case_file.stem}.cycle.png")
    save_figure(result.figure, figure)
    if output is not None:
        result.save(output)
    if as_json:
        echo_json({"case": str(case_file), "scheme": result.scheme, **result.summary_dict(),
                   "regime": result.evaluation.summary.regime, "figure": str(figure)})
        return
    click.echo(f"case {case_file} ({result.description}, scheme {result.scheme})")
    regime = result.evaluation.summary.regime
    if regime != "propulsion":
        click.echo(f"  regime: {regime} (mean thrust and input power are not thrust bought "
                   "with power: no efficiency)")
    for key, (value, unit) in result.summary_with_units().items():
        click.echo(f"  {key:26s} {value: .6g} {unit}")
    click.echo(f"figure: {figure}")


@cli.command()
@click.argument("case_file", type=click.Path(dir_okay=False, path_type=Path))
@click.option("--n-steps", default=40, show_default=True, type=click.IntRange(min=2),
              help="N of the checked motion (steps per half cycle; the work grows as N^2).")
@click.option("--json", "as_json", is_flag=True, help="Print the agreement as JSON.")
@click.option("--out", "out_dir", type=click.Path(file_okay=False, path_type=Path),
              default=None, help="Folder for gradcheck.png and gradcheck.json (default: "
                                 "<case file name>_gradcheck).")
def gradcheck(case_file: Path, n_steps: int, as_json: bool, out_dir: Path | None) -> None:
    """Adjoint gradient vs complex step, finite differences and CasADi at beta = 0, 0.5, 1.

    The point is the case's [motion] sinusoid, perturbed so that no symmetry hides an
    error and scaled down until the case's [optimisation] penalties make at most a tenth of
    J. The controls (dJ/du_j) and dJ/d(dt) are compared separately: the second is about
    1e4 times larger, so one ratio over both would hide an error in the first.
    """
    from tqdm import tqdm

    from mfflap.config import load_case
    from mfflap.optimisation.gradcheck import (
        CHECKED_BETAS,
        FD_NOTE,
        gradient_checks,
        scatter_figure,
    )
    from mfflap.plots import save_figure

    case = load_case(case_file)
    out_dir = out_dir or Path(f"{case_file.stem}_gradcheck")
    # three evaluations of the objective per component: N^2 work, shown as it goes
    with tqdm(total=len(CHECKED_BETAS) * (2 * n_steps + 1), desc="gradient components",
              disable=as_json, leave=False) as bar:
        checks = gradient_checks(case, n_steps, progress=bar.update)
    out_dir.mkdir(parents=True, exist_ok=True)
    figure = out_dir / "gradcheck.png"
    save_figure(scatter_figure(checks), figure)
    summary = {str(b): c.as_dict() for b, c in checks.items()}
    (out_dir / "gradcheck.json").write_text(json.dumps(summary, indent=2) + "\n")
    if as_json:
        echo_json(summary | {"figure": str(figure)})
        return
    for beta, c in checks.items():
        ok = ("ok" if max(c.controls_error_complex_step, c.time_step_error_complex_step)
              <= 1e-10 else "FAILED")
        click.echo(f"beta={beta:g} (penalties {100 * c.penalty_share:.2g} % of J): "
                   f"vs complex step: controls {c.controls_error_complex_step:.2e}, dt "
                   f"{c.time_step_error_complex_step:.2e} ({ok}); vs CasADi AD: controls "
                   f"{c.controls_error_casadi:.2e}, dt {c.time_step_error_casadi:.2e}; vs FD: "
                   f"controls {c.controls_error_finite_difference:.2e}, dt "
                   f"{c.time_step_error_finite_difference:.2e}")
    click.echo(FD_NOTE)
    click.echo(f"figure: {figure}")


_register_subgroups()


def main() -> None:  # pragma: no cover
    cli()
