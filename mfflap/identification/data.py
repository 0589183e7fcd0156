"""CFD records prepared for fitting: transient removed, uniform time base, regressors."""

from __future__ import annotations

import warnings
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
from scipy.ndimage import median_filter

from mfflap.errors import MfflapError
from mfflap.hydro.base import ForceModel
from mfflap.hydro.loads import LOAD_UNITS, Loads
from mfflap.kinematics.state import KINEMATIC_UNITS, KinematicState
from mfflap.parameters import Fluid, FreeStream, Plate
from mfflap.performance import thrust_and_power
from mfflap.records.bursts import bridge_bursts, bridge_load_bursts
from mfflap.records.force_envelope import find_envelope_breaches
from mfflap.records.mixed_set_up import mixed_since_s
from mfflap.records.record import CfdRecord

#: Load components a fit can use, with their units.
COMPONENTS = LOAD_UNITS
#: How a case's notes say that numerical bursts of its CFD were bridged.
BURST_NOTE = "numerical burst(s) bridged by linear interpolation"
#: How a case's notes say that stretches beyond the physical force bound were bridged.
ENVELOPE_NOTE = "stretch(es) beyond the forces the motion can drive bridged"
#: How a case's notes say that a retry changed the run's settings within the fitted window.
SET_UP_NOTE = "a retry changed the CFD's settings within the fitted window"
#: Derived signals that are scored (not fitted directly).
DERIVED = {"thrust": "N", "input_power": "W"}
_STATE_KEYS = tuple(KINEMATIC_UNITS)


def motion_frequency(parameters: dict) -> float:
    """A record's carrier frequency, Hz: its ``frequency``, else one over its ``period`` (a
    back-test's periodic motion), else NaN."""
    if "frequency" in parameters:
        return float(parameters["frequency"])
    period = float(parameters.get("period", np.nan))
    return 1.0 / period if np.isfinite(period) and period > 0 else float("nan")


@dataclass
class CaseData:
    """One CFD case ready for fitting and scoring.

    Attributes
    ----------
    name : str
    parameters : dict
        Motion parameters (frequency Hz, heave_amplitude m, phase_deg, ...).
    state : KinematicState
        Imposed kinematics on a uniform time base after the transient.
    cfd : Loads
        CFD loads on the same time base.
    notes : list of str
        What cleaning the record needed (bridged bursts, replaced spikes).
    provenance : dict
        The record's provenance (how it was run).
    refinement : dict of str to RefinementChange
        The record's mesh and time-step changes, where it has them
        (:mod:`mfflap.records.refinement`).
    """

    name: str
    parameters: dict
    state: KinematicState
    cfd: Loads
    notes: list[str] = field(default_factory=list)
    provenance: dict = field(default_factory=dict)
    refinement: dict = field(default_factory=dict)

    @property
    def frequency(self) -> float:
        """Carrier frequency, Hz (:func:`motion_frequency`)."""
        return motion_frequency(self.parameters)

    @property
    def n_samples(self) -> int:
        """Samples on the uniform time base."""
        return len(self.state.time)

    def regressor_matrix(self, model: ForceModel, component: str) -> np.ndarray:
        """(n_samples, n_terms) regressors of ``component`` for every term of ``model``."""
        regs = model.regressors(self.state)
        return np.column_stack([getattr(regs[t.name], component) for t in model.terms])

    def cfd_signal(self, component: str) -> np.ndarray:
        """A CFD load component, or the derived thrust / input power."""
        if component in COMPONENTS:
            return getattr(self.cfd, component)
        thrust, power = thrust_and_power(self.cfd, self.state)
        return thrust if component == "thrust" else power


def _resample_state(state: KinematicState, t: np.ndarray) -> KinematicState:
    return KinematicState(time=t, **{k: np.interp(t, state.time, getattr(state, k))
                                     for k in _STATE_KEYS})


