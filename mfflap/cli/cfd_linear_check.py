"""``mfflap cfd linear-check``: a CFD set-up against linear unsteady thin-aerofoil theory."""

from __future__ import annotations

from pathlib import Path

import click

from mfflap.cli.json_output import echo_json
from mfflap.cli.options import cfd_settings, mesh_and_setup_options, set_option


@click.command("linear-check")
@click.argument("out_dir", type=click.Path(file_okay=False, path_type=Path))
@click.option("--case-file", type=click.Path(dir_okay=False, exists=True, path_type=Path),
              default=None, help="Plate, fluid, stream and strip-model coefficients (default: "
                                 "the package's, those of cases/paper2026.toml).")
@mesh_and_setup_options()
@click.option("--cases", "case_ids", default=None,
              help="Comma-separated case ids of the default motions (--list shows them).")
@click.option("--list", "list_only", is_flag=True, help="List the motions and exit.")
@click.option("--workers", default=1, show_default=True, type=click.IntRange(min=1),
              help="LocalCluster worker processes.")
@click.option("--retry-failed", is_flag=True,
              help="Rerun the motions that failed before (e.g. with a longer "
                   "--set cfd.timeout_s=...).")
@set_option()
@click.option("--json", "as_json", is_flag=True, help="Print the checks as JSON.")
def linear_check(out_dir: Path, case_file: Path | None, mesh: str | None,
                 setup_name: str | None, case_ids: str | None, list_only: bool,
                 workers: int, retry_failed: bool, settings: tuple[str, ...],
                 as_json: bool) -> None:
    """Verify a CFD set-up against linear unsteady thin-aerofoil theory.

    Runs small harmonic heaves and pitches (effective incidence of a few degrees, reduced
    frequency 0.4-3.4) in OpenFOAM as a resumable campaign in OUT_DIR, then compares each
    run's F_n and M with Theodorsen's theory and with the strip model: a table,
    OUT_DIR/linear_check/checks.h5 and OUT_DIR/linear_check/normal_force.png. A sound set-up
    lies a few percent from the theory; wrong frames, scaling or moment reference show as
    tens of percent. The exit status is 1 when a motion failed (each is listed with why).
    The runs' mesh and solver settings are the case file's [cfd] table, with --mesh,
    --setup and --set cfd.KEY=VALUE.
    """
    from dataclasses import asdict

    from mfflap.campaign.execute import CampaignSetup, run_campaign
    from mfflap.campaign.linear_check import (
        SMALL_MOTIONS,
        check_record,
        plot_checks,
        summary_table,
        write_checks,
    )
    from mfflap.cfd.openfoam.setups import case_mesh_and_solver
    from mfflap.cli.campaign import aborted_with_resume_message
    from mfflap.config import load_case, loads_case
    from mfflap.records.record import read_record
    from mfflap.toml_io import dumps

    motions = list(SMALL_MOTIONS)
    if case_ids is not None:
        known = {c.case_id: c for c in motions}
        wanted = list(dict.fromkeys(s.strip() for s in case_ids.split(",") if s.strip()))
        if not wanted:
            raise click.UsageError("--cases: no case ids (leave it out for every motion; "
                                   "--list shows them)")
        unknown = [s for s in wanted if s not in known]
        if unknown:
            raise click.UsageError(f"--cases: unknown {', '.join(unknown)}; known: "
                                   f"{', '.join(known)}")
        motions = [known[s] for s in wanted]
    if list_only:
        for c in motions:
            click.echo(f"{c.case_id}  duration {c.duration:g} s  ramp {c.ramp_time:g} s")
        return
    settings = cfd_settings(settings, mesh, setup_name)
    config = (load_case(case_file, settings) if case_file
              else loads_case("", "the package's case", settings))
    spec, solver = case_mesh_and_solver(config.cfd, config.source)
    setup = CampaignSetup(mesh=spec.name, solver=solver, plate=config.plate,
                          fluid=config.fluid, stream=config.flow,
                          timeout_s=config.cfd.timeout_s,
                          single_precision=config.cfd.single_precision,
                          retries_from_start=config.cfd.retries_from_start)
    with aborted_with_resume_message(out_dir):
        statuses = run_campaign(motions, out_dir, setup, n_workers=workers,
                                retry_failed=retry_failed, progress=not as_json)
    failed = [s for s in statuses if s.state != "done"]
    records = [read_record(out_dir / f"{s.case_id}.h5") for s in statuses if s.state == "done"]
    model = config.morison_model()
    checks = [check_record(r, model, config.plate, config.fluid, config.flow) for r in records]
    inputs = dumps({"setup": setup.as_dict(),
                    "cases": {c.case_id: c.as_dict() for c in motions},
                    "coefficients": asdict(config.coefficients)})
    summary = out_dir / "linear_check"  # beside the records, not among them
    if checks:
        summary.mkdir(exist_ok=True)
        write_checks(summary / "checks.h5", checks, inputs)
        plot_checks(summary / "normal_force.png", records, model, config.plate, config.fluid,
                    config.flow)
    if as_json:
        echo_json({"checks": [asdict(c) for c in checks],
                   "failed": {s.case_id: s.message for s in failed
                              if s.state == "failed"},
                   "busy": {s.case_id: s.message for s in failed
                            if s.state == "busy"}})
    else:
        click.echo(summary_table(checks))
        for s in failed:  # failed, or busy: being run by another process
            click.echo(f"{s.state.upper()} {s.case_id}: {s.message}")
        if checks:
            click.echo(f"wrote {summary / 'checks.h5'} and {summary / 'normal_force.png'}")
    if failed:
        raise SystemExit(1)
