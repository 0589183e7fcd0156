"""Numerical bursts in a CFD force history: finding them and bridging them.

A PIMPLE run held at its Courant limit sometimes loses the pressure-velocity coupling for a
few time steps and recovers: the adaptive time step drops ten- to a thousandfold and the
forces jump by up to 10^5 times their range within microseconds to milliseconds,
then return to where they were. Such a burst is not flow physics, and a least-squares fit
or an NRMSE takes it at face value. It is also not a one-sample spike: it spans tens of
the shortened time steps, which defeats a running median over samples.

A burst is recognised by the *rate* at which a force changes. The flow's own sharpest
features (shed vortices passing an edge, the end of a start-up ramp) change the forces at
most a few times faster than the 99th percentile of the record's rates (over time, so the
burst's own many short steps do not raise it); after the start-up, no burst-free record of
the Table 1 fixtures exceeds 13 times it, and every burst exceeds 20 times it (25 to 10^9).
Steps above ``rate_factor`` times the 99th percentile seed a burst; the burst then extends
over the neighbouring steps above ``extend_factor`` times it (hysteresis, so its ramp-up
and decay go with it), bursts closer than ``merge_steps`` typical time steps are merged, and
``pad_steps`` typical steps are added on each side. A burst must also be large:
in at least one signal the history departs from the straight line bridging the interval by
more than ``min_departure`` of the signal's range (2nd to 98th percentile). That keeps
measurement-like noise on unevenly spaced samples, whose rates are large where two samples
nearly coincide, from passing as bursts: such noise departs by a few percent of the range,
the fixtures' bursts by 0.3 to 10^5 times it.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from scipy.ndimage import label

from mfflap.hydro.loads import Loads

#: the load components searched and bridged together: a burst is an event of the run
LOAD_COMPONENTS = ("normal_force", "tangential_force", "moment")


@dataclass(frozen=True)
class NumericalBurst:
    """One interval of a force history lost to a numerical burst.

    Attributes
    ----------
    start_s, end_s : float
        The interval, s; samples inside it are replaced when bridged.
    n_samples : int
        Samples of the history inside the interval.
    peak_rate_ratio : float
        The fastest change of any signal inside the interval over the signal's 99th
        percentile rate (how far from flow physics the burst is).
    """

    start_s: float
    end_s: float
    n_samples: int
    peak_rate_ratio: float

    @property
    def duration_s(self) -> float:
        """Length of the interval, s."""
        return self.end_s - self.start_s

    def describe(self) -> str:
        """One line for notes and reports."""
        return (f"t = {self.start_s:.6g}-{self.end_s:.6g} s ({self.n_samples} samples, "
                f"rate up to {self.peak_rate_ratio:.3g} x the 99th percentile)")


def _rate_ratios(time: np.ndarray, values: np.ndarray) -> np.ndarray:
    """|dv/dt| of each step over the 99th percentile of |dv/dt| (0 for a constant signal).

    The percentile is over time, not over steps: each step weighs its length. A burst's
    steps are short, so however many of them there are, they hardly move the scale.
    """
    dt = np.diff(time)
    rate = np.abs(np.diff(values)) / np.where(dt > 0, dt, np.inf)
    order = np.argsort(rate)
    share = np.cumsum(dt[order]) / max(float(np.sum(dt)), 1e-300)
    scale = float(rate[order][min(np.searchsorted(share, 0.99), len(rate) - 1)])
    if scale <= 0.0:
        return np.zeros_like(rate)
    return rate / scale


def find_numerical_bursts(time: np.ndarray, signals: Sequence[np.ndarray],
                          rate_factor: float = 20.0, extend_factor: float = 5.0,
                          merge_steps: float = 10.0, pad_steps: float = 2.0,
                          min_departure: float = 0.2) -> list[NumericalBurst]:
    """The numerical bursts of a force history (see the module notes for the criterion).

    Parameters
    ----------
    time : (n,) s, increasing
        The solver's own time steps (not a resampled base: the burst's shortened steps are
        part of its signature).
    signals : sequence of (n,) arrays
        The load components; a burst in any of them is a burst of the run.
    rate_factor, extend_factor : float
        Seed and extension thresholds, multiples of each signal's 99th percentile rate.
    merge_steps, pad_steps : float
        Merging distance and padding, in typical (median) time steps.
    min_departure : float
        Least departure from the bridging line, as a fraction of the signal's range.

    Returns
    -------
    list of NumericalBurst, in time order. The search starts where the time step first stops
    growing: before, the solver is starting from its initial fields.
    """
    t = np.asarray(time, dtype=float)
    values = [np.asarray(v, dtype=float) for v in signals]
    # the solver's start from its initial fields: the time step grows step after step from
    # the initial one, and the first steps' force impulse (an impulsive start, the initial
    # pressure field) is not a lost coupling; the search starts where the growth stops
    dt = np.diff(t)
    growing = np.append(dt[1:] > 1.01 * dt[:-1], False)
    first = int(np.argmin(growing)) + 1 if len(dt) and growing[0] else 0
    t, values = t[first:], [v[first:] for v in values]
    if len(t) < 3:
        return []
    ratios = np.max([_rate_ratios(t, v) for v in values], axis=0)
    regions, _ = label(ratios > extend_factor)
    seeded = np.unique(regions[ratios > rate_factor])
    steps = np.flatnonzero(np.isin(regions, seeded[seeded > 0]))
    typical_step = float(np.median(np.diff(t)))
    spans: list[list[float]] = []
    for j in steps:
        start, end = t[j] - pad_steps * typical_step, t[j + 1] + pad_steps * typical_step
        if spans and start - spans[-1][1] < merge_steps * typical_step:
            spans[-1][1] = max(spans[-1][1], end)
        else:
            spans.append([start, end])
    ranges = [float(np.subtract(*np.percentile(v, [98.0, 2.0]))) for v in values]
    bursts = []
    for start, end in spans:
        start, end = max(start, t[0]), min(end, t[-1])
        inside = (t >= start) & (t <= end)
        step_inside = inside[:-1] | inside[1:]
        burst = NumericalBurst(float(start), float(end), int(inside.sum()),
                               float(ratios[step_inside].max()))
        if any(_departure(t, v, burst) > min_departure * r
               for v, r in zip(values, ranges, strict=True) if r > 0):
            bursts.append(burst)
    return bursts


def _departure(time: np.ndarray, values: np.ndarray, burst: NumericalBurst) -> float:
    """Largest departure inside ``burst`` from its bridging line."""
    inside = burst_mask(time, [burst])
    gap = np.abs(values - bridge_bursts(time, values, [burst]))[inside]
    return float(gap.max()) if gap.size else 0.0


def burst_mask(time: np.ndarray, bursts: Sequence[NumericalBurst]) -> np.ndarray:
    """True for the samples of ``time`` inside any of ``bursts``."""
    t = np.asarray(time, dtype=float)
    mask = np.zeros(len(t), dtype=bool)
    for b in bursts:
        mask |= (t >= b.start_s) & (t <= b.end_s)
    return mask


def bridge_bursts(time: np.ndarray, values: np.ndarray,
                  bursts: Sequence[NumericalBurst]) -> np.ndarray:
    """``values`` with the samples inside ``bursts`` replaced by linear interpolation.

    The interpolation runs between the nearest samples outside each burst; a burst at an
    end of the record is extrapolated along the least-squares line through the five samples
    next to it.
    """
    t = np.asarray(time, dtype=float)
    v = np.asarray(values, dtype=float)
    mask = burst_mask(t, bursts)
    if not mask.any() or mask.all():
        return v.copy()
    t_out, v_out = t[~mask], v[~mask]
    bridged = np.interp(t, t_out, v_out)
    for ends, near in ((t < t_out[0], slice(None, 5)), (t > t_out[-1], slice(-5, None))):
        if ends.any() and len(t_out[near]) > 1:
            slope, intercept = np.polyfit(t_out[near], v_out[near], 1)
            bridged[ends] = slope * t[ends] + intercept
    return bridged


def find_load_bursts(loads: Loads, window: np.ndarray | None = None) -> list[NumericalBurst]:
    """The numerical bursts of a CFD force history, all components searched together.

    ``window`` (bool per sample) limits the search, for example to after the start-up.
    """
    window = np.ones(len(loads.time), dtype=bool) if window is None else window
    return find_numerical_bursts(loads.time[window],
                                 [getattr(loads, k)[window] for k in LOAD_COMPONENTS])


def bridge_load_bursts(loads: Loads, window: np.ndarray | None = None
                       ) -> tuple[Loads, list[NumericalBurst]]:
    """Find the numerical bursts of ``loads`` (all components together) and bridge them.

    Parameters
    ----------
    loads : Loads
        A CFD force history on the solver's own time steps.
    window : (n,) bool, optional
        The samples searched (for example those after the start-up); the others are left
        as they are and do not set the rate scale.

    Returns
    -------
    The loads with every burst bridged (the same object if there is none), and the bursts.
    """
    window = np.ones(len(loads.time), dtype=bool) if window is None else window
    t = loads.time[window]
    bursts = find_load_bursts(loads, window)
    if not bursts:
        return loads, []
    bridged = {}
    for k in LOAD_COMPONENTS:
        bridged[k] = np.array(getattr(loads, k), dtype=float)
        bridged[k][window] = bridge_bursts(t, bridged[k][window], bursts)
    return dataclasses.replace(loads, **bridged), bursts
