"""What the rounds carry from one round to the next, for each beta: one :class:`BetaState`
each, so that a beta's centre, radius and visited optima cannot fall out of step."""

from __future__ import annotations

from dataclasses import dataclass, field

from mfflap.optimisation.output_correction import CorrectionPoint
from mfflap.records.record import CfdRecord


@dataclass
class BetaState:
    """One beta's state between rounds.

    Attributes
    ----------
    last_point : CorrectionPoint or None
        The last round's optimum with its CFD means (what ``correct_outputs`` corrects to).
    centre : CorrectionPoint or None
        The trust region's centre with its CFD means (``trust_radius``).
    radius : float or None
        The trust region's radius.
    centre_run : CfdRecord or None
        The centre's CFD record (how it ran: :func:`mfflap.records.as_run.as_run_differences`).
    centre_mixed : list of str
        What mixes two set-ups in the cycles the centre's CFD is compared over.
    visited : list of CorrectionPoint
        The back-tested optima its first-order slopes may take.
    records_used : set of str
        The CFD records those optima were measured on.

    Examples
    --------
    >>> state = BetaState()
    >>> state.centre is None and state.visited == []
    True
    """

    last_point: CorrectionPoint | None = None
    centre: CorrectionPoint | None = None
    radius: float | None = None
    centre_run: CfdRecord | None = None
    centre_mixed: list[str] = field(default_factory=list)
    visited: list[CorrectionPoint] = field(default_factory=list)
    records_used: set[str] = field(default_factory=set)


def with_centres(states: dict[float, BetaState]) -> dict[float, BetaState]:
    """The betas of ``states`` that have a trust region's centre."""
    return {b: s for b, s in states.items() if s.centre is not None}


__all__ = ["BetaState", "with_centres"]
