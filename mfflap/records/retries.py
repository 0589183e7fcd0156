"""How a CFD run was retried: one :class:`Retry` per retry, as its case's retry log and its
record's provenance keep them (JSON, one object each), so that what is done next is decided
on their fields and never on their wording.

A retry is caused by the solver diverging (its time step collapsed, its Courant number
exploded), by a force log whose times repeat, by forces beyond what the motion can drive,
or by the same loss of the bound again at a lower Courant limit (then the run is rerun from
t = 0 s). A rerun requested by hand is a line of its own: the retries before it no longer
count against the run's budget.

Records written before the retry log was JSON hold their retries as text only
(``provenance["retries"]``): :func:`legacy_restart_s` reads where their last retry
restarted.
"""

from __future__ import annotations

import json
import re
from dataclasses import asdict, dataclass, fields

from mfflap.errors import COURANT_EXPLODED, TIME_STEP_COLLAPSED, ParseError

# a diverged solver's retry has the divergence's kind (:class:`~mfflap.errors.SolverDiverged`)
# as its cause: TIME_STEP_COLLAPSED or COURANT_EXPLODED
#: the force log's times repeat: the time step fell below the written precision
TIMES_REPEAT = "force log times repeat"
#: the forces left what the motion can drive (:mod:`mfflap.records.force_envelope`)
FORCES_BEYOND_BOUND = "forces beyond bound"
#: the forces left the bound at the same flow time again with a lower Courant limit: rerun
#: from t = 0 s with the settings the case has then
SAME_LOSS_AGAIN = "same loss again"
#: not a retry: a new budget of retries from here (a campaign's ``--retry-failed``)
RERUN_REQUESTED = "rerun requested"
CAUSES = (TIME_STEP_COLLAPSED, COURANT_EXPLODED, TIMES_REPEAT, FORCES_BEYOND_BOUND,
          SAME_LOSS_AGAIN, RERUN_REQUESTED)


