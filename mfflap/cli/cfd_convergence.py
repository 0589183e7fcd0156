"""``mfflap cfd convergence``: the same motion on several meshes and time steps, like the
paper's mesh study."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import click

from mfflap.cli.cfd_motion import motion_and_end_time, motion_table_options
from mfflap.cli.json_output import echo_json
from mfflap.cli.options import (
    CYCLES,
    NON_NEGATIVE,
    FloatList,
    refuse_settings,
    set_option,
)
from mfflap.errors import shown


class CourantLimits(click.ParamType):
    """``LIMITS[@MESH]``: comma-separated Courant limits (:class:`FloatList`) and, after
    ``@``, the mesh repeated at the limits after the first (which needs two or more).

    Examples
    --------
    >>> CourantLimits().convert("4,2@lean", None, None)
    ([4.0, 2.0], 'lean')
    """

    name = "limits"

    def convert(self, value, param, ctx) -> tuple[list[float], str | None]:
        if isinstance(value, tuple):
            return value
        limits, _, mesh = str(value).partition("@")
        numbers = FloatList().convert(limits, param, ctx)
        if mesh and len(numbers) < 2:
            self.fail(f"{shown(value)}: a mesh after @ is repeated at the limits after the "
                      "first; give two or more", param, ctx)
        return numbers, mesh.strip() or None


@click.command()
@click.argument("case_file", type=click.Path(dir_okay=False, exists=True, path_type=Path))
@click.argument("out_dir", type=click.Path(file_okay=False, path_type=Path))
@click.option("--meshes", default="coarse,medium,fine", show_default=True,
              help="Mesh resolutions, coarsest first; the last is the reference.")
@click.option("--courant", "courants", default="4,2", show_default=True, type=CourantLimits(),
              metavar="LIMITS[@MESH]",
              help="Courant limits: every mesh runs at the first; the first mesh, or MESH "
                   "(e.g. 4,2,1@medium), is repeated at each further one.")
@click.option("--cycles", default=1.0, show_default=True, type=CYCLES,
              help="Carrier periods simulated.")
@click.option("--ramp-time", default=None, type=NON_NEGATIVE,
              help="Start-up ramp, s (default: a quarter period).")
@click.option("--floor", is_flag=True,
              help="Rerun the reference, and each set-up, with the other pressure solver: "
                   "the round-off floor under every NRMSE of the study.")
@click.option("--setups", "setup_names", default="",
              help="Named set-ups of setups.toml (comma separated) run as well, each with its "
                   "own mesh and solver settings, and compared with the reference.")
@motion_table_options("")
@set_option()
@click.option("--json", "as_json", is_flag=True, help="Print the NRMSE table as JSON.")
def convergence(case_file: Path, out_dir: Path, meshes: str,
                courants: tuple[list[float], str | None], cycles: float,
                ramp_time: float | None, floor: bool, setup_names: str,
                motion_table: Path | None, end_time: float | None,
                settings: tuple[str, ...], as_json: bool) -> None:
    """Mesh and time-step convergence of the [motion] of CASE_FILE: NRMSE between runs, the
    grid convergence index of mean thrust, power, peak F_n and RMS moment over the three
    finest meshes, and the plate's y+ over time (HDF5 records, HTML report, resumable). A
    harmonic motion run over two or more periods after the first is also compared by mean
    cycles from the first period boundary after its first period (the start-up left out),
    beside each run's cycle-to-cycle scatter.

    Every run takes the solver settings of the case's [cfd] table (--set cfd.KEY=VALUE),
    named set-ups their own mesh and solver settings in the study's far field, k and
    epsilon convection and wall treatment; the study's meshes and Courant limits are its
    own options."""
    from mfflap.campaign.convergence import convergence_figure, run_convergence
    from mfflap.cfd.openfoam.setups import case_mesh_and_solver, setup
    from mfflap.config import load_case
    from mfflap.reports.html import Report, figure_html, table_html, text_html

    courants, time_step_mesh = courants
    mesh_names = [m.strip() for m in meshes.split(",")]
    if time_step_mesh is not None and time_step_mesh not in mesh_names:
        raise click.BadParameter(f"{time_step_mesh!r} is not one of the study's --meshes "
                                 f"({', '.join(mesh_names)})", param_hint="--courant")
    for key, option in (("cfd.mesh", "--meshes"), ("cfd.setup", "--setups"),
                        ("cfd.max_courant", "--courant")):
        refuse_settings(settings, key, f"single runs; a study's are its {option}")
    case = load_case(case_file, settings)
    # the study's meshes, set-ups and Courant limits are its options; the rest of [cfd]
    # sets up every run
    _, solver = case_mesh_and_solver(replace(case.cfd, setup=None, mesh=None,
                                             max_courant=None), source=case.source)
    motion, end = motion_and_end_time(case, motion_table, end_time, cycles)
    period = 1.0 / case.motion.frequency
    if motion_table is None:
        ramp = 0.25 * period if ramp_time is None else ramp_time
        periodic = case.motion.kind == "harmonic"
        described = f"{cycles:g} cycles"
    else:
        ramp, periodic = ramp_time or 0.0, False
        described = f"motion table {motion_table.name}, {end:g} s"
    try:
        study = run_convergence(out_dir, motion, end,
                                meshes=mesh_names,
                                courants=courants, ramp_time=ramp,
                                plate=case.plate, fluid=case.fluid, stream=case.flow,
                                n_procs=case.cfd.procs, floor=floor,
                                time_step_mesh=time_step_mesh,
                                setups=[setup(n.strip()) for n in setup_names.split(",")
                                        if n.strip()],
                                solver=solver, period=period if periodic else None,
                                progress=lambda m: click.echo(m, err=True))
    except KeyboardInterrupt:  # the solver is stopped by then; finished runs are kept
        kept = sorted(p.stem for p in Path(out_dir).glob("*.h5"))
        click.echo(f"interrupted: the runs finished so far are kept in {out_dir} "
                   f"({', '.join(kept) or 'none yet'}); the same command reruns none of "
                   "them and resumes the one stopped from its last written time", err=True)
        raise click.Abort() from None
    if periodic and not study.phase_cycles:
        click.echo(f"no mean cycles compared: the runs hold fewer than two whole periods "
                   f"({period:.6g} s) after their first", err=True)
    made_with = (f"the meshes' runs: PIMPLE {solver.n_outer_correctors}x"
                 f"{solver.n_correctors}, {solver.pressure_solver}; every run, named set-ups "
                 f"included: {solver.far_field} far field, {solver.turbulence_convection} k "
                 f"and epsilon convection, {solver.wall_treatment} wall treatment")
    rep = Report("Mesh and time-step convergence", f"{case.study.name}: {described}; "
                                                   f"{made_with}")
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
    click.echo(made_with)
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
