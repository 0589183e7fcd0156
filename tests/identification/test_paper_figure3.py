"""Figure 3's measures on an identification result (mfflap.identification.paper_figure3):
the grid cases only, the trailing edge's Strouhal number, the paper's bars."""

from types import SimpleNamespace

import numpy as np
import pytest

from mfflap.identification.paper_figure3 import (
    PAPER_MIN_PEARSON,
    figure3_comparison,
)
from mfflap.kinematics.continuous import HarmonicMotion, RampHarmonicMotion


def _case(name, motion, kind, frequency):
    state = motion.sample(np.linspace(1.0, 1.0 + 2.0 / frequency, 400))
    return SimpleNamespace(name=name, state=state, frequency=frequency,
                           parameters={"kind": kind})


def test_only_grid_cases_count_and_the_strouhal_number_is_the_trailing_edges():
    chord, velocity = 0.16, 0.3
    cases = [_case("heave", RampHarmonicMotion(1.0, 0.3, 0.0, np.pi / 2), "ramp_harmonic", 1.0),
             _case("pitching", RampHarmonicMotion(0.5, 0.1, np.radians(10.0), np.pi / 2),
                   "ramp_harmonic", 0.5),
             _case("harmonic", HarmonicMotion(2.0, 0.1, 0.5), "harmonic", 2.0)]
    result = SimpleNamespace(case_names=["heave", "pitching", "harmonic"], metrics={
        "normal_force": {"pearson": np.array([0.95, 0.7, 0.1]),
                         "nrmse": np.array([0.05, 0.2, 0.9])}})
    cmp = figure3_comparison(result, cases, chord, velocity)
    assert cmp.case_names == ("heave", "pitching")  # the harmonic motion is not on the grid
    # pure heave: A = h_amp, St = 2 f h / U
    assert cmp.strouhal[0] == pytest.approx(2 * 1.0 * 0.3 / velocity, rel=1e-3)
    te = cases[1].state.trailing_edge_position(chord)
    assert cmp.strouhal[1] == pytest.approx(0.5 * (te.max() - te.min()) * 2 * 0.5 / velocity)
    assert cmp.min_pearson == 0.7 and cmp.below_paper_pearson == ["pitching"]
    assert cmp.within_bar.tolist() == [True, False]
    assert cmp.strouhal_range_within_bar() == (pytest.approx(2.0, rel=1e-3),) * 2
    rows = {r[0]: r for r in cmp.rows()}
    assert rows[f"cases with Pearson r ≤ {PAPER_MIN_PEARSON}"][1] == 1
