"""Diagnosis plus residual decomposition of a case's model on a set of CFD cases."""

from __future__ import annotations

from collections.abc import Sequence

from mfflap.config import CaseConfig
from mfflap.gap.candidates import FlowContext
from mfflap.gap.diagnose import Diagnosis, _predictions, default_candidates, diagnose
from mfflap.gap.system import GapSystem, group_folds
from mfflap.gap.where import decompose
from mfflap.identification.data import CaseData


def diagnose_cases(config: CaseConfig, cases: Sequence[CaseData], alpha: float = 0.01,
                   min_gain: float = 0.02, residual_scaling: str | None = None
                   ) -> tuple[Diagnosis, dict, list[dict]]:
    """The diagnosis, the decomposition of the base model's held-out residual, and the
    held-out base predictions per case (for flow snapshots at the residual peaks).

    The residuals are scaled as ``residual_scaling`` says, else as the case's
    ``[identification] residual_scaling`` (the diagnosis refits the base model's
    coefficients, so it scales them as their identification does); "auto" lets the base
    model's errors choose."""
    scaling = residual_scaling or config.identification.residual_scaling
    base = config.morison_model()
    candidates = default_candidates(FlowContext(config.plate, config.fluid, config.flow))
    diag = diagnose(cases, base, candidates, alpha=alpha, min_gain=min_gain,
                    residual_scaling=scaling)
    system = GapSystem.build(cases, base.terms, [], residual_scaling=diag.residual_scaling)
    pred = _predictions(system, list(range(len(base.terms))), group_folds(range(len(cases)), 5))
    return diag, decompose(system, pred, config.flow.velocity, config.plate.chord), pred
