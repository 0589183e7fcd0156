"""Weighted linear least squares for the force-model coefficients, with a case bootstrap.

Every term of a :class:`~mfflap.hydro.base.ForceModel` is linear in its coefficient, so the
fit is linear: for each case c and fitted component k (F_n, F_t, M),

    r_ck = (y_ck - A_ck x) / s_k,

with y the CFD signal, A the term regressors and s_k the RMS of component k over all cases
(so that newtons and newton-metres are comparable; ``residual_scaling="grid"``, the
default). With ``residual_scaling="case"``, s_ck is instead the range of component k in
case c, the paper's NRMSE denominator: the fit then minimises the weighted mean square
NRMSE over the cases, and a case of large forces counts no more than one of small forces.
With ``residual_scaling="auto"`` the data choose: the fit is made on the grid's scales,
how its error grows with each case's loads is measured
(:mod:`~mfflap.identification.error_growth`), and where every component's error grows
about in proportion to the loads the fit is made again with each case's ranges.
Case c carries the weight
w_f(c) / (n_cases at f(c) * n_samples(c)): each frequency gets its strategy weight whatever
its number of cases and samples. Coefficients are bounded below by zero (they are physical
drag and added-mass coefficients) and solved by NNLS on the normal equations.

Which components: F_n and M carry C_Dn and C_an; F_t alone carries C_Dt and C_at. All three
are used by default. The moment adds where along the chord the normal load acts.

Uncertainty: samples within a case are strongly correlated, so a sample-based covariance
would be far too optimistic. Cases are resampled with replacement within each frequency
(a stratified case bootstrap); the spread of the refitted coefficients is the uncertainty.

Influence: each case is also left out in turn and the coefficients refitted without it
(a case jackknife, :func:`most_influential`), which names the CFD runs an identified value
rests on: the ones to check or refine first.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np
from scipy.linalg import cholesky
from scipy.optimize import nnls

from mfflap.errors import ConfigError, MfflapError
from mfflap.hydro.base import ForceModel
from mfflap.identification.data import COMPONENTS, DERIVED, CaseData
from mfflap.identification.error_growth import (
    AUTO,
    ErrorGrowth,
    choose_scaling,
    measure_error_growth,
)
from mfflap.identification.weights import frequency_weights
from mfflap.metrics import nrmse, pearson
from mfflap.performance import thrust_and_power

#: How residuals are made comparable across components and cases (``identify``'s
#: ``residual_scaling``), with what each means for the report and the CLI.
RESIDUAL_SCALINGS = {
    "grid": "each component by its RMS over every case (forces in newtons: the cases of "
            "large forces weigh most)",
    "case": "each component of each case by its range in that case (the fit minimises the "
            "mean square NRMSE: every case weighs alike)",
}

#: What may be asked for: a scaling, or "auto" (the one the model's errors ask for)
SCALING_CHOICES = (*RESIDUAL_SCALINGS, AUTO)


def scaling_said(used: str, asked: str) -> str:
    """What the residuals were scaled by, for the CLI and the reports (and that the data
    chose it, where ``asked`` is "auto")."""
    chosen = ', chosen by "auto" as the errors ask' if asked == AUTO else ""
    return f'{RESIDUAL_SCALINGS[used]} (residual_scaling = "{used}"{chosen})'


def scalings_said(results: Mapping[str, IdentificationResult]) -> str:
    """:func:`scaling_said` of several strategies' fits: once where they agree, else each
    (with "auto" each fit's errors choose for it)."""
    said = {label: scaling_said(r.residual_scaling, r.scaling_asked)
            for label, r in results.items()}
    if len(set(said.values())) == 1:
        return next(iter(said.values()))
    return "; ".join(f"{label}: {text}" for label, text in said.items())


#: What a coefficient held at its lower bound 0 means, for the CLI and the report.
HELD_AT_ZERO = ("the fit without the bound makes the coefficient negative, which no drag or "
                "added-mass coefficient is; the identified model has no such term (the data "
                "do not support it, or another term takes its part)")


@dataclass
class IdentificationResult:
    """Fitted coefficients, their uncertainty and the per-case agreement.

    Attributes
    ----------
    coefficients : dict
        Fitted value per term name (fixed ones included).
    standard_error : dict
        Bootstrap standard deviation per fitted term (0 for fixed ones).
    interval : dict
        Bootstrap 95 % interval per fitted term.
    bootstrap : ndarray (n_bootstrap, n_fitted)
    strategy : str
        Weighting strategy name (or ``"custom"``).
    weights : dict
        Weight per frequency, Hz -> weight.
    components : tuple of str
        Components fitted.
    case_names, case_parameters : per case
    metrics : dict
        ``metrics[signal]["nrmse" | "pearson"]`` arrays over cases, for F_n, F_t, M,
        thrust and input power.
    excluded : dict
        Cases left out, with the reason.
    residual_scaling : str
        A key of :data:`RESIDUAL_SCALINGS`: the scaling the fit was made with.
    scaling_asked : str
        What was asked for: that scaling, or ``"auto"`` (the data chose it).
    leave_one_out : ndarray (n_cases, n_fitted)
        The fitted terms refitted without each case in turn (row i: without case i), the
        other cases weighted as in the fit; NaN where the rest do not determine them. Empty
        (0 rows) for a result stored before it was computed.
    error_growth : dict
        Per fitted component, how the fitted model's error grows with each case's loads
        (:class:`~mfflap.identification.error_growth.ErrorGrowth`): which residual scaling
        weighs the cases as their errors say. Empty for a result stored before it was
        measured.
    """

    coefficients: dict[str, float]
    standard_error: dict[str, float]
    interval: dict[str, tuple[float, float]]
    bootstrap: np.ndarray
    fitted_terms: tuple[str, ...]
    strategy: str
    weights: dict[float, float]
    components: tuple[str, ...]
    case_names: list[str]
    case_parameters: list[dict]
    metrics: dict[str, dict[str, np.ndarray]]
    excluded: dict[str, str] = field(default_factory=dict)
    notes: dict[str, list[str]] = field(default_factory=dict)
    leave_one_out: np.ndarray = field(default_factory=lambda: np.empty((0, 0)))
    residual_scaling: str = "grid"
    error_growth: dict[str, ErrorGrowth] = field(default_factory=dict)
    scaling_asked: str = "grid"

    @property
    def at_lower_bound(self) -> tuple[str, ...]:
        """Fitted terms held at the lower bound 0: the least-squares fit without the bound
        makes them negative, which no drag or added-mass coefficient is, so the model has
        no such term (the data do not support it, or another term takes its part)."""
        return tuple(n for n in self.fitted_terms if self.coefficients[n] == 0.0)

    def model(self, base: ForceModel) -> ForceModel:
        """``base`` with the fitted coefficients."""
        return base.with_coefficients(self.coefficients)


@dataclass
class _System:
    grams: np.ndarray  # (n_cases, p, p)
    rhs: np.ndarray  # (n_cases, p)
    frequencies: np.ndarray


@dataclass
class _Blocks:
    """Each case's unscaled, unweighted normal-equation blocks, per component: what any
    subset of the cases is assembled from (:func:`_assemble`)."""

    grams: np.ndarray  # (n_cases, n_components, p, p): A'A
    rhs: np.ndarray  # (n_cases, n_components, p): A'(y - fixed terms)
    square_sums: np.ndarray  # (n_cases, n_components): sum of y^2 (the component scales)
    n_samples: np.ndarray  # (n_cases,)
    frequencies: np.ndarray  # (n_cases,), Hz
    scaled_per_case: bool = False  # each case's blocks already divided by its ranges^2


def _blocks(cases: Sequence[CaseData], model: ForceModel, fitted: Sequence[str],
            fixed: Mapping[str, float], components: Sequence[str],
            residual_scaling: str = "grid") -> _Blocks:
    names = [t.name for t in model.terms]
    idx_fit = [names.index(n) for n in fitted]
    idx_fix = [names.index(n) for n in fixed]
    fix_vals = np.array([fixed[n] for n in fixed])
    n, m, p = len(cases), len(components), len(fitted)
    grams, rhs, squares = np.zeros((n, m, p, p)), np.zeros((n, m, p)), np.zeros((n, m))
    for i, c in enumerate(cases):
        regs = model.regressors(c.state)
        for j, k in enumerate(components):
            a_all = np.column_stack([getattr(regs[t.name], k) for t in model.terms])
            y = c.cfd_signal(k)
            squares[i, j] = float(np.sum(y**2))
            if idx_fix:
                y = y - a_all[:, idx_fix] @ fix_vals
            a = a_all[:, idx_fit]
            span = 1.0
            if residual_scaling == "case":  # the case's range: NRMSE's denominator
                span = float(np.ptp(c.cfd_signal(k))) or 1.0
            grams[i, j] = a.T @ a / span**2
            rhs[i, j] = a.T @ y / span**2
    return _Blocks(grams, rhs, squares, np.array([c.n_samples for c in cases], dtype=float),
                   np.array([c.frequency for c in cases]),
                   scaled_per_case=residual_scaling == "case")


def _assemble(blocks: _Blocks, weights: Mapping[float, float],
              kept: np.ndarray | None = None) -> _System:
    """The weighted, scaled normal equations of the cases ``kept`` (a boolean mask; all by
    default), each case's own: the component scales are the RMS of the CFD over the cases
    kept, and each frequency's weight is shared among its cases kept."""
    kept = np.ones(len(blocks.n_samples), dtype=bool) if kept is None else kept
    scale2 = blocks.square_sums[kept].sum(axis=0) / blocks.n_samples[kept].sum()
    scale2 = np.where((scale2 > 0) & (not blocks.scaled_per_case), scale2, 1.0)
    freqs = blocks.frequencies[kept]
    count = {f: int(np.sum(np.isclose(freqs, f))) for f in weights}
    nearest = [min(weights, key=lambda v, f=f: abs(v - f)) for f in freqs]
    w_case = np.array([weights[f] / count[f] for f in nearest]) / blocks.n_samples[kept]
    grams = np.einsum("c,cmij,m->cij", w_case, blocks.grams[kept], 1.0 / scale2)
    rhs = np.einsum("c,cmi,m->ci", w_case, blocks.rhs[kept], 1.0 / scale2)
    return _System(grams, rhs, freqs)


def _solve(gram: np.ndarray, rhs: np.ndarray, names: Sequence[str]) -> np.ndarray:
    """min x'Gx - 2 g'x subject to x >= 0 (NNLS on the Cholesky factor).

    A term whose regressor is zero on every sample fitted (a tangential term fitted to the
    moment about the pivot alone, which the tangential force has no arm for) is not
    determined by the data: refused by name, where the ridge below would set it to 0.
    """
    diagonal = np.diag(gram)
    idle = [n for n, d in zip(names, diagonal, strict=True)
            if not d > 1e-12 * max(float(diagonal.max()), 0.0)]
    if idle and len(idle) < len(names):
        raise MfflapError(f"the data do not determine the coefficients {idle}: their terms are "
                          "zero on every sample of the fitted components; fit the components "
                          "they act on, or fix them")
    ridge = 1e-12 * np.trace(gram) / len(gram)
    g = gram + ridge * np.eye(len(gram))
    try:
        r = cholesky(g, lower=False)
    except np.linalg.LinAlgError as exc:
        raise MfflapError(f"the data do not determine the coefficients {list(names)} "
                          "(singular normal equations); add cases or fix some terms") from exc
    b = np.linalg.solve(r.T, rhs)
    x, _ = nnls(r, b)
    return x


def _leave_one_out(blocks: _Blocks, weights: Mapping[float, float],
                   fitted: Sequence[str]) -> np.ndarray:
    """The fitted terms refitted without each case in turn (rows), as :func:`identify`
    fits them: the component scales from the cases kept, each frequency's weight shared
    among its cases kept. A frequency left without cases drops out with its weight (the
    others keep theirs). NaN where the cases kept do not determine the terms."""
    n = len(blocks.n_samples)
    out = np.full((n, len(fitted)), np.nan)
    for i in range(n):
        kept = np.arange(n) != i
        present = {min(weights, key=lambda v, f=f: abs(v - f))
                   for f in blocks.frequencies[kept]}
        kept_weights = {f: w for f, w in weights.items() if f in present}
        if not kept.any() or sum(kept_weights.values()) <= 0:
            continue
        system = _assemble(blocks, kept_weights, kept)
        try:
            out[i] = _solve(system.grams.sum(axis=0), system.rhs.sum(axis=0), fitted)
        except MfflapError:
            pass
    return out


@dataclass(frozen=True)
class Influence:
    """The case whose leaving out moves one identified coefficient the most."""

    term: str
    case: str
    value: float  # with every case
    value_without: float  # refitted without ``case``
    standard_error: float  # the bootstrap's, NaN when not estimated

    @property
    def change(self) -> float:
        """value_without - value."""
        return self.value_without - self.value

    @property
    def relative_change(self) -> float:
        """The change over the value (NaN for a value of 0)."""
        return self.change / self.value if self.value else float("nan")

    @property
    def in_standard_errors(self) -> float:
        """The change in bootstrap standard errors (NaN when not estimated)."""
        se = self.standard_error
        return abs(self.change) / se if np.isfinite(se) and se > 0 else float("nan")

    def __str__(self) -> str:
        relative = (f", {self.relative_change:+.1%}" if np.isfinite(self.relative_change)
                    else "")
        spread = (f", {self.in_standard_errors:.1f} s.e."
                  if np.isfinite(self.in_standard_errors) else "")
        return (f"{self.term}: {self.case} ({self.value:.3g} -> {self.value_without:.3g}"
                f"{relative}{spread})")


def most_influential(result: IdentificationResult) -> list[Influence]:
    """For each fitted term that some case moves, the case whose leaving out moves it most
    (``result.leave_one_out``); empty when that was not computed or no case moves any."""
    rows = np.asarray(result.leave_one_out, dtype=float)
    if rows.ndim != 2 or rows.shape != (len(result.case_names), len(result.fitted_terms)):
        return []
    found = []
    for j, term in enumerate(result.fitted_terms):
        change = np.abs(rows[:, j] - result.coefficients[term])
        if not np.any(np.isfinite(change)) or np.nanmax(change) == 0:
            continue
        i = int(np.nanargmax(change))
        found.append(Influence(term, result.case_names[i], result.coefficients[term],
                               float(rows[i, j]), result.standard_error[term]))
    return found


def score(cases: Sequence[CaseData], model: ForceModel,
          signals: Sequence[str] = (*COMPONENTS, *DERIVED)) -> dict[str, dict[str, np.ndarray]]:
    """NRMSE and Pearson of ``model`` against the CFD of every case, per signal."""
    out = {s: {"nrmse": np.empty(len(cases)), "pearson": np.empty(len(cases))}
           for s in signals}
    for i, c in enumerate(cases):
        pred = model.loads(c.state)
        thrust, power = thrust_and_power(pred, c.state)
        for s in signals:
            p = {"thrust": thrust, "input_power": power}.get(s)
            p = getattr(pred, s) if p is None else p
            ref = c.cfd_signal(s)
            out[s]["nrmse"][i] = nrmse(p, ref)
            out[s]["pearson"][i] = pearson(p, ref)
    return out


def identify(cases: Sequence[CaseData], model: ForceModel,
             strategy: str | Sequence[float] = "uniform",
             components: Sequence[str] = tuple(COMPONENTS), fixed: Mapping[str, float] | None
             = None, n_bootstrap: int = 200, seed: int = 0,
             excluded: Mapping[str, str] | None = None,
             residual_scaling: str = "grid") -> IdentificationResult:
    """Fit the coefficients of ``model`` to the CFD of ``cases``.

    Parameters
    ----------
    cases
        Prepared cases (:func:`~mfflap.identification.data.prepare_cases`).
    model
        The force model; every term not in ``fixed`` is fitted.
    strategy
        Frequency weighting (:func:`~mfflap.identification.weights.frequency_weights`).
    components
        Load components fitted (any of ``normal_force``, ``tangential_force``, ``moment``).
    fixed
        Coefficients held at the given values.
    n_bootstrap
        Stratified case-bootstrap replicates (0 for none). Below 2, or when no frequency
        has two cases or more to resample, the fitted coefficients' standard errors and
        intervals are NaN: not estimated (a fixed coefficient's are 0).
    excluded
        Cases already left out (e.g. failed CFD), carried into the result and the report.
    residual_scaling
        ``"grid"`` (each component's residual over its RMS across all cases), ``"case"``
        (over its range in each case: the weighted mean square NRMSE is minimised); see
        :data:`RESIDUAL_SCALINGS`; or ``"auto"``, the one the grid fit's errors ask for
        (:func:`~mfflap.identification.error_growth.choose_scaling`).
    """
    if not cases:
        raise MfflapError("no usable CFD cases to identify from")
    if n_bootstrap < 0:
        raise ConfigError(f"n_bootstrap must be >= 0 (0: none), got {n_bootstrap!r}",
                          key="n_bootstrap")
    if residual_scaling not in SCALING_CHOICES:
        raise ConfigError(f"residual scaling {residual_scaling!r}: choose one of "
                          f"{', '.join(SCALING_CHOICES)}",
                          key="identification.residual_scaling")
    bad = [k for k in components if k not in COMPONENTS]
    if bad or not components:
        raise ConfigError(f"cannot fit components {bad or '(none)'}; choose from "
                          f"{list(COMPONENTS)}", key="identification.components")
    fixed = dict(fixed or {})
    names = [t.name for t in model.terms]
    unknown = set(fixed) - set(names)
    if unknown:
        raise ConfigError(f"fixed coefficients for unknown terms {sorted(unknown)}; terms: "
                          f"{names}", key="identification.fixed")
    fitted = [n for n in names if n not in fixed]
    if not fitted:
        raise ConfigError("every coefficient is fixed: nothing to identify",
                          key="identification.fixed")
    no_frequency = [c.name for c in cases if not (np.isfinite(c.frequency) and c.frequency > 0)]
    if no_frequency:  # it would share no frequency's weight, or take another's
        raise ConfigError(f"case(s) {', '.join(no_frequency)}: the record gives neither a "
                          "frequency nor a period, so it cannot be weighted by frequency",
                          key="identification.strategy")
    weights = frequency_weights([c.frequency for c in cases], strategy)

    def fit_scaled(scaling: str) -> tuple[_Blocks, _System, np.ndarray]:
        blocks = _blocks(cases, model, fitted, fixed, components, scaling)
        system = _assemble(blocks, weights)
        return blocks, system, _solve(system.grams.sum(axis=0), system.rhs.sum(axis=0), fitted)

    asked = residual_scaling
    residual_scaling = "grid" if asked == AUTO else asked
    blocks, system, x = fit_scaled(residual_scaling)
    if asked == AUTO:  # the grid fit's errors say which scaling weighs the cases so
        on_grid = model.with_coefficients({**dict(zip(fitted, x.tolist(), strict=True)),
                                           **fixed})
        residual_scaling = choose_scaling(measure_error_growth(cases, on_grid, components))
        if residual_scaling != "grid":
            blocks, system, x = fit_scaled(residual_scaling)
    rng = np.random.default_rng(seed)
    boot = np.empty((n_bootstrap, len(fitted)))
    groups = [np.flatnonzero(np.isclose(system.frequencies, f)) for f in weights]
    for b in range(n_bootstrap):
        counts = np.zeros(len(cases))
        for g in groups:
            np.add.at(counts, rng.choice(g, size=len(g), replace=True), 1.0)
        gram = np.einsum("c,cij->ij", counts, system.grams)
        rhs = counts @ system.rhs
        try:
            boot[b] = _solve(gram, rhs, fitted)
        except MfflapError:
            boot[b] = np.nan
    coeffs = {**dict(zip(fitted, x.tolist(), strict=True)), **fixed}
    coeffs = {n: coeffs[n] for n in names}
    se = {n: 0.0 if n in fixed else float("nan") for n in names}
    interval = {n: (coeffs[n], coeffs[n]) if n in fixed else (float("nan"), float("nan"))
                for n in names}
    # with one case per frequency every replicate is the data themselves: a spread of 0
    # would claim certainty, so none is estimated
    if n_bootstrap > 1 and any(len(g) > 1 for g in groups):
        for j, n in enumerate(fitted):
            col = boot[:, j][np.isfinite(boot[:, j])]
            se[n] = float(np.std(col, ddof=1))
            interval[n] = (float(np.percentile(col, 2.5)), float(np.percentile(col, 97.5)))
    fitted_model = model.with_coefficients(coeffs)
    name = strategy if isinstance(strategy, str) else "custom"
    jackknife = _leave_one_out(blocks, weights, fitted)
    return IdentificationResult(
        coefficients=coeffs, standard_error=se, interval=interval, bootstrap=boot,
        fitted_terms=tuple(fitted), strategy=name, weights=weights,
        components=tuple(components), case_names=[c.name for c in cases],
        case_parameters=[dict(c.parameters) for c in cases],
        metrics=score(cases, fitted_model), excluded=dict(excluded or {}),
        notes={c.name: list(c.notes) for c in cases if c.notes}, leave_one_out=jackknife,
        residual_scaling=residual_scaling,
        error_growth=measure_error_growth(cases, fitted_model, components),
        scaling_asked=asked,
    )


__all__ = ["HELD_AT_ZERO", "RESIDUAL_SCALINGS", "SCALING_CHOICES", "IdentificationResult",
           "Influence", "identify", "most_influential", "scaling_said", "scalings_said",
           "score"]