@dataclass(frozen=True)
class Retry:
    """One retry of a CFD run.

    Attributes
    ----------
    cause : str
        One of :data:`CAUSES`.
    failed_at_s : float or None
        Flow time of the failure (where the forces left the bound), s; None for a rerun
        request.
    resumed_from_s : float or None
        Written time the retry resumed from, s (0: rerun from the start); None for a rerun
        request.
    remedy : str
        What changed in the case for the retry ("the inletOutlet far field", "maxCo 1",
        ...); '' for a rerun request.
    max_courant : float or None
        The Courant limit the run had when its forces left the bound (the cause
        :data:`FORCES_BEYOND_BOUND` or :data:`SAME_LOSS_AGAIN`), else None.
    earlier_max_courant : float or None
        For :data:`SAME_LOSS_AGAIN`, the Courant limit of the earlier loss at that time.

    Examples
    --------
    >>> r = Retry(FORCES_BEYOND_BOUND, 2.5, 2.0, "maxCo 1", max_courant=2.0)
    >>> r.restart()
    'resumed from t = 2 s with maxCo 1'
    >>> Retry.from_json(r.to_json()) == r
    True
    """

    cause: str
    failed_at_s: float | None
    resumed_from_s: float | None
    remedy: str
    max_courant: float | None = None
    earlier_max_courant: float | None = None

    def __post_init__(self) -> None:
        if self.cause not in CAUSES:
            raise ValueError(f"unknown retry cause {self.cause!r}; one of {', '.join(CAUSES)}")

    @property
    def from_start(self) -> bool:
        """Whether the retry reran the case from t = 0 s."""
        return self.resumed_from_s == 0.0

    def restart(self) -> str:
        """How the run went on, in words: "rerun from t = 0 s with maxCo 1", "resumed from
        t = 2 s with the inletOutlet far field" or, for a rerun request, ''."""
        if self.cause == RERUN_REQUESTED:
            return ""
        if self.cause == SAME_LOSS_AGAIN:
            return f"rerun from t = 0 s with max Co {self.max_courant:g}"
        return f"resumed from t = {self.resumed_from_s:g} s with {self.remedy}"

    def describe(self) -> str:
        """The retry in one line: what failed, where, and how the run went on."""
        t = self.failed_at_s
        if self.cause == RERUN_REQUESTED:
            return "rerun requested: a new budget of retries from here"
        if self.cause == SAME_LOSS_AGAIN:
            return (f"{self.restart()}: the forces left what the motion can drive from "
                    f"t = {t:.6g} s again, as at max Co {self.earlier_max_courant:g}, so the "
                    "flow written before may be spoiled")
        if self.cause == FORCES_BEYOND_BOUND:
            what = (f"forces beyond what the motion can drive from t = {t:.6g} s at max Co "
                    f"{self.max_courant:g}")
        elif self.cause == TIMES_REPEAT:
            what = (f"time step collapsed at t = {t!r} s (the force log's times repeat "
                    "there)")
        else:
            what = f"{self.cause} at t = {t:.10g} s"
        return f"{what}; {self.restart()}"

    def to_json(self) -> str:
        """The retry as one line of JSON."""
        return json.dumps(asdict(self))

    @classmethod
    def from_dict(cls, data: object, path: str = "<text>", lineno: int = 1) -> Retry:
        """A retry from its fields as a dict (:meth:`to_json`'s object).

        Raises
        ------
        ParseError
            Naming ``path`` and ``lineno``, for anything that is not such an object.
        """
        try:
            known = {f.name for f in fields(cls)}
            if not isinstance(data, dict) or not set(data) <= known:
                raise ValueError(f"keys {sorted(data) if isinstance(data, dict) else data!r}")
            return cls(**data)
        except (ValueError, TypeError) as exc:
            raise ParseError(f"not a retry ({exc})", path=path, line=lineno) from None

    @classmethod
    def from_json(cls, line: str, path: str = "<text>", lineno: int = 1) -> Retry:
        """A retry from one line of JSON (:meth:`to_json`).

        Raises
        ------
        ParseError
            Naming ``path`` and ``lineno``, for a line that is not such an object.
        """
        try:
            data = json.loads(line)
        except ValueError as exc:
            raise ParseError(f"not a retry ({exc})", path=path, line=lineno) from None
        return cls.from_dict(data, path, lineno)


def retries_to_json(retries: list[Retry]) -> str:
    """Retries as one JSON array (a record's ``provenance["retry_log"]``)."""
    return json.dumps([asdict(r) for r in retries])


def retries_from_json(text: str, path: str = "<text>") -> list[Retry]:
    """Retries from a JSON array (:func:`retries_to_json`).

    Raises
    ------
    ParseError
        Naming ``path``, for text that is not such an array.
    """
    try:
        items = json.loads(text)
    except ValueError as exc:
        raise ParseError(f"retry log is not JSON ({exc})", path=path) from None
    if not isinstance(items, list):
        raise ParseError("retry log is not a JSON array", path=path)
    return [Retry.from_dict(item, path, k + 1) for k, item in enumerate(items)]


#: where a retry of a record's text-only ``retries`` provenance restarted the run from:
#: group 1 a resume's written time, else a rerun from the start
_LEGACY_RESTART = re.compile(r"resumed from t = ([0-9.eE+-]+) s with |rerun from t = 0(?: s)? "
                             r"with ")


def legacy_restart_s(text: str) -> float:
    """The written time the last retry of a record's text-only ``retries`` provenance (a
    record written before the retry log was JSON) resumed from, s: 0 for a rerun from the
    start, or for text that names none."""
    found = list(_LEGACY_RESTART.finditer(text))
    if not found or found[-1].group(1) is None:
        return 0.0
    return float(found[-1].group(1))


__all__ = ["CAUSES", "COURANT_EXPLODED", "FORCES_BEYOND_BOUND", "RERUN_REQUESTED",
           "SAME_LOSS_AGAIN", "TIMES_REPEAT", "TIME_STEP_COLLAPSED", "Retry",
           "legacy_restart_s", "retries_from_json", "retries_to_json"]
