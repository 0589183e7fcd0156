import numpy as np
import pytest

from mfflap.hydro import MorisonModel


@pytest.fixture()
def model() -> MorisonModel:
    return MorisonModel()


@pytest.fixture()
def rng() -> np.random.Generator:
    return np.random.default_rng(12345)
