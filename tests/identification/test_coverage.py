"""Where a motion lies against the identification data: ranges and leverage."""

import numpy as np
import pytest

from mfflap.errors import MfflapError
from mfflap.gap.blindtest import trial_cases
from mfflap.hydro import MorisonModel
from mfflap.hydro.loads import Loads
from mfflap.identification.coverage import (
    FEATURE_UNITS,
    CoverageReference,
    _rows,
    motion_features,
)
from mfflap.identification.data import CaseData
from mfflap.kinematics.continuous import HarmonicMotion
from mfflap.kinematics.state import KinematicState

MODEL = MorisonModel()
VELOCITY = 0.3


def _cases(n: int = 10) -> list[CaseData]:
    cases = trial_cases(np.random.default_rng(2), n)
    return [CaseData(c.name, c.parameters, c.state, MODEL.loads(c.state)) for c in cases]


def _scaled(state: KinematicState, factor: float) -> KinematicState:
    """The same motion with every amplitude times ``factor``."""
    return KinematicState(state.time, *(factor * getattr(state, k) for k in (
        "pitch_angle", "pitch_rate", "pitch_acceleration", "heave_position", "heave_velocity",
        "heave_acceleration")))


def test_features_of_a_sinusoid_are_its_amplitudes_and_peaks():
    f, h, th = 0.5, 0.2, np.radians(15.0)
    motion = HarmonicMotion(frequency=f, heave_amplitude=h, pitch_amplitude=th,
                            phase=np.pi / 2)
    state = motion.sample(np.linspace(0, 2 / f, 4001))
    feats = motion_features(state, f, VELOCITY)
    w = 2 * np.pi * f
    assert set(feats) == set(FEATURE_UNITS)
    assert feats["heave amplitude"] == pytest.approx(h, rel=1e-6)
    assert feats["pitch amplitude"] == pytest.approx(15.0, rel=1e-6)
    assert feats["peak |heave velocity|"] == pytest.approx(w * h, rel=1e-5)
    assert feats["peak |pitch acceleration|"] == pytest.approx(w**2 * th, rel=1e-5)
    assert feats["frequency"] == f


def test_the_cases_themselves_lie_within_and_the_leverage_is_the_hat_matrix_diagonal():
    cases = _cases()
    ref = CoverageReference.from_cases(cases, MODEL, VELOCITY)
    ratios = []
    for c in cases:
        cov = ref.check(c.state, c.frequency)
        assert cov.outside == {} and not cov.extrapolated
        assert cov.describe().startswith("within the identification data (leverage ")
        ratios.append(cov.leverage_ratio)
    assert max(ratios) == pytest.approx(1.0)  # the case that holds the largest leverage
    # the leverage is diag(X (X'X)^-1 X'): the squared row norms of Q in X = QR
    rows = np.vstack([_rows(MODEL, c.state, ref.scales) for c in cases])
    q, _ = np.linalg.qr(rows)
    assert ref.max_leverage == pytest.approx(float((q**2).sum(axis=1).max()), rel=1e-9)


def test_a_motion_beyond_the_data_is_called_extrapolated_by_variable_and_by_leverage():
    cases = _cases()
    ref = CoverageReference.from_cases(cases, MODEL, VELOCITY)
    widest = max(cases, key=lambda c: np.ptp(c.state.heave_position))
    cov = ref.check(_scaled(widest.state, 3.0), widest.frequency)
    assert cov.extrapolated and "heave amplitude" in cov.outside
    value, lo, hi = cov.outside["heave amplitude"]
    assert value > hi and value == pytest.approx(3 * np.ptp(widest.state.heave_position) / 2)
    assert cov.leverage_ratio > 1  # drag grows as the square: the rows leave the ellipsoid
    said = cov.describe()
    assert said.startswith("outside the identification data: ")
    assert f"heave amplitude {value:.3g} m (data {lo:.3g}-{hi:.3g})" in said
    assert f"leverage {cov.leverage_ratio:.3g} times the data's largest" in said
    # below the range counts too: a motion far smaller than every case
    small = ref.check(_scaled(widest.state, 0.01), widest.frequency)
    assert "heave amplitude" in small.outside and small.outside["heave amplitude"][0] < lo
    assert small.as_dict()["outside"]["heave amplitude"][1] == lo
    # a motion without a frequency is placed on every other variable
    assert "frequency" not in ref.check(widest.state, float("nan")).outside


def test_a_reference_without_cases_or_without_a_load_component_is_refused():
    with pytest.raises(MfflapError, match="at least one case"):
        CoverageReference.from_cases([], MODEL, VELOCITY)
    c = _cases(2)
    zero = [CaseData(x.name, x.parameters, x.state,
                     Loads(x.state.time, x.cfd.normal_force, 0 * x.cfd.normal_force,
                           x.cfd.moment)) for x in c]
    with pytest.raises(MfflapError, match="tangential_force is zero throughout"):
        CoverageReference.from_cases(zero, MODEL, VELOCITY)


def test_a_motion_at_the_edge_of_the_data_is_within_it_up_to_the_tolerance():
    from mfflap.identification.coverage import RANGE_TOLERANCE

    cases = _cases()
    ref = CoverageReference.from_cases(cases, MODEL, VELOCITY)
    widest = max(cases, key=lambda c: np.ptp(c.state.heave_position))
    hi = ref.ranges["heave amplitude"][1]
    assert np.ptp(widest.state.heave_position) / 2 == pytest.approx(hi)
    just = ref.check(_scaled(widest.state, 1 + 0.5 * RANGE_TOLERANCE), widest.frequency)
    beyond = ref.check(_scaled(widest.state, 1 + 2 * RANGE_TOLERANCE), widest.frequency)
    assert "heave amplitude" not in just.outside and "heave amplitude" in beyond.outside
