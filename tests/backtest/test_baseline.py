"""The CFD baseline: the best sinusoid within P_max among real OpenFOAM runs of sinusoids,
and the best back-tested motion within P_max set against it."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from mfflap.backtest.baseline import best_motion_within, cfd_baseline, sinusoid_in_cfd
from mfflap.errors import MfflapError
from mfflap.performance import thrust_and_power
from mfflap.records.record import fixture_dir, read_records

RECORDS = read_records(fixture_dir("baseline_sinusoids"))


def test_each_run_s_figures_are_its_settled_periods_time_means_and_peak():
    """Written apart from the module: trapezoidal time means over each whole period after
    the first, the peak of the instantaneous power over them."""
    for record in RECORDS:
        figures = sinusoid_in_cfd(record)
        f = record.parameters["frequency"]
        period, t = 1.0 / f, record.time
        thrust, power = thrust_and_power(record.loads, record.state)
        end = t[-1]
        n_whole = int(np.floor((end - record.parameters["ramp_time"]) / period + 1e-4))
        starts = end - period * np.arange(n_whole, 0, -1)
        means = []
        for s in starts[1:]:
            inside = (t >= s) & (t <= s + period)
            means.append(np.trapezoid(thrust[inside], t[inside]) / np.ptp(t[inside]))
        assert figures.mean_thrust_n == pytest.approx(np.mean(means), rel=0.01)
        assert figures.periods == len(means)
        settled = t >= starts[1]
        assert figures.peak_power_w == pytest.approx(power[settled].max(), rel=1e-6)


def test_the_baseline_is_the_most_thrust_among_the_runs_that_hold_the_limit():
    baseline = cfd_baseline(RECORDS, 50.0)
    holding = [c for c in baseline.candidates if c.peak_power_w <= 50.0]
    assert baseline.best is not None and holding
    assert baseline.best.mean_thrust_n == max(c.mean_thrust_n for c in holding)
    assert all(c.peak_power_w > 50.0 for c in baseline.candidates
               if c.mean_thrust_n > baseline.best.mean_thrust_n)
    assert cfd_baseline(RECORDS, 1.0).best is None  # none holds a 1 W limit


def test_the_best_motion_within_the_limit_is_set_against_it_with_its_error():
    baseline = cfd_baseline(RECORDS, 50.0)
    b = baseline.best

    def outcome(thrust, se, peak):
        return SimpleNamespace(comparison=SimpleNamespace(
            cfd_mean_thrust=thrust, cfd_thrust_standard_error=se, cfd_mean_power=20.0,
            cfd_max_power=peak))

    backtests = {"best sinusoid": outcome(40.0, 0.1, 49.0),  # the sweep's: not a candidate
                 "β = 0": outcome(60.0, 0.3, 170.0),  # beyond the limit
                 "β = 0 polished": outcome(1.2 * b.mean_thrust_n, 0.5, 48.0),
                 "β = 0.5": outcome(5.0, 0.1, 20.0)}
    pair = best_motion_within(backtests, 50.0, baseline)
    assert pair.label == "β = 0 polished" and pair.gain == pytest.approx(0.2)
    expected = np.hypot(0.5 / b.mean_thrust_n,
                        1.2 * b.thrust_standard_error_n / b.mean_thrust_n)
    assert pair.gain_standard_error == pytest.approx(expected)
    assert best_motion_within({"β = 0": backtests["β = 0"]}, 50.0, baseline) is None


def test_a_record_that_is_not_a_sinusoid_is_refused_by_name():
    grid = read_records(fixture_dir("table1_grid"))[0]
    with pytest.raises(MfflapError, match=f"{grid.name}: not a harmonic motion"):
        sinusoid_in_cfd(grid)
