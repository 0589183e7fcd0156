"""Write a runnable 2D OpenFOAM case of the plate for any motion.

The mesh has the pivot (:attr:`~mfflap.parameters.Plate.pivot_m` behind the leading edge)
at the origin, so the rotation centre, the moments' centre and the plate frame's origin are
the origin whatever the pivot. The templates live in ``cfd_templates/openfoam`` (jinja2
where they carry numbers); the mesh resolutions in ``cfd_templates/openfoam/meshes.toml``.
Two formulations (:attr:`SolverSettings.frame`):

- "inertial": the whole mesh moves as a rigid body (solidBody / tabulated6DoFMotion about
  the pivot), so there is no mesh deformation;
- "plate": the mesh stays still in the plate's frame, which turns with the pitch about the
  pivot (MRF with a tabulated rate, absolute-velocity formulation) and moves with the
  heave (the far field's inflow is the stream minus the heave velocity; the heave
  acceleration is a uniform body force, tabulatedAccelerationSource). The files only this
  formulation needs are in ``cfd_templates/openfoam/plate_frame``.
"""

from __future__ import annotations

import math
import shutil
from dataclasses import asdict, dataclass
from pathlib import Path

import jinja2
import numpy as np

from mfflap.cfd import templates
from mfflap.cfd.case_inputs import recorded_inputs
from mfflap.cfd.frames import FRAMES, case_displacement, case_rotation_deg
from mfflap.cfd.imposed_motion import (
    check_end_time,
    check_ramp_time,
    check_start_at_mesh,
    imposed_state,
)
from mfflap.cfd.openfoam.case_path import prepare_case_folder
from mfflap.cfd.openfoam.cell_counts import check_cell_counts
from mfflap.cfd.openfoam.foam_files import decode_error, foam_file
from mfflap.cfd.openfoam.h_grid import HGridSpec
from mfflap.cfd.openfoam.plate_frame import (
    format_acceleration_table,
    format_function1_table,
    plate_frame_tables,
)
from mfflap.errors import ConfigError, shown
from mfflap.kinematics.continuous import Motion
from mfflap.parameters import Fluid, FreeStream, Plate
from mfflap.toml_io import read_toml


def template_dir() -> Path:
    """The OpenFOAM template folder (``cfd_templates/openfoam``)."""
    return templates.template_dir("openfoam")


@dataclass(frozen=True)
class MeshSpec:
    """An O-grid resolution (see meshes.toml)."""

    name: str
    n_chord: int
    n_edge: int
    n_radial: int
    radial_expansion: float
    radius_chords: float
    chord_grading: float = 1.0  # mid-chord cell / end cell along the faces (1: uniform)

    def __post_init__(self) -> None:
        check_cell_counts(self.name, {"n_chord": self.n_chord, "n_edge": self.n_edge,
                                      "n_radial": self.n_radial})
        if not self.chord_grading > 0:
            raise ConfigError(f"mesh {self.name!r}: chord_grading must be > 0, got "
                              f"{self.chord_grading!r}", key="chord_grading")
        if not self.radial_expansion > 0 or not self.radius_chords > 1:
            raise ConfigError(f"mesh {self.name!r}: radial_expansion must be > 0 and "
                              "radius_chords > 1", key="radial_expansion")

    @property
    def n_cells(self) -> int:
        """Cells of the one-cell-thick mesh."""
        return (2 * self.n_chord + 2 * self.n_edge) * self.n_radial


#: A mesh of meshes.toml: an O-grid, or the H-type baseline (``topology = "H"``)
AnyMeshSpec = MeshSpec | HGridSpec
#: The dataclass of each ``topology`` of meshes.toml
MESH_TOPOLOGIES: dict[str, type] = {"O": MeshSpec, "H": HGridSpec}


def mesh_specs() -> dict[str, AnyMeshSpec]:
    """The named resolutions of meshes.toml.

    Raises
    ------
    ConfigError
        For an unknown ``topology`` or a key its mesh kind does not have (naming the file and
        the table).
    """
    path = template_dir() / "meshes.toml"
    data = read_toml(path)
    specs = {}
    for name, values in data.items():
        values = dict(values)
        topology = values.pop("topology", "O")
        if topology not in MESH_TOPOLOGIES:
            raise ConfigError(f"mesh {name!r}: topology must be one of "
                              f"{', '.join(MESH_TOPOLOGIES)}, got {topology!r}",
                              key=f"{name}.topology", source=str(path))
        try:
            specs[name] = MESH_TOPOLOGIES[topology](name=name, **values)
        except TypeError as err:
            raise ConfigError(f"mesh {name!r} ({topology}-grid): {err}", key=name,
                              source=str(path)) from err
        except ConfigError as err:  # a value the mesh refuses: name the file and table too
            raise ConfigError(err._message, key=f"{name}.{err.key}" if err.key else name,
                              source=str(path)) from err
    return specs


