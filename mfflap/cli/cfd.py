"""``mfflap cfd``: write, run and parse OpenFOAM cases."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import click
import numpy as np

from mfflap.cli.json_output import echo_json
from mfflap.cli.options import (
    NON_NEGATIVE,
    POSITIVE,
    WALL_TREATMENT_NAMES,
    FigureFile,
    FloatList,
    ResultsOutput,
    mesh_and_setup_options,
    refuse_given,
    velocity_convection_option,
)

if TYPE_CHECKING:
    from mfflap.kinematics.continuous import TabulatedMotion


def _motion_table_options(note: str):
    """--motion-table and --end-time, for the commands that take any motion."""
    def decorate(command):
        command = click.option(
            "--end-time", type=POSITIVE, default=None,
            help="With --motion-table: simulated time, s (default: the table's last row).",
        )(command)
        return click.option(
            "--motion-table", type=click.Path(dir_okay=False, exists=True, path_type=Path),
            default=None,
            help="CSV of any motion instead of the case file's [motion]: columns time (s, "
                 "from 0), heave_position (m), pitch_angle (rad) or pitch_angle_deg. --cycles "
                 f"does not apply. {note}".strip(),
        )(command)
    return decorate


@click.group()
def cfd() -> None:
    """CFD adapters: OpenFOAM cases (write, run, mesh study), Fluent UDFs, both solvers' forces."""


@cfd.command()
@click.argument("case_file", type=click.Path(dir_okay=False, path_type=Path))
@click.argument("case_dir", type=click.Path(file_okay=False, path_type=Path))
@mesh_and_setup_options()
@click.option("--cycles", default=3.0, show_default=True, type=POSITIVE,
              help="Carrier periods to simulate.")
@click.option("--ramp-time", default=0.0, show_default=True, type=NON_NEGATIVE,
              help="Smooth start-up ramp, s.")
@click.option("--y-plus", is_flag=True, help="Add the yPlus function object.")
@click.option("--far-field", type=click.Choice(["freestream", "inletOutlet"]), default=None,
              help="Far-field conditions (inletOutlet: for heaves much faster than the "
                   "stream); default freestream.")
@click.option("--pressure-solver", type=click.Choice(["PCG", "GAMG"]), default=None,
              help="Linear solver of the pressure equation; default PCG (or the set-up's).")
@velocity_convection_option
@click.option("--turbulence-convection", type=click.Choice(["limitedLinear", "upwind"]),
              default=None, help="Convection of k and epsilon (upwind: no clipping of "
                                 "negative epsilon); default limitedLinear (or the set-up's).")
@click.option("--max-courant", type=POSITIVE, default=None,
              help="Courant limit of the adaptive time step; default 4 (or the set-up's).")
@click.option("--outer-correctors", type=click.IntRange(min=1), default=None,
              help="PIMPLE outer iterations per time step (1: PISO); default 2 (or the "
              "set-up's).")
@click.option("--correctors", type=click.IntRange(min=1), default=None,
              help="Pressure correctors per outer iteration; default 1 (or the set-up's).")
@click.option("--writes", default=4, show_default=True, type=click.IntRange(min=1),
              help="Times the fields are written over the run; `cfd run` restarts a killed "
                   "run from the last one.")
@click.option("--frame", type=click.Choice(["inertial", "plate"]), default=None,
              help="inertial: the whole mesh moves with the plate; plate: a static mesh in "
                   "the plate's frame (about a third less CPU; inletOutlet far field unless "
                   "--far-field says otherwise); default inertial (or the set-up's).")
@_motion_table_options("Kept in the case.")
@click.option("--overwrite", is_flag=True,
              help="Delete a case written into CASE_DIR before (its results, mesh and logs "
                   "too) and write this one; without it such a folder is refused.")
