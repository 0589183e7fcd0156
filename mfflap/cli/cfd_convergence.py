"""``mfflap cfd convergence``: the same motion on several meshes and time steps, like the
paper's mesh study."""

from __future__ import annotations

from pathlib import Path

import click

from mfflap.cli.cfd_motion import motion_and_end_time, motion_table_options
from mfflap.cli.json_output import echo_json
from mfflap.cli.options import (
    CYCLES,
    NON_NEGATIVE,
    FloatList,
    refuse_given,
)
from mfflap.study_tables import WALL_TREATMENT_NAMES


@click.command()
@click.argument("case_file", type=click.Path(dir_okay=False, exists=True, path_type=Path))
@click.argument("out_dir", type=click.Path(file_okay=False, path_type=Path))
@click.option("--meshes", default="coarse,medium,fine", show_default=True,
              help="Mesh resolutions, coarsest first; the last is the reference.")
@click.option("--courant", "courants", default="4,2", show_default=True, type=FloatList(),
              help="Courant limits; one mesh (--time-step-mesh) is repeated at each further "
                   "one.")
@click.option("--time-step-mesh", default=None,
              help="The mesh repeated at the further Courant limits (default the first).")
@click.option("--cycles", default=1.0, show_default=True, type=CYCLES,
              help="Carrier periods simulated.")
@click.option("--ramp-time", default=None, type=NON_NEGATIVE,
              help="Start-up ramp, s (default: a quarter period).")
@click.option("--procs", default=1, show_default=True, type=click.IntRange(min=1),
              help="MPI ranks per run.")
@click.option("--pressure-solver", type=click.Choice(["PCG", "GAMG"]), default="PCG",
              show_default=True, help="Linear solver of the pressure equation.")
@click.option("--n-correctors", default=1, show_default=True, type=click.IntRange(min=1),
              help="PIMPLE pressure correctors per outer iteration.")
@click.option("--far-field", type=click.Choice(["freestream", "inletOutlet"]),
              default="freestream", show_default=True,
              help="Far-field conditions (inletOutlet where the fine mesh's time step "
                   "collapses with freestream under large, fast heaves).")
@click.option("--turbulence-convection", type=click.Choice(["limitedLinear", "upwind"]),
              default="limitedLinear", show_default=True,
              help="Convection of k and epsilon in every run, set-ups included (upwind: no "
                   "clipping of negative epsilon).")
@click.option("--wall-treatment", type=click.Choice(WALL_TREATMENT_NAMES), default="log_law",
              show_default=True,
              help="The plate's wall conditions in every run, set-ups included: log_law "
                   "(k-epsilon wall functions, for a first cell at y+ 30-300) or all_y_plus "
                   "(Spalding's law for nut and epsilon's low-Re correction: any y+).")
@click.option("--floor", is_flag=True,
              help="Rerun the reference, and each set-up, with the other pressure solver: "
                   "the round-off floor under every NRMSE of the study.")
@click.option("--setups", "setup_names", default="",
              help="Named set-ups of setups.toml (comma separated) run as well, each with its "
                   "own mesh and solver settings, and compared with the reference.")
@click.option("--phase-from", default=None, type=float,
              help="Periodic motions: start of the mean cycles compared, s (default: the "
                   "first period boundary after the first cycle; needs two whole periods "
                   "after it, e.g. --cycles 3).")
