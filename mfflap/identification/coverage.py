"""Does a motion lie within the CFD data its model's coefficients were identified on?

Two answers, because a reduced model predicts well only where its identification data reach:

- **By variable.** Each motion's period, amplitudes, peak rates and accelerations and peak
  effective angle of attack, against their range over the identification cases (beyond
  it by more than :data:`RANGE_TOLERANCE` of its end: an optimum the optimiser holds at a
  limit of the data by a penalty overshoots it a little). Readable,
  but blind to combinations: a motion can be within every range and still combine them as
  no case did.
- **By leverage** (the regression diagnostic for hidden extrapolation; Montgomery, Peck and
  Vining, *Introduction to Linear Regression Analysis*, section 3.8). The model is linear
  in its coefficients, so a sample whose regressor row x has x' (X'X)^-1 x above the largest
  such value over the identification samples lies outside the smallest ellipsoid holding
  them all: the fit is extrapolated there. The rows are those of the fit, each load
  component scaled by its RMS over the identification cases' CFD.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from mfflap.errors import MfflapError
from mfflap.hydro.base import ForceModel
from mfflap.hydro.morison import RelativeFlow
from mfflap.identification.data import COMPONENTS, CaseData
from mfflap.kinematics.state import KinematicState

#: How far beyond the identification data's range a variable may lie, as a share of the
#: range's end, before the motion is called outside it.
RANGE_TOLERANCE = 0.02

#: The variables compared, with their units.
FEATURE_UNITS = {
    "frequency": "Hz",
    "heave amplitude": "m",
    "pitch amplitude": "deg",
    "peak |heave velocity|": "m/s",
    "peak |heave acceleration|": "m/s^2",
    "peak |pitch rate|": "rad/s",
    "peak |pitch acceleration|": "rad/s^2",
    "peak effective angle of attack": "deg",
}


def motion_features(state: KinematicState, frequency: float, velocity: float
                    ) -> dict[str, float]:
    """The variables of :data:`FEATURE_UNITS` of one motion over ``state`` (a window of whole
    periods); ``frequency`` (Hz) NaN when it has none."""
    flow = RelativeFlow.of(state, velocity)
    alpha = np.degrees(np.arctan2(flow.normal_velocity, -flow.tangential_velocity))
    return {
        "frequency": float(frequency),
        "heave amplitude": float(np.ptp(state.heave_position) / 2),
        "pitch amplitude": float(np.degrees(np.ptp(state.pitch_angle) / 2)),
        "peak |heave velocity|": float(np.max(np.abs(state.heave_velocity))),
        "peak |heave acceleration|": float(np.max(np.abs(state.heave_acceleration))),
        "peak |pitch rate|": float(np.max(np.abs(state.pitch_rate))),
        "peak |pitch acceleration|": float(np.max(np.abs(state.pitch_acceleration))),
        "peak effective angle of attack": float(np.max(np.abs(alpha))),
    }


@dataclass
class Coverage:
    """Where one motion lies against the identification data.

    Attributes
    ----------
    features : variable -> the motion's value (units in :data:`FEATURE_UNITS`)
    outside : variable -> (value, lowest, highest over the cases) for each variable beyond
        the cases' range
    leverage_ratio : the motion's largest leverage over the cases' largest; above 1 the
        fit is extrapolated (hidden extrapolation when no variable is outside)
    ranges : variable -> (lowest, highest) over the cases
    """

    features: dict[str, float]
    outside: dict[str, tuple[float, float, float]] = field(default_factory=dict)
    leverage_ratio: float = float("nan")
    ranges: dict[str, tuple[float, float]] = field(default_factory=dict)

    @property
    def extrapolated(self) -> bool:
        """Some variable lies beyond the cases' range, or the leverage beyond theirs."""
        return bool(self.outside) or self.leverage_ratio > 1

    def describe(self) -> str:
        """One line: within the identification data, or where it leaves it."""
        lev = f"leverage {self.leverage_ratio:.3g} times the data's largest"
        if not self.extrapolated:
            return f"within the identification data ({lev})"
        parts = [f"{name} {v:.3g} {FEATURE_UNITS[name]} (data {lo:.3g}-{hi:.3g})"
                 for name, (v, lo, hi) in self.outside.items()]
        if self.leverage_ratio > 1:
            parts.append(lev + (": hidden extrapolation" if not self.outside else ""))
        return "outside the identification data: " + "; ".join(parts)

    def as_dict(self) -> dict:
        """For JSON and HDF5 attributes."""
        return {"extrapolated": self.extrapolated, "leverage_ratio": self.leverage_ratio,
                "features": self.features,
                "outside": {k: list(v) for k, v in self.outside.items()},
                "ranges": {k: list(v) for k, v in self.ranges.items()},
                "said": self.describe()}


@dataclass
class CoverageReference:
    """The identification data's ranges and regressor ellipsoid.

    Build with :meth:`from_cases`; :meth:`check` places a motion against them.
    """

    model: ForceModel
    velocity: float
    ranges: dict[str, tuple[float, float]]
    scales: dict[str, float]
    inverse_gram: np.ndarray
    max_leverage: float
    n_cases: int

    @classmethod
    def from_cases(cls, cases: Sequence[CaseData], model: ForceModel, velocity: float
                   ) -> CoverageReference:
        """The reference of ``cases`` for ``model``'s regressors at stream speed ``velocity``
        (m/s).

        Raises
        ------
        MfflapError
            Without cases, or when a load component's CFD is zero in every case.
        """
        if not cases:
            raise MfflapError("the identification data's coverage needs at least one case")
        feats = [motion_features(c.state, c.frequency, velocity) for c in cases]
        ranges = {}
        for name in FEATURE_UNITS:
            vals = np.array([f[name] for f in feats])
            vals = vals[np.isfinite(vals)]
            if vals.size:
                ranges[name] = (float(vals.min()), float(vals.max()))
        scales = {}
        for k in COMPONENTS:
            rms = float(np.sqrt(np.mean(np.concatenate([c.cfd_signal(k) for c in cases])**2)))
            if not rms > 0:
                raise MfflapError(f"the identification cases' CFD {k} is zero throughout: "
                                  "no scale to place a motion's regressors on")
            scales[k] = rms
        rows = np.vstack([_rows(model, c.state, scales) for c in cases])
        inverse = np.linalg.pinv(rows.T @ rows)
        lev = np.einsum("ij,jk,ik->i", rows, inverse, rows)
        return cls(model, velocity, ranges, scales, inverse, float(lev.max()), len(cases))

    def check(self, state: KinematicState, frequency: float = float("nan")) -> Coverage:
        """Place a motion (``state`` over whole periods; ``frequency`` Hz, NaN if it has none)
        against the data."""
        feats = motion_features(state, frequency, self.velocity)
        outside = {}
        for name, (lo, hi) in self.ranges.items():
            v = feats[name]
            if np.isfinite(v) and not (lo * (1 - RANGE_TOLERANCE) <= v
                                       <= hi * (1 + RANGE_TOLERANCE)):
                outside[name] = (v, lo, hi)
        rows = _rows(self.model, state, self.scales)
        lev = np.einsum("ij,jk,ik->i", rows, self.inverse_gram, rows)
        return Coverage(feats, outside, float(lev.max() / self.max_leverage),
                        dict(self.ranges))


def _rows(model: ForceModel, state: KinematicState, scales: dict[str, float]) -> np.ndarray:
    """The fit's regressor rows of ``state``, every component scaled by ``scales``."""
    regs = model.regressors(state)
    return np.vstack([np.column_stack([getattr(regs[t.name], k) for t in model.terms])
                      / scales[k] for k in COMPONENTS])