def write(case_file: Path, case_dir: Path, mesh: str | None, setup_name: str | None,
          cycles: float, ramp_time: float, y_plus: bool, far_field: str | None,
          pressure_solver: str | None, velocity_convection: str | None, writes: int,
          turbulence_convection: str | None, frame: str | None, motion_table: Path | None,
          end_time: float | None, max_courant: float | None, outer_correctors: int | None,
          correctors: int | None, wall_treatment: str | None, overwrite: bool) -> None:
    """Write an OpenFOAM case for the [motion] of CASE_FILE (or a --motion-table) into
    CASE_DIR, a new or empty folder (or a case written before, with --overwrite)."""
    from dataclasses import replace

    from mfflap.cfd.openfoam.setups import mesh_and_solver
    from mfflap.cfd.openfoam.writer import attach_motion_table, write_case
    from mfflap.config import load_case
    from mfflap.errors import ConfigError

    spec, solver = mesh_and_solver(mesh, setup_name, wall_treatment)
    case = load_case(case_file)
    motion, end_time = _motion_and_end_time(case, motion_table, end_time, cycles)
    if frame == "plate" and far_field is None:
        far_field = "inletOutlet"
    overrides = {k: v for k, v in (("far_field", far_field),
                                   ("pressure_solver", pressure_solver),
                                   ("velocity_convection", velocity_convection),
                                   ("turbulence_convection", turbulence_convection),
                                   ("frame", frame), ("max_courant", max_courant),
                                   ("n_outer_correctors", outer_correctors),
                                   ("n_correctors", correctors))
                 if v is not None}
    try:
        solver = replace(solver, write_interval=end_time / writes, **overrides)
    except ConfigError as exc:  # named by the option that set it, not the library's key
        option = _SOLVER_OPTIONS.get(exc.key or "")
        if option is None:
            raise
        raise click.BadParameter(exc.detail, param_hint=option) from exc
    write_case(case_dir, motion, end_time, mesh=spec, plate=case.plate,
               fluid=case.fluid, stream=case.flow, ramp_time=ramp_time, y_plus=y_plus,
               solver=solver, overwrite=overwrite)
    if motion_table is not None:
        attach_motion_table(case_dir, motion_table)
    loop = (f"{'PISO' if solver.n_outer_correctors == 1 else 'PIMPLE'} "
            f"{solver.n_outer_correctors}x{solver.n_correctors}")  # outer x pressure correctors
    click.echo(f"wrote {case_dir} (mesh {spec.name}, {solver.frame} frame, {loop}, max Co "
               f"{solver.max_courant:g}, {solver.pressure_solver}, {solver.wall_treatment} "
               f"wall treatment, end time {end_time:g} s)")


#: the `cfd write` option that sets each solver setting
_SOLVER_OPTIONS = {"far_field": "--far-field", "pressure_solver": "--pressure-solver",
                   "velocity_convection": "--velocity-convection",
                   "turbulence_convection": "--turbulence-convection", "frame": "--frame",
                   "max_courant": "--max-courant", "n_outer_correctors": "--outer-correctors",
                   "n_correctors": "--correctors", "wall_treatment": "--wall-treatment"}


def _run_state(source: Path) -> str:
    """Why a run's forces stop short, as far as its folder tells: a solver still running in
    an OpenFOAM case (who holds its lock), or a run that stopped."""
    from mfflap.cfd.openfoam.case_lock import lock_holder

    holder = lock_holder(source) if source.is_dir() else None
    if holder is not None:
        return f"a run is still going: {holder}"
    return "the run is still going or stopped there"


def _motion_and_end_time(case, motion_table: Path | None, end_time: float | None,
                         cycles: float):
    """The motion a command writes or parses, and its end time: the case file's [motion]
    over ``cycles`` periods, or a user's table up to ``end_time`` (default its last row)."""
    if motion_table is None:
        if end_time is not None:
            raise click.UsageError("--end-time goes with --motion-table; the case file's "
                                   "motion runs for --cycles periods")
        end_time = cycles / case.motion.frequency
        case.motion.check_upright(end_time, f"--cycles {cycles:g}", source=case.source)
        return case.motion.build(), end_time
    from mfflap.errors import MotionError
    from mfflap.kinematics.table_file import read_motion_table, table_end_time

    refuse_given(("cycles",), "the case file's [motion]; a --motion-table runs to --end-time "
                              "(default: the table's last row)")
    motion = read_motion_table(motion_table)
    try:
        end_time = table_end_time(motion, end_time)
    except MotionError as exc:
        raise click.BadParameter(str(exc), param_hint="--end-time") from exc
    _warn_pitch_past_upright(motion, motion_table, end_time)
    return motion, end_time


