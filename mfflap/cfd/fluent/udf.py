"""Generate DEFINE_CG_MOTION UDFs and the batch journal from templates (jinja2)."""

from __future__ import annotations

import math
import re
from pathlib import Path

import jinja2
import numpy as np

from mfflap.cfd import templates
from mfflap.cfd.case_inputs import recorded_inputs
from mfflap.cfd.frames import case_displacement, case_rotation_deg
from mfflap.cfd.imposed_motion import (
    check_end_time,
    check_ramp_time,
    check_start_at_mesh,
    imposed_state,
)
from mfflap.errors import ConfigError, MotionError
from mfflap.kinematics.continuous import HarmonicMotion, Motion, RampHarmonicMotion
from mfflap.parameters import Fluid, FreeStream, Plate
from mfflap.version import __version__


def template_dir() -> Path:
    """The Fluent template folder (``cfd_templates/fluent``)."""
    return templates.template_dir("fluent")


def standin_header_dir() -> Path:
    """Folder of the stand-in ``udf.h`` used to compile UDFs without Fluent."""
    return template_dir() / "standin"


def _env() -> jinja2.Environment:
    return jinja2.Environment(loader=jinja2.FileSystemLoader(str(template_dir())),
                              undefined=jinja2.StrictUndefined, keep_trailing_newline=True)


def _signs() -> tuple[float, float]:
    """Case-frame sign of a positive heave (along y) and of a positive pitch (about z)."""
    heave = float(case_displacement(np.array([1.0]))[0, 1])
    pitch = float(case_rotation_deg(np.array([1.0]))[0, 2])
    return math.copysign(1.0, heave), math.copysign(1.0, pitch)


_C_IDENTIFIER = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")
#: C keywords (C17 and the common extensions) that cannot name a UDF function
_C_KEYWORDS = frozenset(
    "auto break case char const continue default do double else enum extern float for goto "
    "if inline int long register restrict return short signed sizeof static struct switch "
    "typedef union unsigned void volatile while _Alignas _Alignof _Atomic _Bool _Complex "
    "_Generic _Imaginary _Noreturn _Static_assert _Thread_local asm typeof".split())


def _check_name(udf_name: str) -> None:
    """Refuse a UDF name gcc and Fluent's compiler cannot take as a function name (Python's
    str.isidentifier accepts non-ASCII letters and C keywords)."""
    if not _C_IDENTIFIER.fullmatch(udf_name) or udf_name in _C_KEYWORDS:
        raise ConfigError(f"UDF name {udf_name!r} is not a C identifier (ASCII letters, "
                          "digits and _, not starting with a digit, not a C keyword)",
                          key="udf_name")


def analytic_udf(motion: HarmonicMotion | RampHarmonicMotion, ramp_time: float = 0.0,
                 udf_name: str = "mfflap_motion") -> str:
    """C source of an analytic DEFINE_CG_MOTION for a sinusoid (with or without the
    theta_kamp t pitch ramp) and the C^2 start-up ramp."""
    _check_name(udf_name)
    ramp = isinstance(motion, RampHarmonicMotion)
    coeff = motion.pitch_ramp_rate if ramp else motion.pitch_amplitude
    values = [motion.frequency, motion.heave_amplitude, coeff, motion.phase]
    if any(np.ndim(v) for v in values):
        raise MotionError("one UDF is written for one motion; got array parameters")
    heave_sign, pitch_sign = _signs()
    return _env().get_template("cg_motion_analytic.c.j2").render(
        version=__version__, ramp=ramp, frequency=float(motion.frequency),
        heave_amplitude=float(motion.heave_amplitude), pitch_coefficient=float(coeff),
        phase=float(motion.phase), ramp_time=check_ramp_time(ramp_time), udf_name=udf_name,
        heave_sign=heave_sign, pitch_sign=pitch_sign)


def velocity_table(motion: Motion, end_time: float, rows_per_second: float = 2000.0,
                   ramp_time: float = 0.0) -> np.ndarray:
    """Rows (t, heave velocity, pitch rate) of the imposed motion from 0 to 1.1 end_time."""
    end_time = check_end_time(end_time)
    t = np.linspace(0.0, 1.1 * end_time, max(int(1.1 * end_time * rows_per_second), 8) + 1)
    s = imposed_state(motion, t, ramp_time).check_finite("UDF table")
    return np.column_stack([t, s.heave_velocity, s.pitch_rate])