def despike(values: np.ndarray, window: int = 9, threshold: float = 12.0,
            min_share: float = 0.25) -> tuple[np.ndarray, np.ndarray]:
    """Replace isolated one-to-few-step spikes by the running median.

    A sample is a spike when it departs from the running median (``window`` samples) by more
    than ``threshold`` times the median absolute departure *and* by more than ``min_share``
    of the signal's robust range (2nd to 98th percentile). CFD time steps are far shorter
    than the flow's time scales, so real force variations pass; the one-step pressure glitches
    a PIMPLE step can produce do not. Returns the cleaned values and the spike mask.
    """
    med = median_filter(values, size=window, mode="nearest")
    dev = np.abs(values - med)
    mad = float(np.median(dev))
    scale = max(mad, 1e-6 * float(np.max(np.abs(values))) + 1e-300)
    lo, hi = np.percentile(values, [2.0, 98.0])
    mask = (dev > threshold * scale) & (dev > min_share * (hi - lo))
    return np.where(mask, med, values), mask


def _neighbour_step(dt: np.ndarray, k: int = 20) -> np.ndarray:
    """The larger of the medians of the ``k`` steps before and the ``k`` steps after each step.

    A lost stretch of a run is a step far above the steps on both sides; a change of the
    adaptive time step (a sudden drop when the flow gets violent, growth by at most 20 % a
    step) has steps of its own size on at least one side.
    """
    n = len(dt)
    pad = np.full(k, np.nan)
    windows = np.lib.stride_tricks.sliding_window_view(np.concatenate([pad, dt, pad]), k)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # all-NaN windows at the ends
        before = np.nanmedian(windows[:n], axis=1)
        after = np.nanmedian(windows[k + 1:k + 1 + n], axis=1)
    return np.fmax(before, after)