def _warn_pitch_past_upright(motion: TabulatedMotion, motion_table: Path,
                             end_time: float) -> None:
    """Warn on stderr when a table's pitch reaches 90 deg or more up to ``end_time``: most
    likely degrees in the ``pitch_angle`` column, which is in rad."""
    from mfflap.kinematics.continuous import UPRIGHT_PITCH
    from mfflap.kinematics.table_file import largest_pitch

    pitch, time = largest_pitch(motion, end_time)
    if abs(pitch) >= UPRIGHT_PITCH:
        click.echo(f"warning: {motion_table}: the pitch reaches {np.degrees(pitch):.4g} deg at "
                   f"t = {time:g} s, past the {np.degrees(UPRIGHT_PITCH):g} deg at which the "
                   "plate stands across the stream (the column pitch_angle is in rad, "
                   "pitch_angle_deg in degrees)", err=True)


@cfd.command()
@click.argument("case_dir", type=click.Path(file_okay=False, exists=True, path_type=Path))
@click.option("--timeout", default=3600.0, show_default=True, type=POSITIVE,
              help="Seconds for pimpleFoam.")
@click.option("--procs", default=1, show_default=True, type=click.IntRange(min=1),
              help="MPI ranks: above 1 the case is decomposed once (method simple) and "
              "pimpleFoam runs under mpirun; a restart resumes from the processor folders.")
@click.option("--progress-every", default=10.0, show_default=True, type=NON_NEGATIVE,
              help="Seconds between progress lines on stderr (simulated time of the end "
              "time, time step, time left); 0: none.")
@click.option("--json", "as_json", is_flag=True,
              help="Print the run's summary (build, CPU, time steps, clipping) as JSON.")
