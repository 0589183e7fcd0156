"""Retries as typed records: every cause round-trips through JSON, its words come from its
fields, and what is not a retry is refused with where it was read."""

import json

import pytest

from mfflap.errors import ParseError
from mfflap.records.as_run import as_run_since_s
from mfflap.records.record import CfdRecord
from mfflap.records.retries import (
    CAUSES,
    COURANT_EXPLODED,
    FORCES_BEYOND_BOUND,
    RERUN_REQUESTED,
    SAME_LOSS_AGAIN,
    TIME_STEP_COLLAPSED,
    TIMES_REPEAT,
    Retry,
    legacy_restart_s,
    retries_from_json,
    retries_to_json,
)

EVERY_CAUSE = [
    Retry(TIME_STEP_COLLAPSED, 1.69, 1.5, "the inletOutlet far field"),
    Retry(COURANT_EXPLODED, 0.25, 0.0, "maxCo 2"),
    Retry(TIMES_REPEAT, 10.000001, 9.75, "maxCo 1 and first-order upwind k and epsilon"),
    Retry(FORCES_BEYOND_BOUND, 1.4, 1.125, "maxCo 2", max_courant=4.0),
    Retry(SAME_LOSS_AGAIN, 1.4, 0.0, "max Co 2", max_courant=2.0, earlier_max_courant=4.0),
    Retry(RERUN_REQUESTED, None, None, ""),
]


def test_every_cause_is_covered_and_round_trips_through_json():
    assert {r.cause for r in EVERY_CAUSE} == set(CAUSES)
    for retry in EVERY_CAUSE:
        assert Retry.from_json(retry.to_json()) == retry
    assert retries_from_json(retries_to_json(EVERY_CAUSE)) == EVERY_CAUSE


def test_the_words_are_made_from_the_fields():
    collapsed, _, repeat, breach, again, request = EVERY_CAUSE
    assert collapsed.describe() == ("time step collapsed at t = 1.69 s; resumed from "
                                    "t = 1.5 s with the inletOutlet far field")
    assert "t = 10.000001 s (the force log's times repeat there)" in repeat.describe()
    assert breach.describe().startswith("forces beyond what the motion can drive from "
                                        "t = 1.4 s at max Co 4; resumed from t = 1.125 s")
    assert again.restart() == "rerun from t = 0 s with max Co 2"
    assert "as at max Co 4" in again.describe()
    assert again.from_start and not breach.from_start
    assert request.restart() == ""


@pytest.mark.parametrize("line", ['{"cause": "struck by lightning", "failed_at_s": 1, '
                                  '"resumed_from_s": 0, "remedy": ""}',
                                  '{"cause": "time step collapsed"}', "[1, 2]", "not json",
                                  '{"cause": "time step collapsed", "failed_at_s": 1, '
                                  '"resumed_from_s": 0, "remedy": "", "colour": "red"}'])
def test_a_line_that_is_not_a_retry_is_refused_with_its_path_and_line(line):
    with pytest.raises(ParseError) as caught:
        Retry.from_json(line, "case/mfflap_retries.jsonl", 7)
    assert (caught.value.path, caught.value.line) == ("case/mfflap_retries.jsonl", 7)


def _record(provenance: dict) -> CfdRecord:
    import numpy as np

    from mfflap.hydro.loads import Loads
    from mfflap.kinematics.state import KinematicState

    t = np.linspace(0.0, 1.0, 5)
    zero = np.zeros_like(t)
    state = KinematicState(t, *([zero] * 6))
    return CfdRecord("r", state, Loads(t, zero, zero, zero, source="test"), {}, provenance)


def test_the_settings_hold_since_the_last_retrys_restart_from_its_fields():
    """The record's retry_log decides; its words are not read."""
    breach, again = EVERY_CAUSE[3], EVERY_CAUSE[4]
    misleading = "resumed from t = 99 s with maxCo 1"  # the text is not what is read
    assert as_run_since_s(_record({"retry_log": retries_to_json([breach]),
                                   "retries": misleading})) == 1.125
    assert as_run_since_s(_record({"retry_log": retries_to_json([breach, again])})) == 0.0
    assert as_run_since_s(_record({"retry_log": retries_to_json(
        [breach, EVERY_CAUSE[5]])})) == 1.125  # a rerun request is no restart
    assert as_run_since_s(_record({"retry_log": "[]"})) == 0.0
    with pytest.raises(ParseError, match="r: retry_log"):
        as_run_since_s(_record({"retry_log": json.dumps({"cause": 1})}))


@pytest.mark.parametrize("text, since", [
    ("", 0.0),
    ("time step collapsed; resumed from the last written time with maxCo 2", 0.0),
    ("time step collapsed at t = 6.2 s; resumed from t = 6 s with maxCo 2", 6.0),
    ("forces beyond what the motion can drive from t = 1.4 s at max Co 4; resumed from "
     "t = 1.125 s with maxCo 2; rerun from t = 0 s with max Co 2: again", 0.0),
])
def test_records_written_before_the_retry_log_was_json_are_read_from_their_text(text, since):
    assert legacy_restart_s(text) == since
    assert as_run_since_s(_record({"retries": text})) == since
