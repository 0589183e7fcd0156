"""An actuator's bandwidth: the equality rows vanish exactly on motions within the band,
the projection keeps what is in it, the chatter measure tells a smooth motion from one that
alternates sample to sample, and the vortex polish delivers motions within the band."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mfflap.errors import ConfigError
from mfflap.kinematics.discrete import DiscreteMotion
from mfflap.optimisation.bandwidth import (
    MAX_HIGH_FREQUENCY_SHARE,
    band_limited,
    bandwidth_rows,
    high_frequency_share,
    motion_chatter,
)


def _harmonic(n, k, shift):
    """The k-th harmonic of the flapping frequency over the half period's samples, written
    apart from the module: the antisymmetric extension's samples at (j + 1/2) dt."""
    t = (np.arange(n) + 0.5) / (2 * n)  # in periods
    return np.sin(2 * np.pi * k * t + shift)


@settings(max_examples=60, deadline=None)
@given(n=st.integers(6, 80), highest=st.integers(1, 40), seed=st.integers(0, 2**31))
def test_rows_vanish_on_the_band_and_the_projection_keeps_it(n, highest, seed):
    rng = np.random.default_rng(seed)
    odd = list(range(1, n + 1, 2))
    inside = [k for k in odd if k <= highest]
    outside = [k for k in odd if k > highest]
    u = sum(rng.normal() * _harmonic(n, k, rng.uniform(0, np.pi)) for k in inside)
    w = sum(rng.normal() * _harmonic(n, k, rng.uniform(0, np.pi)) for k in outside[:3]) \
        if outside else np.zeros(n)
    rows = bandwidth_rows(n, highest)
    # two rows a harmonic above the band on each channel; the N-th (N odd) has its sine only
    per_channel = sum(1 if k == n else 2 for k in outside)
    assert rows.shape == (2 * per_channel, 2 * n + 1)
    z = np.concatenate([u, 0.5 * u, [0.01]])
    assert np.abs(rows @ z).max(initial=0.0) <= 1e-9 * (1 + np.abs(z).max())
    motion = DiscreteMotion(u + w, u - w, 0.01)
    limited = band_limited(motion, highest)
    assert limited.pitch_acceleration == pytest.approx(u, abs=1e-9 * (1 + np.abs(u).max()))
    if outside and np.abs(w).max() > 1e-6:
        zw = np.concatenate([w, w, [0.0]])
        assert np.abs(rows @ zw).max() > 1e-6 * np.abs(w).max()
    again = band_limited(limited, highest)
    assert again.heave_acceleration == pytest.approx(limited.heave_acceleration, abs=1e-12)


def test_the_chatter_measure_tells_alternation_from_a_smooth_optimum():
    n = 50
    smooth = 20 * _harmonic(n, 1, 0.3) + 4 * _harmonic(n, 3, 1.0)
    alternating = smooth + 0.25 * 20 * (-1.0) ** np.arange(n)
    assert high_frequency_share(smooth) < 1e-12
    assert high_frequency_share(alternating) > 0.02
    assert motion_chatter(DiscreteMotion(alternating, smooth, 0.01))[1] < 1e-12
    assert high_frequency_share(np.zeros(n)) == 0.0


def test_a_bandwidth_without_the_first_harmonic_is_refused():
    with pytest.raises(ConfigError, match="bandwidth_harmonics"):
        bandwidth_rows(50, 0)


def test_the_polish_delivers_a_motion_within_the_band():
    """The polish's rounds hold the band at every SQP iterate: its motion has no energy
    above the band, whatever the vortex model's offsets ask for."""
    from mfflap.hydro.discrete_vortex import VortexModelSettings
    from mfflap.hydro.morison import MorisonModel
    from mfflap.optimisation.problem import FlappingProblem
    from mfflap.optimisation.vortex_polish import polish_on_vortex_model
    from mfflap.optimisation.vortex_problem import VortexFlappingProblem

    n = 16
    j = np.arange(n)
    start = DiscreteMotion(-20 * _harmonic(n, 1, 0.0) + 3 * (-1.0) ** j,
                           -4 * _harmonic(n, 1, 1.2), 0.05)
    vortex = VortexFlappingProblem(VortexModelSettings(wake_chords=0.5, chord_points=16),
                                   cycles=2)
    result = polish_on_vortex_model(FlappingProblem(MorisonModel(), max_power=5.0), vortex,
                                    start, min_period=0.5, max_period=3.0, max_rounds=2,
                                    steps_per_period=40, bandwidth_harmonics=3)
    rows = bandwidth_rows(n, 3)
    z = np.real(result.motion.controls())
    scale = np.real(result.motion.control_scales())
    # the candidates are rounded to QUANTUM of their scales: within that, on the band
    assert np.abs(rows @ z).max() <= 1e-3 * scale[:2 * n].max()
    assert max(motion_chatter(result.motion)) <= MAX_HIGH_FREQUENCY_SHARE
