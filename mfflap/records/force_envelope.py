"""The forces a flow can give a moving plate: a bound derived by hand from the imposed motion.

A run held at its Courant limit can lose its numerics gradually: an oscillation that grows
over hundreds of time steps while the time step shrinks a few times over, not the sudden
jump of a numerical burst (:mod:`mfflap.records.bursts`) nor a collapse of the time step. Its
forces then grow far beyond anything the motion can drive. This module bounds them.

At time t the plate's normal acceleration is at most ``|h''| + c |theta''|`` anywhere on the
chord (c the chord, the pivot anywhere on it) and the flow's speed relative to it at most
``U + |h'| + c |theta'|``. A plate's normal force is then at most its added mass
``rho pi (c/2)^2 s`` times that acceleration plus ``rho c s C_N V^2 / 2`` at that speed, with
``C_N`` = 3 (a flat plate normal to a steady stream gives 2; dynamic stall's leading-edge
vortex about 3). Shed vortices act after the motion that shed them, so the bound at t is the
largest over the preceding and following convective times ``c / U``. The moment about the
pivot is bounded by the chord times the same force.

The stream starts impulsively at t = 0 (a uniform initial field around a no-slip plate): the
solver spreads that start's pressure impulse over its first time steps, whatever the motion,
so the first :data:`FLOW_START_STEPS` samples of a run are not judged.

Real runs that kept their numerics stay inside 2.8 times it, the median run inside 0.36
times (over the shipped fixtures and the test data, see the tests); a record beyond
:data:`BREACH_FACTOR` times it has lost its numerics.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.ndimage import maximum_filter1d

from mfflap.hydro.loads import Loads
from mfflap.kinematics.state import KinematicState
from mfflap.parameters import Fluid, FreeStream, Plate

#: normal-force coefficient of the quasi-steady part of the bound
MAX_NORMAL_FORCE_COEFFICIENT = 3.0
#: a force this many times the bound is numerics, not flow
BREACH_FACTOR = 3.0
#: samples at the start of a run left unjudged: the impulsive start of the stream
FLOW_START_STEPS = 10


@dataclass(frozen=True)
class EnvelopeBreach:
    """One stretch of a force history beyond what the motion can drive.

    The stretch is where the forces exceed the bound itself, around a sample that exceeds
    :data:`BREACH_FACTOR` times it (stretches closer than one convective time are one).

    Attributes
    ----------
    start_s, end_s : float
        The stretch, s; samples inside it are replaced when bridged.
    n_samples : int
        Samples of the history inside it.
    peak_s : float
        Time of the largest ratio of force to bound, s.
    peak_ratio : float
        That ratio.
    """

    start_s: float
    end_s: float
    n_samples: int
    peak_s: float
    peak_ratio: float

    @property
    def duration_s(self) -> float:
        """Length of the stretch, s."""
        return self.end_s - self.start_s

    def describe(self) -> str:
        """One line for notes, errors and reports."""
        return (f"t = {self.start_s:.6g}-{self.end_s:.6g} s ({self.n_samples} samples, up to "
                f"{self.peak_ratio:.3g} x the largest force the motion can drive, at "
                f"t = {self.peak_s:.6g} s)")


def normal_force_bound_n(state: KinematicState, plate: Plate, fluid: Fluid,
                         stream: FreeStream) -> np.ndarray:
    """The largest normal force the motion can drive at each time of ``state``, N.

    Parameters
    ----------
    state : KinematicState
        The imposed motion, one motion (1-D arrays).
    plate, fluid, stream : Plate, Fluid, FreeStream
        Chord and span, density, stream speed.

    Returns
    -------
    ndarray
        The bound, on ``state.time``.
    """
    chord, span, rho = plate.chord, plate.span, fluid.density
    time = np.asarray(state.time, dtype=float)
    acceleration = (np.abs(state.heave_acceleration)
                    + chord * np.abs(state.pitch_acceleration))
    speed = (abs(stream.velocity) + np.abs(state.heave_velocity)
             + chord * np.abs(state.pitch_rate))
    added_mass_kg = rho * np.pi * (chord / 2) ** 2 * span
    local = (added_mass_kg * acceleration
             + 0.5 * rho * chord * span * MAX_NORMAL_FORCE_COEFFICIENT * speed**2)
    return _running_max(time, local, _memory_s(plate, stream))


def _running_max(time: np.ndarray, values: np.ndarray, half_width_s: float) -> np.ndarray:
    """Max of ``values`` over ``[t - half_width_s, t + half_width_s]`` at each sample."""
    if len(time) < 2:
        return values.copy()
    # on a uniform base fine enough for the smallest step that matters, then back
    span_s = time[-1] - time[0]
    n = int(min(max(span_s / max(np.median(np.diff(time)), 1e-12), 2), 200_000))
    uniform = np.linspace(time[0], time[-1], n + 1)
    step = span_s / n
    # the sampled maximum of each uniform cell, so that no peak between samples is lost
    cell = np.clip(np.searchsorted(uniform, time, side="right") - 1, 0, n)
    peaks = np.zeros(n + 1)
    np.maximum.at(peaks, cell, values)
    peaks = np.maximum(peaks, np.interp(uniform, time, values))
    size = 2 * int(np.ceil(half_width_s / step)) + 1
    smoothed = maximum_filter1d(peaks, size=size, mode="nearest")
    return np.maximum(np.interp(time, uniform, smoothed), values)


def envelope_ratio(state: KinematicState, loads: Loads, plate: Plate, fluid: Fluid,
                   stream: FreeStream) -> np.ndarray:
    """max(|F_n|, |M| / c) over the bound at each sample."""
    bound = normal_force_bound_n(state, plate, fluid, stream)
    force = np.maximum(np.abs(loads.normal_force), np.abs(loads.moment) / plate.chord)
    return force / bound


def find_envelope_breaches(state: KinematicState, loads: Loads, plate: Plate, fluid: Fluid,
                           stream: FreeStream, window: np.ndarray | None = None,
                           factor: float = BREACH_FACTOR) -> list[EnvelopeBreach]:
    """The stretches of a force history that the motion cannot have driven.

    Parameters
    ----------
    state, loads
        The imposed motion and the CFD loads on the same time base (bridge numerical bursts
        first: :func:`mfflap.records.bursts.bridge_load_bursts`).
    plate, fluid, stream
        Chord and span, density, stream speed.
    window : ndarray of bool, optional
        Samples to judge (all by default); the first :data:`FLOW_START_STEPS` samples (a history
        starts with its run) are never judged: the stream's impulsive start.
    factor : float
        How many times the bound a force must reach to be numerics.

    Returns
    -------
    list of EnvelopeBreach
        In time order; empty for a run that kept its numerics.
    """
    time = np.asarray(loads.time, dtype=float)
    ratio = envelope_ratio(state, loads, plate, fluid, stream)
    judged = np.ones(len(time), bool) if window is None else np.asarray(window, bool).copy()
    judged[:FLOW_START_STEPS] = False  # the stream's impulsive start
    above = judged & (ratio > min(1.0, factor))
    # runs of consecutive samples above the bound
    edges = np.flatnonzero(np.diff(np.concatenate([[0], above.astype(np.int8), [0]])))
    breaches = []
    for first, stop in zip(edges[::2], edges[1::2], strict=True):
        peak = first + int(np.argmax(ratio[first:stop]))
        if ratio[peak] <= factor:
            continue
        start_s = time[max(first - 1, 0)]
        end_s = time[min(stop, len(time) - 1)]
        breach = EnvelopeBreach(float(start_s), float(end_s), int(stop - first),
                                float(time[peak]), float(ratio[peak]))
        if breaches and breach.start_s - breaches[-1].end_s < _memory_s(plate, stream):
            # one lost stretch that swings across the bound: samples in between are lost too
            last = breaches[-1]
            n_between = int(np.sum((time > last.end_s) & (time < breach.start_s)))
            peak_first = last.peak_ratio >= breach.peak_ratio
            breaches[-1] = EnvelopeBreach(last.start_s, breach.end_s,
                                          last.n_samples + n_between + breach.n_samples,
                                          last.peak_s if peak_first else breach.peak_s,
                                          max(last.peak_ratio, breach.peak_ratio))
        else:
            breaches.append(breach)
    return breaches


def _memory_s(plate: Plate, stream: FreeStream) -> float:
    """The convective time c / U over which shed vortices act on the plate, s."""
    return plate.chord / max(abs(stream.velocity), 1e-9)
