"""The CFD baseline: the best sinusoid whose CFD peak power holds the power limit.

An optimised motion's gain means something only against the best sinusoid under the same
limit in the same CFD. The cheap levels cannot name that sinusoid (Morison under-predicts
the peak power of large motions by half, the vortex model is not converged there), so the
baseline is read from CFD runs of sinusoids near the limit (the shipped
``baseline_sinusoids`` records, a campaign of harmonic motions): each run's periods after
its first whole one give its mean thrust and power with their standard errors and its peak
power (the largest over those periods, as a back-test's ``max_power_ok`` takes it), and the
baseline is the one with the most thrust among those whose peak holds the limit.

Examples
--------
>>> from mfflap.records.record import fixture_dir, read_records
>>> baseline = cfd_baseline(read_records(fixture_dir("baseline_sinusoids")), 50.0)
>>> baseline.best is not None and baseline.best.peak_power_w <= 50.0
True
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np

from mfflap.backtest.cycles import cycle_means
from mfflap.errors import MfflapError
from mfflap.performance import thrust_and_power
from mfflap.records.record import CfdRecord


@dataclass(frozen=True)
class CfdSinusoid:
    """One sinusoid's CFD run, over its periods after the first whole one.

    Attributes
    ----------
    name : the record's name
    frequency_hz, heave_amplitude_m, pitch_amplitude_deg, phase_deg : the motion
    mean_thrust_n, mean_power_w : the means over the periods
    thrust_standard_error_n, power_standard_error_w : of those means over the periods
    peak_power_w : the largest instantaneous input power over the periods
    periods : how many periods the means are taken over
    """

    name: str
    frequency_hz: float
    heave_amplitude_m: float
    pitch_amplitude_deg: float
    phase_deg: float
    mean_thrust_n: float
    thrust_standard_error_n: float
    mean_power_w: float
    power_standard_error_w: float
    peak_power_w: float
    periods: int

    def holds(self, max_power_w: float) -> bool:
        """Whether its CFD peak power holds ``max_power_w``."""
        return self.peak_power_w <= max_power_w

    def said(self) -> str:
        """The motion and its CFD figures in one phrase."""
        return (f"f = {self.frequency_hz:.3g} Hz, h = {self.heave_amplitude_m:.3g} m, "
                f"θ = {self.pitch_amplitude_deg:.3g}°, φ = {self.phase_deg:.3g}°: "
                f"{self.mean_thrust_n:.3g} ± {self.thrust_standard_error_n:.2g} N at "
                f"{self.peak_power_w:.3g} W peak")


@dataclass(frozen=True)
class CfdBaseline:
    """The sinusoids run in CFD and the best of those that hold the limit (None: none
    does)."""

    max_power_w: float
    candidates: tuple[CfdSinusoid, ...]
    best: CfdSinusoid | None

    def as_dict(self) -> dict:
        """JSON-friendly dict."""
        return {"max_power_w": self.max_power_w,
                "candidates": [asdict(c) for c in self.candidates],
                "best": None if self.best is None else self.best.name}


def sinusoid_in_cfd(record: CfdRecord) -> CfdSinusoid:
    """A harmonic record's CFD figures over its periods after the first whole one.

    Raises
    ------
    MfflapError
        Naming the record, if it is not of a harmonic motion or holds fewer than two whole
        periods after its start-up ramp.
    """
    p = record.parameters
    if p.get("kind") != "harmonic":
        raise MfflapError(f"{record.name}: not a harmonic motion's record (kind "
                          f"{p.get('kind')!r}); the baseline is made of sinusoids")
    period = 1.0 / float(p["frequency"])
    means = cycle_means(record, period)
    if means.thrust.size < 2:
        raise MfflapError(f"{record.name}: {means.thrust.size} whole period(s) after the "
                          "start-up ramp; the baseline takes the periods after the first")
    thrust, power = means.thrust[1:], means.power[1:]
    _, instantaneous = thrust_and_power(record.loads, record.state)
    t = record.time
    settled = (t >= means.start_s[1]) & (t <= means.start_s[-1] + period)
    n = thrust.size
    return CfdSinusoid(record.name, float(p["frequency"]), float(p["heave_amplitude"]),
                       float(p["pitch_amplitude_deg"]), float(p["phase_deg"]),
                       float(thrust.mean()), float(thrust.std(ddof=1) / np.sqrt(n)),
                       float(power.mean()), float(power.std(ddof=1) / np.sqrt(n)),
                       float(instantaneous[settled].max()), n)


@dataclass(frozen=True)
class CfdPair:
    """The best back-tested motion within the limit in CFD against the CFD baseline.

    Attributes
    ----------
    label : the motion's label (e.g. "β = 0 polished")
    mean_thrust_n, thrust_standard_error_n, peak_power_w, mean_power_w : its CFD figures
    baseline : the best sinusoid within the limit in CFD
    gain, gain_standard_error : its mean thrust over the baseline's, less one, and the
        standard error of that ratio from both standard errors
    """

    label: str
    mean_thrust_n: float
    thrust_standard_error_n: float
    mean_power_w: float
    peak_power_w: float
    baseline: CfdSinusoid
    gain: float
    gain_standard_error: float


def best_motion_within(backtests: Mapping[str, Any], max_power_w: float,
                       baseline: CfdBaseline | None) -> CfdPair | None:
    """The back-tested motion (other than the sweep's best sinusoid) with the most CFD
    thrust among those whose CFD peak power holds ``max_power_w``, against ``baseline``'s
    best; None without either."""
    if baseline is None or baseline.best is None:
        return None
    within = {k: o.comparison for k, o in backtests.items()
              if k != "best sinusoid" and o.comparison is not None
              and o.comparison.cfd_max_power <= max_power_w}
    if not within:
        return None
    label, c = max(within.items(), key=lambda item: item[1].cfd_mean_thrust)
    b = baseline.best
    se = float(np.nan_to_num(getattr(c, "cfd_thrust_standard_error", np.nan)))
    ratio = c.cfd_mean_thrust / b.mean_thrust_n
    gain_se = float(np.hypot(se / b.mean_thrust_n,
                             ratio * b.thrust_standard_error_n / b.mean_thrust_n))
    return CfdPair(label, float(c.cfd_mean_thrust), se, float(c.cfd_mean_power),
                   float(c.cfd_max_power), b, float(ratio - 1.0), gain_se)


def cfd_baseline(records: Sequence[CfdRecord], max_power_w: float) -> CfdBaseline:
    """The best sinusoid within ``max_power_w`` in CFD among ``records`` (module notes)."""
    candidates = tuple(sorted((sinusoid_in_cfd(r) for r in records),
                              key=lambda c: (c.frequency_hz, c.heave_amplitude_m)))
    holding = [c for c in candidates if c.holds(max_power_w)]
    best = max(holding, key=lambda c: c.mean_thrust_n) if holding else None
    return CfdBaseline(float(max_power_w), candidates, best)


__all__ = ["CfdBaseline", "CfdPair", "CfdSinusoid", "best_motion_within", "cfd_baseline",
           "sinusoid_in_cfd"]
