"""``mfflap gap diagnose | blindtest | levels``."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import click
import numpy as np

from mfflap.cli.json_output import echo_json
from mfflap.cli.options import (
    POSITIVE,
    RESIDUAL_SCALING_NAMES,
    ResultsOutput,
    set_option,
)

if TYPE_CHECKING:
    from mfflap.config import CaseConfig


@click.group()
def gap() -> None:
    """Sim-to-real gap diagnosis of the reduced model against CFD."""


@gap.command("diagnose")
@click.argument("case_file", type=click.Path(dir_okay=False, exists=True, path_type=Path))
@click.option("--fixtures", "folders", multiple=True,
              type=click.Path(exists=True, path_type=Path),
              help="Folders of CFD records (campaign, back-test) or record files; default: "
                   "shipped fixtures, unless --csv is given.")
@click.option("--csv", "csv_files", multiple=True,
              type=click.Path(exists=True, path_type=Path),
              help="External (motion, force) CSV files, or folders of them: time, "
                   "pitch_angle, heave_position, normal_force, tangential_force, moment "
                   "(rad, m, N, N*m about the pivot). A folder with a manifest.toml "
                   "is one dataset: the manifest gives each run's motion and the set-up "
                   "(checked against the case file); otherwise '# frequency = 1.5' lines "
                   "before a file's header do. With --fixtures, pooled with the records.")
@click.option("--flow", "flow_dirs", multiple=True,
              help="CASE=DIR: an OpenFOAM case folder with written fields for record CASE; the "
                   "report shows its vorticity where the model misses most.")
@click.option("--check-on", "check_on", multiple=True,
              type=click.Path(exists=True, path_type=Path),
              help="Folders of CFD records or record files the fits must not see (e.g. the "
                   "back-tested optimised motions): whether the claimed effect (else the best "
                   "candidate) predicts their last period better. Repeat for several.")
@click.option("--alpha", default=0.01, show_default=True, help="Significance level.")
@click.option("--min-gain", default=0.02, show_default=True,
              help="Smallest held-out error reduction worth claiming.")
@set_option()
@click.option("--output", type=ResultsOutput("gap_diagnosis"),
              default=Path("gap.h5"), show_default=True)
@click.option("--report", "report_path", type=click.Path(dir_okay=False, path_type=Path),
              default=None, help="HTML report (default: <output>.html).")
@click.option("--json", "as_json", is_flag=True)
def diagnose_cmd(case_file: Path, folders: tuple[Path, ...], csv_files: tuple[Path, ...],
                 flow_dirs: tuple[str, ...], check_on: tuple[Path, ...], alpha: float,
                 min_gain: float, settings: tuple[str, ...], output: Path,
                 report_path: Path | None, as_json: bool) -> None:
    """Where the model of CASE_FILE departs from CFD, and which effect explains it.

    The start-up left out of every case (records and CSV files alike) and the weighing of
    the cases' residuals are the case file's [identification] discard_time and
    residual_scaling (--set identification.discard_time=2.0)."""
    from mfflap.config import load_case
    from mfflap.gap.external import csv_paths, read_csv_case
    from mfflap.gap.manifest import MANIFEST_NAME, has_manifest, read_dataset
    from mfflap.gap.store import write_diagnosis
    from mfflap.gap.system import MIN_CASES
    from mfflap.gap.workflow import diagnose_cases
    from mfflap.identification.data import prepare_cases
    from mfflap.identification.error_growth import scaling_advice
    from mfflap.identification.fit import scaling_said
    from mfflap.identification.workflow import pooled_records
    from mfflap.records.record import identification_fixture_dirs
    from mfflap.reports.gap import gap_report
    from mfflap.results import ResultsFile

    case = load_case(case_file, settings)
    discard = case.identification.discard_time
    cases = []
    sources = []
    given_folders = bool(folders)
    folders = folders or (identification_fixture_dirs() if not csv_files else ())
    level_records = None
    if folders:
        records, _ = pooled_records(folders, case, use="gap diagnosis")
        prepared, excluded = prepare_cases(
            records, discard, plate=case.plate, fluid=case.fluid, stream=case.flow)
        cases += prepared
        level_records = [r for r in records if r.name in {c.name for c in prepared}]
        sources += [str(f) for f in folders]
        for name, why in excluded.items():
            click.echo(f"left out {name}: {why}", err=True)
    for dataset in [p for p in csv_files if p.is_dir() and has_manifest(p)]:
        cases += read_dataset(dataset, discard_s=discard, config=case)
        sources.append(str(dataset / MANIFEST_NAME))
    csv_files = tuple(csv_paths(p for p in csv_files if not (p.is_dir() and has_manifest(p))))
    cases += [read_csv_case(p, discard_s=discard, config=case) for p in csv_files]
    sources += [str(p) for p in csv_files]
    if len(cases) < MIN_CASES and csv_files and not given_folders:
        raise click.UsageError(f"{len(cases)} case(s) from --csv; a diagnosis needs at least "
                               f"{MIN_CASES}, and the shipped fixtures are read only without "
                               "--csv: add CSV files, or --fixtures DIR to pool records")
    flows = [_flow_record(item, cases, case) for item in flow_dirs]  # before the work
    held_out, held_out_excluded, held_out_records = (_held_out(check_on, case, cases)
                                                     if check_on else (None, None, []))
    diag, where, pred = diagnose_cases(
        case, cases, alpha=alpha, min_gain=min_gain, held_out=held_out,
        held_out_excluded=held_out_excluded, records=level_records,
        held_out_records=held_out_records,
        progress=lambda line: click.echo(f"vortex level, {line}", err=True))
    snapshots = []
    for index, folder in flows:
        from mfflap.gap.flowfield import vorticity_figure

        c = cases[index]
        residual = c.cfd_signal("normal_force") - pred[index]["normal_force"]
        t_peak = float(c.state.time[int(np.argmax(np.abs(residual)))])
        fig, shown = vorticity_figure(folder, t_peak, case.plate.chord)
        snapshots.append((fig, f"{c.name}: vorticity at t = {shown:.4g} s, the written time "
                               f"nearest the largest F_n residual (t = {t_peak:.4g} s)"))
    with ResultsFile(output, "w", kind="gap_diagnosis", config_toml=case.to_toml()) as rf:
        write_diagnosis(rf, diag, where)
    html = gap_report(report_path or output.with_suffix(".html"), diag, where,
                      ", ".join(sources), snapshots)
    if as_json:
        echo_json({"finding": diag.finding, "verdict": diag.verdict,
                   "whiteness": diag.whiteness,
                   "indistinguishable": diag.indistinguishable,
                   "residual_scaling": diag.residual_scaling,
                   "error_growth": {k: g.summary() for k, g in diag.error_growth.items()},
                   "chosen": diag.chosen.label if diag.chosen else None,
                   "ranking": [[s.label, s.gain, s.p_value] for s in diag.scores],
                   "candidates": [
                       {"label": s.label, "heldout_gain": s.gain,
                        "physical_names": [diag.descriptions.get(n, {}).get("physical_name")
                                           for n in s.names],
                        "p_value": s.p_value, "significant": s.significant,
                        "coefficients": s.coefficients,
                        "held_coefficients": s.held_coefficients,
                        # an exact dependence (inf) is printed as null
                        "variance_inflation": s.variance_inflation,
                        "confounded_with": s.confounded_with}
                       for s in diag.scores],
                   "validation": diag.validation,
                   "validation_skipped": diag.validation_skipped,
                   "transfer": diag.transfer.as_dict() if diag.transfer else None,
                   "levels": None if diag.levels is None else {
                       "summary": {g: diag.levels.summary(g) for g in ("diagnosed",
                                                                        "held out")},
                       "records": [row.__dict__ for row in diag.levels.rows],
                       "excluded": diag.levels.excluded}})
        return
    click.echo(diag.headline())
    if diag.chosen is not None:
        click.echo(diag.claim_said())
    click.echo(f"residuals scaled {scaling_said(diag.residual_scaling, diag.scaling_asked)}; "
               f"the base model's {scaling_advice(diag.error_growth, diag.residual_scaling)}")
    click.echo("where the model departs most (a component's or harmonic's share of the "
               "squared residual; for a state or regime, the share of the residual's variance "
               "it explains, eta^2):")
    for name, share in where["ranking"][:5]:
        click.echo(f"  {name}: {share:.2f}")
    for key, why in diag.validation_skipped.items():
        click.echo(f"not checked by {key}: {why}")
    if diag.transfer is not None:
        click.echo(f"on runs outside the cases: {diag.transfer.verdict}")
        for name, why in diag.transfer.excluded.items():
            click.echo(f"  not checked on {name}: {why}")
    if diag.levels is not None:
        for group in ("diagnosed", "held out"):
            summary = diag.levels.summary(group)
            if summary["n_records"]:
                click.echo(_levels_said(summary, group))
    click.echo(f"wrote {output} and {html}")


def _levels_said(summary: dict, group: str) -> str:
    """One line of the vortex level over ``group``'s records."""
    return (f"vortex level, {summary['n_records']} {group} records: median F_n NRMSE Morison "
            f"{summary['median_morison_nrmse']:.1%}, vortex {summary['median_vortex_nrmse']:.1%}"
            f" (CFD's own {summary['median_cfd_repeat_nrmse']:.1%}); the vortex model removes "
            f"a median {summary['median_explained_share']:.0%} of Morison's residual, and "
            f"some of it on {summary['records_explained']} of {summary['n_records']}")