def resolve_mesh(mesh: str | AnyMeshSpec) -> AnyMeshSpec:
    """``mesh`` itself, or the named resolution of meshes.toml.

    Raises
    ------
    ConfigError
        For a name meshes.toml does not have (the message lists those it has).
    """
    if isinstance(mesh, AnyMeshSpec):
        return mesh
    specs = mesh_specs()
    if mesh not in specs:
        raise ConfigError(f"unknown mesh {shown(mesh)}; meshes.toml has: {', '.join(specs)}",
                          key="mesh",
                          source=str(template_dir() / "meshes.toml"))
    return specs[mesh]


#: Convection schemes of U that the case template accepts (each with ``grad(U)``).
VELOCITY_CONVECTION_SCHEMES = ("linearUpwind", "LUST")
#: fvSchemes entry of each turbulence_convection choice
TURBULENCE_CONVECTION_SCHEMES = {"limitedLinear": "limitedLinear 1", "upwind": "upwind"}
#: The plate's wall conditions of each wall_treatment choice: the type of nut's and the
#: options of epsilon's epsilonWallFunction (k keeps kqRWallFunction, a zero gradient)
WALL_TREATMENTS = {
    "log_law": {"nut": "nutkWallFunction", "epsilon_options": ""},
    "all_y_plus": {"nut": "nutUSpaldingWallFunction",
                   "epsilon_options": " lowReCorrection true;"},
}
#: The template folder of the files only the plate's frame needs
PLATE_FRAME_TEMPLATES = "plate_frame"
#: The template folder of the H-type mesh's blockMeshDict (:mod:`~.h_grid`)
H_GRID_TEMPLATES = "h_grid"


def written_wall_treatment(case_dir: str | Path) -> str:
    """The :data:`WALL_TREATMENTS` name of the plate's wall condition of nut in a case's
    0/nut (as written, or as changed by hand since, read with foamlib), or "other"."""
    path = Path(case_dir) / "0" / "nut"
    try:
        nut = foam_file(path) if path.is_file() else None
        written = nut["boundaryField"]["plate"]["type"] if nut is not None else None
    except (decode_error(), KeyError, TypeError):  # no plate patch, or no type
        written = None
    return next((name for name, wall in WALL_TREATMENTS.items() if written == wall["nut"]),
                "other")