def run(case_dir: Path, timeout: float, procs: int, progress_every: float,
        as_json: bool) -> None:
    """Mesh (once), check and run CASE_DIR with pimpleFoam; restarts from the latest time.

    Prints the CPU time, the number of time steps, how many k and epsilon solves OpenFOAM
    had to clip ("bounding epsilon") from the log, the numerical bursts of the force
    history (a few time steps where the run lost its pressure coupling, mfflap.cfd.bursts)
    and, for a case written with --y-plus, the plate's y+ against the wall functions'
    log-law range.
    """
    from mfflap.cfd.bursts import find_numerical_bursts
    from mfflap.cfd.openfoam.forces import read_forces
    from mfflap.cfd.openfoam.runner import (
        latest_solution_time,
        run_case,
        solver_progress,
        written_where_stopped,
    )
    from mfflap.cfd.openfoam.solver_log import solver_provenance
    from mfflap.cfd.openfoam.writer import written_wall_treatment
    from mfflap.cfd.openfoam.yplus import read_y_plus, wall_function_note, y_plus_summary

    progress = (None if progress_every <= 0 else
                lambda message: click.echo(f"[cfd run] {message}", err=True))
    try:
        run_case(case_dir, timeout_s=timeout, n_procs=procs, progress=progress,
                 progress_every_s=progress_every)
    except KeyboardInterrupt:  # the solver is stopped by then; say where a rerun resumes
        written = written_where_stopped(case_dir)
        if written is not None:
            click.echo(f"interrupted: pimpleFoam wrote its fields at t = {written} s and "
                       f"stopped; `mfflap cfd run {case_dir}` resumes there", err=True)
        else:  # stopped before it could write (a second Ctrl-C, or before its first step)
            reached = solver_progress(case_dir)
            resume = latest_solution_time(case_dir) or "0"
            click.echo(f"interrupted: pimpleFoam stopped"
                       f"{f' at t = {reached[0]:.6g} s' if reached else ''}; the last time "
                       f"written whole is {resume} s, where `mfflap cfd run {case_dir}` "
                       "resumes", err=True)
        raise click.Abort() from None
    summary = {"case": str(case_dir), "n_procs": procs, **solver_provenance(case_dir)}
    history = read_forces(case_dir)
    signals = [history.force[:, 0], history.force[:, 1]]
    if history.moment is not None:
        signals.append(history.moment[:, 2])
    summary["numerical_bursts"] = [b.describe()
                                   for b in find_numerical_bursts(history.time, signals)]
    summary["wall_treatment"] = written_wall_treatment(case_dir)
    if (case_dir / "postProcessing" / "yPlus").is_dir():  # written with --y-plus
        summary.update(y_plus_summary(read_y_plus(case_dir)))
        summary["wall_function_note"] = wall_function_note(summary, summary["wall_treatment"])
    if as_json:
        echo_json(summary)
        return
    click.echo(f"finished {case_dir}: {summary['cpu_time_s']:.1f} s CPU, "
               f"{summary['n_time_steps']} time steps")
    if "y_plus_mean" in summary:
        click.echo(f"  y+ on the plate: mean {summary['y_plus_mean']:.3g} (from "
                   f"{summary['y_plus_min']:.3g} to {summary['y_plus_max']:.3g} over the run; "
                   f"{summary['wall_treatment']} wall treatment)")
        if summary["wall_function_note"]:
            click.echo(f"  {summary['wall_function_note']}")
    for burst in summary["numerical_bursts"]:
        click.echo(f"  numerical burst {burst}")
    for field in ("k", "epsilon"):
        n = summary[f"n_steps_bounding_{field}"]
        if n:
            click.echo(f"  {field} clipped after {n} solves (most negative "
                       f"{100 * summary[f'worst_bounding_{field}']:.2g} % of the maximum); "
                       "turbulence_convection = \"upwind\" in a set-up avoids it")


@cfd.command()
@click.argument("source", type=click.Path(exists=True, path_type=Path))
@click.option("--case-file", type=click.Path(dir_okay=False, path_type=Path), required=True,
              help="The case file whose [motion] the CFD case imposes.")
@click.option("--discard", default=0.0, show_default=True, type=NON_NEGATIVE,
              help="Seconds of start-up transient left out of the comparison.")
@click.option("--fx", default="fx-plate", show_default=True,
              help="Fluent: report column of the x force.")
@click.option("--fy", default="fy-plate", show_default=True,
              help="Fluent: report column of the y force.")
@click.option("--mz", default="mz-plate", show_default=True,
              help="Fluent: report column of the z moment about the origin.")
@click.option("--depth", default=1.0, show_default=True, type=POSITIVE,
              help="Fluent: depth the 2D forces are given for, m (Fluent 2D: 1 m).")
@click.option("--ramp-time", type=NON_NEGATIVE, default=None,
              help="Start-up ramp of the case, s; default: the one it was written with "
                   "(an OpenFOAM case's mfflap_case.toml, the mfflap_fluent.toml `cfd "
                   "fluent` writes beside a UDF and its report file), else 0. A value "
                   "other than the kept one is refused.")
@click.option("--thin-aerofoil", is_flag=True,
              help="Also compare F_n, M and the mean input power with linear unsteady "
                   "thin-aerofoil theory (Theodorsen/Wagner): the yardstick for small "
                   "motions (effective incidence of a few degrees, printed).")
@click.option("--motion-table", type=click.Path(dir_okay=False, exists=True, path_type=Path),
              default=None, help="Fluent: the CSV motion table the UDF was written from, "
                                 "for a report file without the mfflap_fluent.toml of "
                                 "`cfd fluent` beside it (that and an OpenFOAM case written "
                                 "from a table keep it).")