def table_udf(motion: Motion, end_time: float, ramp_time: float = 0.0,
              udf_name: str = "mfflap_motion", rows_per_second: float = 2000.0,
              periodic_period: float | None = None, description: str = "tabulated motion"
              ) -> str:
    """C source of a table-driven DEFINE_CG_MOTION (linear interpolation).

    With ``periodic_period`` (a motion periodic once its start-up ramp is over) the table
    holds the ramp and one period after it, ``[0, ramp_time + periodic_period]``, and later
    times wrap into that period, so the table's size does not grow with the run;
    ``end_time`` is then not used. Otherwise the table covers the run and its end values
    are held past it.
    """
    _check_name(udf_name)
    ramp_time = check_ramp_time(ramp_time)
    if periodic_period is not None:
        if not (math.isfinite(periodic_period) and periodic_period > 0):
            raise ConfigError(f"periodic_period must be a finite time > 0 s, got "
                              f"{periodic_period!r}", key="periodic_period")
        table_end = ramp_time + periodic_period
        rows = velocity_table(motion, table_end / 1.1, rows_per_second, ramp_time)
        rows = rows[rows[:, 0] <= table_end * (1 + 1e-12)]
        at_wrap = imposed_state(motion, np.array([ramp_time]), ramp_time)
        rows[-1, 1:] = at_wrap.heave_velocity[0], at_wrap.pitch_rate[0]  # one period on
    else:
        rows = velocity_table(motion, end_time, rows_per_second, ramp_time)
    heave_sign, pitch_sign = _signs()
    return _env().get_template("cg_motion_table.c.j2").render(
        version=__version__, rows=rows.tolist(), n_rows=len(rows), t_first=rows[0, 0],
        t_last=rows[-1, 0], periodic=periodic_period is not None,
        period=float(periodic_period or 0.0), wrap_from=ramp_time, interpolation="linear",
        udf_name=udf_name, heave_sign=heave_sign, pitch_sign=pitch_sign,
        description=description)


#: the report file the journal makes Fluent write, beside the UDF
REPORT_FILE = "plate-forces.out"
#: what a UDF was written for, beside it (:mod:`mfflap.cfd.case_inputs`)
FLUENT_KEPT_FILE = "mfflap_fluent.toml"
#: the fewest time steps a journal may run: fewer jump over the motion
MIN_STEPS_PER_RUN = 10
#: the most time steps a written journal runs
MAX_STEPS_PER_RUN = 10_000_000
#: time steps per carrier period below which `cfd fluent` warns (Fluent's flapping-foil
#: studies use a few hundred)
FEW_STEPS_PER_PERIOD = 50


def journal(udf_file: str, report_file: str = REPORT_FILE, case_file: str = "plate.cas.h5",
            udf_name: str = "mfflap_motion", time_step: float = 1e-3, n_steps: int = 1000,
            max_iterations: int = 20, velocity: float = 0.3, plate_zone: str = "plate",
            fluid_zone: str = "fluid", journal_name: str = "mfflap_run.jou",
            output_case: str = "plate_final.cas.h5", pivot_x_m: float = 0.0) -> str:
    """Batch journal: read the case, compile and load the UDF, make the fluid zone a rigid
    body driven by it about the pivot (``pivot_x_m`` behind the leading edge, which the
    case has at the origin), add force/moment report definitions (moments about the origin)
    and a report file with the flow time, and run ``n_steps`` time steps."""
    _check_name(udf_name)
    if n_steps < 1 or time_step <= 0 or max_iterations < 1:
        raise ConfigError("n_steps and max_iterations must be >= 1 and time_step > 0",
                          key="journal")
    return _env().get_template("run.jou.j2").render(
        version=__version__, udf_file=udf_file, report_file=report_file, case_file=case_file,
        udf_name=udf_name, time_step=time_step, n_steps=n_steps, max_iterations=max_iterations,
        velocity=velocity, plate_zone=plate_zone, fluid_zone=fluid_zone,
        journal_name=journal_name, output_case=output_case, pivot_x=float(pivot_x_m))


