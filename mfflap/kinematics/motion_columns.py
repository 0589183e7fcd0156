"""The columns of a motion table by what they hold, whatever the header calls them: a time,
a heave and a pitch, and optionally their rates and accelerations, each in the unit its
header names.

A header names a column by one of its aliases (any case), with its unit in brackets or
parentheses, or as a suffix after an underscore: ``t``, ``time [s]``, ``h (mm)``,
``heave_position``, ``theta``, ``pitch [deg]``, ``pitch_angle_deg``, ``theta_dot [deg/s]``.
A column without a unit is in SI units (s, m, rad and their rates). Other columns are
ignored. Two columns of one quantity, or a unit the quantity cannot have, are refused.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from mfflap.csv_columns import CsvColumns
from mfflap.errors import ParseError

_DEG = math.pi / 180.0

#: quantity -> (its aliases in a header, the factor to SI of each unit it may be given in;
#: the first unit is the one a column without a unit is in)
QUANTITIES: dict[str, tuple[tuple[str, ...], dict[str, float]]] = {
    "time": (("t", "time"), {"s": 1.0, "ms": 1e-3}),
    "heave_position": (("h", "heave", "heave_position"), {"m": 1.0, "cm": 1e-2, "mm": 1e-3}),
    "pitch_angle": (("theta", "pitch", "pitch_angle"), {"rad": 1.0, "deg": _DEG}),
    "heave_velocity": (("h_dot", "dh/dt", "heave_rate", "heave_velocity"),
                       {"m/s": 1.0, "mm/s": 1e-3}),
    "pitch_rate": (("theta_dot", "dtheta/dt", "pitch_rate"), {"rad/s": 1.0, "deg/s": _DEG}),
    "heave_acceleration": (("h_ddot", "d2h/dt2", "heave_acceleration"),
                           {"m/s^2": 1.0, "m/s2": 1.0}),
    "pitch_acceleration": (("theta_ddot", "d2theta/dt2", "pitch_acceleration"),
                           {"rad/s^2": 1.0, "rad/s2": 1.0, "deg/s^2": _DEG, "deg/s2": _DEG}),
}
#: the quantities every motion table has
REQUIRED = ("time", "heave_position", "pitch_angle")


@dataclass(frozen=True)
class MotionColumn:
    """One column of a motion table: what it holds, in SI units."""

    quantity: str
    header: str  # as the file names it
    unit: str  # the unit it was given in
    values: np.ndarray  # in SI units
    unit_named: bool = True  # False: the header gave no unit, SI was taken


def _split_unit(header: str) -> tuple[str, str | None]:
    """``"pitch [deg]"`` -> ("pitch", "deg"); ``"pitch_angle_deg"`` -> ("pitch_angle",
    "deg") where "deg" is a unit; else (the name, None)."""
    text = header.strip().lower()
    for open_, close in (("[", "]"), ("(", ")")):
        if text.endswith(close) and open_ in text:
            name, _, unit = text[:-1].rpartition(open_)
            return name.strip(), unit.strip().replace(" ", "").replace("²", "^2")
    return text, None


def _quantity_of(header: str) -> tuple[str, str | None] | None:
    """(quantity, unit) a header names (unit None: not named), or None for a column of
    something else."""
    name, unit = _split_unit(header)
    for quantity, (aliases, units) in QUANTITIES.items():
        if name in aliases:
            return quantity, unit
        if unit is None:  # a unit as a suffix: pitch_angle_deg, time_s, h_mm
            stem, _, suffix = name.rpartition("_")
            if stem in aliases and suffix in units:
                return quantity, suffix
    return None


def motion_columns(table: CsvColumns, path: str) -> dict[str, MotionColumn]:
    """The motion table's columns by quantity (:data:`QUANTITIES`), in SI units.

    Raises
    ------
    ParseError
        Naming the file and its header line: a quantity of :data:`REQUIRED` missing, two
        columns of one quantity, or a unit the quantity cannot be given in.

    Examples
    --------
    >>> import numpy as np
    >>> from mfflap.csv_columns import CsvColumns
    >>> table = CsvColumns({"t": np.array([0.0, 1.0]), "pitch [deg]": np.array([0.0, 90.0]),
    ...                     "h (mm)": np.array([0.0, 5.0])}, np.array([2, 3]))
    >>> found = motion_columns(table, "motion.csv")
    >>> found["pitch_angle"].values.round(4).tolist(), found["heave_position"].values.tolist()
    ([0.0, 1.5708], [0.0, 0.005])
    """
    found: dict[str, MotionColumn] = {}
    for header, values in table.columns.items():
        named = _quantity_of(header)
        if named is None:
            continue
        quantity, named_unit = named
        units = QUANTITIES[quantity][1]
        unit = named_unit or next(iter(units))
        if unit not in units:
            raise ParseError(f"column {header!r}: {quantity} cannot be in {unit!r}; use one of "
                             f"{', '.join(units)}", path=path, line=table.header_line)
        if quantity in found:
            raise ParseError(f"columns {found[quantity].header!r} and {header!r} both hold "
                             f"{quantity}", path=path, line=table.header_line)
        found[quantity] = MotionColumn(quantity, header, unit, values * units[unit],
                                       unit_named=named_unit is not None)
    missing = [q for q in REQUIRED if q not in found]
    if missing:
        said = "; ".join(f"{q} (as {' or '.join(QUANTITIES[q][0])})" for q in missing)
        raise ParseError(f"missing column(s) for {said}; the header has "
                         f"{list(table.columns)}", path=path, line=table.header_line)
    return found


__all__ = ["QUANTITIES", "REQUIRED", "MotionColumn", "motion_columns"]
