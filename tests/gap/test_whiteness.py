"""The whiteness test against AR(1) noise: it passes noise of any correlation at about its
significance level and rejects a residual that follows the motion."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.stats import kstest

from mfflap.gap.whiteness import ar1_innovations, ljung_box, residual_whiteness
from mfflap.hydro.loads import Loads
from mfflap.identification.data import CaseData
from mfflap.kinematics.state import KinematicState


def ar1(rng: np.random.Generator, n: int, rho: float) -> np.ndarray:
    """AR(1) noise written out here, independently of the blind test's generator."""
    out = np.zeros(n)
    shocks = rng.normal(size=n)
    for i in range(1, n):
        out[i] = rho * out[i - 1] + shocks[i]
    return out


@pytest.mark.parametrize("rho", [0.0, 0.5, 0.95])
def test_ar1_noise_passes_at_about_the_significance_level(rho):
    """On noise alone the p-values are uniform, so a 1 % test rejects about 1 % of series."""
    from scipy.stats import chi2

    rng = np.random.default_rng(int(rho * 100))
    p = []
    for _ in range(300):
        q, lags = ljung_box(ar1_innovations(ar1(rng, 600, rho)))
        p.append(chi2.sf(q, lags - 1))
    assert kstest(p, "uniform").pvalue > 1e-3
    assert np.mean(np.array(p) < 0.01) < 0.04


def _case(name: str, signal: np.ndarray) -> CaseData:
    t = np.linspace(0.0, 6.0, len(signal))
    zero = np.zeros_like(t)
    return CaseData(name, {}, KinematicState(t, zero, zero, zero, zero, zero, zero),
                    Loads(t, signal, signal.copy(), signal.copy()))


def test_a_residual_that_follows_the_motion_is_not_noise():
    rng = np.random.default_rng(3)
    t = np.linspace(0.0, 6.0, 600)
    zero = {k: np.zeros(600) for k in ("normal_force", "tangential_force", "moment")}
    noise = [_case(f"c{i}", ar1(rng, 600, 0.9)) for i in range(10)]
    assert residual_whiteness(noise, [zero] * 10, 0.01).within_noise
    # the second harmonic of a 1 Hz motion, its amplitude 1.5 noise standard deviations
    # (smooth residuals much below the noise pass for noise: the whitening takes them too)
    size = 1.5 * np.std(ar1(rng, 600, 0.9))
    mixed = [_case(f"c{i}", ar1(rng, 600, 0.9) + size * np.sin(4 * np.pi * t))
             for i in range(10)]
    test = residual_whiteness(mixed, [zero] * 10, 0.01)
    assert not test.within_noise and test.p_value < 1e-4
    assert "Ljung-Box" in test.said() and test.as_dict()["n_series"] == 30
