"""Mean cycles of periodic runs (mfflap.cfd.phase_average) and their use in the convergence
study (mfflap.campaign.convergence.compare_mean_cycles)."""

from __future__ import annotations

import numpy as np
import pytest

from mfflap.campaign.convergence import (
    ConvergenceRun,
    ConvergenceStudy,
    compare,
    compare_mean_cycles,
)
from mfflap.cfd.phase_average import phase_average, whole_periods
from mfflap.errors import ConfigError, MfflapError
from mfflap.hydro.loads import Loads
from mfflap.kinematics import HarmonicMotion
from mfflap.metrics import nrmse
from mfflap.records.record import CfdRecord

PERIOD_S = 0.8


def cycle_shape(t: np.ndarray) -> np.ndarray:
    """A periodic force with harmonics, N."""
    w = 2 * np.pi / PERIOD_S
    return 100 * np.sin(w * t) + 30 * np.sin(3 * w * t + 0.4) + 5


def uneven_times(end_s: float, seed: int) -> np.ndarray:
    """Sample times with steps of 0.4-1.6 ms, as an adjustable time step writes them."""
    rng = np.random.default_rng(seed)
    steps = rng.uniform(4e-4, 1.6e-3, int(2 * end_s / 4e-4))
    t = np.concatenate([[0.0], np.cumsum(steps)])
    return t[t <= end_s]


def per_cycle_bump(t: np.ndarray, amplitudes: np.ndarray, start_s: float) -> np.ndarray:
    """A different bump in each cycle (the same shape, amplitude amplitudes[k] in cycle k):
    what a vortex that arrives a little differently each cycle adds."""
    k = np.clip(np.floor((t - start_s) / PERIOD_S).astype(int), 0, len(amplitudes) - 1)
    phase = np.mod(t - start_s, PERIOD_S) / PERIOD_S
    return amplitudes[k] * np.exp(-(((phase - 0.6) / 0.05) ** 2))


def test_mean_cycle_of_a_periodic_signal_on_uneven_steps_is_the_cycle():
    t = uneven_times(4 * PERIOD_S + 0.01, seed=1)
    avg = phase_average(t, cycle_shape(t), PERIOD_S, 0.0)
    assert avg.n_cycles == 4
    exact = cycle_shape(avg.phase * PERIOD_S)
    # linear interpolation between samples at most 1.6 ms apart: error < w^2 dt^2 / 8 * A
    w = 2 * np.pi / PERIOD_S
    bound = (100 + 30 * 9) * (w * 1.6e-3) ** 2 / 8
    assert np.max(np.abs(avg.mean - exact)) < bound
    assert np.max(avg.std) < bound
    assert avg.scatter < 1e-4


def test_scatter_is_the_cycle_to_cycle_spread_and_the_mean_averages_it_out():
    start = 0.3
    amplitudes = np.array([20.0, -10.0, 5.0, -15.0])
    t = uneven_times(start + 4 * PERIOD_S + 0.01, seed=2)
    signal = cycle_shape(t) + per_cycle_bump(t, amplitudes, start)
    avg = phase_average(t, signal, PERIOD_S, start, n_phase=512)
    assert avg.n_cycles == 4
    bump = np.exp(-(((avg.phase - 0.6) / 0.05) ** 2))
    expected_mean = cycle_shape(start + avg.phase * PERIOD_S) + amplitudes.mean() * bump
    assert np.max(np.abs(avg.mean - expected_mean)) < 0.05
    expected_std = amplitudes.std(ddof=1) * bump
    assert np.max(np.abs(avg.std - expected_std)) < 0.05
    expected_scatter = np.sqrt(np.mean(expected_std**2)) / np.ptp(expected_mean)
    assert avg.scatter == pytest.approx(expected_scatter, rel=1e-2)
    # fewer cycles on request: the first two only
    two = phase_average(t, signal, PERIOD_S, start, n_cycles=2, n_phase=512)
    assert two.n_cycles == 2
    assert np.max(np.abs(two.mean - (expected_mean - amplitudes.mean() * bump
                                     + amplitudes[:2].mean() * bump))) < 0.05


def test_whole_periods_counts_a_period_that_ends_on_the_last_sample():
    assert whole_periods(0.25, 0.25 + 3 * PERIOD_S, PERIOD_S) == 3
    assert whole_periods(0.25, 0.25 + 3 * PERIOD_S - 1e-6, PERIOD_S) == 2
    assert whole_periods(1.0, 0.5, PERIOD_S) == 0


