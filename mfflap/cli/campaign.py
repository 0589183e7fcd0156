"""``mfflap campaign``: run a grid of CFD cases on dask, resumably, and show where it stands."""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import click

from mfflap.cli.json_output import echo_json
from mfflap.cli.options import (
    NON_NEGATIVE,
    POSITIVE,
    FigureFile,
    ResultsOutput,
    cfd_settings,
    mesh_and_setup_options,
    refuse_given,
    set_option,
)


@contextmanager
def aborted_with_resume_message(out_dir: Path) -> Iterator[None]:
    """Turn a Ctrl-C during a campaign into a count of its cases and how to resume them
    (run_campaign has stopped the cluster and its solvers by then)."""
    try:
        yield
    except KeyboardInterrupt:
        from mfflap.campaign.execute import campaign_status

        states = [s.state for s in campaign_status(out_dir)]
        click.echo(f"interrupted: {states.count('done')} of {len(states)} cases done in "
                   f"{out_dir}, {states.count('started')} stopped part-way; the same command "
                   "resumes them from their last written times (`mfflap campaign status "
                   f"{out_dir}` lists them)", err=True)
        raise click.Abort() from None


@click.group()
def campaign() -> None:
    """CFD campaigns over the identification grid ([identification] of a case file)."""


@campaign.command("run")
@click.argument("case_file", type=click.Path(dir_okay=False, exists=True, path_type=Path))
@click.option("--out", "out_dir", type=click.Path(file_okay=False, path_type=Path),
              required=True, help="Campaign folder: one HDF5 record per finished case.")
@mesh_and_setup_options()
@click.option("--workers", default=1, show_default=True, type=click.IntRange(min=1),
              help="LocalCluster worker processes.")
@click.option("--scheduler", default=None,
              help="Address of an existing dask scheduler (tcp://host:8786) instead of a "
                   "LocalCluster, e.g. one from dask-jobqueue's SLURMCluster.")
@click.option("--retry-failed", is_flag=True, help="Rerun cases that failed before, and "
              "finished cases whose forces leave what the motion can drive (status 'lost'; "
              "their records kept as <case>.lost.h5).")
@click.option("--rerun-mixed", is_flag=True, help="Rerun from t = 0 s, as one set-up, "
              "finished cases whose run a retry resumed with other settings after the "
              "identification's start-up (the case file's [identification] discard_time): "
              "two set-ups in the fitted window (`campaign status` names them); their "
              "records kept as <case>.mixed.h5.")
@click.option("--cases", "case_set", type=click.Choice(["grid", "harmonic"]), default="grid",
              show_default=True,
              help="grid: the [identification] grid of pitch-ramp motions (the paper's "
                   "Table 1); harmonic: the [harmonic_set] of harmonic motions at large "
                   "pitch, the second identification set. Each in its own --out folder.")
@click.option("--dry-run", is_flag=True,
              help="List the cases with their state in --out (done, failed, pending, ...) "
                   "and exit; a folder of another setup is refused as the run would be.")
