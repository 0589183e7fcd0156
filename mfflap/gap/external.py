"""(motion, force history) pairs from outside mfflap: CSV files or plain arrays."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from scipy.interpolate import make_smoothing_spline

from mfflap.csv_columns import read_csv_columns
from mfflap.errors import ParseError
from mfflap.hydro.loads import Loads
from mfflap.identification.data import CaseData
from mfflap.kinematics.state import KinematicState

CSV_COLUMNS = ("time", "pitch_angle", "heave_position", "normal_force", "tangential_force",
               "moment")
#: the fewest samples a case may have (the smoothing splines of its motion need them)
MIN_SAMPLES = 8


def case_from_arrays(name: str, time, pitch_angle, heave_position, normal_force,
                     tangential_force, moment, parameters: dict | None = None,
                     source: str | None = None) -> CaseData:
    """A case from sampled positions (rad, m) and loads (N, N*m, body frame, about the LE).

    Rates and accelerations come from smoothing splines of the positions (the generalised
    cross-validation choice of smoothing), so noisy measured motions can be used.

    Raises
    ------
    ParseError
        Naming ``source`` (the file the arrays came from), for fewer than
        :data:`MIN_SAMPLES` samples, a time that does not increase (which sample), or
        positions that are not finite.
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
    for key, values in (("pitch", pitch_angle), ("heave", heave_position)):
        y = np.asarray(values, dtype=float)
        if y.shape != t.shape or not np.all(np.isfinite(y)):
            raise ParseError(f"{name}: {key} must be finite with one value per time",
                             path=source)
        spline = make_smoothing_spline(t, y)
        arrays[key] = (spline(t), spline.derivative(1)(t), spline.derivative(2)(t))
    state = KinematicState(time=t, pitch_angle=arrays["pitch"][0],
                           pitch_rate=arrays["pitch"][1],
                           pitch_acceleration=arrays["pitch"][2],
                           heave_position=arrays["heave"][0],
                           heave_velocity=arrays["heave"][1],
                           heave_acceleration=arrays["heave"][2])
    loads = Loads(t, *(np.asarray(v, dtype=float) for v in (normal_force, tangential_force,
                                                            moment)), source=name)
    return CaseData(name, dict(parameters or {}), state, loads)


def read_csv_case(path: str | Path, parameters: dict | None = None) -> CaseData:
    """A CSV with a header naming the columns of :data:`CSV_COLUMNS` (any order; SI units;
    ``#`` comment lines allowed).

    Raises
    ------
    ParseError
        Naming the file and the line for a missing column or an unreadable value.
    """
    path = Path(path)
    col = read_csv_columns(path, CSV_COLUMNS)
    return case_from_arrays(path.stem, *(col[c] for c in CSV_COLUMNS), parameters=parameters,
                            source=str(path))