@dataclass(frozen=True)
class SolverSettings:
    """PIMPLE and time-step settings of a run."""

    max_courant: float = 4.0
    n_outer_correctors: int = 2
    n_correctors: int = 1
    max_time_step: float = 5e-3
    initial_time_step: float = 1e-4
    turbulence_intensity: float = 0.01
    #: s between field writes (a killed run restarts from the last one); the case writes at
    #: least at its end time, so that a finished run is not run again and can be continued
    write_interval: float = 1.0e9
    pressure_solver: str = "PCG"
    pressure_tolerance: float = 1e-7
    #: "freestream": freestreamVelocity/freestreamPressure on the far field;
    #: "inletOutlet": inletOutlet velocity and a fixed pressure (stable where the whole mesh
    #: heaves much faster than the stream; see :func:`mfflap.cfd.openfoam.run_motion.run_motion`)
    far_field: str = "freestream"
    #: convection scheme of U: "linearUpwind" (second-order upwind) or "LUST" (75 % linear,
    #: 25 % linearUpwind: less numerical diffusion of the shed vortices on a coarse mesh)
    velocity_convection: str = "linearUpwind"
    #: relative tolerance of the last pressure corrector of a time step (0: converge to
    #: ``pressure_tolerance``, which costs most of the pressure solve's iterations)
    pressure_final_rel_tol: float = 0.0
    #: convection scheme of k and epsilon: "limitedLinear" (TVD, second order where smooth)
    #: or "upwind" (first order, bounded at any Courant number; with limitedLinear the
    #: implicit matrix is not an M-matrix at max Co 4 and epsilon goes negative in a few
    #: cells every time step, which OpenFOAM clips with a "bounding epsilon" message)
    turbulence_convection: str = "limitedLinear"
    #: "inertial": the whole mesh moves with the plate; "plate": a static mesh in the plate's
    #: frame (no mesh motion, about a third less CPU per time step; needs the inletOutlet
    #: far field, whose inflow follows the heave and pitch)
    frame: str = "inertial"
    #: the plate's wall conditions: "log_law": nutkWallFunction and epsilonWallFunction,
    #: made for a first cell in the log layer (y+ 30-300), which take a cell below y+ of
    #: about 11 as laminar; "all_y_plus": Spalding's law of the wall for nut (viscous
    #: sublayer, buffer and log layer in one formula) and epsilon's low-Re correction
    #: (2 k nu / y^2 in the sublayer), valid at any y+ of the first cell, as Fluent's
    #: enhanced wall treatment, which the paper used, is
    wall_treatment: str = "log_law"

    def __post_init__(self) -> None:
        if self.pressure_solver not in ("PCG", "GAMG"):
            raise ConfigError(f"pressure_solver must be PCG or GAMG, got {self.pressure_solver!r}",
                              key="pressure_solver")
        if self.far_field not in ("freestream", "inletOutlet"):
            raise ConfigError(f"far_field must be freestream or inletOutlet, got "
                              f"{self.far_field!r}", key="far_field")
        if self.frame not in FRAMES:
            raise ConfigError(f"frame must be one of {', '.join(FRAMES)}, got {self.frame!r}",
                              key="frame")
        if self.frame == "plate" and self.far_field != "inletOutlet":
            raise ConfigError(f"the plate frame needs the inletOutlet far field, not "
                              f"{self.far_field}: the stream enters the plate's frame with "
                              f"the heave and pitch, which the {self.far_field} far field "
                              "cannot follow", key="far_field")
        if self.wall_treatment not in WALL_TREATMENTS:
            raise ConfigError(f"wall_treatment must be one of {', '.join(WALL_TREATMENTS)}, "
                              f"got {self.wall_treatment!r}", key="wall_treatment")
        if self.velocity_convection not in VELOCITY_CONVECTION_SCHEMES:
            raise ConfigError(f"velocity_convection must be one of "
                              f"{', '.join(VELOCITY_CONVECTION_SCHEMES)}, got "
                              f"{self.velocity_convection!r}", key="velocity_convection")
        if self.turbulence_convection not in TURBULENCE_CONVECTION_SCHEMES:
            raise ConfigError(f"turbulence_convection must be one of "
                              f"{', '.join(TURBULENCE_CONVECTION_SCHEMES)}, got "
                              f"{self.turbulence_convection!r}", key="turbulence_convection")
        if not self.max_courant > 0:
            raise ConfigError(f"max_courant must be > 0, got {self.max_courant!r}",
                              key="max_courant")
        if self.n_outer_correctors < 1 or self.n_correctors < 1:
            raise ConfigError("n_outer_correctors and n_correctors must be >= 1",
                              key="n_outer_correctors")
        if not 0 <= self.pressure_final_rel_tol < 1:
            raise ConfigError(f"pressure_final_rel_tol must be in [0, 1), got "
                              f"{self.pressure_final_rel_tol!r}", key="pressure_final_rel_tol")
        if not self.pressure_tolerance > 0:
            raise ConfigError(f"pressure_tolerance must be > 0, got {self.pressure_tolerance!r}",
                              key="pressure_tolerance")


def table_times(end_time: float, rows_per_second: float = 400.0) -> np.ndarray:
    """Times of the motion tables, s: from 0 to 10 % (+ 0.05 s) past ``end_time``."""
    t_end = 1.1 * check_end_time(end_time) + 0.05
    n = max(math.ceil(t_end * rows_per_second), 8)
    return np.linspace(0.0, t_end, n + 1)