@set_option()
def run_cmd(case_file: Path, out_dir: Path, mesh: str | None, setup_name: str | None,
            workers: int, scheduler: str | None, retry_failed: bool, rerun_mixed: bool,
            case_set: str, dry_run: bool, settings: tuple[str, ...]) -> None:
    """Run an identification set of CASE_FILE in OpenFOAM.

    The grid is the case file's [identification] table (a part of it:
    ``--set identification.frequencies=[1,2]``, likewise heave_amplitudes and
    phases_deg), the harmonic set its [harmonic_set] table; the runs' mesh, solver
    settings, time limit, retries, record precision and kept case folders are its [cfd]
    table, with --mesh, --setup and --set cfd.KEY=VALUE. Finished cases are never rerun:
    rerun the same command to continue a campaign that was stopped. Failed cases are
    reported and do not stop the others. The exit status is 1 unless every case
    is done (failed, or left busy to another process running it).
    """
    if scheduler is not None:
        refuse_given(("workers",), "the LocalCluster mfflap starts; with --scheduler the "
                                   "cluster's own workers run the cases")
    from mfflap.campaign.cases import grid_cases, harmonic_set_cases
    from mfflap.campaign.execute import (
        CampaignSetup,
        campaign_status,
        check_same_cases,
        check_same_setup,
        run_campaign,
    )
    from mfflap.cfd.openfoam.setups import case_mesh_and_solver
    from mfflap.config import load_case

    case = load_case(case_file, cfd_settings(settings, mesh, setup_name))
    spec, solver = case_mesh_and_solver(case.cfd, case.source)
    cases = (grid_cases(case.identification) if case_set == "grid"
             else harmonic_set_cases(case.harmonic_set))
    campaign_setup = CampaignSetup(mesh=spec.name, solver=solver, plate=case.plate,
                                   fluid=case.fluid, stream=case.flow,
                                   timeout_s=case.cfd.timeout_s,
                                   keep_case_dirs=case.cfd.keep_case_dirs,
                                   single_precision=case.cfd.single_precision,
                                   retries_from_start=case.cfd.retries_from_start)
    discard_s = case.identification.discard_time
    if dry_run:  # what the run would do: refused as it would be, or each case's state
        check_same_setup(out_dir, campaign_setup)
        check_same_cases(out_dir, cases)
        found = ({s.case_id: s for s in campaign_status(out_dir, discard_s)}
                 if (out_dir / "campaign.toml").is_file() else {})
        for c in cases:
            state = found[c.case_id].state if c.case_id in found else "pending"
            if c.case_id in found and found[c.case_id].mixed_since_s is not None:
                state += (f" (two set-ups from t = {found[c.case_id].mixed_since_s:.4g} s"
                          + ("; to be rerun)" if rerun_mixed else "; --rerun-mixed reruns it)"))
            click.echo(f"{c.case_id}  duration {c.duration:g} s  ramp {c.ramp_time:g} s"
                       f"  {state}")
        return
    with aborted_with_resume_message(out_dir):
        statuses = run_campaign(cases, out_dir, campaign_setup, n_workers=workers,
                                scheduler_address=scheduler, retry_failed=retry_failed,
                                rerun_mixed=rerun_mixed, discard_time_s=discard_s)
    done = sum(s.state == "done" for s in statuses)
    click.echo(f"{done}/{len(statuses)} cases done in {out_dir}")
    for s in statuses:
        if s.state in ("failed", "busy"):
            click.echo(f"{s.state.upper()} {s.case_id}: {s.message}")
    if any(s.state == "busy" for s in statuses):
        click.echo("busy cases are left to the process running them; `mfflap campaign status "
                   f"{out_dir}` follows them")
    if done < len(statuses):  # a script's next step (identify) must not take it as complete
        failed = sum(s.state == "failed" for s in statuses)
        click.echo(f"exit status 1: {len(statuses) - done} of {len(statuses)} cases not done"
                   + (f" ({failed} failed: `--retry-failed` reruns them)" if failed else ""),
                   err=True)
        raise SystemExit(1)


@campaign.command("status")
@click.argument("out_dir", type=click.Path(file_okay=False, exists=True, path_type=Path))
@click.option("--discard-time", "discard_time_s", type=NON_NEGATIVE, default=None,
              help="The identification's start-up, s (the case file's [identification] "
                   "discard_time; default 0.75): a done run resumed with other settings "
                   "after it mixes two set-ups in the fitted window.")
@click.option("--json", "as_json", is_flag=True, help="Print the statuses as JSON.")
def status_cmd(out_dir: Path, discard_time_s: float | None, as_json: bool) -> None:
    """Per-case status of the campaign in OUT_DIR (done, with the numerical bursts and a
    retry that resumed it with other settings within the fitted window, if any; lost:
    finished with forces beyond what the motion can drive, failed with why, running: by the
    process named, started: stopped with how far its solver got, pending, unreadable: a
    record cut short, which the next `campaign run` keeps aside and reruns)."""
    from mfflap.campaign.execute import campaign_status
    from mfflap.records.mixed_set_up import DEFAULT_DISCARD_TIME_S

    statuses = campaign_status(out_dir, DEFAULT_DISCARD_TIME_S if discard_time_s is None
                               else discard_time_s)
    if as_json:
        echo_json([vars(s) for s in statuses])
        return
    for s in statuses:
        click.echo(f"{s.state:8s} {s.case_id}  {s.message}")
    counts = {k: sum(s.state == k for s in statuses)
              for k in ("done", "lost", "failed", "running", "started", "pending",
                        "unreadable")}
    mixed = sum(s.mixed_since_s is not None for s in statuses)
    click.echo(", ".join(f"{v} {k}" for k, v in counts.items())
               + (f"; {mixed} done mixing two set-ups in the fitted window (`campaign run "
                  "--rerun-mixed` reruns them as one set-up)" if mixed else ""))