@click.option("--plot", "plot_path", type=FigureFile(), default=None,
              help="Write a figure of F_n, F_t, M, thrust and power, CFD beside the model, "
                   "over time (.png, .pdf or .svg).")
@click.option("--save", "save_path", type=ResultsOutput("cfd_model_comparison"),
              default=None, help="Write the comparison to HDF5: both time series, the summary, "
              "the case file and what the run was written for.")
@click.option("--json", "as_json", is_flag=True, help="Print results as JSON.")
def parse(source: Path, case_file: Path, discard: float, fx: str, fy: str, mz: str,
          depth: float, ramp_time: float | None, thin_aerofoil: bool,
          motion_table: Path | None, plot_path: Path | None, save_path: Path | None,
          as_json: bool) -> None:
    """Parse forces into F_n, F_t, M, thrust and power, compared with the model.

    SOURCE is an OpenFOAM case folder written by mfflap, or a Fluent report file (.out) with
    force and moment columns and the flow time. Numerical bursts after --discard (a few
    time steps where the solver lost its pressure coupling, mfflap.cfd.bursts) are bridged
    before the comparison and listed, and so are stretches whose forces the motion cannot
    have driven (a run that lost its numerics, mfflap.cfd.force_envelope: listed, not
    bridged); means are time averages over the solver's steps. A case file other than the
    one the case was written from is refused (mfflap.cfd.model_comparison); a Fluent report
    with no mfflap_fluent.toml beside it cannot be checked, and a warning says so.
    """
    from mfflap.cfd.fluent.udf import FLUENT_KEPT_FILE
    from mfflap.cfd.model_comparison import model_comparison, write_model_comparison

    if source.is_dir():  # an OpenFOAM case: the Fluent report's options would be ignored
        refuse_given(("fx", "fy", "mz", "depth"),
                     f"a Fluent report; {source} is an OpenFOAM case folder (its forces and "
                     "depth are read from the case)")
    comparison = model_comparison(source, case_file, discard_s=discard, ramp_time_s=ramp_time,
                                  motion_table=motion_table, fluent_columns=(fx, fy, mz),
                                  fluent_depth_m=depth, thin_aerofoil=thin_aerofoil)
    out = comparison.summary
    if plot_path is not None:
        from mfflap.plots import model_comparison_figure, save_figure

        save_figure(model_comparison_figure(comparison), plot_path)
        click.echo(f"wrote {plot_path}", err=True)
    if save_path is not None:  # its folder made by ResultsFile
        write_model_comparison(save_path, comparison, case_file)
        click.echo(f"wrote {save_path}", err=True)
    if out["forces_reach_end_time"] is False:
        click.echo(f"warning: {source}: its forces end at t = {out['end_time']:.6g} s, before "
                   f"the {out['written_end_time']:g} s the run was written for "
                   f"({_run_state(source)}); the means, NRMSE and Pearson cover only that",
                   err=True)
    if out["inputs_checked_against"] is None:
        click.echo(f"warning: nothing beside {source} says what the run was written for, so "
                   f"{case_file} and the ramp and motion table given were not checked against "
                   f"it (`mfflap cfd fluent` writes {FLUENT_KEPT_FILE} where the journal "
                   "makes Fluent write its report)", err=True)
    if thin_aerofoil:
        from mfflap.hydro.thin_aerofoil import LINEAR_INCIDENCE_LIMIT_DEG

        incidence = out["thin_aerofoil"]["max_effective_incidence_deg"]
        if incidence > LINEAR_INCIDENCE_LIMIT_DEG:
            click.echo(f"warning: the motion's effective incidence reaches {incidence:.3g} deg; "
                       "thin-aerofoil theory (linear, attached flow) is a yardstick up to "
                       f"about {LINEAR_INCIDENCE_LIMIT_DEG:g} deg, so its numbers here say "
                       "little about the CFD", err=True)
    if as_json:
        echo_json(out)
    else:
        for k, v in out.items():
            if isinstance(v, dict):
                click.echo(f"  {k}:")
                for kk, vv in v.items():
                    click.echo(f"    {kk:28s} {_shown(kk, vv)}")
            else:
                click.echo(f"  {k:24s} {_shown(k, v)}")