def motion_table(motion: Motion, end_time: float, rows_per_second: float = 400.0,
                 ramp_time: float = 0.0) -> np.ndarray:
    """Rows (t, dx, dy, dz, rx, ry, rz) of the tabulated6DoFMotion table.

    The kinematics are :func:`~mfflap.cfd.imposed_motion.imposed_state` (heave from zero,
    optional C^2 start-up ramp over ``ramp_time`` s), the same the force conversion uses; the
    table runs 10 % past ``end_time`` (:func:`table_times`).
    """
    t = table_times(end_time, rows_per_second)
    s = imposed_state(motion, t, ramp_time).check_finite("motion table")
    heave, pitch = s.heave_position, s.pitch_angle
    return np.column_stack([t, case_displacement(heave), case_rotation_deg(pitch)])


def format_motion_table(rows: np.ndarray) -> str:
    """OpenFOAM text of the table: ``N ( (t ((dx dy dz) (rx ry rz))) ... )``."""
    lines = [f"{len(rows)}", "("]
    for r in rows:
        lines.append(f"({r[0]:.9g} (({r[1]:.9g} {r[2]:.9g} {r[3]:.9g}) "
                     f"({r[4]:.9g} {r[5]:.9g} {r[6]:.9g})))")
    lines.append(")")
    return "\n".join(lines) + "\n"


#: the fewest of its first time steps a run must hold
MIN_STEPS_PER_RUN = 10


def write_case(case_dir: str | Path, motion: Motion, end_time: float,
               mesh: str | AnyMeshSpec = "coarse",
               plate: Plate | None = None, fluid: Fluid | None = None,
               stream: FreeStream | None = None, solver: SolverSettings | None = None,
               depth: float | None = None, ramp_time: float = 0.0,
               y_plus: bool = False, overwrite: bool = False) -> Path:
    """Write a complete OpenFOAM case folder for ``motion`` up to ``end_time`` seconds.

    Parameters
    ----------
    depth : m
        Depth of the one-cell-thick mesh; the plate's span by default, so forces are those of
        the whole plate (:func:`mfflap.cfd.openfoam.forces.to_loads` scales otherwise).
    overwrite
        Delete a case written into ``case_dir`` before (its results, mesh and logs too)
        instead of refusing it (:func:`~mfflap.cfd.openfoam.case_path.prepare_case_folder`).

    Raises
    ------
    ConfigError, MotionError
        For an impossible setting (end time, ramp, depth, mesh, a case folder whose path
        OpenFOAM cannot read: :func:`~mfflap.cfd.openfoam.case_path.check_case_path`), a
        folder that is not empty (a case written before, unless ``overwrite``), or a motion
        that cannot be sampled, before anything is written or deleted.
    """
    plate, fluid, stream = plate or Plate(), fluid or Fluid(), stream or FreeStream()
    solver = solver or SolverSettings()
    spec = resolve_mesh(mesh)
    depth = plate.span if depth is None else depth
    if not (math.isfinite(depth) and depth > 0):
        raise ConfigError(f"the mesh depth must be > 0 m, got {depth!r}", key="depth")
    u = stream.velocity
    check_ramp_time(ramp_time, check_end_time(end_time))
    if end_time < MIN_STEPS_PER_RUN * solver.initial_time_step:
        raise ConfigError(f"the run's {end_time:.6g} s hold fewer than {MIN_STEPS_PER_RUN} of "
                          f"its first time steps ({solver.initial_time_step:g} s): OpenFOAM "
                          "would end before it began; run longer (more cycles, or a later "
                          "end time)", key="end_time")
    check_start_at_mesh(motion, ramp_time)
    # the motion's tables first: they check the end time, the ramp and the motion
    if solver.frame == "plate":
        tables = plate_frame_tables(motion, table_times(end_time), u, ramp_time=ramp_time)
    else:
        rows = motion_table(motion, end_time, ramp_time=ramp_time)
    case_dir = prepare_case_folder(case_dir, "mfflap_case.toml", overwrite)
    case_dir.mkdir(parents=True, exist_ok=True)
    k = 1.5 * (solver.turbulence_intensity * max(u, 1e-3)) ** 2
    length_scale = 0.07 * plate.chord
    epsilon = 0.09**0.75 * k**1.5 / length_scale
    context = {
        "mesh": spec, "chord": plate.chord, "half_t": plate.thickness / 2, "depth": depth,
        "end_time": end_time, "initial_time_step": solver.initial_time_step,
        "max_time_step": solver.max_time_step, "max_courant": solver.max_courant,
        "write_interval": min(solver.write_interval, end_time), "density": fluid.density,
        "kinematic_viscosity": fluid.kinematic_viscosity, "velocity": u, "k": k,
        "epsilon": epsilon, "n_outer_correctors": solver.n_outer_correctors,
        "n_correctors": solver.n_correctors, "y_plus": y_plus, "y_plus_interval": 20,
        "n_procs": 2, "pressure_solver": solver.pressure_solver,
        "pressure_tolerance": solver.pressure_tolerance, "far_field": solver.far_field,
        "velocity_convection": solver.velocity_convection,
        "pressure_final_rel_tol": solver.pressure_final_rel_tol,
        "turbulence_convection": TURBULENCE_CONVECTION_SCHEMES[solver.turbulence_convection],
        "frame": solver.frame, "wall": WALL_TREATMENTS[solver.wall_treatment],
    }
    env = jinja2.Environment(undefined=jinja2.StrictUndefined, keep_trailing_newline=True)
    src = template_dir()
    skip = [src / PLATE_FRAME_TEMPLATES, src / H_GRID_TEMPLATES]
    if isinstance(spec, HGridSpec):  # its own blockMeshDict instead of the O-grid's
        context["grid"] = spec.block_mesh_context(plate.chord, plate.thickness,
                                                  pivot_m=plate.pivot_m)
        skip.append(src / "system" / "blockMeshDict.j2")
        _render_templates(src / H_GRID_TEMPLATES, case_dir, env, context)
    else:
        radius = spec.radius_chords * plate.chord
        x_le = 0.0 - plate.pivot_m
        context.update(x_le=x_le, x_te=x_le + plate.chord, xc=x_le + plate.chord / 2,
                       radius=radius, r45=radius / math.sqrt(2))
    _render_templates(src, case_dir, env, context, skip=skip)
    constant = case_dir / "constant"
    if solver.frame == "plate":
        _render_templates(src / PLATE_FRAME_TEMPLATES, case_dir, env, context)
        (constant / "pitchRate.dat").write_text(format_function1_table(tables["pitch_rate"]))
        (constant / "farFieldVelocity.dat").write_text(
            format_function1_table(tables["inflow"]))
        (constant / "acceleration.dat").write_text(
            format_acceleration_table(tables["acceleration"]))
    else:
        (constant / "motion.dat").write_text(format_motion_table(rows))
    (case_dir / "mfflap_case.toml").write_text(
        f'mesh = "{spec.name}"\nend_time = {end_time!r}\ndepth = {depth!r}\nspan = {plate.span!r}\n'
        f'ramp_time = {ramp_time!r}\nn_cells = {spec.n_cells}\nframe = "{solver.frame}"\n'
        + recorded_inputs(motion, end_time, ramp_time, plate, fluid, stream)
        + "".join(f"solver_{key} = {value!r}\n" for key, value in asdict(solver).items())
    )
    return case_dir