@campaign.command("scatter")
@click.argument("out_dir", type=click.Path(file_okay=False, exists=True, path_type=Path))
@click.option("--json", "as_json", is_flag=True, help="Print the scatters as JSON.")
def scatter_cmd(out_dir: Path, as_json: bool) -> None:
    """Each record's own statistical uncertainty: the means over its whole periods after the
    start-up of thrust, input power and RMS F_n, with their cycle-to-cycle standard
    deviation (stored in each record's /cycle_scatter group; added to records that lack
    it). A pitch-ramp record's scatter includes the ramp's change ("ramp")."""
    from dataclasses import asdict

    from mfflap.records.cycle_scatter import folder_cycle_scatter

    rows = folder_cycle_scatter(out_dir)
    if as_json:
        echo_json([{"name": n, **(asdict(s) if s else {})} for n, s in rows])
        return
    click.echo(f"{'record':44s} cycles  thrust [N]           power [W]            "
               "RMS F_n [N]")
    for name, s in rows:
        if s is None:
            click.echo(f"{name:44s} no whole period after the start-up")
            continue
        kind = "" if s.repeats else "  ramp"
        click.echo(f"{name:44s} {s.n_cycles:6d}  {s.mean_thrust_n:8.3g} +- "
                   f"{s.thrust_scatter_n:<8.2g}  {s.mean_power_w:8.3g} +- "
                   f"{s.power_scatter_w:<8.2g}  {s.rms_normal_force_n:8.3g} +- "
                   f"{s.rms_normal_force_scatter_n:<8.2g}{kind}")


@campaign.command("reduce")
@click.argument("out_dir", type=click.Path(file_okay=False, exists=True, path_type=Path))
@click.argument("copy_dir", type=click.Path(file_okay=False, path_type=Path))
def reduce_cmd(out_dir: Path, copy_dir: Path) -> None:
    """A compact copy of every record of OUT_DIR in COPY_DIR: each history as means over
    windows of a hundredth of a period, in single precision, without the raw case-frame
    forces (what identification, back-tests and the gap diagnosis compare; the shipped
    identification sets are such copies). Parameters, provenance, cycle scatter and
    refinement are kept."""
    from mfflap.records.reduce import SAMPLES_PER_PERIOD, reduce_folder

    written = reduce_folder(out_dir, copy_dir)
    size = sum(p.stat().st_size for p in written)
    click.echo(f"{len(written)} records reduced to {SAMPLES_PER_PERIOD} samples a period in "
               f"{copy_dir} ({size / 1e6:.1f} MB)")


@campaign.command("refinement")
@click.argument("coarse_dir", type=click.Path(file_okay=False, exists=True, path_type=Path))
@click.argument("refined_dir", type=click.Path(file_okay=False, exists=True, path_type=Path))
@click.option("--json", "as_json", is_flag=True, help="Print the changes as JSON.")
def refinement_cmd(coarse_dir: Path, refined_dir: Path, as_json: bool) -> None:
    """The mesh or time-step uncertainty of the records of COARSE_DIR from the refined runs
    of their motions in REFINED_DIR (a finer mesh or a smaller Courant limit, which is read
    from the records): per record, the NRMSE and Pearson r of its F_n against the refined
    run's, and the change and two-level index (Roache, Fs 3, order 2) of its mean thrust,
    power and RMS F_n. Stored in each coarse record's /refinement group, where the reports
    show it beside the model's NRMSE."""
    from dataclasses import asdict

    from mfflap.campaign.refinement import add_refinement

    rows = add_refinement(coarse_dir, refined_dir)
    if as_json:
        echo_json([{"name": n, **asdict(c)} for n, c in rows])
        return
    click.echo(f"{'record':44s} {'refined':9s}   r     NRMSE F_n  Pearson  change (GCI) of: "
               "thrust          power           RMS F_n")
    for name, c in rows:
        cells = "  ".join(f"{100 * c.relative_change(m):+6.1f} % ({100 * g:4.0f} %)"
                          for m, g in (("mean_thrust", c.gci_mean_thrust),
                                       ("mean_power", c.gci_mean_power),
                                       ("rms_normal_force", c.gci_rms_normal_force)))
        click.echo(f"{name:44s} {c.kind:9s} {c.refinement_ratio:5.2f}  "
                   f"{100 * c.normal_force_nrmse:7.1f} %  {c.normal_force_pearson:7.3f}  "
                   f"{cells}")


def _setups_line(differences: list[tuple[str, Any, Any]] | None) -> str:
    """What separates the two campaigns' set-ups, for the head of the comparison."""
    if differences is None:
        return "set-ups: not both known (a folder without campaign.toml)"
    if not differences:
        return "set-ups: the same mesh and solver settings"
    return "set-ups differ in: " + "; ".join(f"{key} ({a!r} in A, {b!r} in B)"
                                             for key, a, b in differences)


@campaign.command("compare")
@click.argument("folder_a", type=click.Path(file_okay=False, exists=True, path_type=Path))
@click.argument("folder_b", type=click.Path(file_okay=False, exists=True, path_type=Path))
@click.option("--start", "start_s", type=NON_NEGATIVE, default=None,
              help="Compare after this time, s (default: each case's start-up ramp).")
@click.option("--end", "end_s", type=POSITIVE, default=None,
              help="Compare up to this time, s (default: the shorter record's end).")
