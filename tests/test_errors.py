"""mfflap's errors keep their message and context when they cross a process boundary."""

import pickle
from concurrent.futures import ProcessPoolExecutor

import pytest

from mfflap.errors import CfdRunError, ConfigError, MotionError, ParseError

ERRORS = [
    CfdRunError("time step collapsed to 6.2e-11 s", case="/runs/f1", log_tail="deltaT = 6e-11"),
    ConfigError("must be > 0, got 0.0", source="setups.toml", key="a.max_courant"),
    ParseError("3 columns, expected 10", path="force.dat", line=17),
    MotionError("NaN in the heave samples"),
]


@pytest.mark.parametrize("error", ERRORS, ids=lambda e: type(e).__name__)
def test_error_survives_pickling_with_its_context(error):
    copy = pickle.loads(pickle.dumps(error))
    assert type(copy) is type(error)
    assert str(copy) == str(error)
    assert vars(copy) == vars(error)


def _raise(error: Exception) -> None:
    raise error


def test_error_raised_in_a_worker_process_arrives_whole():
    error = ERRORS[0]
    with ProcessPoolExecutor(max_workers=1) as pool:
        with pytest.raises(CfdRunError) as caught:
            pool.submit(_raise, error).result()
    assert caught.value.case == "/runs/f1"
    assert "time step collapsed" in str(caught.value)
    assert caught.value.log_tail == "deltaT = 6e-11"