#: units of the numbers `cfd parse` prints, by a word of their name
_UNIT_BY_WORD = (("_deg", "deg"), ("thrust", "N"), ("power", "W"), ("time", "s"))


def _shown(key: str, value) -> str:
    """A value of the parse summary as text: numbers to 6 digits with their unit, empty
    lists as 'none'."""
    if isinstance(value, float):
        unit = next((u for word, u in _UNIT_BY_WORD if word in key), "")
        return f"{value:.6g}{' ' + unit if unit else ''}"
    if isinstance(value, list):
        return "none" if not value else "; ".join(str(item) for item in value)
    return str(value)


@cfd.command()
@click.argument("case_file", type=click.Path(dir_okay=False, exists=True, path_type=Path))
@click.argument("out_dir", type=click.Path(file_okay=False, path_type=Path))
@click.option("--cycles", default=3.0, show_default=True, type=POSITIVE,
              help="Carrier periods to simulate.")
@click.option("--ramp-time", default=0.0, show_default=True, type=NON_NEGATIVE,
              help="Smooth start-up ramp, s.")
@click.option("--time-step", default=1e-3, show_default=True, type=POSITIVE,
              help="Fluent time step, s.")
@click.option("--table", is_flag=True, help="Table-driven UDF even for a sinusoid.")
@_motion_table_options("A table-driven UDF; the table is kept beside it.")
@click.option("--overwrite", is_flag=True,
              help="Delete the report file of an earlier run in OUT_DIR (refused without "
                   "it: beside the new UDF its forces would parse as the new motion's).")
def fluent(case_file: Path, out_dir: Path, cycles: float, ramp_time: float, time_step: float,
           table: bool, motion_table: Path | None, end_time: float | None,
           overwrite: bool) -> None:
    """Write a DEFINE_CG_MOTION UDF and a batch journal for the [motion] of CASE_FILE (or a
    --motion-table)."""
    from mfflap.cfd.fluent.udf import FEW_STEPS_PER_PERIOD, FLUENT_KEPT_FILE, write_fluent_case
    from mfflap.cfd.openfoam.writer import attach_motion_table
    from mfflap.config import load_case

    case = load_case(case_file)
    motion, end_time = _motion_and_end_time(case, motion_table, end_time, cycles)
    write_fluent_case(out_dir, motion, end_time, ramp_time=ramp_time,
                      time_step=time_step, velocity=case.flow.velocity, table=table,
                      plate=case.plate, fluid=case.fluid, overwrite=overwrite)
    per_period = 1.0 / (case.motion.frequency * time_step)
    if motion_table is None and per_period < FEW_STEPS_PER_PERIOD:
        click.echo(f"warning: --time-step {time_step:g} s gives {per_period:.3g} steps per "
                   f"period of the {case.motion.frequency:g} Hz motion; flapping-foil runs "
                   f"use a few hundred (fewer than {FEW_STEPS_PER_PERIOD} smear the forces)",
                   err=True)
    if motion_table is not None:
        attach_motion_table(out_dir, motion_table, kept_file=FLUENT_KEPT_FILE)
    click.echo(f"wrote {out_dir / 'mfflap_motion.c'}, {out_dir / 'mfflap_run.jou'} and "
               f"{out_dir / 'mfflap_fluent.toml'} (what the UDF was written for: `cfd parse` "
               "reads it beside the report file)")


@cfd.command()
@click.argument("case_file", type=click.Path(dir_okay=False, exists=True, path_type=Path))
@click.argument("out_dir", type=click.Path(file_okay=False, path_type=Path))
@click.option("--meshes", default="coarse,medium,fine", show_default=True,
              help="Mesh resolutions, coarsest first; the last is the reference.")
@click.option("--courant", "courants", default="4,2", show_default=True, type=FloatList(),
              help="Courant limits; one mesh (--time-step-mesh) is repeated at each further "
                   "one.")
