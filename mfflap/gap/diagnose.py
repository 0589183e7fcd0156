"""Which unmodelled effect explains the gap: cross-validated candidate selection.

Every candidate (and every small combination) is added to the base model, fitted on training
cases and scored on held-out cases (folds grouped by case). A candidate is *claimed* only
when it lowers the held-out error by at least ``min_gain`` of the base model's and the
per-case improvements pass a one-sided Wilcoxon signed-rank test at level ``alpha``.
Otherwise the verdict says whether anything is left to explain: "within noise" when the base
model's held-out residual passes the whiteness test of :mod:`mfflap.gap.whiteness`, else
"structured, unexplained", with the best candidate's score. A combination is preferred over the
best single candidate only if it clears the same bar against that candidate.

Beside the claim, each candidate's coefficient is reported two ways, and how far it can be
told apart from the base terms:

- refitted together with the base terms (what the claim rests on). Where the base model is
  misspecified the refitted base terms absorb part of the effect, so this value need not be
  the effect's physical coefficient;
- fitted alone to the residual of the base model with its coefficients as configured (the
  base terms held);
- the variance inflation factor of the candidate among the base terms, and the term it is
  most correlated with. Above :data:`CONFOUNDED_VIF` the verdict says that its coefficient
  is confounded with that term.
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np
from scipy.stats import wilcoxon

from mfflap.errors import ConfigError
from mfflap.gap.candidates import CandidateEffect, FlowContext, load_all
from mfflap.gap.system import COMPONENTS, GapSystem, group_folds
from mfflap.gap.whiteness import residual_whiteness
from mfflap.hydro.base import ForceModel
from mfflap.hydro.loads import Loads
from mfflap.identification.data import CaseData
from mfflap.identification.error_growth import (
    AUTO,
    ErrorGrowth,
    choose_scaling,
    measure_error_growth,
)
from mfflap.identification.repeatability import cycle_nrmse
from mfflap.metrics import nrmse, pearson
from mfflap.performance import thrust_and_power

if TYPE_CHECKING:
    from mfflap.gap.levels import LevelComparison
    from mfflap.gap.transfer import TransferCheck


@dataclass
class CandidateScore:
    """Held-out performance of the base model plus a set of candidates."""

    names: tuple[str, ...]
    heldout_sse: np.ndarray  # per case
    gain: float  # relative reduction of the total held-out error vs the base model
    p_value: float
    significant: bool
    coefficients: dict[str, float]  # mean over folds
    coefficient_spread: dict[str, float]  # std over folds
    plausible: dict[str, bool]
    #: fitted on all cases to the base model's residual, its coefficients held as configured
    held_coefficients: dict[str, float] = field(default_factory=dict)
    #: variance inflation factor among the base terms and the other candidates of the set
    variance_inflation: dict[str, float] = field(default_factory=dict)
    #: the term each candidate is most correlated with, and that (uncentred) correlation
    confounded_with: dict[str, tuple[str, float]] = field(default_factory=dict)

    @property
    def label(self) -> str:
        """``a + b`` for reports."""
        return " + ".join(self.names)

    def unclaimable(self) -> list[str]:
        """Why this set's coefficients may not be claimed, one reason per coefficient: a
        value outside the candidate's plausible range, or one confounded with another term
        (variance inflation above :data:`CONFOUNDED_VIF`); empty when they may."""
        reasons = [f"{n} = {self.coefficients[n]:.3g} is implausible" for n in self.names
                   if not self.plausible.get(n, True)]
        reasons += [f"{n} is confounded with {self.confounded_with[n][0]} (variance "
                    f"inflation {self.variance_inflation[n]:.3g})" for n in self.names
                    if self.variance_inflation.get(n, 1.0) > CONFOUNDED_VIF]
        return reasons

    @property
    def claimable(self) -> bool:
        """Significant, with plausible coefficients that are not confounded."""
        return self.significant and not self.unclaimable()


@dataclass
class Diagnosis:
    """Result of a gap diagnosis."""

    base_names: list[str]
    base_sse: np.ndarray
    scores: list[CandidateScore]
    chosen: CandidateScore | None
    verdict: str
    gap: dict[str, dict] = field(default_factory=dict)
    validation: dict[str, dict] = field(default_factory=dict)
    #: the leave-one-group-out checks that could not run, with why (e.g. a case without a
    #: frequency, or a single frequency among the cases)
    validation_skipped: dict[str, str] = field(default_factory=dict)
    case_names: list[str] = field(default_factory=list)
    residual_scaling: str = "grid"
    #: how the base model's error (its terms refitted over every case on the grid's scale)
    #: grows with each case's loads, per component: which residual scaling weighs the cases
    #: as their errors say
    error_growth: dict[str, ErrorGrowth] = field(default_factory=dict)
    #: the scaling asked for: ``residual_scaling``, or "auto" (chosen by ``error_growth``)
    scaling_asked: str = "grid"
    #: per candidate: what it is and what its coefficient means (physical_name,
    #: coefficient_name of its class)
    descriptions: dict[str, dict[str, str]] = field(default_factory=dict)
    #: the candidates the chosen one cannot be told from on these cases
    #: (:func:`indistinguishable_from`)
    indistinguishable: list[str] = field(default_factory=list)
    #: when the chosen (else the best) candidate's relatives of its family
    #: (:attr:`CandidateEffect.family`) explain the cases as well: the family's name, then
    #: its forms the cases cannot tell apart; else empty
    family: list[str] = field(default_factory=list)
    #: the same test of the residual left with the chosen effect added (empty when none is)
    whiteness_after: dict = field(default_factory=dict)
    #: significant candidates that explain more than the claim (or than nothing) but were
    #: not claimed, with why (:meth:`CandidateScore.unclaimable`)
    not_claimed: dict[str, list[str]] = field(default_factory=dict)
    #: the Ljung-Box test of the base model's held-out residual
    #: (:meth:`mfflap.gap.whiteness.WhitenessTest.as_dict`): whether it is noise
    whiteness: dict = field(default_factory=dict)
    #: whether the claimed effect (else the best candidate) predicts CFD runs outside the
    #: cases better (:mod:`mfflap.gap.transfer`); None when none were given
    transfer: TransferCheck | None = None
    #: the discrete-vortex model as a level over the cases' records and the held-out runs:
    #: what its F_n residual leaves of Morison's (:mod:`mfflap.gap.levels`); None when the
    #: cases came without their records
    levels: LevelComparison | None = None

    @property
    def finding(self) -> str:
        """The verdict's class, what a user acts on: "within noise" (nothing structured is
        left to explain), "explained by X" (the claim leaves a residual that passes the
        whiteness test), "partly explained by X" (the claim lowers the held-out error, but
        a structured residual remains with it: it stands in for part of the gap, or for an
        effect no candidate has), or "structured, unexplained"."""
        if self.chosen is not None:
            whole = self.whiteness_after.get("within_noise", True)
            return f"{'explained' if whole else 'partly explained'} by {self.chosen.label}"
        if self.whiteness.get("within_noise", False):
            return "within noise"
        return "structured, unexplained"

    def headline(self) -> str:
        """The finding and the verdict in one sentence, the finding said once: "Structured,
        unexplained: no candidate explains it ...", "Explained by X: held-out error ...".
        """
        verdict, finding = self.verdict, self.finding
        for lead in (finding, finding.split(" by ", 1)[-1]):
            if verdict.lower().startswith(lead.lower()):
                verdict = verdict[len(lead):].lstrip(":;,. ")
                break
        head = finding[0].upper() + finding[1:]
        return f"{head}: {verdict}" if verdict else f"{head}."

    def claim_said(self) -> str | None:
        """The claimed effect in words: what it is, what its coefficient means and its
        value both ways (refitted with the base terms; fitted to the residual of the model
        as configured). None when nothing is claimed."""
        if self.chosen is None:
            return None
        parts = []
        for name in self.chosen.names:
            said = self.descriptions.get(name, {})
            parts.append(f"{name}, {said.get('physical_name', 'a candidate effect')}: "
                         f"{said.get('coefficient_name', 'its coefficient')} = "
                         f"{self.chosen.coefficients[name]:.3g} refitted with the base terms, "
                         f"{self.chosen.held_coefficients[name]:.3g} fitted to the residual "
                         "of the model as configured")
        return "claimed " + "; ".join(parts)


#: variance inflation factor above which a coefficient is called confounded (the usual rule
#: of thumb: its variance ten times what it would be were the regressor orthogonal)
CONFOUNDED_VIF = 10.0

#: ``Diagnosis.gap`` keys of CFD's own NRMSE per case (NaN where not known): its cycles
#: against its mean cycle (every signal), and its F_n against the run on a finer mesh and
#: at a smaller Courant limit where the record holds one (:mod:`mfflap.records.refinement`)
CFD_OWN = ("cfd_cycle", "cfd_mesh", "cfd_time_step")


def indistinguishable_from(chosen: CandidateScore, singles: Sequence[CandidateScore],
                           alpha: float) -> list[CandidateScore]:
    """The significant single candidates outside ``chosen`` whose held-out errors
    ``chosen``'s are not significantly below (the one-sided signed-rank test at ``alpha``):
    on these cases the data cannot tell them from it (near-duplicate effects, such as
    circulatory lift at three-quarter chord and its wake-lagged form at low reduced
    frequency)."""
    return [s for s in singles if s.significant and not set(s.names) & set(chosen.names)
            and _significance(s.heldout_sse, chosen.heldout_sse) > alpha]


def _one_family(names: Sequence[str], candidates: dict[str, CandidateEffect]) -> str | None:
    """The family all of ``names`` belong to (:attr:`CandidateEffect.family`), else None."""
    families = {candidates[n].family for n in names}
    return families.pop() if len(families) == 1 else None


def _family_said(top: CandidateScore | None, singles: Sequence[CandidateScore],
                 candidates: dict[str, CandidateEffect], alpha: float) -> list[str]:
    """When the top single candidate has relatives of its family whose held-out errors are
    not significantly above its own: the family's name and its forms, top first, as one
    effect whose form these cases cannot pin down (so the claim or the not-claimed name
    stands for the family, not for a form picked by the noise); else empty."""
    if top is None or len(top.names) != 1:
        return []
    family = candidates[top.names[0]].family
    if family is None:
        return []
    kin = [s.names[0] for s in singles if len(s.names) == 1 and s.names != top.names
           and candidates[s.names[0]].family == family
           and _significance(s.heldout_sse, top.heldout_sse) > alpha]
    return [family, top.names[0], *kin] if kin else []


def _significance(before: np.ndarray, after: np.ndarray) -> float:
    d = before - after
    if np.allclose(d, 0):
        return 1.0
    try:
        return float(wilcoxon(d, alternative="greater").pvalue)
    except ValueError:
        return 1.0


def _score(system: GapSystem, names: tuple[str, ...], folds, base_sse: np.ndarray,
           candidates: dict[str, CandidateEffect], alpha: float, min_gain: float,
           base_values: np.ndarray, reference: np.ndarray | None = None) -> CandidateScore:
    base_cols = list(range(system.n_base))
    own = [system.names.index(n) for n in names]
    cols = base_cols + own
    sse, coefs = system.cross_validate(cols, folds)
    ref = base_sse if reference is None else reference
    gain = 1.0 - sse.sum() / base_sse.sum()
    rel = 1.0 - sse.sum() / ref.sum()
    p = _significance(ref, sse)
    c = np.array(coefs)[:, system.n_base:]
    means = dict(zip(names, c.mean(axis=0).tolist(), strict=True))
    spread = dict(zip(names, c.std(axis=0).tolist(), strict=True))
    plausible = {n: candidates[n].is_plausible(means[n]) for n in names}
    held = system.fit_held(own, base_cols, base_values, np.arange(len(system.cases)))
    vif = system.variance_inflation(cols)
    corr = system.correlation(cols)
    confounded = {}
    for k, n in enumerate(names):
        j = system.n_base + k
        r = np.abs(corr[j]).copy()
        r[j] = -1.0
        i = int(np.argmax(r))
        confounded[n] = (system.names[cols[i]], float(corr[j, i]))
    return CandidateScore(names, sse, float(gain), p, bool(p < alpha and rel >= min_gain),
                          means, spread, plausible,
                          dict(zip(names, held.tolist(), strict=True)),
                          {n: float(vif[system.n_base + k]) for k, n in enumerate(names)},
                          confounded)


def _predictions(system: GapSystem, cols: list[int], folds) -> list[dict[str, np.ndarray]]:
    every = np.arange(len(system.cases))
    out: list[dict[str, np.ndarray]] = [{} for _ in system.cases]
    for held in folds:
        x = system.fit(cols, np.setdiff1d(every, held))
        for i in held:
            for k in COMPONENTS:
                out[i][k] = system.predict(i, cols, x, k)
    return out


def gap_metrics(system: GapSystem, predictions: list[dict[str, np.ndarray]]) -> dict:
    """Per case, per signal: NRMSE, Pearson; mean-thrust and mean-power errors."""
    n = len(system.cases)
    out = {s: {"nrmse": np.empty(n), "pearson": np.empty(n)} for s in
           (*COMPONENTS, "thrust", "input_power")}
    out["mean_thrust_error"] = np.empty(n)
    out["mean_power_error"] = np.empty(n)
    for i, c in enumerate(system.cases):
        p = predictions[i]
        loads = Loads(c.state.time, p["normal_force"], p["tangential_force"], p["moment"])
        thrust, power = thrust_and_power(loads, c.state)
        sig = {**p, "thrust": thrust, "input_power": power}
        for s, v in sig.items():
            ref = c.cfd_signal(s)
            out[s]["nrmse"][i] = nrmse(v, ref)
            out[s]["pearson"][i] = pearson(v, ref)
        ct, cp = c.cfd_signal("thrust"), c.cfd_signal("input_power")
        out["mean_thrust_error"][i] = (thrust.mean() - ct.mean()) / max(np.abs(ct).mean(),
                                                                        1e-12)
        out["mean_power_error"][i] = (power.mean() - cp.mean()) / max(np.abs(cp).mean(), 1e-12)
    return out


def cfd_own_metrics(cases: Sequence[CaseData]) -> dict[str, dict]:
    """CFD's own NRMSE of each case, the yardstick beside :func:`gap_metrics`: per
    :data:`CFD_OWN` key, signal -> {"nrmse": one value a case}.

    Examples
    --------
    >>> own = cfd_own_metrics([])
    >>> sorted(own), own["cfd_mesh"]["normal_force"]["nrmse"].shape
    (['cfd_cycle', 'cfd_mesh', 'cfd_time_step'], (0,))
    """
    out = {"cfd_cycle": {s: {"nrmse": np.array([cycle_nrmse(c, s) for c in cases])}
                         for s in (*COMPONENTS, "thrust", "input_power")}}
    for key, kind in (("cfd_mesh", "mesh"), ("cfd_time_step", "time_step")):
        out[key] = {"normal_force": {"nrmse": np.array(
            [c.refinement[kind].normal_force_nrmse if kind in c.refinement else np.nan
             for c in cases])}}
    return out


def _refitted_error_growth(cases: Sequence[CaseData], base_model: ForceModel
                           ) -> dict[str, ErrorGrowth]:
    """How the base model's error grows with each case's loads, its terms refitted over all
    cases on the grid's scale: the errors its fits face (with the coefficients as
    configured, their own misfit, in proportion to the loads, would decide)."""
    on_grid = GapSystem.build(cases, base_model.terms, [])
    fitted = on_grid.fit(range(on_grid.n_base), np.arange(len(cases)))
    refitted = base_model.with_coefficients(dict(zip(on_grid.names, fitted.tolist(),
                                                     strict=True)))
    return measure_error_growth(cases, refitted)


def default_candidates(context: FlowContext | None = None) -> dict[str, CandidateEffect]:
    """One instance of every registered candidate."""
    return {name: cls(context) for name, cls in sorted(load_all().items())}


def diagnose(cases: Sequence[CaseData], base_model: ForceModel,
             candidates: dict[str, CandidateEffect] | None = None, *,
             context: FlowContext | None = None, max_combination: int = 2,
             n_folds: int = 5, alpha: float = 0.01, min_gain: float = 0.02, seed: int = 0,
             validate_by: Sequence[str] = ("frequency", "heave_amplitude"),
             residual_scaling: str = "grid", system: GapSystem | None = None) -> Diagnosis:
    """Rank the candidate effects by held-out improvement and claim one only if significant.

    Parameters
    ----------
    cases
        Any (motion, force history) pairs, prepared as :class:`CaseData`.
    base_model
        The reduced model whose terms are refitted together with each candidate.
    validate_by
        Case parameters for leave-one-group-out validation of the chosen effect (e.g.
        leave-one-frequency-out).
    residual_scaling
        How each case's residuals are scaled (a key of
        :data:`~mfflap.identification.fit.RESIDUAL_SCALINGS`): by each component's RMS over
        every case ("grid"), or by its range in the case ("case": every case weighs alike
        in the fits, the held-out errors and the significance test); or "auto", the one
        the base model's errors ask for
        (:func:`~mfflap.identification.error_growth.choose_scaling`). Ignored when
        ``system`` is given (it holds its own).

    Raises
    ------
    ConfigError
        If ``alpha`` is not in (0, 1), ``min_gain`` is negative or ``residual_scaling`` is
        none of the scalings.
    """
    if not 0 < alpha < 1:
        raise ConfigError(f"the significance level must be in (0, 1), got {alpha!r}",
                          key="alpha")
    if not (np.isfinite(min_gain) and min_gain >= 0):
        raise ConfigError(f"the smallest error reduction worth claiming must be a finite "
                          f"share >= 0, got {min_gain!r}", key="min_gain")
    candidates = candidates or default_candidates(context)
    growth = _refitted_error_growth(system.cases if system else cases, base_model)
    asked = system.residual_scaling if system is not None else residual_scaling
    if system is None:
        system = GapSystem.build(cases, base_model.terms, list(candidates.values()),
                                 residual_scaling=(choose_scaling(growth) if asked == AUTO
                                                   else asked))
    folds = group_folds(range(len(system.cases)), n_folds, seed)
    base_cols = list(range(system.n_base))
    base_values = np.array([base_model.coefficients[n] for n in system.names[:system.n_base]])
    base_sse, _ = system.cross_validate(base_cols, folds)
    singles = [_score(system, (n,), folds, base_sse, candidates, alpha, min_gain, base_values)
               for n in candidates]
    singles.sort(key=lambda s: -s.gain)
    scores = list(singles)
    # a claim is the best single candidate when its coefficient is plausible and not
    # confounded, or the best such pair with it; when the best one's is not, nothing is
    # claimed (a lesser candidate would be claimed for what the best one explains, and an
    # implausible or confounded fit says the form stands in for another effect)
    best = singles[0] if singles and singles[0].claimable else None
    chosen = best
    if best is not None and max_combination >= 2:
        for combo in itertools.combinations(candidates, 2):
            if best.names[0] not in combo or _one_family(combo, candidates):
                continue  # two forms of one effect are not fitted together
            pair = _score(system, combo, folds, base_sse, candidates, alpha, min_gain,
                          base_values, reference=best.heldout_sse)
            scores.append(pair)
            if pair.claimable and pair.gain > chosen.gain:
                chosen = pair
    scores.sort(key=lambda s: -s.gain)
    bar = chosen.gain if chosen is not None else -np.inf
    not_claimed = {sc.label: why for sc in scores
                   if sc.significant and sc.gain > bar and (why := sc.unclaimable())}
    rivals = indistinguishable_from(chosen, singles, alpha) if chosen is not None else []
    family = _family_said(chosen or (singles[0] if singles else None), singles, candidates,
                          alpha)
    base_predictions = _predictions(system, base_cols, folds)
    whiteness = residual_whiteness(system.cases, base_predictions, alpha)
    if chosen is None:
        top = singles[0] if singles else None
        best_said = (f" (best: {top.label}, held-out gain {top.gain:+.1%}, p = "
                     f"{top.p_value:.2g})" if top else "")
        verdict = (f"within noise: {whiteness.said()}; no candidate explains more"
                   if whiteness.within_noise else
                   f"structured, unexplained: no candidate explains it{best_said}; "
                   f"{whiteness.said()}")
    else:
        # the family's forms are said below, with the family
        others = [s for s in rivals if s.label not in family[1:]]
        verdict = (f"{chosen.label}: held-out error {chosen.gain:.1%} lower "
                   f"(p = {chosen.p_value:.2g})"
                   + ("; indistinguishable on these cases from "
                      + ", ".join(f"{s.label} ({s.gain:.1%} lower)" for s in others)
                      + " (the chosen one's error not significantly below theirs)"
                      if others else ""))
    if family:
        gains = {sc.label: sc.gain for sc in singles}
        verdict += (f"; {family[0]}: "
                    + " and ".join(f"{n} ({gains[n]:.1%} lower)" for n in family[1:])
                    + " are forms of one effect that these cases cannot tell apart")
    if not_claimed:
        first, reasons = next(iter(not_claimed.items()))
        more = len(not_claimed) - 1
        verdict += (f"; not claimed although {'they explain' if more else 'it explains'} "
                    f"more: {first} ({'; '.join(reasons)})"
                    + (f" and {more} other set{'s' if more > 1 else ''} of candidates"
                       if more else ""))
    n_cases = len(system.cases)
    if 0.5**n_cases > alpha:
        verdict += (f"; with {n_cases} cases no improvement can reach p < {alpha:g} (the "
                    f"one-sided signed-rank test needs at least "
                    f"{int(np.ceil(np.log2(1 / alpha)))} cases): add cases")
    diag = Diagnosis(list(system.names[: system.n_base]), base_sse, scores, chosen, verdict,
                     indistinguishable=[s.label for s in rivals],
                     case_names=[c.name for c in system.cases],
                     residual_scaling=system.residual_scaling, error_growth=growth,
                     scaling_asked=asked,
                     descriptions={n: {"physical_name": c.physical_name,
                                       "coefficient_name": c.coefficient_name}
                                   for n, c in candidates.items()},
                     whiteness=whiteness.as_dict(), not_claimed=not_claimed,
                     family=family)
    diag.gap["before"] = gap_metrics(system, base_predictions)
    diag.gap.update(cfd_own_metrics(system.cases))
    validated = chosen or (singles[0] if singles else None)
    if chosen is not None:
        cols = base_cols + [system.names.index(n) for n in chosen.names]
        after_predictions = _predictions(system, cols, folds)
        diag.gap["after"] = gap_metrics(system, after_predictions)
        left = residual_whiteness(system.cases, after_predictions, alpha)
        diag.whiteness_after = left.as_dict()
        if not left.within_noise:  # the claim is not the whole gap
            diag.verdict += (f"; a structured residual remains with it (Ljung-Box against "
                             f"AR(1) noise, p = {left.p_value:.2g}): it explains part of the "
                             "gap, or stands in for an effect no candidate has")
    if validated is not None:
        # leave-one-group-out of the chosen effect; of the best candidate when none is
        # claimed, so the user sees how it would generalise (labelled as not claimed)
        cols = base_cols + [system.names.index(n) for n in validated.names]
        for key in validate_by:
            labels = [c.parameters.get(key) for c in system.cases]
            unlabelled = [c.name for c, v in zip(system.cases, labels, strict=True)
                          if v is None]
            if unlabelled:
                diag.validation_skipped[f"leave-one-{key}-out"] = (
                    f"{len(unlabelled)} of {len(labels)} cases give no {key} (e.g. "
                    f"{unlabelled[0]}); give each case its {key} to check how the effect "
                    "carries over between them")
                continue
            if len(set(labels)) < 2:
                diag.validation_skipped[f"leave-one-{key}-out"] = (
                    f"every case has the same {key} ({labels[0]}): there is no other "
                    "group to withhold")
                continue
            g = group_folds(labels)
            before, _ = system.cross_validate(base_cols, g)
            after, _ = system.cross_validate(cols, g)
            per_group = {}
            for fold in g:
                lab = labels[fold[0]]
                per_group[str(lab)] = float(1.0 - after[fold].sum() / before[fold].sum())
            diag.validation[f"leave-one-{key}-out"] = {
                "candidate": validated.label, "claimed": chosen is not None,
                "gain": float(1.0 - after.sum() / before.sum()),
                "p_value": _significance(before, after), "per_group_gain": per_group}
    return diag
