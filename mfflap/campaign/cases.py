"""One CFD case of a campaign and the sets of them: the identification grid (the paper's
Table 1 by default) and the harmonic set at large pitch."""

from __future__ import annotations

import itertools
import math
from collections.abc import Iterable, Sequence
from dataclasses import asdict, dataclass
from typing import Protocol

from mfflap.cfd.imposed_motion import check_end_time, check_ramp_time
from mfflap.config import CASE_ID_DECIMALS, IdentificationGrid
from mfflap.errors import ConfigError, MotionError
from mfflap.kinematics.continuous import HarmonicMotion, Motion, RampHarmonicMotion
from mfflap.study_tables import HarmonicSet


class CampaignCase(Protocol):
    """What a campaign needs of a case: an identifier, the motion, how long, its parameters."""

    #: the record's ``parameters["kind"]``
    kind: str
    duration: float
    ramp_time: float

    @property
    def case_id(self) -> str: ...

    def motion(self) -> Motion: ...

    def as_dict(self) -> dict[str, float]: ...


def _check_run_times(case_id: str, duration: float, ramp_time: float) -> None:
    """Refuse, when a case is made, a run of no or endless length or a start-up ramp that
    lasts it all (the case would be refused only when it came to run, after its campaign
    had started), naming the case."""
    try:
        check_ramp_time(ramp_time, check_end_time(duration))
    except ConfigError as exc:
        raise ConfigError(exc._message, source=f"case {case_id}", key=exc.key) from exc
    except MotionError as exc:
        raise ConfigError(str(exc).replace("end_time", "the duration"),
                          source=f"case {case_id}", key="duration") from exc


@dataclass(frozen=True)
class CfdCase:
    """An identification motion, theta = k t sin(2 pi f t), h = h_a sin(2 pi f t + phi).

    Attributes
    ----------
    frequency : Hz
    heave_amplitude : m
    phase_deg : deg
    pitch_ramp_rate_deg : deg/s (theta_kamp)
    duration : s, simulated time
    ramp_time : s, C^2 start-up ramp of the imposed motion (removes the start-up spike)
    """

    frequency: float
    heave_amplitude: float
    phase_deg: float
    pitch_ramp_rate_deg: float
    duration: float
    ramp_time: float
    kind = "ramp_harmonic"

    def __post_init__(self) -> None:
        _check_run_times(self.case_id, self.duration, self.ramp_time)

    @property
    def case_id(self) -> str:
        """Stable, file-name and TOML-key safe identifier, e.g. ``f1p000_h0p300_phi090p0``."""
        f, h, phi = (CASE_ID_DECIMALS[k] for k in ("frequencies", "heave_amplitudes",
                                                    "phases_deg"))
        text = (f"f{self.frequency:.{f}f}_h{self.heave_amplitude:.{h}f}"
                f"_phi{self.phase_deg:0{4 + phi}.{phi}f}")
        return text.replace(".", "p").replace("-", "m")

    def motion(self) -> RampHarmonicMotion:
        """The continuous motion the case imposes (before the start-up ramp)."""
        return RampHarmonicMotion(self.frequency, self.heave_amplitude,
                                  math.radians(self.pitch_ramp_rate_deg),
                                  math.radians(self.phase_deg))

    def as_dict(self) -> dict[str, float]:
        """Plain values (for TOML and HDF5 attributes)."""
        return asdict(self)


@dataclass(frozen=True)
class HarmonicCase:
    """A harmonic motion, theta = theta_a sin(2 pi f t), h = h_a sin(2 pi f t + phi).

    Attributes
    ----------
    frequency : Hz
    heave_amplitude : m
    pitch_amplitude_deg : deg
    phase_deg : deg, by which heave leads pitch
    duration : s, simulated time
    ramp_time : s, C^2 start-up ramp of the imposed motion
    """

    frequency: float
    heave_amplitude: float
    pitch_amplitude_deg: float
    phase_deg: float
    duration: float
    ramp_time: float
    kind = "harmonic"

    def __post_init__(self) -> None:
        _check_run_times(self.case_id, self.duration, self.ramp_time)

    @property
    def case_id(self) -> str:
        """E.g. ``harmonic_f1p000_h0p0050_th2p00_phi090p0`` (file-name and TOML-key safe)."""
        text = (f"harmonic_f{self.frequency:.3f}_h{self.heave_amplitude:.4f}"
                f"_th{self.pitch_amplitude_deg:.2f}_phi{self.phase_deg:05.1f}")
        return text.replace(".", "p").replace("-", "m")

    def motion(self) -> HarmonicMotion:
        """The continuous motion the case imposes (before the start-up ramp)."""
        return HarmonicMotion(self.frequency, self.heave_amplitude,
                              math.radians(self.pitch_amplitude_deg),
                              math.radians(self.phase_deg))

    def as_dict(self) -> dict[str, float]:
        """Plain values (for TOML and HDF5 attributes)."""
        return asdict(self)


def case_for(grid: IdentificationGrid, frequency: float, heave_amplitude: float,
             phase_deg: float) -> CfdCase:
    """The case of ``grid`` at one (f, h_amp, phi): n_cycles periods capped at max_duration,
    its pitch ramp no faster than reaches ``max_ramp_pitch_deg`` at the end."""
    duration = grid.case_duration(frequency)
    ramp_time = grid.case_ramp_time(frequency)
    return CfdCase(float(frequency), float(heave_amplitude), float(phase_deg),
                   float(grid.case_pitch_ramp_rate_deg(frequency)), float(duration),
                   float(ramp_time))


def _pick(values: Sequence[float], subset: Iterable[float] | None, name: str) -> list[float]:
    if subset is None:
        return list(values)
    chosen = []
    for v in subset:
        match = [x for x in values if math.isclose(x, v, rel_tol=1e-9, abs_tol=1e-12)]
        if not match:
            raise ConfigError(f"{v!r} is not on the grid ({list(values)})", key=name)
        chosen.append(match[0])
    return chosen


def grid_cases(grid: IdentificationGrid, frequencies: Iterable[float] | None = None,
               heave_amplitudes: Iterable[float] | None = None,
               phases_deg: Iterable[float] | None = None) -> list[CfdCase]:
    """All cases of the grid, or of a sub-grid; ordered so that every frequency comes early.

    The order interleaves frequencies (f varies fastest), so a campaign stopped part-way
    still covers the whole frequency range.
    """
    fs = _pick(grid.frequencies, frequencies, "identification.frequencies")
    hs = _pick(grid.heave_amplitudes, heave_amplitudes, "identification.heave_amplitudes")
    ps = _pick(grid.phases_deg, phases_deg, "identification.phases_deg")
    # middle values first: a partial campaign then spans the grid instead of one corner
    hs = sorted(hs, key=lambda v: abs(v - sorted(hs)[len(hs) // 2]))
    ps = sorted(ps, key=lambda v: abs(v - 90.0))
    return [case_for(grid, f, h, p) for p, h, f in itertools.product(ps, hs, fs)]


def harmonic_set_cases(harmonic_set: HarmonicSet) -> list[HarmonicCase]:
    """The cases of the second identification set (the case file's ``[harmonic_set]``).

    Examples
    --------
    >>> cases = harmonic_set_cases(HarmonicSet())
    >>> len(cases), cases[0].case_id, cases[0].duration
    (36, 'harmonic_f1p000_h0p0500_th30p00_phi060p0', 4.0)
    """
    return [HarmonicCase(f, h, theta, phi, harmonic_set.duration(f), harmonic_set.ramp_time(f))
            for f, h, theta, phi in harmonic_set.motions()]