@click.option("--output", type=ResultsOutput("campaign_comparison"), default=None,
              help="HDF5 file of the comparison, both manifests beside it.")
@click.option("--figure", type=FigureFile(), default=None,
              help="Figure (.png, .pdf or .svg): NRMSE of F_n and M and the thrust "
                   "difference per case.")
@click.option("--histories", "histories_dir", default=None,
              type=click.Path(file_okay=False, path_type=Path),
              help="Folder for one PNG per case: F_n, F_t, M and thrust of both runs over "
                   "time.")
@click.option("--case", "case_ids", multiple=True,
              help="With --histories: only this case (repeat for several).")
@click.option("--json", "as_json", is_flag=True)
def compare_cmd(folder_a: Path, folder_b: Path, start_s: float | None, end_s: float | None,
                output: Path | None, figure: Path | None, histories_dir: Path | None,
                case_ids: tuple[str, ...], as_json: bool) -> None:
    """Case by case, the forces of campaign FOLDER_A against FOLDER_B (the reference):
    NRMSE and Pearson of F_n, F_t, M, mean thrust and power, numerical bursts, CPU."""
    from dataclasses import asdict

    from mfflap.campaign.compare import compare_campaigns, plot_comparison, write_comparison

    if case_ids and histories_dir is None:
        raise click.UsageError("--case chooses the cases of --histories; give --histories DIR")
    if start_s is not None and end_s is not None and end_s <= start_s:
        raise click.UsageError(f"--end {end_s:g} is not after --start {start_s:g}")
    if folder_a.resolve() == folder_b.resolve():
        click.echo(f"warning: {folder_a} and {folder_b} are the same folder: each case is "
                   "compared with itself, so every difference below is 0", err=True)
    result = compare_campaigns(folder_a, folder_b, start_s, end_s)
    if output is not None:
        write_comparison(output, result)
    if figure is not None:
        plot_comparison(figure, result, (folder_a.name, folder_b.name))
    if histories_dir is not None:
        from mfflap.campaign.history_plot import plot_histories

        written = plot_histories(histories_dir, result, (folder_a.name, folder_b.name),
                                 case_ids)
        click.echo(f"wrote {len(written)} history figure(s) to {histories_dir}", err=True)
    if as_json:
        echo_json({"cases": [{**asdict(c), "thrust_difference": c.thrust_difference,
                              "power_difference": c.power_difference,
                              "cpu_ratio": c.cpu_ratio} for c in result.cases],
                   "summary": result.summary(), "only_a": result.only_a,
                   "only_b": result.only_b, "outside_window": result.outside_window,
                   "setup_differences": None if result.setup_differences is None else
                   [{"setting": k, "a": a, "b": b} for k, a, b in result.setup_differences]})
        return
    click.echo(_setups_line(result.setup_differences))
    width = max(len(c.case_id) for c in result.cases)
    click.echo(f"{'case':{width}s} {'F_n':>7s} {'F_t':>7s} {'M':>7s} {'thrust':>8s} "
               f"{'bursts A/B':>10s} {'lost s A/B':>11s} {'CPU A/B':>8s}    "
               "(NRMSE; thrust: (A - B) / |B|)")
    for c in result.cases:
        click.echo(f"{c.case_id:{width}s} {c.nrmse_normal_force:7.2%} "
                   f"{c.nrmse_tangential_force:7.2%} {c.nrmse_moment:7.2%} "
                   f"{c.thrust_difference:+8.1%} {c.n_bursts_a:>5d}/{c.n_bursts_b:<4d} "
                   f"{c.lost_a_s:>5.2f}/{c.lost_b_s:<5.2f} {c.cpu_ratio:8.2f}")
    s = result.summary()
    lost = len(result.cases) - int(s["n_cases_compared"])
    click.echo(f"{len(result.cases)} cases" + (f" ({lost} with lost stretches left out of "
                                               "the medians)" if lost else "")
               + "; NRMSE median / max: F_n "
               f"{s['median_nrmse_normal_force']:.2%} / {s['max_nrmse_normal_force']:.2%}, M "
               f"{s['median_nrmse_moment']:.2%} / {s['max_nrmse_moment']:.2%}; CPU A / B "
               f"{s['cpu_ratio']:.2f}")
    if result.outside_window:
        names = list(result.outside_window)
        click.echo(f"outside the window: {len(names)} case(s) with fewer than two common "
                   f"samples in it: {', '.join(names[:5])}" + (", ..." if len(names) > 5 else ""))
    for label, only in (("A", result.only_a), ("B", result.only_b)):
        if only:
            click.echo(f"only in {label}: {len(only)} case(s): {', '.join(only[:5])}"
                       + (", ..." if len(only) > 5 else ""))
