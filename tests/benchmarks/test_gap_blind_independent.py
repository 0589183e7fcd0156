"""The gap diagnosis on effects written apart from its candidates
(benchmarks/gap_blind_independent.py): its goals on a few datasets of each effect, and the
benchmark's own forms against their limits."""

from __future__ import annotations

import numpy as np
import pytest

from mfflap.config import CaseConfig
from mfflap.gap.workflow import diagnose_cases
from mfflap.kinematics.continuous import HarmonicMotion


@pytest.fixture(scope="module")
def bench(load_benchmark):
    return load_benchmark("gap_blind_independent.py")


def test_the_textbook_forms_meet_their_limits(bench):
    """Quasi-steady lift of a plate held at a small incidence is 2 pi alpha q S; Wagner's
    lag of a constant input is the input; the Polhamus force of a plate at 90 deg is
    K_v q S; Blasius friction at Re 1e4 has C_f = 0.0133."""
    rng = np.random.default_rng(0)
    c, s, rho, nu, u = 0.16, 0.18, 1000.0, 1e-6, 0.3
    t = np.linspace(0.0, 5.0, 501)
    still = HarmonicMotion(1.0, 0.0, 0.0).sample(t)
    alpha = np.radians(2.0)
    object.__setattr__(still, "pitch_angle", np.full_like(t, alpha))
    q_s = 0.5 * rho * u**2 * c * s
    lift = bench.effect_loads("thin_aerofoil_lift", still, c, s, rho, nu, u, rng)
    assert lift.normal_force == pytest.approx(-2 * np.pi * q_s * np.sin(alpha) * np.cos(alpha))
    lagged = bench.effect_loads("wagner_relative_flow", still, c, s, rho, nu, u, rng)
    assert lagged.normal_force == pytest.approx(lift.normal_force)
    upright = HarmonicMotion(1.0, 0.0, 0.0).sample(t)
    object.__setattr__(upright, "pitch_angle", np.full_like(t, np.pi / 2))
    vortex = bench.effect_loads("polhamus_normal_force", upright, c, s, rho, nu, u, rng)
    assert vortex.normal_force == pytest.approx(-np.pi * q_s)
    fast = HarmonicMotion(1.0, 0.0, 0.0).sample(t)
    friction = bench.effect_loads("laminar_friction", fast, c, s, rho, 0.3 * c / 1e4, u, rng)
    assert friction.tangential_force == pytest.approx(2 * q_s * 1.328 / 100.0)


@pytest.mark.slow
def test_the_diagnosis_meets_the_goals_on_independent_effects(bench):
    """Three datasets of each effect (forty of none): every in-library effect attributed,
    at most 5 % of the null datasets called anything but noise, at least two thirds of the
    out-of-library ones called structured and unexplained (docs/findings/gap_diagnosis.md
    has 20 of each)."""
    said = bench.run(trials=3, progress=lambda _: None)
    config = CaseConfig()
    said["none"] = [bench.outcome(diagnose_cases(config, bench.dataset(
        "none", 50000 + k, config, 3.0))[0]) for k in range(40)]
    scores = bench.scores(said)
    assert scores["in_library_attributed"] >= 0.9, said
    assert scores["null_false_alarms"] <= 0.05, said["none"]
    assert scores["out_of_library_structured"] >= 2 / 3, said