#: the copy of a user's motion table (:mod:`mfflap.kinematics.table_file`) that a case
#: written from it keeps, named in its mfflap_case.toml
MOTION_TABLE_FILE = "mfflap_motion.csv"


def attach_motion_table(case_dir: str | Path, table_path: str | Path,
                        kept_file: str = "mfflap_case.toml") -> Path:
    """Keep the user's motion table in a case written from it and name it in the file that
    says what the case was written for (``kept_file``: an OpenFOAM case's mfflap_case.toml,
    a Fluent UDF's mfflap_fluent.toml), so that parsing the case needs nothing from outside
    it."""
    case_dir = Path(case_dir)
    dest = case_dir / MOTION_TABLE_FILE
    shutil.copyfile(table_path, dest)
    with open(case_dir / kept_file, "a") as fh:
        fh.write(f'motion_table = "{MOTION_TABLE_FILE}"\n')
    return dest


def _render_templates(src: Path, case_dir: Path, env: jinja2.Environment,
                      context: dict, skip: list[Path] = ()) -> None:
    """Copy or render (``.j2``) every template file under ``src`` into ``case_dir``, except
    those at or under a path of ``skip``."""
    for path in src.rglob("*"):
        if (path.is_dir() or path.suffix == ".toml"
                or any(path.is_relative_to(s) for s in skip)):
            continue
        rel = path.relative_to(src)
        out = case_dir / rel.parent / rel.name.removesuffix(".j2")
        out.parent.mkdir(parents=True, exist_ok=True)
        if path.suffix == ".j2":
            out.write_text(env.from_string(path.read_text()).render(**context))
        else:
            shutil.copyfile(path, out)
