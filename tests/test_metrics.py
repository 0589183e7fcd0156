import numpy as np
import pytest

from mfflap.errors import MfflapError
from mfflap.metrics import cosine_similarity, nrmse, pearson


def test_nrmse_hand_value():
    ref = np.array([0.0, 1.0, 2.0, 3.0])  # range 3
    pred = ref + np.array([1.0, -1.0, 1.0, -1.0])  # RMS error 1
    assert np.isclose(nrmse(pred, ref), 1 / 3)
    assert nrmse(ref, ref) == 0.0


def test_nrmse_constant_reference():
    assert nrmse([1.0, 1.0], [1.0, 1.0]) == 0.0
    assert np.isinf(nrmse([1.0, 2.0], [1.0, 1.0]))


def test_pearson_hand_values():
    x = np.linspace(0, 1, 11)
    assert np.isclose(pearson(2 * x + 3, x), 1.0)
    assert np.isclose(pearson(-x, x), -1.0)
    t = np.linspace(0, 2 * np.pi, 1000, endpoint=False)
    assert abs(pearson(np.sin(t), np.cos(t))) < 1e-12  # quadrature signals
    assert np.isclose(pearson(np.sin(t + 0.3), np.sin(t)), np.cos(0.3), atol=1e-12)
    assert np.isnan(pearson(np.ones(5), x[:5]))


def test_batched_metrics_along_last_axis():
    ref = np.stack([np.arange(5.0), np.arange(5.0) * 2])
    pred = ref + 1
    np.testing.assert_allclose(nrmse(pred, ref), [1 / 4, 1 / 8])


def test_cosine_similarity():
    assert np.isclose(cosine_similarity([1, 0], [0, 1]), 0.0)
    assert np.isclose(cosine_similarity([1, 2], [2, 4]), 1.0)
    assert np.isnan(cosine_similarity([0, 0], [1, 1]))


@pytest.mark.parametrize(("a", "b"), [([1.0, np.nan], [1.0, 2.0]), ([1.0, 2.0], [1.0]),
                                      ([1.0], [1.0])])
def test_bad_metric_input(a, b):
    with pytest.raises(MfflapError):
        nrmse(a, b)
