"""The model ladder's CFD figures on a real OpenFOAM back-test: time averages over the
solver's adaptive samples, not plain means of them."""

from __future__ import annotations

import numpy as np
import pytest

from mfflap.backtest.model_ladder import compare_model_ladder
from mfflap.metrics import time_mean
from mfflap.performance import thrust_and_power
from mfflap.records.record import fixture_dir, read_records


def test_cfd_means_weigh_each_sample_by_its_share_of_the_time():
    """The best sinusoid's run samples its fast parts densely: a plain mean over its samples
    differs from the time average by more than the test's tolerance, and the ladder gives
    the time average (as the back-test's comparison does)."""
    record = next(r for r in read_records(fixture_dir("backtest_main_job"))
                  if r.parameters.get("label") == "best sinusoid")
    ladder = compare_model_ladder(record, periods=2.0, steps_per_period=50)
    _, start = record.last_periods(2.0)
    t = record.state.time
    window = t >= start
    thrust, power = thrust_and_power(record.loads, record.state)
    assert ladder.cfd.mean_thrust == pytest.approx(time_mean(t[window], thrust[window]),
                                                   rel=1e-12)
    assert ladder.cfd.mean_power == pytest.approx(time_mean(t[window], power[window]),
                                                  rel=1e-12)
    assert abs(np.mean(thrust[window]) / ladder.cfd.mean_thrust - 1) > 0.02
    assert ladder.cfd.peak_power == pytest.approx(float(np.max(power[window])))
