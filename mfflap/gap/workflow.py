"""Diagnosis plus residual decomposition of a case's model on a set of CFD cases."""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence

from mfflap.config import CaseConfig
from mfflap.gap.candidates import FlowContext
from mfflap.gap.diagnose import Diagnosis, _predictions, default_candidates, diagnose
from mfflap.gap.system import GapSystem, group_folds
from mfflap.gap.transfer import HeldOutMotion, check_transfer
from mfflap.gap.where import decompose
from mfflap.identification.data import CaseData
from mfflap.records.record import CfdRecord


def diagnose_cases(config: CaseConfig, cases: Sequence[CaseData], alpha: float = 0.01,
                   min_gain: float = 0.02, residual_scaling: str | None = None,
                   held_out: Sequence[HeldOutMotion] | None = None,
                   held_out_excluded: Mapping[str, str] | None = None, *,
                   records: Sequence[CfdRecord] | None = None,
                   held_out_records: Sequence[CfdRecord] = (),
                   progress: Callable[[str], None] | None = None
                   ) -> tuple[Diagnosis, dict, list[dict]]:
    """The diagnosis, the decomposition of the base model's held-out residual, and the
    held-out base predictions per case (for flow snapshots at the residual peaks).

    The residuals are scaled as ``residual_scaling`` says, else as the case's
    ``[identification] residual_scaling`` (the diagnosis refits the base model's
    coefficients, so it scales them as their identification does); "auto" lets the base
    model's errors choose. Given ``held_out`` motions (CFD runs outside ``cases``, such as
    the back-tested ones), ``diagnosis.transfer`` says whether the claimed effect (else the
    best candidate) predicts them better (:func:`~mfflap.gap.transfer.check_transfer`);
    ``held_out_excluded`` are the runs that could not be used, with the reason. Given the
    cases' ``records`` (and ``held_out_records``), ``diagnosis.levels`` puts the case's
    discrete-vortex model ([vortex]) beside its Morison model on each
    (:func:`~mfflap.gap.levels.compare_levels`; ``progress`` is told each record)."""
    scaling = residual_scaling or config.identification.residual_scaling
    base = config.morison_model()
    candidates = default_candidates(FlowContext(config.plate, config.fluid, config.flow))
    diag = diagnose(cases, base, candidates, alpha=alpha, min_gain=min_gain,
                    residual_scaling=scaling)
    if held_out is not None:
        checked = diag.chosen or next((sc for sc in diag.scores if len(sc.names) == 1), None)
        if checked is not None:
            diag.transfer = check_transfer(
                cases, held_out, base.terms, candidates, checked.names,
                claimed=diag.chosen is not None, residual_scaling=diag.residual_scaling,
                excluded=held_out_excluded, alpha=alpha)
    if records is not None:
        from mfflap.gap.levels import compare_levels  # loads the compiled vortex kernel

        diag.levels = compare_levels(records, base, config.vortex, held_out=held_out_records,
                                     progress=progress)
    system = GapSystem.build(cases, base.terms, [], residual_scaling=diag.residual_scaling)
    pred = _predictions(system, list(range(len(base.terms))), group_folds(range(len(cases)), 5))
    return diag, decompose(system, pred, config.flow.velocity, config.plate.chord), pred
