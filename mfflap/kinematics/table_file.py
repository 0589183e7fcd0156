"""A user's motion table from a CSV file: any pitch and heave history a solver should
impose.

The file has a header line naming its columns, in any order and by any of their aliases,
with their units (:mod:`mfflap.kinematics.motion_columns`): a time (``t``, ``time``; it
starts at 0 and increases), a heave (``h``, ``heave``, ``heave_position``) and a pitch
(``theta``, ``pitch``, ``pitch_angle``), for example ``t, theta [deg], h [m]``; without a
unit, SI (s, m, rad). Rate and acceleration columns (``theta_dot``, ``h_dot``,
``theta_ddot``, ``h_ddot``, ...) are used as given at the rows. A flapping plate pitches
less than 90 deg (:data:`~mfflap.kinematics.continuous.UPRIGHT_PITCH`); the commands that
write a case from a table warn when it does not (:func:`largest_pitch`).

Values beyond any flapping motion are refused, naming the line: a pitch above pi rad in
magnitude (degrees in a radians column), a heave beyond :data:`MAX_HEAVE_M`, a time beyond
:data:`MAX_TIME_S`. Values that a plate could reach but that are far more likely a unit left
out need the unit named in the header: a heave column without a unit whose heave exceeds
:data:`MAX_HEAVE_CHORDS` chords (millimetres taken as metres), and a pitch column without a
unit that passes the upright, pi / 2 (a small pitch in degrees taken as radians).

Other columns are ignored; lines starting with ``#`` are comments. Between rows the motion
is a cubic spline (continuous rates and accelerations); past the last row it is held at
rest, which only the solver's padding rows past the end of a run see.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from mfflap.csv_columns import read_csv_columns
from mfflap.errors import MotionError, ParseError
from mfflap.kinematics.continuous import UPRIGHT_PITCH, Motion, TabulatedMotion
from mfflap.kinematics.motion_columns import motion_columns
from mfflap.parameters import Plate

#: the fewest rows a cubic spline through the table needs
MIN_ROWS = 4
#: the largest heave a table may give, m (a mistake in the units beyond it)
MAX_HEAVE_M = 100.0
#: the latest time a table may give, s (about 12 days)
MAX_TIME_S = 1.0e6
#: the largest heave, in chords, a heave column may hold without naming its unit
MAX_HEAVE_CHORDS = 10.0


def _check_range(path: Path, lines: np.ndarray, values: np.ndarray, limit: float,
                 what: str, hint: str) -> None:
    """Refuse the first row whose ``values`` exceed ``limit`` in magnitude."""
    beyond = np.flatnonzero(np.abs(values) > limit)
    if beyond.size:
        i = int(beyond[0])
        raise ParseError(f"{what} {values[i]:.6g} is beyond {limit:g}{hint}", path=str(path),
                         line=int(lines[i]))


def read_motion_table(path: str | Path, chord: float | None = None) -> TabulatedMotion:
    """The motion of a CSV table (module notes for the columns).

    Parameters
    ----------
    path
        The CSV file.
    chord
        The plate's chord, m, against which a heave column without a unit is checked
        (:data:`MAX_HEAVE_CHORDS`); the package's default plate if omitted.

    Raises
    ------
    ParseError
        Naming the file and the line: a missing column, an unreadable or non-finite value,
        a time that does not increase, a first time other than 0, too few rows, a value
        beyond any flapping motion.
    """
    path = Path(path)
    table = read_csv_columns(path, ())
    col = motion_columns(table, str(path))
    t, lines = col["time"].values, table.line_numbers
    if t[0] != 0.0:
        raise ParseError(f"the table must start at t = 0 s (the solver starts there), "
                         f"got {t[0]:g} s", path=str(path), line=int(lines[0]))
    back = np.flatnonzero(np.diff(t) <= 0)
    if back.size:
        i = int(back[0]) + 1
        raise ParseError(f"time {t[i]:g} s does not increase (previous row {t[i - 1]:g} s)",
                         path=str(path), line=int(lines[i]))
    if len(t) < MIN_ROWS:
        raise ParseError(f"{len(t)} data rows; a motion table needs at least {MIN_ROWS}",
                         path=str(path), line=int(lines[-1]))
    _check_range(path, lines, t, MAX_TIME_S, col["time"].header, " s")
    heave = col["heave_position"]
    _check_range(path, lines, heave.values, MAX_HEAVE_M, heave.header, " m in magnitude")
    if not heave.unit_named:
        chord = Plate().chord if chord is None else chord
        _check_range(path, lines, heave.values, MAX_HEAVE_CHORDS * chord, heave.header,
                     f" m ({MAX_HEAVE_CHORDS:g} chords of {chord:g} m) in magnitude: is it "
                     f"in mm or cm? Name its unit: '{heave.header} [mm]' (or [cm], or [m] "
                     "for a heave this large)")
    pitch = col["pitch_angle"]
    if not pitch.unit_named:
        _check_range(path, lines, pitch.values, UPRIGHT_PITCH, pitch.header,
                     " rad (the upright, 90 deg) in magnitude: is it in degrees? Name its "
                     f"unit: '{pitch.header} [deg]' (or [rad] for a plate pitched past the "
                     "upright)")
    if pitch.unit == "rad":
        _check_range(path, lines, pitch.values, np.pi, pitch.header,
                     " rad in magnitude: is it in degrees? Name its unit: "
                     f"'{pitch.header} [deg]'")
    else:
        _check_range(path, lines, np.degrees(pitch.values), 180.0, pitch.header,
                     " deg in magnitude")
    extra = {q: c.values for q, c in col.items()
             if q not in ("time", "heave_position", "pitch_angle")}
    try:
        return TabulatedMotion(t, pitch.values, heave.values, hold_after_end=True, **extra)
    except MotionError as exc:  # what the reader has not caught already
        raise ParseError(str(exc), path=str(path)) from exc


def table_end_time(motion: TabulatedMotion, end_time: float | None = None) -> float:
    """The end time of a run of a table motion: its last row unless ``end_time`` is given,
    which must not be past it.

    Raises
    ------
    MotionError
        If ``end_time`` is not positive or lies past the table's last row.
    """
    last = float(motion.table_time[-1])
    if end_time is None:
        return last
    if not 0 < end_time <= last:
        raise MotionError(f"end time {end_time:g} s must lie in (0, {last:g}] s, the range of "
                          f"the motion table")
    return float(end_time)


#: times at which :func:`largest_pitch` samples the spline between two rows of a table
SAMPLES_BETWEEN_ROWS = 15


def largest_pitch(motion: TabulatedMotion, end_time: float) -> tuple[float, float]:
    """The largest pitch in magnitude of a table's motion up to ``end_time``, and its time.

    The motion is the spline through the rows, which can overshoot them: rows at 89.5 deg
    either side of a peak give a spline that turns past 90 deg between them. It is sampled
    at the rows and at :data:`SAMPLES_BETWEEN_ROWS` times between each two.

    Returns
    -------
    tuple
        The pitch (rad, with its sign) and its time (s).
    """
    rows = motion.table_time[motion.table_time <= end_time]
    share = np.arange(SAMPLES_BETWEEN_ROWS + 1) / (SAMPLES_BETWEEN_ROWS + 1)
    between = (rows[:-1, None] + np.diff(rows)[:, None] * share[None, :]).ravel()
    times = np.append(between, rows[-1:])
    pitch = motion.sample(times).pitch_angle
    worst = int(np.argmax(np.abs(pitch)))
    return float(pitch[worst]), float(times[worst])


def write_motion_table(path: str | Path, motion: Motion, end_time: float, n_rows: int,
                       comment: str = "") -> Path:
    """Write ``motion`` from 0 to ``end_time`` as a table :func:`read_motion_table` reads
    (``n_rows`` + 1 evenly spaced rows, pitch in rad, 17 significant digits).

    With rows much closer than the motion's own features (for a periodic optimised motion,
    a few hundred per period) the spline through them is the motion to round-off, so an
    optimised motion goes to any solver through the same table as a user's.
    """
    if not end_time > 0 or n_rows < MIN_ROWS - 1:
        raise MotionError(f"need end_time > 0 and at least {MIN_ROWS} rows, got "
                          f"{end_time!r} s and {n_rows + 1}")
    t = np.linspace(0.0, end_time, n_rows + 1)
    s = motion.sample(t).check_finite("motion table")
    lines = [f"# {line}" for line in comment.splitlines()]
    lines.append("time,heave_position,pitch_angle")
    lines += [f"{a!r},{b!r},{c!r}" for a, b, c in zip(t.tolist(), s.heave_position.tolist(),
                                                     s.pitch_angle.tolist(), strict=True)]
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text("\n".join(lines) + "\n")
    return path
