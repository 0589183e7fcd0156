"""(motion, force history) pairs from outside mfflap: CSV files or plain arrays."""

from __future__ import annotations

import dataclasses
import re
from pathlib import Path

import numpy as np
from scipy.interpolate import make_smoothing_spline

from mfflap.csv_columns import read_csv_columns
from mfflap.errors import ConfigError, ParseError
from mfflap.hydro.loads import Loads
from mfflap.identification.data import CaseData
from mfflap.kinematics.state import KinematicState

CSV_COLUMNS = ("time", "pitch_angle", "heave_position", "normal_force", "tangential_force",
               "moment")
#: the motion's rates a CSV file may give too (rad/s, rad/s^2, m/s, m/s^2): all four, or
#: none and they are derived from the positions
RATE_COLUMNS = ("pitch_rate", "pitch_acceleration", "heave_velocity", "heave_acceleration")
#: the fewest samples a case may have (the smoothing splines of its motion need them)
MIN_SAMPLES = 8
#: the share of samples left out at each end of a record whose rates come from smoothing
#: splines: a natural spline's second derivative is zero at the ends, and its accelerations
#: are wrong there (measured: up to 1.5 standard deviations of the heave acceleration within
#: the last 2 % of the samples, below 0.01 beyond them)
SPLINE_END_SHARE = 0.03
#: the ``# key = value`` parameters a CSV file may give of its run's motion
MOTION_KEYS = ("frequency", "heave_amplitude", "phase_deg", "pitch_amplitude_deg", "period")
#: the set-up a CSV file may state, checked against the case file: (table, key, unit)
SETUP_KEYS = {"velocity": ("flow", "velocity", "m/s"), "chord": ("plate", "chord", "m"),
              "span": ("plate", "span", "m"), "density": ("fluid", "density", "kg/m^3"),
              "kinematic_viscosity": ("fluid", "kinematic_viscosity", "m^2/s"),
              "pivot_chord_fraction": ("plate", "pivot_chord_fraction", "")}
#: relative difference within which a stated set-up value is the case file's
SETUP_TOLERANCE = 1e-3
_PARAMETER_LINE = re.compile(r"#\s*([A-Za-z_][A-Za-z0-9_]*)\s*[=:]\s*(\S+)\s*$")


def case_from_arrays(name: str, time, pitch_angle, heave_position, normal_force,
                     tangential_force, moment, parameters: dict | None = None,
                     source: str | None = None, discard_s: float = 0.0,
                     rates: dict | None = None) -> CaseData:
    """A case from sampled positions (rad, m) and loads (N, N*m, body frame, about the pivot).

    Rates and accelerations are ``rates`` (the four :data:`RATE_COLUMNS`, as the motion
    imposed them: exact, and no fit) when given, else they come from smoothing splines of
    the positions (the generalised cross-validation choice of smoothing), so noisy measured
    motions can be used; a natural spline's second derivative is zero at the record's ends,
    which biases the accelerations there: the first and last :data:`SPLINE_END_SHARE` of
    the samples (at least 3) are then left out. The first
    ``discard_s`` seconds (a start-up transient) are left out after the splines are fitted
    over the whole record, so that the splines' end conditions fall in the part left out.

    Raises
    ------
    ParseError
        Naming ``source`` (the file the arrays came from), for fewer than
        :data:`MIN_SAMPLES` samples (before or after ``discard_s``), a time that does not
        increase (which sample), or positions that are not finite.

    Examples
    --------
    >>> t = np.linspace(0.0, 2.0, 201)
    >>> case = case_from_arrays("c", t, 0.1 * np.sin(t), 0.05 * np.cos(t), t, t, t,
    ...                         discard_s=0.5)
    >>> float(case.state.time[0]), float(case.cfd.time[0])
    (0.5, 0.5)
    """
    t = np.asarray(time, dtype=float)
    if t.ndim != 1 or len(t) < MIN_SAMPLES:
        raise ParseError(f"{name}: {t.size} samples; the smoothing splines of the motion need "
                         f"at least {MIN_SAMPLES}", path=source)
    back = np.flatnonzero(~(np.diff(t) > 0))
    if back.size:
        i = int(back[0]) + 1
        raise ParseError(f"{name}: time must increase: sample {i} (t = {t[i]:g} s) is not "
                         f"after sample {i - 1} (t = {t[i - 1]:g} s)", path=source)
    arrays = {}
    given = {k: np.asarray(v, dtype=float) for k, v in (rates or {}).items()}
    for key, values in (("pitch", pitch_angle), ("heave", heave_position)):
        y = np.asarray(values, dtype=float)
        if y.shape != t.shape or not np.all(np.isfinite(y)):
            raise ParseError(f"{name}: {key} must be finite with one value per time",
                             path=source)
        if given:
            rate, acceleration = (given[c] for c in RATE_COLUMNS if c.startswith(key))
            arrays[key] = (y, rate, acceleration)
        else:
            spline = make_smoothing_spline(t, y)
            arrays[key] = (spline(t), spline.derivative(1)(t), spline.derivative(2)(t))
    kept = np.ones(t.shape, dtype=bool)
    if not given:
        ends = max(3, int(np.ceil(SPLINE_END_SHARE * len(t))))
        kept[:ends] = kept[-ends:] = False
    state = KinematicState(time=t, pitch_angle=arrays["pitch"][0],
                           pitch_rate=arrays["pitch"][1],
                           pitch_acceleration=arrays["pitch"][2],
                           heave_position=arrays["heave"][0],
                           heave_velocity=arrays["heave"][1],
                           heave_acceleration=arrays["heave"][2])
    loads = Loads(t, *(np.asarray(v, dtype=float) for v in (normal_force, tangential_force,
                                                            moment)), source=name)
    if discard_s > 0:
        kept &= t >= t[0] + discard_s - 1e-9 * max(1.0, abs(t[-1]))
        if kept.sum() < MIN_SAMPLES:
            raise ParseError(f"{name}: {int(kept.sum())} samples after the first "
                             f"{discard_s:g} s left out (identification.discard_time); the "
                             f"diagnosis needs at least {MIN_SAMPLES}", path=source)
    if not kept.all():
        state = KinematicState(**{f.name: getattr(state, f.name)[kept]
                                  for f in dataclasses.fields(KinematicState)})
        loads = Loads(t[kept], loads.normal_force[kept], loads.tangential_force[kept],
                      loads.moment[kept], source=name)
    return CaseData(name, dict(parameters or {}), state, loads)