def _held_out(paths: tuple[Path, ...], config: CaseConfig, cases: list
              ) -> tuple[list, dict[str, str], list]:
    """The ``--check-on`` runs as held-out motions, those left out with why, and their
    records; refused when one of them is also among the diagnosed cases (a run the fits saw
    says nothing about how the effect carries over)."""
    from mfflap.gap.transfer import held_out_motions
    from mfflap.identification.workflow import pooled_records

    records, failed = pooled_records(paths, config, use="the transfer check")
    seen = sorted({r.name for r in records} & {c.name for c in cases})
    if seen:
        raise click.BadParameter(f"{', '.join(seen)} are also among the diagnosed cases; the "
                                 "check needs runs the fits do not see", param_hint="--check-on")
    motions, excluded = held_out_motions(
        records, config.identification.discard_time, plate=config.plate, fluid=config.fluid,
        stream=config.flow)
    return motions, {**failed, **excluded}, records


def _flow_record(item: str, cases: list, config: CaseConfig) -> tuple[int, str]:
    """The record index and case folder of a ``--flow CASE=DIR``, refused naming what is
    wrong: the form, a case id that is no record's (with the nearest ones), a folder that is
    not there, or the run of another motion, plate, fluid or stream than the case file's."""
    import difflib

    from mfflap.cfd.case_inputs import check_case_inputs, motion_mismatch
    from mfflap.errors import ConfigError
    from mfflap.toml_io import read_toml

    name, _, folder = item.partition("=")
    if not name or not folder:
        raise click.BadParameter(f"{item!r}: expected CASE=DIR, a record's case id and the "
                                 "OpenFOAM case folder of its run", param_hint="--flow")
    names = [c.name for c in cases]
    if name not in names:
        near = difflib.get_close_matches(name, names, n=3, cutoff=0.6)
        raise click.BadParameter(f"{item!r}: no record {name!r} among the {len(names)} records"
                                 + (f"; nearest: {', '.join(near)}" if near else ""),
                                 param_hint="--flow")
    if not Path(folder).is_dir():
        raise click.BadParameter(f"{item!r}: {folder} is not a folder", param_hint="--flow")
    index = names.index(name)
    mismatch = motion_mismatch(folder, cases[index].state)
    if mismatch is not None:
        raise click.BadParameter(f"{item!r}: {folder} is not the run of record {name}: "
                                 f"{mismatch}", param_hint="--flow")
    kept = Path(folder) / "mfflap_case.toml"
    if kept.is_file():
        try:
            check_case_inputs(kept, read_toml(kept), None, None, config.plate, config.fluid,
                              config.flow, advice="its flow field is not this case's")
        except ConfigError as exc:
            raise click.BadParameter(f"{item!r}: {exc.key}: {exc.detail}",
                                     param_hint="--flow") from exc
    return index, folder


