"""A case's retry log: JSON lines appended across calls, a line cut short by a killed
process dropped, a damaged line named, and the text log of an earlier mfflap counted."""

import pytest

from mfflap.cfd.openfoam.retry_log import (
    LEGACY_RETRY_LOG,
    RETRY_LOG,
    append_retry,
    budget_retries,
    describe_retries,
    read_retry_log,
    request_rerun,
)
from mfflap.errors import ParseError
from mfflap.records.retries import FORCES_BEYOND_BOUND, TIME_STEP_COLLAPSED, Retry

FIRST = Retry(TIME_STEP_COLLAPSED, 0.7, 0.5, "the inletOutlet far field")
SECOND = Retry(FORCES_BEYOND_BOUND, 1.2, 1.0, "maxCo 2", 4.0)


def test_retries_are_kept_across_calls_and_a_rerun_request_starts_a_new_budget(tmp_path):
    assert read_retry_log(tmp_path) == ([], []) and budget_retries(tmp_path) == ([], 0)
    append_retry(tmp_path, FIRST)
    append_retry(tmp_path, SECOND)
    assert budget_retries(tmp_path) == ([FIRST, SECOND], 0)
    request_rerun(tmp_path)
    assert budget_retries(tmp_path) == ([], 0)
    append_retry(tmp_path, FIRST)
    assert budget_retries(tmp_path) == ([FIRST], 0)
    assert len(read_retry_log(tmp_path)[0]) == 4  # every one is kept
    assert describe_retries(tmp_path)[2] == "rerun requested: a new budget of retries from here"


def test_a_line_cut_short_by_a_killed_process_is_dropped_and_a_damaged_one_named(tmp_path):
    append_retry(tmp_path, FIRST)
    log = tmp_path / RETRY_LOG
    with open(log, "a") as fh:
        fh.write(SECOND.to_json()[:20])  # no newline: the write was cut short
    assert read_retry_log(tmp_path) == ([FIRST], [])
    log.write_text(FIRST.to_json() + "\n" + SECOND.to_json()[:20] + "\n")
    with pytest.raises(ParseError) as caught:
        read_retry_log(tmp_path)
    assert (caught.value.path, caught.value.line) == (str(log), 2)


def test_the_text_log_of_an_earlier_mfflap_counts_against_the_budget(tmp_path):
    (tmp_path / LEGACY_RETRY_LOG).write_text(
        "time step collapsed; resumed with maxCo 1\n"
        "rerun requested: a new budget of retries from here\n"
        "time step collapsed; resumed with maxCo 0.5\n")
    assert budget_retries(tmp_path) == ([], 1)
    append_retry(tmp_path, SECOND)
    assert budget_retries(tmp_path) == ([SECOND], 1)
    assert describe_retries(tmp_path)[0] == "time step collapsed; resumed with maxCo 1"
    request_rerun(tmp_path)
    assert budget_retries(tmp_path) == ([], 0)