def csv_parameters(path: str | Path) -> dict[str, float]:
    r"""The ``# key = value`` lines of a CSV file before its header, for the keys of
    :data:`MOTION_KEYS` and :data:`SETUP_KEYS` (other comment lines are comments).

    Raises
    ------
    ParseError
        Naming the file and line, for a known key whose value is not a finite number or
        that is given twice.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "run.csv"
    >>> _ = p.write_text("# frequency = 1.5\n# a note\ntime,pitch_angle\n0,0\n")
    >>> csv_parameters(p)
    {'frequency': 1.5}
    """
    path = Path(path)
    out: dict[str, float] = {}
    with path.open(encoding="utf-8-sig") as fh:
        for number, line in enumerate(fh, start=1):
            text = line.strip()
            if not text:
                continue
            if not text.startswith("#"):
                break  # the header: parameters come before it
            match = _PARAMETER_LINE.match(text)
            if match is None or match[1] not in (*MOTION_KEYS, *SETUP_KEYS):
                continue
            key, value = match[1], match[2]
            try:
                number_value = float(value)
            except ValueError:
                number_value = float("nan")
            if not np.isfinite(number_value):
                raise ParseError(f"parameter {key}: {value!r} is not a finite number",
                                 path=str(path), line=number)
            if key in out:
                raise ParseError(f"parameter {key} given twice", path=str(path), line=number)
            out[key] = number_value
    return out


def check_setup(parameters: dict[str, float], config, source: str) -> None:
    """Refuse a case whose stated set-up (:data:`SETUP_KEYS`) is not ``config``'s (a
    :class:`~mfflap.config.CaseConfig`) within :data:`SETUP_TOLERANCE`.

    Raises
    ------
    ConfigError
        Naming the file, the key, both values and the case file's table.
    """
    for key, (table, attribute, unit) in SETUP_KEYS.items():
        if key not in parameters:
            continue
        stated, expected = float(parameters[key]), float(getattr(getattr(config, table),
                                                                 attribute))
        if abs(stated - expected) > SETUP_TOLERANCE * abs(expected):
            raise ConfigError(
                f"the run states {key} = {stated:g} {unit}; the case file's "
                f"[{table}] {attribute} is {expected:g} {unit}: a run of another set-up "
                f"cannot be compared with this model (give the case file its {key}, or "
                "diagnose the run with a case file of its own)", source=source, key=key)


def read_csv_case(path: str | Path, parameters: dict | None = None,
                  discard_s: float = 0.0, config=None) -> CaseData:
    """A CSV with a header naming the columns of :data:`CSV_COLUMNS` and, optionally, all
    four of :data:`RATE_COLUMNS` (any order; SI units; ``#`` comment lines allowed,
    ``# key = value`` ones before the header giving its parameters,
    :func:`csv_parameters`), its first ``discard_s`` seconds left out
    (:func:`case_from_arrays`). ``parameters`` adds to and overrides the file's own; with
    ``config`` (a :class:`~mfflap.config.CaseConfig`) a stated set-up is checked against it
    (:func:`check_setup`).

    Raises
    ------
    ParseError
        Naming the file and the line for a missing column or an unreadable value.
    ConfigError
        For a stated set-up that is not the case file's.
    """
    path = Path(path)
    given = {**csv_parameters(path), **(parameters or {})}
    if config is not None:
        check_setup(given, config, str(path))
    col = read_csv_columns(path, CSV_COLUMNS)
    present = [c for c in RATE_COLUMNS if c in col]
    if present and len(present) < len(RATE_COLUMNS):
        missing = [c for c in RATE_COLUMNS if c not in col]
        raise ParseError(f"rate columns {present} without {missing}: give all four of "
                         f"{list(RATE_COLUMNS)}, or none and they are derived from the "
                         "positions", path=str(path), line=col.header_line)
    rates = {c: col[c] for c in present} or None
    return case_from_arrays(path.stem, *(col[c] for c in CSV_COLUMNS), parameters=given,
                            source=str(path), discard_s=discard_s, rates=rates)


def csv_paths(paths) -> list[Path]:
    """CSV files from files and folders (a folder: every ``*.csv`` in it, by name).

    Raises
    ------
    ParseError
        For a folder without CSV files.
    """
    out: list[Path] = []
    for p in map(Path, paths):
        if p.is_dir():
            found = sorted(p.glob("*.csv"))
            if not found:
                raise ParseError("a folder given as --csv holds no *.csv file", path=str(p))
            out += found
        else:
            out.append(p)
    return out