@click.option("--time-step-mesh", default=None,
              help="The mesh repeated at the further Courant limits (default the first).")
@click.option("--cycles", default=1.0, show_default=True, type=POSITIVE,
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
@_motion_table_options("")
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
    from mfflap.cfd.convergence import convergence_figure, run_convergence
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
    motion, end = _motion_and_end_time(case, motion_table, end_time, cycles)
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


@cfd.command("linear-check")
@click.argument("out_dir", type=click.Path(file_okay=False, path_type=Path))
@click.option("--case-file", type=click.Path(dir_okay=False, exists=True, path_type=Path),
              default=None, help="Plate, fluid, stream and strip-model coefficients (default: "
                                 "the package's, those of cases/paper2026.toml).")
@mesh_and_setup_options()
@velocity_convection_option
@click.option("--cases", "case_ids", default=None,
              help="Comma-separated case ids of the default motions (--list shows them).")
@click.option("--list", "list_only", is_flag=True, help="List the motions and exit.")
@click.option("--workers", default=1, show_default=True, type=click.IntRange(min=1),
              help="LocalCluster worker processes.")
@click.option("--timeout", default=3600.0, show_default=True, type=POSITIVE,
              help="Seconds per case.")
@click.option("--single-precision", is_flag=True, help="Store the records in float32.")
@click.option("--retry-failed", is_flag=True,
              help="Rerun the motions that failed before (e.g. with a longer --timeout).")
@click.option("--json", "as_json", is_flag=True, help="Print the checks as JSON.")
def linear_check(out_dir: Path, case_file: Path | None, mesh: str | None,
                 setup_name: str | None, wall_treatment: str | None,
                 velocity_convection: str | None, case_ids: str | None, list_only: bool,
                 workers: int, timeout: float,
                 single_precision: bool, retry_failed: bool, as_json: bool) -> None:
    """Verify a CFD set-up against linear unsteady thin-aerofoil theory.

    Runs small harmonic heaves and pitches (effective incidence of a few degrees, reduced
    frequency 0.4-3.4) in OpenFOAM as a resumable campaign in OUT_DIR, then compares each
    run's F_n and M with Theodorsen's theory and with the strip model: a table,
    OUT_DIR/linear_check/checks.h5 and OUT_DIR/linear_check/normal_force.png. A sound set-up
    lies a few percent from the theory; wrong frames, scaling or moment reference show as
    tens of percent. The exit status is 1 when a motion failed (each is listed with why).
    """
    from dataclasses import asdict, replace

    from mfflap.campaign.execute import CampaignSetup, run_campaign
    from mfflap.campaign.records import read_record
    from mfflap.cfd.linear_check import (
        SMALL_MOTIONS,
        check_record,
        plot_checks,
        summary_table,
        write_checks,
    )
    from mfflap.cfd.openfoam.setups import mesh_and_solver
    from mfflap.cli.campaign import aborted_with_resume_message
    from mfflap.config import CaseConfig, load_case
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
    config = load_case(case_file) if case_file else CaseConfig()
    spec, solver = mesh_and_solver(mesh, setup_name, wall_treatment)
    if velocity_convection is not None:
        solver = replace(solver, velocity_convection=velocity_convection)
    setup = CampaignSetup(mesh=spec.name, solver=solver, plate=config.plate,
                          fluid=config.fluid, stream=config.flow, timeout_s=timeout,
                          single_precision=single_precision)
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


@cfd.command("motion-table")
@click.argument("results_file", type=click.Path(dir_okay=False, exists=True, path_type=Path))
@click.argument("table_file", type=click.Path(dir_okay=False, path_type=Path))
@click.option("--beta", type=float, default=None,
              help="The optimised motion of this β (from `mfflap optimise` or `mfflap run`).")
@click.option("--best-sinusoid", is_flag=True,
              help="The best sinusoid of the sweep instead of an optimised motion.")
@click.option("--cycles", default=3.0, show_default=True, type=POSITIVE,
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