@gap.command("blindtest")
@click.option("--trials", default=12, show_default=True, type=click.IntRange(min=1),
              help="Datasets per hidden effect (nine effects, none among them: 12 make 108 "
                   "trials).")
@click.option("--snr", default=3.0, show_default=True, type=POSITIVE,
              help="Signal-to-noise ratio of the part of the effect no refit of the Morison "
                   "coefficients absorbs.")
@click.option("--seed", default=0, show_default=True,
              help="Seed of the datasets (the same seed, the same benchmark).")
@click.option("--noise", type=click.Choice(["relative", "absolute"]), default="relative",
              show_default=True,
              help="The noise's size in each dataset's cases: in proportion to the case's own "
                   "loads (relative, as the reduced model's errors against CFD grow), or the "
                   "same in every case (absolute).")
@click.option("--residual-scaling", type=click.Choice([*RESIDUAL_SCALING_NAMES, "auto"]),
              default="auto", show_default=True,
              help="How the diagnosis scales each case's residuals: by each component's RMS "
                   "over every case (grid), by its range in the case (case), or as the base "
                   "model's errors ask (auto).")
@click.option("--json", "as_json", is_flag=True)
def blindtest_cmd(trials: int, snr: float, seed: int, noise: str, residual_scaling: str,
                  as_json: bool) -> None:
    """Diagnose datasets with a hidden effect written from its textbook form, apart from
    the candidates (five the library can explain, three it cannot, and none), and score
    the verdicts against the goals."""
    from tqdm import tqdm

    from mfflap.gap.textbook_effects import ACCEPTED, confusion, recall, run, scores, summary

    bar = tqdm(total=trials * len(ACCEPTED), desc="blind trials", disable=as_json)
    said = run(trials, snr, seed=seed, noise=noise, residual_scaling=residual_scaling,
               progress=lambda _: bar.update())
    bar.close()
    if as_json:
        echo_json({"noise": noise, "residual_scaling": residual_scaling, "snr": snr,
                   "trials": trials * len(ACCEPTED), "verdicts": said,
                   "scores": scores(said), "recall": recall(said),
                   "confusion": confusion(said)})
        return
    click.echo(summary(said))


