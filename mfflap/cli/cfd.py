"""``mfflap cfd``: the group, and writing, running and parsing cases (OpenFOAM) and UDFs
(Fluent); its other commands are in the modules ``cfd_*`` beside this one."""

from __future__ import annotations

from pathlib import Path

import click

from mfflap.cli.cfd_motion import motion_and_end_time, motion_table_options, warn_not_at_rest
from mfflap.cli.json_output import echo_json
from mfflap.cli.options import (
    CYCLES,
    NON_NEGATIVE,
    POSITIVE,
    TIMEOUT,
    FigureFile,
    ResultsOutput,
    cfd_settings,
    mesh_and_setup_options,
    refuse_given,
    set_option,
)
from mfflap.errors import shown


@click.group()
def cfd() -> None:
    """CFD adapters: OpenFOAM cases (write, run, mesh study), Fluent UDFs, both solvers' forces."""


@cfd.command()
@click.argument("case_file", type=click.Path(dir_okay=False, path_type=Path))
@click.argument("case_dir", type=click.Path(file_okay=False, path_type=Path))
@mesh_and_setup_options()
@click.option("--cycles", default=3.0, show_default=True, type=CYCLES,
              help="Carrier periods to simulate.")
@click.option("--ramp-time", default=0.0, show_default=True, type=NON_NEGATIVE,
              help="Smooth start-up ramp, s.")
@motion_table_options("Kept in the case.")
@click.option("--overwrite", is_flag=True,
              help="Delete a case written into CASE_DIR before (its results, mesh and logs "
                   "too) and write this one; without it such a folder is refused.")
@set_option()
def write(case_file: Path, case_dir: Path, mesh: str | None, setup_name: str | None,
          cycles: float, ramp_time: float, motion_table: Path | None,
          end_time: float | None, overwrite: bool, settings: tuple[str, ...]) -> None:
    """Write an OpenFOAM case for the [motion] of CASE_FILE (or a --motion-table) into
    CASE_DIR, a new or empty folder (or a case written before, with --overwrite).

    The mesh and solver settings are the case file's [cfd] table (a named set-up, a mesh,
    and the solver keys that replace the set-up's: frame, far_field, wall_treatment,
    max_courant, correctors, ...), with --mesh, --setup and --set cfd.KEY=VALUE for this
    case; `mfflap case show CASE_FILE` lists them with their defaults.
    """
    from dataclasses import replace

    from mfflap.cfd.openfoam.setups import case_mesh_and_solver
    from mfflap.cfd.openfoam.writer import attach_motion_table, write_case
    from mfflap.config import load_case

    case = load_case(case_file, cfd_settings(settings, mesh, setup_name))
    spec, solver = case_mesh_and_solver(case.cfd, case.source)
    motion, end_time = motion_and_end_time(case, motion_table, end_time, cycles)
    solver = replace(solver, write_interval=end_time / case.cfd.writes)
    write_case(case_dir, motion, end_time, mesh=spec, plate=case.plate,
               fluid=case.fluid, stream=case.flow, ramp_time=ramp_time,
               y_plus=case.cfd.y_plus, solver=solver, overwrite=overwrite)
    warn_not_at_rest(motion, ramp_time, end_time)
    if motion_table is not None:
        attach_motion_table(case_dir, motion_table)
    loop = (f"{'PISO' if solver.n_outer_correctors == 1 else 'PIMPLE'} "
            f"{solver.n_outer_correctors}x{solver.n_correctors}")  # outer x pressure correctors
    click.echo(f"wrote {case_dir} (mesh {spec.name}, {solver.frame} frame, {loop}, max Co "
               f"{solver.max_courant:g}, {solver.pressure_solver}, {solver.wall_treatment} "
               f"wall treatment, end time {end_time:g} s)")


