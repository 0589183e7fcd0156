"""``mfflap identify-vortex``: the discrete-vortex model's parameters from CFD records."""

from __future__ import annotations

from pathlib import Path

import click

from mfflap.cli.json_output import echo_json


@click.command("identify-vortex")
@click.argument("case_file", type=click.Path(dir_okay=False, exists=True, path_type=Path))
@click.option("--fixtures", "folders", multiple=True, required=True,
              type=click.Path(file_okay=False, exists=True, path_type=Path),
              help="Folders of CFD records to identify from (repeatable), e.g. "
                   "campaigns/harmonic_set; keep the back-tests, the check, out of them.")
@click.option("--json", "as_json", is_flag=True, help="Print the grid and the pair as JSON.")
def identify_vortex(case_file: Path, folders: tuple[Path, ...], as_json: bool) -> None:
    """Identify the discrete-vortex model's critical LESP and core radius from CFD records.

    Every pair of the grid (critical LESP 0.1-0.3 and never shedding, core radius 0.01-0.05
    chords) runs through every record's motion from rest; the pair whose F_n follows the
    records' best (RMS over the records of each one's NRMSE over its last two periods) is
    the identified one. Records run for another plate, fluid or stream than CASE_FILE's
    are refused.
    """
    from mfflap.config import load_case
    from mfflap.identification.vortex_parameters import identify_vortex_parameters
    from mfflap.records.inputs import check_records_inputs
    from mfflap.records.record import read_records

    case = load_case(case_file)
    records = [(record, folder) for folder in folders for record in read_records(folder)]
    check_records_inputs(records, case.plate, case.fluid, case.flow,
                         case_source=str(case_file), use="vortex identification")
    fit = identify_vortex_parameters(
        [r for r, _ in records], case.plate, case.fluid, case.flow, base=case.vortex,
        progress=None if as_json else lambda line: click.echo(line, err=True))
    if as_json:
        echo_json({"critical_lesp": fit.critical_lesp,
                   "core_radius_chords": fit.core_radius_chords,
                   "rms_nrmse_normal_force": fit.score,
                   "grid": [{"critical_lesp": lesp, "core_radius_chords": core,
                             "rms_nrmse_normal_force": score, "blown_up": blown}
                            for lesp, core, score, blown in fit.grid],
                   "record_nrmse_normal_force": fit.record_nrmse,
                   "n_records": len(records)})
        return
    click.echo(f"{len(records)} records; identified: critical LESP {fit.critical_lesp:g}, "
               f"core radius {fit.core_radius_chords:g} chords, RMS NRMSE of F_n "
               f"{fit.score:.1%}")
    lesp = "inf" if fit.critical_lesp == float("inf") else f"{fit.critical_lesp:g}"
    click.echo(f"to use them: [vortex] critical_lesp = {lesp}, core_radius_chords = "
               f"{fit.core_radius_chords:g} in the case file")
    for name, value in fit.record_nrmse.items():
        click.echo(f"  {name}: F_n NRMSE {value:.1%}")
