"""mfflap's errors keep their message and context when they cross a process boundary."""

import pickle
from concurrent.futures import ProcessPoolExecutor

import pytest

from mfflap.errors import (
    TIME_STEP_COLLAPSED,
    CfdRunError,
    ConfigError,
    MotionError,
    ParseError,
    RepeatedTimes,
    RunStoppedByWatch,
    SolverDiverged,
    UnreadableRecordError,
)

ERRORS = [
    SolverDiverged("pimpleFoam diverged", case="/runs/f1", log_tail="deltaT = 6e-11",
                   kind=TIME_STEP_COLLAPSED, time_s=0.75),
    RunStoppedByWatch("pimpleFoam stopped: beyond the bound", case="/runs/f1",
                      reason="beyond the bound"),
    RepeatedTimes("time does not increase after t = 10.5", path="force.dat", time_s=10.5),
    UnreadableRecordError("its data cannot be read", path="r.h5", dataset="loads"),
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
    assert type(caught.value) is SolverDiverged
    assert caught.value.case == "/runs/f1"
    assert caught.value.kind == TIME_STEP_COLLAPSED and caught.value.time_s == 0.75
    assert "pimpleFoam diverged" in str(caught.value)
    assert caught.value.log_tail == "deltaT = 6e-11"
