"""The CFD baseline's first runs (campaigns/baseline_sinusoids): the main job's best
sinusoid's shape (0.35 m, 60 deg, heave leading by 112 deg) at lower frequencies, real
OpenFOAM runs on the table1 set-up. What docs/findings/optimised_motions.md says of them:
at 0.78 Hz it holds P_max = 50 W within CFD's cycle scatter with 17-18 N, more than the
vortex-model polish that holds P_max in CFD (13.75 N); at 0.70 Hz it stays far below the
limit."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from mfflap.backtest.cycles import cycle_means
from mfflap.performance import thrust_and_power
from mfflap.records.record import read_record

FOLDER = Path(__file__).parents[2] / "campaigns" / "baseline_sinusoids"
P_MAX_W = 50.0
#: the β = 0 polish of the main job in CFD (docs/findings/optimised_motions.md)
POLISH_CFD_THRUST_N = 13.75

pytestmark = pytest.mark.findings


def _settled(name: str):
    """Mean thrust and power of each whole cycle after the first, and each one's peak
    power."""
    record = read_record(FOLDER / f"{name}.h5")
    period = 1.0 / record.parameters["frequency"]
    means = cycle_means(record, period)
    _, power = thrust_and_power(record.loads, record.state)
    t = record.time
    peaks = np.array([power[(t >= s) & (t <= s + period)].max() for s in means.start_s])
    return record, means.thrust[1:], means.power[1:], peaks[1:]


def test_at_0_78_hz_the_shape_holds_the_power_limit_within_cfd_s_scatter():
    record, thrust, power, peaks = _settled("harmonic_f0p780_h0p3500_th60p00_phi112p0")
    assert record.parameters["heave_amplitude"] == 0.35
    assert record.parameters["pitch_amplitude_deg"] == 60
    assert len(thrust) >= 2
    assert 16.5 < thrust.mean() < 18.5 and 20.0 < power.mean() < 24.0
    assert np.all(np.abs(peaks - P_MAX_W) < 0.06 * P_MAX_W), peaks
    assert thrust.mean() > 1.2 * POLISH_CFD_THRUST_N


def test_at_0_70_hz_it_stays_well_below_the_limit():
    _, thrust, _, peaks = _settled("harmonic_f0p700_h0p3500_th60p00_phi112p0")
    assert 13.0 < thrust.mean() < 15.0
    assert np.all(peaks < 0.75 * P_MAX_W), peaks


def test_the_smooth_polish_breaks_the_limit_in_cfd_where_the_vortex_model_held_it():
    """The main job's β = 0 polish held to 11 harmonics, live in OpenFOAM: more thrust than
    any sinusoid near the limit, but its peak power over P_max by more than a fifth."""
    from mfflap.backtest.model_ladder import compare_model_ladder
    from mfflap.records.record import fixture_dir, read_records

    (record,) = read_records(fixture_dir("backtest_polish_bandwidth"))
    assert record.parameters["label"] == "β = 0 polished"
    assert record.provenance["solver"] == "OpenFOAM pimpleFoam"
    ladder = compare_model_ladder(record)
    assert 22.0 < ladder.cfd.mean_thrust < 26.0
    assert ladder.cfd.peak_power > 1.2 * P_MAX_W
    assert ladder.vortex.peak_power < 0.85 * ladder.cfd.peak_power


def test_the_strict_baseline_is_the_run_that_holds_the_limit_in_every_period():
    from mfflap.backtest.baseline import cfd_baseline
    from mfflap.records.record import fixture_dir, read_records

    baseline = cfd_baseline(read_records(fixture_dir("baseline_sinusoids")), P_MAX_W)
    assert baseline.best.frequency_hz == 0.70 and baseline.best.heave_amplitude_m == 0.35
    near = [c for c in baseline.candidates if 1.0 < c.peak_power_w / P_MAX_W < 1.05]
    assert len(near) >= 3 and max(c.mean_thrust_n for c in near) > 17.0