@gap.command("levels")
@click.argument("case_file", type=click.Path(dir_okay=False, exists=True, path_type=Path))
@click.option("--fixtures", "folders", multiple=True, required=True,
              type=click.Path(file_okay=False, exists=True, path_type=Path),
              help="Folders of CFD records (repeatable), e.g. a back-test's.")
@click.option("--json", "as_json", is_flag=True)
def levels_cmd(case_file: Path, folders: tuple[Path, ...], as_json: bool) -> None:
    """The discrete-vortex model as a level: per record, the F_n NRMSE of CASE_FILE's
    Morison model and of its vortex model ([vortex]) against CFD over the last two
    periods, and the share of Morison's residual the vortex model removes."""
    from mfflap.config import load_case
    from mfflap.gap.levels import level_residuals
    from mfflap.records.inputs import check_records_inputs
    from mfflap.records.record import read_records

    case = load_case(case_file)
    records = [(record, folder) for folder in folders for record in read_records(folder)]
    check_records_inputs(records, case.plate, case.fluid, case.flow,
                         case_source=str(case_file), use="the levels' comparison")
    rows = level_residuals([r for r, _ in records], case.morison_model(), case.vortex,
                           progress=None if as_json else lambda line: click.echo(line))
    shares = np.array([row.explained_share for row in rows], dtype=float)
    summary = {"n_records": len(rows),
               "median_morison_nrmse": float(np.median([r.morison_nrmse for r in rows])),
               "median_vortex_nrmse": float(np.median([r.vortex_nrmse for r in rows])),
               "median_explained_share": float(np.nanmedian(shares)),
               "records_explained": int(np.sum(shares > 0))}
    if as_json:
        echo_json({**summary, "records": [row.__dict__ for row in rows]})
        return
    click.echo(f"{summary['n_records']} records: median F_n NRMSE Morison "
               f"{summary['median_morison_nrmse']:.1%}, vortex "
               f"{summary['median_vortex_nrmse']:.1%}; the vortex model removes a median "
               f"{summary['median_explained_share']:.0%} of Morison's residual, and some of "
               f"it on {summary['records_explained']} of {summary['n_records']}")
