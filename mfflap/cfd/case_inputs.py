"""What a CFD case was written for, kept beside it (an OpenFOAM case's mfflap_case.toml, a
Fluent UDF's mfflap_fluent.toml), and the check that a case file read with it describes the
same run.

Forces are turned into F_n, F_t and M with the imposed motion, the plate's span and chord and
the stream (:func:`mfflap.cfd.force_history.to_loads`). Parsing a case against a case file
other than the one it was written from (another pitch amplitude, span or stream velocity)
would give wrong numbers without any sign of it, so :func:`~mfflap.cfd.openfoam.writer.
write_case` and :func:`~mfflap.cfd.fluent.udf.write_fluent_case` keep the plate, fluid and
stream they wrote the case for and samples of the motion it imposes (with its start-up
ramp), and :func:`check_case_inputs` compares a case file with them. The
Morison coefficients are not kept: comparing a run with another identified model is the
point of parsing it again.
"""

from __future__ import annotations

from dataclasses import asdict
from pathlib import Path
from typing import Any

import numpy as np

from mfflap.cfd.imposed_motion import imposed_state
from mfflap.errors import ConfigError
from mfflap.kinematics.continuous import Motion
from mfflap.parameters import Fluid, FreeStream, Plate
from mfflap.records.inputs import IMPLIED_KEYS, PHYSICAL_KEYS, RELATIVE_TOLERANCE
from mfflap.toml_io import read_toml

#: Solver settings added after cases, records and campaigns first kept theirs, at the values
#: those runs used: what keeps solver settings without one of these ran with this value
ADDED_SOLVER_SETTINGS = {"pressure_solver": "PCG", "pressure_tolerance": 1e-7,
                         "far_field": "freestream", "velocity_convection": "linearUpwind",
                         "pressure_final_rel_tol": 0.0,
                         "turbulence_convection": "limitedLinear", "frame": "inertial",
                         "wall_treatment": "log_law"}
#: Plate settings added after campaigns first kept theirs, at the values those runs used
ADDED_PLATE_SETTINGS = {"pivot_chord_fraction": 0.0}
#: samples of the imposed motion kept with a case
N_MOTION_SAMPLES = 64


def motion_sample_times(end_time: float) -> np.ndarray:
    """Times at which a case keeps its imposed motion, s: evenly over (0, ``end_time``]."""
    return end_time * np.arange(1, N_MOTION_SAMPLES + 1) / N_MOTION_SAMPLES


def recorded_inputs(motion: Motion, end_time: float, ramp_time: float, plate: Plate,
                    fluid: Fluid, stream: FreeStream) -> str:
    """The lines of mfflap_case.toml that say what the case was written for (``span`` is
    written with the other case keys)."""
    lines = [f"{key} = {getter(plate, fluid, stream)!r}"
             for key, (_, getter) in PHYSICAL_KEYS.items() if key != "span"]
    t = motion_sample_times(end_time)
    state = imposed_state(motion, t, ramp_time)
    for key, values in (("motion_sample_time_s", t),
                        ("motion_sample_heave_m", state.heave_position),
                        ("motion_sample_pitch_rad", state.pitch_angle)):
        lines.append(f"{key} = [{', '.join(repr(float(v)) for v in values)}]")
    return "\n".join(lines) + "\n"


def _close(a: np.ndarray | float, b: np.ndarray | float) -> np.ndarray:
    """Where ``a`` equals ``b`` to RELATIVE_TOLERANCE of the largest ``|b|``."""
    scale = max(float(np.max(np.abs(b), initial=0.0)), 1e-12)
    return np.abs(a - b) <= RELATIVE_TOLERANCE * scale


def check_case_inputs(kept: str | Path, meta: dict[str, Any], case_file: str | Path | None,
                      motion: Motion | None, plate: Plate, fluid: Fluid, stream: FreeStream, *,
                      advice: str = "parse the case with the case file it was written from",
                      given_as: str = "in the case file") -> None:
    """Raise unless ``case_file``'s plate, fluid, stream and motion are those the case was
    written for (its plate, fluid and stream alone, given no ``motion``).

    Parameters
    ----------
    kept
        The file that says what the case was written for: an OpenFOAM case's
        mfflap_case.toml, or the mfflap_fluent.toml beside a Fluent UDF.
    meta
        Its contents. Keys it lacks are not checked, but for those of
        :data:`~mfflap.records.inputs.IMPLIED_KEYS`, taken at the values they imply.
    case_file
        Where ``motion``, ``plate``, ``fluid`` and ``stream`` came from, for the message.
    advice, given_as
        What to do, and where the values given come from, for the message.

    Raises
    ------
    ConfigError
        Naming the case file's key, its value and the one the case was written for.
    """
    kept = Path(kept)
    case_dir = kept.parent
    source = None if case_file is None else str(case_file)
    for key, (case_key, getter) in PHYSICAL_KEYS.items():
        if key not in meta and key not in IMPLIED_KEYS:
            continue
        given = float(getter(plate, fluid, stream))
        written = float(meta.get(key, IMPLIED_KEYS.get(key)))
        if not _close(given, written):
            raise ConfigError(f"{given!r} {given_as}, but {case_dir} was written for "
                              f"{written!r} ({kept}); {advice}", source=source,
                              key=case_key)
    if motion is None or "motion_sample_time_s" not in meta:
        return
    t = np.asarray(meta["motion_sample_time_s"], dtype=float)
    state = imposed_state(motion, t, float(meta.get("ramp_time", 0.0)))
    for name, unit, given, key in (
            ("heave", "m", state.heave_position, "motion_sample_heave_m"),
            ("pitch", "rad", state.pitch_angle, "motion_sample_pitch_rad")):
        written = np.asarray(meta[key], dtype=float)
        bad = np.flatnonzero(~_close(given, written))
        if bad.size:
            i = int(bad[0])
            raise ConfigError(f"not the motion {case_dir} imposes: at t = {t[i]:.6g} s its "
                              f"{name} is {given[i]:.6g} {unit}, the case's "
                              f"{written[i]:.6g} {unit} ({kept}, {key}); {advice}",
                              source=source, key="motion")