def write_fluent_case(folder: str | Path, motion: Motion, end_time: float, *,
                      ramp_time: float = 0.0, time_step: float = 1e-3, velocity: float = 0.3,
                      table: bool | None = None, udf_name: str = "mfflap_motion",
                      plate: Plate | None = None, fluid: Fluid | None = None,
                      overwrite: bool = False) -> Path:
    """Write ``mfflap_motion.c`` (analytic for sinusoids, else table-driven),
    ``mfflap_run.jou`` and ``mfflap_fluent.toml`` into ``folder``.

    mfflap_fluent.toml keeps what the UDF was written for (the start-up ramp, the plate,
    fluid and stream, samples of the motion: :mod:`mfflap.cfd.case_inputs`), so that the
    report file the journal writes beside it parses with the same ramp and is checked
    against the case file it is parsed with. The folder may hold other files (the Fluent
    case the journal reads), but not the report of an earlier run: beside a new UDF its
    forces would parse as the new motion's. ``overwrite`` deletes that report.

    Raises
    ------
    ConfigError
        If ``folder`` holds the report file of an earlier run and ``overwrite`` is not set,
        the ramp does not end before the run, or ``time_step`` leaves fewer than
        :data:`MIN_STEPS_PER_RUN` steps in it.
    """
    plate, fluid = plate or Plate(), fluid or Fluid()
    end_time = check_end_time(end_time)
    check_ramp_time(ramp_time, end_time)
    check_start_at_mesh(motion, ramp_time)
    if not (math.isfinite(time_step) and time_step > 0):
        raise ConfigError(f"time_step must be a finite time > 0 s, got {time_step!r}",
                          key="time_step")
    if time_step * MIN_STEPS_PER_RUN > end_time:
        raise ConfigError(f"time_step {time_step:g} s leaves fewer than {MIN_STEPS_PER_RUN} "
                          f"steps in the {end_time:g} s run: Fluent would jump over the "
                          "motion", key="time_step")
    if end_time > MAX_STEPS_PER_RUN * time_step:
        raise ConfigError(f"time_step {time_step:.6g} s makes {end_time / time_step:.3g} steps "
                          f"of the {end_time:g} s run; at most {MAX_STEPS_PER_RUN:,} are "
                          "written (a thousand periods of a thousand steps each is a tenth "
                          "of that)", key="time_step")
    folder = Path(folder)
    report = folder / REPORT_FILE
    if report.exists() and not overwrite:
        raise ConfigError(f"{folder} holds {REPORT_FILE}, the report of a run of the UDF "
                          "written there before; beside a new UDF `cfd parse` would read its "
                          "forces as the new motion's: move it away, write into another "
                          "folder, or overwrite (--overwrite deletes the report)")
    analytic = isinstance(motion, HarmonicMotion | RampHarmonicMotion) and not table
    # a sinusoid's table: its ramp and one period, wrapped (not the whole run, which at 200
    # periods made a 30 MB C file)
    period = (1.0 / float(motion.frequency) if isinstance(motion, HarmonicMotion)
              and end_time > ramp_time + 1.0 / float(motion.frequency) else None)
    source = (analytic_udf(motion, ramp_time, udf_name) if analytic  # type: ignore[arg-type]
              else table_udf(motion, end_time, ramp_time, udf_name, periodic_period=period))
    n_steps = max(math.ceil(end_time / time_step), 1)
    run_journal = journal("mfflap_motion.c", time_step=time_step, n_steps=n_steps,
                          velocity=velocity, udf_name=udf_name, pivot_x_m=plate.pivot_m)
    folder.mkdir(parents=True, exist_ok=True)
    report.unlink(missing_ok=True)  # only once the new UDF is sure to be written
    (folder / "mfflap_motion.c").write_text(source)
    (folder / "mfflap_run.jou").write_text(run_journal)
    (folder / FLUENT_KEPT_FILE).write_text(
        f'udf = "mfflap_motion.c"\njournal = "mfflap_run.jou"\n'
        f'report_file = "{REPORT_FILE}"\nend_time = {end_time!r}\n'
        f'ramp_time = {ramp_time!r}\ntime_step = {time_step!r}\nspan = {plate.span!r}\n'
        + recorded_inputs(motion, end_time, ramp_time, plate, fluid, FreeStream(velocity)))
    return folder