@pytest.mark.parametrize("kwargs, key", [
    ({"period_s": 0.0}, "period"),
    ({"period_s": -1.0}, "period"),
    ({"start_s": -0.1}, "start"),
    ({"start_s": 5.0}, "start"),
    ({"n_cycles": 4}, "n_cycles"),
    ({"n_cycles": 0}, "n_cycles"),
    ({"n_phase": 1}, "n_phase"),
])
def test_impossible_averages_are_refused_by_key(kwargs, key):
    t = np.linspace(0, 3 * PERIOD_S, 500)
    args = {"period_s": PERIOD_S, "start_s": 0.0, **kwargs}
    with pytest.raises(ConfigError) as err:
        phase_average(t, cycle_shape(t), args.pop("period_s"), args.pop("start_s"), **args)
    assert err.value.key == key


def test_bad_samples_are_refused_with_the_sample():
    t = np.linspace(0, 3 * PERIOD_S, 500)
    t[200] = t[199]
    with pytest.raises(MfflapError, match=r"t\[199\] = .*, t\[200\]"):
        phase_average(t, cycle_shape(t), PERIOD_S, 0.0)
    t = np.linspace(0, 3 * PERIOD_S, 500)
    values = cycle_shape(t)
    values[10] = np.nan
    with pytest.raises(MfflapError, match="NaN or infinite value at index 10"):
        phase_average(t, values, PERIOD_S, 0.0)
    with pytest.raises(MfflapError, match="two or more samples"):
        phase_average(t, values[:-1], PERIOD_S, 0.0)


def run(label: str, end_s: float, bump_amplitudes: np.ndarray, scale: float, seed: int):
    """A synthetic convergence run: every load component is the cycle shape times ``scale``
    plus a bump of ``bump_amplitudes[k]`` in the k-th cycle from one period on (the first
    period has the first bump too)."""
    t = uneven_times(end_s, seed)
    f = scale * cycle_shape(t) + per_cycle_bump(t, bump_amplitudes, PERIOD_S)
    state = HarmonicMotion(1 / PERIOD_S, 0.3, np.deg2rad(20), np.pi / 2).sample(t)
    record = CfdRecord(label, state, Loads(t, f, 0.1 * f, 0.02 * f, source="test"),
                       {"kind": "harmonic"}, {"n_cells": 1})
    return ConvergenceRun(label, label, 4.0, record)


def test_mean_cycles_separate_a_real_difference_from_cycle_to_cycle_scatter():
    """Two runs that differ by 1 % in amplitude and by bumps that change every cycle: point by
    point they differ by much more than 1 %; their mean cycles by about the 1 %, and the
    scatter of each run says how far apart single cycles are."""
    end = 4 * PERIOD_S + 0.005
    fine = run("fine", end, np.array([30.0, -25.0, 5.0]), 1.0, seed=3)
    coarse = run("coarse", end, np.array([-30.0, 25.0, 0.0]), 1.01, seed=4)
    study = ConvergenceStudy([coarse, fine], "fine")
    key = "coarse vs fine"
    study.nrmse[key] = compare(coarse.record, fine.record, PERIOD_S)
    study.pairs[key] = ("coarse", "fine")
    compare_mean_cycles(study, PERIOD_S, PERIOD_S)
    assert study.phase_cycles == 3
    point = study.nrmse[key]["normal_force"]
    mean = study.phase_nrmse[key]["normal_force"]
    # bumps averaged over the three cycles from one period on: (30 - 25 + 5) / 3 against
    # (-30 + 25 + 0) / 3
    t = np.linspace(0, PERIOD_S, 2000, endpoint=False)
    bump = np.exp(-(((t / PERIOD_S - 0.6) / 0.05) ** 2))
    expected = nrmse(1.01 * cycle_shape(t) - (5 / 3) * bump, cycle_shape(t) + (10 / 3) * bump)
    assert mean == pytest.approx(float(expected), rel=0.05)
    assert point > 2 * mean
    for label in ("coarse", "fine"):
        assert study.cycle_scatter[label]["normal_force"] > 0.02
        # every component scaled alike: the same scatter
        assert study.cycle_scatter[label]["moment"] == pytest.approx(
            study.cycle_scatter[label]["normal_force"], rel=1e-9)
    assert study.as_dict()["phase_cycles"] == 3
    assert study.as_dict()["phase_nrmse"][key]["moment"] == pytest.approx(mean, rel=1e-9)


def test_mean_cycles_need_two_whole_periods_in_every_run():
    long = run("long", 4 * PERIOD_S + 0.005, np.zeros(4), 1.0, seed=5)
    short = run("short", 2.9 * PERIOD_S, np.zeros(4), 1.0, seed=6)
    study = ConvergenceStudy([long, short], "long")
    study.pairs["short vs long"] = ("short", "long")
    compare_mean_cycles(study, PERIOD_S, PERIOD_S)
    assert study.phase_cycles == 0 and study.phase_nrmse == {} and study.cycle_scatter == {}