@motion_table_options("")
@click.option("--json", "as_json", is_flag=True, help="Print the NRMSE table as JSON.")
def convergence(case_file: Path, out_dir: Path, meshes: str, courants: list[float],
                cycles: float, ramp_time: float | None, procs: int, pressure_solver: str,
                n_correctors: int, far_field: str, turbulence_convection: str,
                wall_treatment: str, floor: bool,
                setup_names: str, time_step_mesh: str | None, phase_from: float | None,
                motion_table: Path | None, end_time: float | None, as_json: bool) -> None:
    """Mesh and time-step convergence of the [motion] of CASE_FILE: NRMSE between runs, the
    grid convergence index of mean thrust, power, peak F_n and RMS moment over the three
    finest meshes, and the plate's y+ over time (HDF5 records, HTML report, resumable). A
    harmonic motion run over two or more periods after the first is also compared by mean
    cycles, beside each run's cycle-to-cycle scatter."""
    from mfflap.campaign.convergence import convergence_figure, run_convergence
    from mfflap.cfd.openfoam.setups import setup
    from mfflap.cfd.openfoam.writer import SolverSettings
    from mfflap.config import load_case
    from mfflap.reports.html import Report, figure_html, table_html, text_html

    if len(courants) < 2:
        refuse_given(("time_step_mesh",), "a study of two or more --courant limits (the mesh "
                                          "repeated at each limit after the first)")
    mesh_names = [m.strip() for m in meshes.split(",")]
    if time_step_mesh is not None and time_step_mesh not in mesh_names:
        raise click.BadParameter(f"{time_step_mesh!r} is not one of the study's --meshes "
                                 f"({', '.join(mesh_names)})", param_hint="--time-step-mesh")
    case = load_case(case_file)
    motion, end = motion_and_end_time(case, motion_table, end_time, cycles)
    period = 1.0 / case.motion.frequency
    if motion_table is None:
        ramp = 0.25 * period if ramp_time is None else ramp_time
        periodic = case.motion.kind == "harmonic"
        if phase_from is not None and not periodic:
            raise click.UsageError(f"--phase-from compares mean cycles of a periodic motion; "
                                   f"the [motion] of {case_file} is {case.motion.kind!r}")
        described = f"{cycles:g} cycles"
    else:
        ramp, periodic = ramp_time or 0.0, False
        if phase_from is not None:
            raise click.UsageError("--phase-from compares mean cycles of the case file's "
                                   "periodic motion, not of a --motion-table")
        described = f"motion table {motion_table.name}, {end:g} s"
    try:
        study = run_convergence(out_dir, motion, end,
                                meshes=mesh_names,
                                courants=courants, ramp_time=ramp,
                                plate=case.plate, fluid=case.fluid, stream=case.flow,
                                n_procs=procs, floor=floor, time_step_mesh=time_step_mesh,
                                setups=[setup(n.strip()) for n in setup_names.split(",")
                                        if n.strip()],
                                solver=SolverSettings(pressure_solver=pressure_solver,
                                                      n_correctors=n_correctors,
                                                      far_field=far_field,
                                                      turbulence_convection=turbulence_convection,
                                                      wall_treatment=wall_treatment),
                                period=period if periodic else None,
                                phase_from=phase_from,
                                progress=lambda m: click.echo(m, err=True))
    except KeyboardInterrupt:  # the solver is stopped by then; finished runs are kept
        kept = sorted(p.stem for p in Path(out_dir).glob("*.h5"))
        click.echo(f"interrupted: the runs finished so far are kept in {out_dir} "
                   f"({', '.join(kept) or 'none yet'}); the same command reruns none of "
                   "them and resumes the one stopped from its last written time", err=True)
        raise click.Abort() from None
    if phase_from is not None and not study.phase_cycles:
        click.echo(f"no mean cycles compared: the runs hold fewer than two whole periods "
                   f"({period:.6g} s) after --phase-from {phase_from:g} s", err=True)
    settings = (f"the meshes' runs: PIMPLE 2x{n_correctors}, {pressure_solver}; every run, "
                f"named set-ups included: {far_field} far field, {turbulence_convection} k "
                f"and epsilon convection, {wall_treatment} wall treatment")
    rep = Report("Mesh and time-step convergence", f"{case.study.name}: {described}; "
                                                   f"{settings}")
    sec = rep.section("NRMSE between runs")
    sec.blocks.append(table_html(["comparison", "F_n", "F_t", "M"],
                                 [[k, *v.values()] for k, v in study.nrmse.items()]))
    runs = study.as_dict()["runs"]
    sec.blocks.append(table_html(["run", "cells", "CPU [s]", "mean y+", "max y+",
                                  "steps with epsilon clipped", "numerical bursts"],
                                 [[k, v["n_cells"], v["cpu_time_s"], v["y_plus_mean"],
                                   v["y_plus_max"], v["epsilon_clipped_step_fraction"],
                                   "; ".join(v["numerical_bursts"]) or "-"]
                                  for k, v in runs.items()]))
    notes = {k: v["wall_function_note"] for k, v in runs.items() if v["wall_function_note"]}
    for k, note in notes.items():  # the plate's y+ against the wall functions' range
        sec.blocks.append(text_html(f"{k}: {note}", warn=True))
    sec.blocks.append(figure_html(convergence_figure(study), "F_n and y+ over the run"))
    if study.phase_nrmse:
        psec = rep.section(f"Mean cycles ({study.phase_cycles} periods per run)")
        psec.blocks.append(table_html(["comparison", "F_n", "F_t", "M"],
                                      [[k, *v.values()] for k, v in study.phase_nrmse.items()]))
        psec.blocks.append(table_html(["run: cycle-to-cycle scatter", "F_n", "F_t", "M"],
                                      [[k, *v.values()]
                                       for k, v in study.cycle_scatter.items()]))
    if study.gci:
        gsec = rep.section(f"Grid convergence index ({', '.join(study.gci_meshes)}; Celik et "
                           "al. 2008, Fs = 1.25)")
        gsec.blocks.append(table_html(
            ["quantity", "fine", "medium", "coarse", "behaviour", "order p", "extrapolated",
             "GCI fine", "GCI medium"],
            [[k, *g.values, g.behaviour, g.apparent_order, g.extrapolated, g.gci_fine,
              g.gci_medium] for k, g in study.gci.items()]))
    rep.write(Path(out_dir) / "convergence.html")
    if as_json:
        echo_json(study.as_dict())
        return
    click.echo(settings)
    for k, note in notes.items():
        click.echo(f"{k}: {note}")
    for k, v in runs.items():
        if v["numerical_bursts"]:
            click.echo(f"{k}: {len(v['numerical_bursts'])} numerical burst(s), counted in "
                       f"its NRMSE: {'; '.join(v['numerical_bursts'])}")
    for k, v in study.nrmse.items():
        click.echo(f"{k:32s} NRMSE F_n {v['normal_force']:.4f}  F_t "
                   f"{v['tangential_force']:.4f}  M {v['moment']:.4f}")
    for k, v in study.phase_nrmse.items():
        click.echo(f"{k:32s} mean cycles ({study.phase_cycles}) NRMSE F_n "
                   f"{v['normal_force']:.4f}  F_t {v['tangential_force']:.4f}  M "
                   f"{v['moment']:.4f}")
    for k, g in study.gci.items():
        click.echo(f"GCI {k:22s} {g.behaviour:12s} p {g.apparent_order:6.2f}  fine "
                   f"{g.values[0]:10.4g} +- {100 * g.gci_fine:6.2f} %  medium {g.values[1]:10.4g} "
                   f"+- {100 * g.gci_medium:6.2f} %  extrapolated {g.extrapolated:10.4g}")
    click.echo(f"wrote {Path(out_dir) / 'convergence.html'}")
