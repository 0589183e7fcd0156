"""CFD's cycle-to-cycle repeatability of a periodic case (mfflap.identification.repeatability)."""

import numpy as np
import pytest

from mfflap.hydro.loads import Loads
from mfflap.identification.data import CaseData
from mfflap.identification.repeatability import cycle_nrmse
from mfflap.kinematics.continuous import HarmonicMotion


def _case(fn, t, kind="harmonic", frequency=1.0):
    state = HarmonicMotion(1.0, 0.1, 0.2).sample(t)
    return CaseData("c", {"kind": kind, "frequency": frequency}, state,
                    Loads(t, fn, 0 * t, 0 * t))


def test_a_load_that_repeats_has_none_and_one_that_grows_has_its_known_share():
    t = np.linspace(0.0, 4.0, 2001)
    repeating = np.sin(2 * np.pi * t) + 0.3 * np.sin(4 * np.pi * t)
    assert cycle_nrmse(_case(repeating, t)) < 1e-3
    # cycles scaled by 1 - e, 1, 1 + e (a = 1 amplitude, range 2 (1 + e)): each cycle's
    # difference from the mean is e sin, RMS e / sqrt(2), for two of the three cycles
    e = 0.05
    t3 = np.linspace(1.0, 4.0, 3001)
    scale = np.select([t3 < 2.0, t3 < 3.0], [1 - e, 1.0], 1 + e)
    value = cycle_nrmse(_case(scale * np.sin(2 * np.pi * t3), t3))
    expected = np.sqrt(2 / 3) * (e / np.sqrt(2)) / (2 * (1 + e))
    assert value == pytest.approx(expected, rel=0.02)


def test_a_motion_that_does_not_repeat_or_too_short_a_run_has_none():
    t = np.linspace(0.0, 4.0, 401)
    assert np.isnan(cycle_nrmse(_case(np.sin(t), t, kind="ramp_harmonic")))
    assert np.isnan(cycle_nrmse(_case(np.sin(t), t, frequency=0.4)))  # 1.6 cycles
    assert np.isnan(cycle_nrmse(CaseData("c", {}, HarmonicMotion(1.0, 0.1, 0.2).sample(t),
                                         Loads(t, np.sin(t), 0 * t, 0 * t))))
