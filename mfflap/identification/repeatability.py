"""CFD's own cycle-to-cycle repeatability of a periodic case, in the units of the model's
error: the NRMSE of each whole cycle's load against the case's mean cycle.

A model cannot be asked to follow a CFD run more closely than the run repeats itself: a
harmonic motion's CFD cycles differ by their numerics and by the wake they meet, and that
difference, as an NRMSE over the same range as the model's, is the yardstick beside which
the model's NRMSE is read. A motion that does not repeat (the Table 1 grid's pitch ramp)
has none.
"""

from __future__ import annotations

import numpy as np

from mfflap.identification.data import CaseData

#: the fewest whole cycles a case needs for its repeatability
MIN_CYCLES = 2


def cycle_nrmse(case: CaseData, component: str = "normal_force") -> float:
    """The RMS over a case's whole cycles of each cycle's NRMSE against the mean cycle
    (normalised by the case's range of ``component``, as the model's NRMSE is), or NaN for a
    case that does not repeat (``kind = "ramp_harmonic"``), has no frequency, or holds fewer
    than :data:`MIN_CYCLES` whole cycles.

    Examples
    --------
    >>> from mfflap.hydro.loads import Loads
    >>> from mfflap.kinematics.continuous import HarmonicMotion
    >>> t = np.linspace(0.0, 3.0, 601)
    >>> state = HarmonicMotion(1.0, 0.1, 0.2).sample(t)
    >>> fn = np.sin(2 * np.pi * t) + 0.01 * np.cos(2 * np.pi * 7.3 * t)
    >>> case = CaseData("c", {"kind": "harmonic", "frequency": 1.0}, state,
    ...                 Loads(t, fn, 0 * t, 0 * t))
    >>> bool(0.001 < cycle_nrmse(case) < 0.01)
    True
    """
    if case.parameters.get("kind") == "ramp_harmonic":
        return float("nan")
    frequency = case.frequency
    if not (np.isfinite(frequency) and frequency > 0):
        return float("nan")
    t = np.asarray(case.state.time, dtype=float)
    y = np.asarray(case.cfd_signal(component), dtype=float)
    period = 1.0 / frequency
    n_cycles = int(np.floor((t[-1] - t[0]) / period + 1e-9))
    if n_cycles < MIN_CYCLES:
        return float("nan")
    start = t[-1] - n_cycles * period
    phase = np.linspace(0.0, period, 101)[:-1]
    cycles = np.array([np.interp(start + k * period + phase, t, y) for k in range(n_cycles)])
    spread = float(np.ptp(y[t >= start]))
    if spread == 0.0:
        return float("nan")
    each = np.sqrt(np.mean((cycles - cycles.mean(axis=0)) ** 2, axis=1)) / spread
    return float(np.sqrt(np.mean(each**2)))


__all__ = ["MIN_CYCLES", "cycle_nrmse"]
