"""``mfflap cfd cycles``: how a periodic run's mean thrust and power go from cycle to cycle."""

from __future__ import annotations

from pathlib import Path

import click

from mfflap.cli.json_output import echo_json
from mfflap.cli.options import FigureFile


@click.command("cycles")
@click.argument("records", nargs=-1, required=True,
                type=click.Path(dir_okay=False, exists=True, path_type=Path))
@click.option("--skip-cycles", type=int, default=1, show_default=True,
              help="Whole cycles after the start-up ramp left out as start-up before the "
                   "settled cycles' mean (a back-test's second cycle can lie 30 % below the "
                   "ones after it: docs/findings/optimised_motions.md, 'How long a back-test "
                   "runs').")
@click.option("--figure", type=FigureFile(), default=None,
              help="Draw each run's cycle means with its settled mean and standard error.")
@click.option("--json", "as_json", is_flag=True, help="Print results as JSON.")
def cycles(records: tuple[Path, ...], skip_cycles: int, figure: Path | None,
           as_json: bool) -> None:
    """Mean CFD thrust and power of each whole cycle of RECORDS (HDF5 CFD records of
    periodic motions: back-tests, sinusoids), the mean over the settled ones with its
    standard error, and one cycle's scatter: the noise of a comparison that reads one cycle.

    Cycles are counted back from each run's end, after its start-up ramp, with numerical
    bursts bridged (mfflap.backtest.cycles). The retries a run made (a collapsed time step
    rerun with another far field or Courant limit) are shown, and the cycles that ran before
    a retry that resumed the run part-way: they are not of the set-up of the cycles after
    it (a retry from t = 0 s, mfflap backtest --retries-from-start, leaves one). A record
    of the identification's pitch-ramp sinusoids, whose cycles are not meant to repeat, is
    refused.
    """
    from mfflap.backtest.cycles import cycle_means, cycles_figure, record_period
    from mfflap.records.as_run import as_run_since_s
    from mfflap.records.record import read_record

    found, retries, since, before = [], {}, {}, {}
    for path in records:
        record = read_record(path)
        # a retry that resumed the run part-way changed its settings there (run_motion):
        # its cycles before and after are not of one set-up
        retries[path] = str(record.provenance.get("retries", "")) or None
        since[path] = as_run_since_s(record)
        every = cycle_means(record, record_period(record))
        before[path] = [int(n) for n, t in zip(every.numbers, every.start_s, strict=True)
                        if t < since[path] - 1e-9]
        found.append((path, every, every.after(skip_cycles)))
    if figure is not None:
        from mfflap.plots import save_figure

        save_figure(cycles_figure([(e, s) for _, e, s in found],  # named by file: records
                                  [path.stem for path, _, _ in found]), figure)  # may share one
        click.echo(f"wrote {figure}", err=True)
    if as_json:
        echo_json({"skip_cycles": skip_cycles, "runs": {
            str(path): {"cycle_numbers": [int(n) for n in every.numbers],
                        "every_cycle": every.as_dict(), "settled": settled.as_dict(),
                        "retries": retries[path], "settings_since_s": since[path],
                        "cycles_before_settings": before[path]}
            for path, every, settled in found}})
        return
    for path, every, settled in found:
        click.echo(f"{path}: cycles {', '.join(str(n) for n in every.numbers)} after the "
                   f"ramp; thrust {', '.join(f'{t:.4g}' for t in every.thrust)} N; power "
                   f"{', '.join(f'{p:.4g}' for p in every.power)} W")
        if since[path] > 0.0:
            click.echo(f"  retried part-way, so not one set-up throughout: its settings changed"
                       f" at t = {since[path]:.4g} s"
                       + (f"; cycle(s) {', '.join(map(str, before[path]))} ran (at least "
                          "partly) before that, with other settings" if before[path] else
                          ", before every whole cycle")
                       + f" (retries: {retries[path]})")
        elif retries[path]:
            click.echo(f"  retried from t = 0 s, so one set-up throughout: {retries[path]}")
        if settled.n_cycles < 2:
            click.echo(f"  settled: cycle {settled.numbers[0]} alone: no cycle-to-cycle "
                       "scatter from one cycle (run more periods, or --skip-cycles 0)")
            continue
        click.echo(f"  settled (cycles {settled.numbers[0]}-{settled.numbers[-1]}): mean "
                   f"thrust {settled.mean_thrust:.4g} ± {settled.thrust_standard_error:.2g} N, "
                   f"mean power {settled.mean_power:.4g} ± {settled.power_standard_error:.2g} W;"
                   f" one cycle's scatter {settled.thrust_scatter:.1%} (thrust), "
                   f"{settled.power_scatter:.1%} (power)")
