"""A case's retry log: every retry of its runs across the calls that ran it, as JSON lines
of :class:`~mfflap.records.retries.Retry`, so that a run resumed after its process was killed
goes on with what is left of its retry budget and its record keeps every retry.

A case written before the log was JSON may hold the text log ``mfflap_retries.txt``; its
lines count against the budget (as retries whose fields are not known) and are kept in the
record as they are.
"""

from __future__ import annotations

from pathlib import Path

from mfflap.records.retries import RERUN_REQUESTED, Retry

#: every retry of a case, one JSON object a line, across the calls that ran it
RETRY_LOG = "mfflap_retries.jsonl"
#: the text log of cases written before the log was JSON
LEGACY_RETRY_LOG = "mfflap_retries.txt"
_LEGACY_RERUN = "rerun requested: a new budget of retries from here"


def append_retry(case_dir: str | Path, retry: Retry) -> None:
    """Add ``retry`` to the case's log."""
    with open(Path(case_dir) / RETRY_LOG, "a") as fh:
        fh.write(retry.to_json() + "\n")


def request_rerun(case_dir: str | Path) -> None:
    """Give a case that failed after its retries a new budget of retries for its next run
    (a campaign's ``--retry-failed``). Its earlier retries stay in the log and in the
    record's provenance; its settings keep every remedy they had."""
    case_dir = Path(case_dir)
    if case_dir.is_dir():
        append_retry(case_dir, Retry(RERUN_REQUESTED, None, None, ""))


def read_retry_log(case_dir: str | Path) -> tuple[list[Retry], list[str]]:
    """Every retry in the case's log, rerun requests included, and the lines of a text log
    of an earlier mfflap (``[]`` if none).

    Raises
    ------
    ParseError
        Naming the log and the line, for a line that is not a retry (a line cut short by a
        killed process is the last one and is dropped).
    """
    case_dir = Path(case_dir)
    log = case_dir / RETRY_LOG
    retries: list[Retry] = []
    if log.is_file():
        text = log.read_text()
        lines = text.split("\n")
        if not text.endswith("\n"):  # the last line cut short by a killed process
            lines = lines[:-1]
        retries = [Retry.from_json(line, str(log), k + 1)
                   for k, line in enumerate(lines) if line.strip()]
    legacy = case_dir / LEGACY_RETRY_LOG
    earlier = ([line for line in legacy.read_text().splitlines() if line.strip()]
               if legacy.is_file() else [])
    return retries, earlier


def budget_retries(case_dir: str | Path) -> tuple[list[Retry], int]:
    """The retries that count against the case's budget: those since its last rerun request,
    and how many lines of a text log before them count too."""
    retries, earlier = read_retry_log(case_dir)
    requests = [k for k, r in enumerate(retries) if r.cause == RERUN_REQUESTED]
    if requests:
        return retries[requests[-1] + 1:], 0
    if _LEGACY_RERUN in earlier:
        earlier = earlier[len(earlier) - earlier[::-1].index(_LEGACY_RERUN):]
    return retries, len(earlier)


def retry_lines(retries: list[Retry], earlier: list[str]) -> list[str]:
    """A read retry log (:func:`read_retry_log`) in words, one line a retry, rerun requests
    included."""
    return earlier + [r.describe() for r in retries]


def describe_retries(case_dir: str | Path) -> list[str]:
    """Every retry of the case so far in words, one line each, rerun requests included."""
    return retry_lines(*read_retry_log(case_dir))


__all__ = ["LEGACY_RETRY_LOG", "RETRY_LOG", "append_retry", "budget_retries",
           "describe_retries", "read_retry_log", "request_rerun", "retry_lines"]
