"""(motion, force history) pairs from outside mfflap: CSV files or plain arrays."""

from __future__ import annotations

import dataclasses
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
                     source: str | None = None, discard_s: float = 0.0) -> CaseData:
    """A case from sampled positions (rad, m) and loads (N, N*m, body frame, about the LE).

    Rates and accelerations come from smoothing splines of the positions (the generalised
    cross-validation choice of smoothing), so noisy measured motions can be used. The first
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
    if discard_s > 0:
        kept = t >= t[0] + discard_s - 1e-9 * max(1.0, abs(t[-1]))
        if kept.sum() < MIN_SAMPLES:
            raise ParseError(f"{name}: {int(kept.sum())} samples after the first "
                             f"{discard_s:g} s left out (identification.discard_time); the "
                             f"diagnosis needs at least {MIN_SAMPLES}", path=source)
        state = KinematicState(**{f.name: getattr(state, f.name)[kept]
                                  for f in dataclasses.fields(KinematicState)})
        loads = Loads(t[kept], loads.normal_force[kept], loads.tangential_force[kept],
                      loads.moment[kept], source=name)
    return CaseData(name, dict(parameters or {}), state, loads)


def read_csv_case(path: str | Path, parameters: dict | None = None,
                  discard_s: float = 0.0) -> CaseData:
    """A CSV with a header naming the columns of :data:`CSV_COLUMNS` (any order; SI units;
    ``#`` comment lines allowed), its first ``discard_s`` seconds left out
    (:func:`case_from_arrays`).

    Raises
    ------
    ParseError
        Naming the file and the line for a missing column or an unreadable value.
    """
    path = Path(path)
    col = read_csv_columns(path, CSV_COLUMNS)
    return case_from_arrays(path.stem, *(col[c] for c in CSV_COLUMNS), parameters=parameters,
                            source=str(path), discard_s=discard_s)