def _run_state(source: Path) -> str:
    """Why a run's forces stop short, as far as its folder tells: a solver still running in
    an OpenFOAM case (who holds its lock), or a run that stopped."""
    from mfflap.cfd.openfoam.case_lock import lock_holder

    holder = lock_holder(source) if source.is_dir() else None
    if holder is not None:
        return f"a run is still going: {holder}"
    return "the run is still going or stopped there"



class FluentColumns(click.ParamType):
    """Three comma-separated names of a Fluent report's columns (x force, y force, z
    moment), refused by the option's name otherwise."""

    name = "fx,fy,mz"

    def convert(self, value, param, ctx) -> tuple[str, str, str]:
        if isinstance(value, tuple):
            return value
        names = tuple(v.strip() for v in str(value).split(","))
        if len(names) != 3 or not all(names):
            self.fail(f"{shown(value)}: give the three columns of the x force, the y force "
                      "and the z moment, comma separated (e.g. fx-plate,fy-plate,mz-plate)",
                      param, ctx)
        return names  # type: ignore[return-value]


@cfd.command()
@click.argument("case_dir", type=click.Path(file_okay=False, exists=True, path_type=Path))
@click.option("--timeout", default=3600.0, show_default=True, type=TIMEOUT,
              help="Seconds for pimpleFoam.")
@click.option("--procs", default=1, show_default=True, type=click.IntRange(min=1),
              help="MPI ranks: above 1 the case is decomposed once (method simple) and "
              "pimpleFoam runs under mpirun; a restart resumes from the processor folders.")
@click.option("--progress-every", default=10.0, show_default=True, type=NON_NEGATIVE,
              help="Seconds between progress lines on stderr (simulated time of the end "
              "time, time step, time left); 0: none.")
@click.option("--rewind-before", "rewind_before_s", type=POSITIVE, default=None,
              help="First go back to the last time written before this many s: the later "
              "time folders and the function-object output begun after it go, and the run "
              "resumes there (a run whose time step collapsed, or whose forces went wrong, "
              "at that time).")
@click.option("--json", "as_json", is_flag=True,
              help="Print the run's summary (build, CPU, time steps, clipping) as JSON.")
def run(case_dir: Path, timeout: float, procs: int, progress_every: float,
        rewind_before_s: float | None, as_json: bool) -> None:
    """Mesh (once), check and run CASE_DIR with pimpleFoam; restarts from the latest time.

    Prints the CPU time, the number of time steps, how many k and epsilon solves OpenFOAM
    had to clip ("bounding epsilon") from the log, the numerical bursts of the force
    history (a few time steps where the run lost its pressure coupling, mfflap.records.bursts)
    and, for a case written with cfd.y_plus = true, the plate's y+ against the wall functions'
    log-law range.
    """
    from mfflap.cfd.openfoam.forces import read_forces
    from mfflap.cfd.openfoam.runner import run_case, written_where_stopped
    from mfflap.cfd.openfoam.solver_log import solver_progress, solver_provenance
    from mfflap.cfd.openfoam.time_folders import latest_solution_time
    from mfflap.cfd.openfoam.writer import written_wall_treatment
    from mfflap.cfd.openfoam.yplus import read_y_plus, wall_function_note, y_plus_summary
    from mfflap.records.bursts import find_numerical_bursts

    progress = (None if progress_every <= 0 else
                lambda message: click.echo(f"[cfd run] {message}", err=True))
    if rewind_before_s is not None:
        from mfflap.cfd.openfoam.case_lock import case_lock
        from mfflap.cfd.openfoam.rewind import rewind_case

        with case_lock(case_dir):  # not under a solver that is running it
            resume = rewind_case(case_dir, rewind_before_s)
        click.echo(f"[cfd run] rewound to t = {resume} s, the last time written before "
                   f"{rewind_before_s:g} s", err=True)
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
    if (case_dir / "postProcessing" / "yPlus").is_dir():  # written with cfd.y_plus = true
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
@click.option("--columns", type=FluentColumns(), default="fx-plate,fy-plate,mz-plate",
              show_default=True,
              help="Fluent: the report's columns of the x force, the y force and the z "
                   "moment about the origin, comma separated.")
