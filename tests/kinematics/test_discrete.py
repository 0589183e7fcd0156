import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mfflap.errors import MotionError
from mfflap.kinematics import (
    DiscreteMotion,
    HarmonicMotion,
    PeriodicSplineMotion,
    RampHarmonicMotion,
    harmonic_to_discrete,
    resample,
    to_discrete,
    to_spline,
)


def random_controls(rng, n=40, batch=()):
    return DiscreteMotion(rng.normal(size=(*batch, n)) * 20, rng.normal(size=(*batch, n)) * 5,
                          0.01 if not batch else rng.uniform(0.005, 0.02, size=batch))


def test_trajectory_closes_antisymmetrically(rng):
    m = random_controls(rng, 37)
    tr = m.trajectory()
    for k, v in tr.items():
        assert abs(v[-1] + v[0]) < 1e-12 * max(1, np.abs(v).max()), k


def test_initial_state_formula_matches_stepping(rng):
    # integrate the semi-implicit Euler steps by hand from the closed-form x_1
    m = random_controls(rng, 11)
    dt = m.time_step
    n = m.n_steps
    acc = m.pitch_acceleration
    rate = -(dt / 2) * acc.sum()
    angle = dt**2 / 4 * sum((2 * j - n - 2) * acc[j - 1] for j in range(1, n + 1))
    tr = m.trajectory()
    for j in range(n):
        assert np.isclose(tr["pitch_rate"][j], rate, atol=1e-13)
        assert np.isclose(tr["pitch_angle"][j], angle, atol=1e-13)
        rate = rate + dt * acc[j]
        angle = angle + dt * rate
    assert np.isclose(rate, -tr["pitch_rate"][0]) and np.isclose(angle, -tr["pitch_angle"][0])


@pytest.mark.parametrize("phase", [0.3, np.pi / 2, 2.0])
def test_sinusoid_to_controls_reproduces_samples(phase):
    motion = HarmonicMotion(1.3, 0.25, np.deg2rad(30), phase)
    n = 64
    period = 1 / 1.3
    d = to_discrete(motion, period, n)
    t = np.arange(n) * period / (2 * n)
    ref = motion.sample(t)
    s = d.states()
    np.testing.assert_allclose(s.pitch_angle, ref.pitch_angle, atol=1e-14)
    np.testing.assert_allclose(s.heave_position, ref.heave_position, atol=1e-14)
    # backward-difference rates of the samples
    prev = motion.sample(t - period / (2 * n))
    np.testing.assert_allclose(s.heave_velocity,
                               (ref.heave_position - prev.heave_position) / (period / (2 * n)),
                               atol=1e-11)


def test_batched_harmonic_conversion_matches_single():
    f = np.array([0.5, 1.0, 2.0])
    d = harmonic_to_discrete(f, 0.2, 0.3, np.pi / 2, 30)
    for i in range(3):
        single = to_discrete(HarmonicMotion(f[i], 0.2, 0.3, np.pi / 2), 1 / f[i], 30)
        np.testing.assert_allclose(d.pitch_acceleration[i], single.pitch_acceleration,
                                   rtol=1e-10)
        np.testing.assert_allclose(d.time_step[i], single.time_step)


def test_ramp_derivatives_match_finite_differences():
    m = RampHarmonicMotion(0.7, 0.3, 0.2, 1.0)
    t = np.linspace(0.1, 3, 50)
    h = 1e-6
    s, sp, sm = m.sample(t), m.sample(t + h), m.sample(t - h)
    np.testing.assert_allclose(s.pitch_rate, (sp.pitch_angle - sm.pitch_angle) / (2 * h),
                               atol=1e-7)
    np.testing.assert_allclose(s.pitch_acceleration, (sp.pitch_rate - sm.pitch_rate) / (2 * h),
                               atol=1e-6)
    np.testing.assert_allclose(s.heave_acceleration,
                               (sp.heave_velocity - sm.heave_velocity) / (2 * h), atol=1e-6)
    np.testing.assert_allclose(m.sample(np.array([0.0])).pitch_angle, 0.0)


def test_spline_and_resample_round_trip():
    motion = HarmonicMotion(1.0, 0.3, 0.4, np.pi / 2)
    d = to_discrete(motion, 1.0, 50)
    spline = to_spline(d)
    t = np.linspace(0, 2, 333)
    np.testing.assert_allclose(spline.sample(t).pitch_angle, motion.sample(t).pitch_angle,
                               atol=2e-5)
    fine = resample(d, 200)
    np.testing.assert_allclose(fine.states().pitch_angle[::4], d.states().pitch_angle,
                               atol=1e-12)
    assert fine.n_steps == 200 and np.isclose(fine.period, 1.0)


@pytest.mark.parametrize(
    "make",
    [
        lambda: DiscreteMotion(np.array([1.0, np.nan]), np.zeros(2), 0.1),
        lambda: DiscreteMotion(np.zeros(4), np.zeros(4), 0.0),
        lambda: DiscreteMotion(np.zeros(4), np.zeros(4), -1.0),
        lambda: DiscreteMotion(np.zeros(1), np.zeros(1), 0.1),
        lambda: DiscreteMotion(np.zeros(3), np.zeros(4), 0.1),
        lambda: HarmonicMotion(0.0, 0.1, 0.1),
        lambda: HarmonicMotion(1.0, np.inf, 0.1),
        lambda: PeriodicSplineMotion(-1.0, np.zeros(8), np.zeros(8)),
        lambda: HarmonicMotion(1.0, 0.1, 0.1).sample(np.array([0.0, 0.2, 0.1])),
        lambda: HarmonicMotion(1.0, 0.1, 0.1).sample(np.array([0.0, np.nan])),
        lambda: to_discrete(HarmonicMotion(1.0, 0.1, 0.1), 0.0, 10),
        lambda: to_discrete(HarmonicMotion(1.0, 0.1, 0.1), 1.0, 1),
    ],
)
def test_bad_motion_input_is_refused(make):
    with pytest.raises(MotionError):
        make()


@settings(max_examples=40, deadline=None)
@given(n=st.integers(2, 80), seed=st.integers(0, 2**31))
def test_closure_property(n, seed):
    rng = np.random.default_rng(seed)
    m = DiscreteMotion(rng.normal(size=n), rng.normal(size=n), float(rng.uniform(1e-3, 1)))
    tr = m.trajectory()
    for v in tr.values():
        assert abs(v[-1] + v[0]) <= 1e-9 * (1 + np.abs(v).max())