def prepare_case(record: CfdRecord, discard_time: float = 0.75, n_samples: int = 400,
                 max_gap_ratio: float = 25.0, max_burst_share: float = 0.05, *,
                 plate: Plate | None = None, fluid: Fluid | None = None,
                 stream: FreeStream | None = None) -> CaseData:
    """Drop the start-up transient and resample a record onto a uniform time base.

    Adaptive CFD time steps crowd samples where the flow is fast; a uniform base keeps them
    from weighting the fit. The start is the later of ``discard_time`` and the record's own
    start-up ramp. Numerical bursts after the start (:mod:`mfflap.records.bursts`) are bridged
    by linear interpolation, and so are stretches whose forces the motion cannot have
    driven (:mod:`mfflap.records.force_envelope`: a run that lost its numerics gradually); then
    isolated spikes are replaced by the running median (:func:`despike`). All are listed in
    the case's notes, and so is a retry that resumed the run with other settings after the
    start (:func:`~mfflap.records.mixed_set_up.mixed_since_s`): the fit then mixes two
    set-ups.

    Parameters
    ----------
    plate, fluid, stream : optional
        Of the force bound; by default the record's chord and span (its provenance) and the
        default fluid and stream.

    Raises
    ------
    MfflapError
        If the record has a gap (a step more than ``max_gap_ratio`` times the steps on both
        sides of it: the adaptive time step itself may change a hundredfold over a run), or
        too little data after the transient, or if numerical bursts and stretches beyond
        the force bound together cover more than ``max_burst_share`` of the time after the
        transient; the message names the record and the time.
    """
    t = record.time
    start = max(discard_time, float(record.parameters.get("ramp_time", 0.0)))
    dt = np.diff(t)
    if len(dt) > 1:
        with np.errstate(divide="ignore", invalid="ignore"):
            ratio = dt / _neighbour_step(dt)
        if np.any(ratio > max_gap_ratio):
            i = int(np.argmax(ratio))
            raise MfflapError(f"record {record.name}: gap in the force history between "
                              f"t = {t[i]:.6g} s and {t[i + 1]:.6g} s ({ratio[i]:.0f} times "
                              "the steps around it); rerun or trim the case")
    if t[-1] - start < 0.2 * (t[-1] - t[0]) or t[-1] <= start:
        raise MfflapError(f"record {record.name}: only {max(t[-1] - start, 0):.3g} s of "
                          f"{t[-1] - t[0]:.3g} s remain after discarding {start:.3g} s of "
                          "start-up")
    n = int(min(n_samples, max(8, np.sum(t >= start))))
    tu = np.linspace(start, t[-1], n)
    state = _resample_state(record.state, tu)
    kept = t >= t[max(int(np.searchsorted(t, start)) - 1, 0)]
    loads, bursts = bridge_load_bursts(record.loads, kept)
    breaches = find_envelope_breaches(record.state, loads, *_bound_parameters(
        record, plate, fluid, stream), window=kept)
    t = t[kept]
    notes, cleaned = [], []
    if bursts:
        lost = sum(b.duration_s for b in bursts)
        if lost > max_burst_share * (t[-1] - t[0]):
            raise MfflapError(f"record {record.name}: numerical bursts cover {lost:.3g} s "
                              f"of the {t[-1] - t[0]:.3g} s after the start-up "
                              f"({len(bursts)} of them, first {bursts[0].describe()}); "
                              "rerun the case (a lower Courant limit)")
        notes.append(f"{len(bursts)} {BURST_NOTE}: "
                     + "; ".join(b.describe() for b in bursts))
    if breaches:
        lost = sum(b.duration_s for b in breaches) + sum(b.duration_s for b in bursts)
        if lost > max_burst_share * (t[-1] - t[0]):
            raise MfflapError(f"record {record.name}: its forces leave what the motion can "
                              f"drive for {lost:.3g} s of the {t[-1] - t[0]:.3g} s after the "
                              f"start-up, first {breaches[0].describe()}: the run lost its "
                              "numerics; rerun the case (a lower Courant limit)")
        loads = Loads(loads.time, *(bridge_bursts(loads.time, getattr(loads, k), breaches)
                                    for k in COMPONENTS), source=loads.source)
        notes.append(f"{len(breaches)} {ENVELOPE_NOTE}: "
                     + "; ".join(b.describe() for b in breaches))
    if (since := mixed_since_s(record, discard_time)) is not None:
        notes.append(f"{SET_UP_NOTE}: at t = {since:.4g} s, after the start at {start:.4g} s "
                     f"({record.provenance.get('retries')}); `mfflap campaign run "
                     "--rerun-mixed` reruns the case as one set-up")
    for k in COMPONENTS:
        values, mask = despike(getattr(loads, k)[kept])
        if mask.any():
            first = t[np.argmax(mask)]
            notes.append(f"{k}: {int(mask.sum())} spike sample(s) replaced by the running "
                         f"median (first at t = {first:.4g} s)")
        cleaned.append(np.interp(tu, t, values))
    cfd = Loads(tu, *cleaned, source=record.loads.source)
    return CaseData(record.name, dict(record.parameters), state, cfd, notes,
                    dict(record.provenance), dict(record.refinement))


def _bound_parameters(record: CfdRecord, plate: Plate | None, fluid: Fluid | None,
                      stream: FreeStream | None) -> tuple[Plate, Fluid, FreeStream]:
    """Plate, fluid and stream of a record's force bound: given, or its own and defaults."""
    if plate is None:
        prov = record.provenance
        plate = Plate(chord=float(prov.get("chord_m", Plate().chord)),
                      span=float(prov.get("span_m", Plate().span)))
    return plate, fluid or Fluid(), stream or FreeStream()


def prepare_cases(records: Sequence[CfdRecord], discard_time: float = 0.75,
                  n_samples: int = 400, *, plate: Plate | None = None,
                  fluid: Fluid | None = None, stream: FreeStream | None = None
                  ) -> tuple[list[CaseData], dict[str, str]]:
    """Prepare every record; records that cannot be used are returned with the reason."""
    cases, excluded = [], {}
    for rec in records:
        try:
            cases.append(prepare_case(rec, discard_time, n_samples, plate=plate,
                                      fluid=fluid, stream=stream))
        except MfflapError as exc:
            excluded[rec.name] = str(exc)
    return cases, excluded