@click.option("--depth", default=None, type=POSITIVE,
              help="Depth the forces are given for, m: a Fluent report's (default 1 m, "
                   "Fluent 2D) or an OpenFOAM case's that mfflap did not write (default the "
                   "z extent of its mesh).")
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
              default=None, help="The CSV motion table the run imposed: for a Fluent report "
                                 "without the mfflap_fluent.toml of `cfd fluent` beside it, "
                                 "or an OpenFOAM case mfflap did not write (default: the "
                                 "motion of its dynamicMeshDict). A case mfflap wrote keeps "
                                 "its own.")
@click.option("--plot", "plot_path", type=FigureFile(), default=None,
              help="Write a figure of F_n, F_t, M, thrust and power, CFD beside the model, "
                   "over time (.png, .pdf or .svg).")
@click.option("--save", "save_path", type=ResultsOutput("cfd_model_comparison"),
              default=None, help="Write the comparison to HDF5: both time series, the summary, "
              "the case file and what the run was written for.")
@click.option("--json", "as_json", is_flag=True, help="Print results as JSON.")
def parse(source: Path, case_file: Path, discard: float, columns: tuple[str, str, str],
          depth: float, ramp_time: float | None, thin_aerofoil: bool,
          motion_table: Path | None, plot_path: Path | None, save_path: Path | None,
          as_json: bool) -> None:
    """Parse forces into F_n, F_t, M, thrust and power, compared with the model.

    SOURCE is an OpenFOAM case folder, or a Fluent report file (.out) with force and
    moment columns and the flow time. A case mfflap did not write is read from its own
    files: the motion of its dynamicMeshDict (solidBody: tabulated6DoFMotion, or
    oscillatingLinearMotion and oscillatingRotatingMotion under multiMotion; the rotation's
    centre is the pivot) or --motion-table, the depth of its mesh or --depth, the loads of
    its forces function object about its CofR. Numerical bursts after --discard (a few
    time steps where the solver lost its pressure coupling, mfflap.records.bursts) are bridged
    before the comparison and listed, and so are stretches whose forces the motion cannot
    have driven (a run that lost its numerics, mfflap.records.force_envelope: listed, not
    bridged); means are time averages over the solver's steps. A case file other than the
    one the case was written from is refused (mfflap.cfd.model_comparison); a Fluent report
    with no mfflap_fluent.toml beside it cannot be checked, and a warning says so.
    """
    from mfflap.cfd.fluent.udf import FLUENT_KEPT_FILE
    from mfflap.cfd.model_comparison import model_comparison, write_model_comparison

    if source.is_dir():  # an OpenFOAM case: the Fluent report's options would be ignored
        refuse_given(("columns",),
                     f"a Fluent report; {source} is an OpenFOAM case folder (its forces are "
                     "read from the case)")
    comparison = model_comparison(source, case_file, discard_s=discard, ramp_time_s=ramp_time,
                                  motion_table=motion_table, fluent_columns=columns,
                                  depth_m=depth, thin_aerofoil=thin_aerofoil)
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
@click.option("--cycles", default=3.0, show_default=True, type=CYCLES,
              help="Carrier periods to simulate.")
@click.option("--ramp-time", default=0.0, show_default=True, type=NON_NEGATIVE,
              help="Smooth start-up ramp, s.")
@click.option("--time-step", default=1e-3, show_default=True, type=POSITIVE,
              help="Fluent time step, s.")
@click.option("--table", is_flag=True, help="Table-driven UDF even for a sinusoid.")
@motion_table_options("A table-driven UDF; the table is kept beside it.")
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
    motion, end_time = motion_and_end_time(case, motion_table, end_time, cycles)
    write_fluent_case(out_dir, motion, end_time, ramp_time=ramp_time,
                      time_step=time_step, velocity=case.flow.velocity, table=table,
                      plate=case.plate, fluid=case.fluid, overwrite=overwrite)
    warn_not_at_rest(motion, ramp_time, end_time)
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
