import itertools

import numpy as np
import pytest

from mfflap.hydro import MorisonModel
from mfflap.kinematics import harmonic_to_discrete
from mfflap.performance import evaluate_discrete
from mfflap.sweep import pareto_front, sinusoid_sweep


def test_pareto_front_hand_example():
    thrust = np.array([1.0, 2.0, 1.5, 3.0, 2.5, 0.5])
    power = np.array([1.0, 2.0, 3.0, 4.0, 4.0, 0.5])
    front = pareto_front(thrust, power)
    assert list(front) == [5, 0, 1, 3]  # (0.5, 0.5), (1, 1), (2, 2), (3, 4)


def test_pareto_points_are_not_dominated(rng):
    t, p = rng.normal(size=200), rng.normal(size=200)
    front = set(pareto_front(t, p).tolist())
    for i in range(200):
        dominated = np.any((t >= t[i]) & (p <= p[i]) & ((t > t[i]) | (p < p[i])))
        assert (i in front) == (not dominated)


def test_sweep_matches_single_evaluations_and_feasibility():
    model = MorisonModel()
    res = sinusoid_sweep(model, [0.5, 1.0], [0.1, 0.3], np.deg2rad([10, 30]),
                         np.deg2rad([45, 90]), n_steps=30, max_power=50.0, chunk=5)
    assert res.mean_thrust.size == 16
    for i in (0, 7, 15):
        d = harmonic_to_discrete(res.frequency[i], res.heave_amplitude[i],
                                 res.pitch_amplitude[i], res.phase[i], 30)
        s = evaluate_discrete(model, d).summary
        assert np.isclose(s.mean_thrust, res.mean_thrust[i], rtol=1e-12)
        assert res.feasible[i] == (s.max_power <= 50.0)
    best = res.best_feasible()
    assert res.feasible[best]
    assert np.all(res.mean_thrust[res.feasible] <= res.mean_thrust[best])
    assert not res.feasible.all()  # 1 Hz, 0.3 m is beyond 50 W


@pytest.mark.parametrize("scheme", ["paper", "midpoint"])
def test_compiled_sweep_kernel_equals_the_array_evaluation(scheme):
    """The fused numba kernel evaluates exactly what evaluate_discrete evaluates."""
    from mfflap.hydro import MorisonModel

    model = MorisonModel()
    args = (np.linspace(0.1, 2.5, 7), np.linspace(0.0, 0.5, 5), np.deg2rad([0, 15, 40, 70]),
            np.deg2rad([0, 45, 90, 170]))
    fast = sinusoid_sweep(model, *args, n_steps=40, max_power=30.0, scheme=scheme)
    slow = sinusoid_sweep(model, *args, n_steps=40, max_power=30.0, scheme=scheme,
                          compiled=False)
    for key in ("mean_thrust", "mean_power", "max_power", "strouhal_number", "efficiency"):
        a, b = getattr(fast, key), getattr(slow, key)
        ok = np.isfinite(b)
        np.testing.assert_array_equal(np.isfinite(a), ok)
        np.testing.assert_allclose(a[ok], b[ok], rtol=1e-9,
                                   atol=1e-12 * np.nanmax(np.abs(b[ok])))
    np.testing.assert_array_equal(fast.feasible, slow.feasible)


def test_compiled_sweep_in_small_blocks_reports_progress_and_keeps_the_grid_order():
    """Several kernel calls (blocks of (f, theta, phi) groups) fill the C-ordered grid."""
    from mfflap.hydro import MorisonModel

    model = MorisonModel()
    args = (np.array([0.4, 1.3, 2.0]), np.array([0.0, 0.2, 0.45]), np.deg2rad([10, 50]),
            np.deg2rad([30, 90, 150]))
    seen = []
    fast = sinusoid_sweep(model, *args, n_steps=20, chunk=4,
                          progress=lambda done, total: seen.append((done, total)))
    assert len(seen) > 3 and seen[-1] == (54, 54)
    assert all(a[0] < b[0] for a, b in itertools.pairwise(seen))
    for i in (0, 13, 31, 53):
        one = sinusoid_sweep(model, fast.frequency[i], fast.heave_amplitude[i],
                             fast.pitch_amplitude[i], fast.phase[i], n_steps=20, compiled=False)
        assert np.isclose(one.mean_thrust[0], fast.mean_thrust[i], rtol=1e-10)
        assert np.isclose(one.max_power[0], fast.max_power[i], rtol=1e-10)