def motion_mismatch(case_dir: str | Path, state) -> str | None:
    """How the motion an mfflap OpenFOAM case was written for differs from a record's, or
    None if they agree (or the case keeps no motion samples: not written by mfflap).

    The case keeps samples of its imposed heave and pitch in mfflap_case.toml
    (:func:`recorded_inputs`); those within the record's time span are compared with
    the record's kinematics, to 1 % of their amplitude. A flow field of another run would
    show the vorticity of a motion the record never had.

    Parameters
    ----------
    case_dir
        The OpenFOAM case folder.
    state
        The record's :class:`~mfflap.kinematics.state.KinematicState`.
    """
    kept_path = Path(case_dir) / "mfflap_case.toml"
    kept = read_toml(kept_path) if kept_path.is_file() else {}
    if "motion_sample_time_s" not in kept:
        return None
    times = np.asarray(kept["motion_sample_time_s"], dtype=float)
    inside = (times >= state.time[0]) & (times <= state.time[-1])
    if not inside.any():
        return (f"it was written for t = {times[0]:g}-{times[-1]:g} s, outside the record's "
                f"{state.time[0]:g}-{state.time[-1]:g} s")
    for key, name, unit, recorded in (
            ("motion_sample_heave_m", "heave", "m", state.heave_position),
            ("motion_sample_pitch_rad", "pitch", "rad", state.pitch_angle)):
        case_values = np.asarray(kept[key], dtype=float)[inside]
        record_values = np.interp(times[inside], state.time, recorded)
        scale = max(float(np.max(np.abs(record_values))), float(np.max(np.abs(case_values))))
        worst = int(np.argmax(np.abs(case_values - record_values)))
        if abs(case_values[worst] - record_values[worst]) > 0.01 * scale + 1e-9:
            return (f"it was written for another motion: its {name} at t = "
                    f"{times[inside][worst]:.4g} s is {case_values[worst]:.4g} {unit}, the "
                    f"record's {record_values[worst]:.4g} {unit}")
    return None


def kept_differences(kept: dict[str, Any], asked: dict[str, Any]) -> list[tuple[str, Any, Any]]:
    """(key, kept value, asked value) for each key of ``asked`` that ``kept`` (a case's
    mfflap_case.toml, a record's provenance) has with another value: floats to
    :data:`RELATIVE_TOLERANCE`, others exactly. Keys ``kept`` lacks (written by an earlier
    mfflap) are not compared, except the :data:`ADDED_SOLVER_SETTINGS` where ``kept`` has
    solver settings: those it lacks are at the values its run used."""
    kept = with_added_solver_settings(kept)
    out = []
    for key, value in asked.items():
        if key not in kept:
            continue
        had = kept[key]
        if had == value or (isinstance(value, float) and isinstance(had, (int, float))
                            and bool(_close(float(had), value))):
            continue
        out.append((key, had, value))
    return out


def kept_wall_treatment(kept: dict[str, Any]) -> str | None:
    """The plate's wall treatment a case or record (its mfflap_case.toml, its provenance)
    says it ran with: as run (read from its 0/nut), as written, or, for one that keeps
    solver settings but not this one, the value :data:`ADDED_SOLVER_SETTINGS` gives; None
    if it keeps no solver setting at all."""
    treatment = kept.get("as_run_wall_treatment",
                         with_added_solver_settings(kept).get("solver_wall_treatment"))
    return None if treatment is None else str(treatment)


def with_added_solver_settings(kept: dict[str, Any]) -> dict[str, Any]:
    """``kept`` (a case's mfflap_case.toml, a record's provenance) with the
    :data:`ADDED_SOLVER_SETTINGS` it lacks, at the values its run used, if it keeps solver
    settings at all; as it is otherwise."""
    if not any(key.startswith("solver_") for key in kept):
        return kept
    return {**{f"solver_{key}": value for key, value in ADDED_SOLVER_SETTINGS.items()}, **kept}


def solver_keys(solver: Any, leave_out: tuple[str, ...] = ()) -> dict[str, Any]:
    """A solver's settings under the keys a case and a record keep them (``solver_<name>``),
    without those named in ``leave_out``."""
    return {f"solver_{key}": value for key, value in asdict(solver).items()
            if key not in leave_out}

