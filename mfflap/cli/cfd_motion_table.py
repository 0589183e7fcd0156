"""``mfflap cfd motion-table``: an optimised motion (or the best sinusoid) as a CSV motion
table."""

from __future__ import annotations

from pathlib import Path

import click
import numpy as np

from mfflap.cli.options import (
    CYCLES,
)


@click.command("motion-table")
@click.argument("results_file", type=click.Path(dir_okay=False, exists=True, path_type=Path))
@click.argument("table_file", type=click.Path(dir_okay=False, path_type=Path))
@click.option("--beta", type=float, default=None,
              help="The optimised motion of this β (from `mfflap optimise` or `mfflap run`).")
@click.option("--best-sinusoid", is_flag=True,
              help="The best sinusoid of the sweep instead of an optimised motion.")
@click.option("--cycles", default=3.0, show_default=True, type=CYCLES,
              help="Periods in the table.")
@click.option("--rows-per-period", default=400, show_default=True,
              type=click.IntRange(min=8), help="Table rows per period.")
def motion_table_cmd(results_file: Path, table_file: Path, beta: float | None,
                     best_sinusoid: bool, cycles: float, rows_per_period: int) -> None:
    """Write an optimised motion (or the best sinusoid) of RESULTS_FILE as a CSV motion table
    for `cfd write --motion-table` and `cfd fluent --motion-table`: the periodic spline the
    back-test imposes, from t = 0."""
    from mfflap.backtest.run import cfd_motion
    from mfflap.kinematics.table_file import write_motion_table
    from mfflap.optimisation.store import read_result, read_sweep
    from mfflap.optimisation.study import sinusoid_motion
    from mfflap.results import ResultsFile

    if beta is None and not best_sinusoid:
        raise click.UsageError("give --beta B or --best-sinusoid")
    if beta is not None and best_sinusoid:
        raise click.UsageError("give --beta B or --best-sinusoid, not both: a table holds "
                               "one motion")
    with ResultsFile(results_file, kinds=("optimisation", "run")) as rf:
        if "optimisation/sqp" not in rf.h5:
            raise click.UsageError(f"{results_file} holds no optimised motions "
                                   "(optimisation/sqp)")
        results = [read_result(rf, f"optimisation/sqp/{key}")
                   for key in sorted(rf.h5["optimisation/sqp"])]
        if best_sinusoid:
            sweep, best = read_sweep(rf, "optimisation/sweep")
            motion, label = sinusoid_motion(sweep, best, results[0].motion.n_steps), \
                "the best sinusoid"
        else:
            chosen = [r for r in results if abs(r.beta - beta) < 1e-9]
            if not chosen:
                raise click.BadParameter(f"{results_file} has β = "
                                         f"{', '.join(f'{r.beta:g}' for r in results)}",
                                         param_hint="--beta")
            motion, label = chosen[0].motion, f"the optimised motion of beta = {beta:g}"
    spline = cfd_motion(motion)
    write_motion_table(table_file, spline, cycles * spline.period,
                       max(round(cycles * rows_per_period), 8),
                       comment=f"{label} of {results_file}, period {spline.period:.9g} s")
    start = spline.sample(np.array([0.0]))
    click.echo(f"wrote {table_file}: {label}, period {spline.period:.4g} s, {cycles:g} periods")
    at_start = {"pitch": (np.degrees(start.pitch_angle[0]), "deg"),
                "pitch rate": (np.degrees(start.pitch_rate[0]), "deg/s"),
                "heave velocity": (start.heave_velocity[0], "m/s")}
    moving = {name: value for name, value in at_start.items() if abs(value[0]) > 1e-6}
    if moving:  # round-off (1e-15 deg) is no motion, and is not shown
        click.echo("it does not start at rest ("
                   + ", ".join(f"{name} {value:.3g} {unit}"
                               for name, (value, unit) in moving.items())
                   + "): write the case with "
                   f"--ramp-time (the back-test uses half a period, {0.5 * spline.period:.4g} s)")
