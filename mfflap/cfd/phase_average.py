"""Phase averages of a periodic run: the mean cycle and how much the cycles scatter about it.

Beyond the first cycle, a flapping plate meets the vortices it shed before, and where those
arrive is sensitive to round-off: two runs that differ only in the linear solver can drift
several percent apart point by point (docs/findings/cfd_cost_study.md). Comparing the mean cycle
of each
run over several periods, and reading that comparison against how much one run's own cycles
scatter, separates a real difference between meshes or set-ups from that sensitivity.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mfflap.errors import ConfigError, MfflapError
from mfflap.kinematics.continuous import check_times


@dataclass(frozen=True)
class PhaseAverage:
    """The mean cycle of a signal over whole periods.

    Attributes
    ----------
    phase : ndarray
        Fraction of a period, 0 <= phase < 1, uniform.
    mean : ndarray
        Mean over the cycles at each phase, in the signal's unit.
    std : ndarray
        Sample standard deviation over the cycles at each phase (ddof 1; zeros with one
        cycle).
    n_cycles : int
        Whole periods averaged.
    start_s, period_s : float
        Start of the first averaged cycle and the period, s.
    """

    phase: np.ndarray
    mean: np.ndarray
    std: np.ndarray
    n_cycles: int
    start_s: float
    period_s: float

    @property
    def scatter(self) -> float:
        """Cycle-to-cycle scatter: the RMS over phase of ``std`` over the range of ``mean``
        (the NRMSE a single cycle would have against the mean cycle, to within the ddof);
        infinite when the mean cycle is constant and the cycles are not."""
        rms = float(np.sqrt(np.mean(self.std**2)))
        span = float(np.ptp(self.mean))
        if span > 0:
            return rms / span
        return 0.0 if rms == 0 else float("inf")


def whole_periods(start_s: float, end_s: float, period_s: float) -> int:
    """Number of whole periods in ``[start_s, end_s]`` (a period that ends within 1e-9 of a
    period short of ``end_s`` counts)."""
    return max(int(np.floor((end_s - start_s) / period_s + 1e-9)), 0)


def phase_average(time, values, period_s: float, start_s: float, *,
                  n_cycles: int | None = None, n_phase: int = 256) -> PhaseAverage:
    """Average ``values`` over whole periods from ``start_s`` at ``n_phase`` phases.

    Parameters
    ----------
    time : array_like, s
        Strictly increasing sample times (non-uniform steps allowed, as an adjustable time
        step writes them).
    values : array_like
        Samples at ``time``; linearly interpolated to each cycle's phases.
    period_s, start_s : float, s
        Period and the start of the first cycle averaged (after any start-up transient).
    n_cycles : int, optional
        Cycles to average (default: every whole period from ``start_s`` to the last sample).
    n_phase : int
        Phases per cycle.

    Raises
    ------
    ConfigError
        A non-positive period, a start outside the samples, or fewer whole periods than asked
        for (key ``period``, ``start`` or ``n_cycles``).
    MfflapError
        Times not strictly increasing (a :class:`~mfflap.errors.MotionError`), non-finite
        samples, or values not one per time.
    """
    t = check_times(time, "phase_average's time array")
    v = np.asarray(values, dtype=float)
    if v.shape != t.shape or len(t) < 2:
        raise MfflapError(f"phase_average needs two or more samples of one signal, got time "
                          f"{t.shape} and values {v.shape}")
    if not np.all(np.isfinite(v)):
        raise MfflapError(f"phase_average got a NaN or infinite value at index "
                          f"{int(np.argmin(np.isfinite(v)))}")
    if not period_s > 0:
        raise ConfigError(f"the period must be > 0 s, got {period_s!r}", key="period")
    if not t[0] <= start_s < t[-1]:
        raise ConfigError(f"the averaging starts at {start_s!r} s, outside the samples "
                          f"({t[0]:.6g}-{t[-1]:.6g} s)", key="start")
    available = whole_periods(start_s, t[-1], period_s)
    n = available if n_cycles is None else n_cycles
    if n < 1 or n > available:
        raise ConfigError(f"{n} cycle(s) of {period_s:.6g} s asked for from {start_s:.6g} s, "
                          f"but the samples end at {t[-1]:.6g} s ({available} whole "
                          f"period(s))", key="n_cycles")
    if n_phase < 2:
        raise ConfigError(f"n_phase must be >= 2, got {n_phase}", key="n_phase")
    phase = np.arange(n_phase) / n_phase
    cycles = np.array([np.interp(start_s + (k + phase) * period_s, t, v) for k in range(n)])
    std = cycles.std(axis=0, ddof=1) if n > 1 else np.zeros(n_phase)
    return PhaseAverage(phase, cycles.mean(axis=0), std, n, float(start_s), float(period_s))
