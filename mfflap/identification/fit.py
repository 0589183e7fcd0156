"""Weighted linear least squares for the force-model coefficients, with a case bootstrap.

Every term of a :class:`~mfflap.hydro.base.ForceModel` is linear in its coefficient, so the
fit is linear: for each case c and fitted component k (F_n, F_t, M),

    r_ck = (y_ck - A_ck x) / s_k,

with y the CFD signal, A the term regressors and s_k the RMS of component k over all cases
(so that newtons and newton-metres are comparable). Case c carries the weight
w_f(c) / (n_cases at f(c) * n_samples(c)): each frequency gets its strategy weight whatever
its number of cases and samples. Coefficients are bounded below by zero (they are physical
drag and added-mass coefficients) and solved by NNLS on the normal equations.

Which components: F_n and M carry C_Dn and C_an; F_t alone carries C_Dt and C_at. All three
are used by default. The moment adds where along the chord the normal load acts.

Uncertainty: samples within a case are strongly correlated, so a sample-based covariance
would be far too optimistic. Cases are resampled with replacement within each frequency
(a stratified case bootstrap); the spread of the refitted coefficients is the uncertainty.
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
from mfflap.identification.weights import frequency_weights
from mfflap.metrics import nrmse, pearson

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


def _system(cases: Sequence[CaseData], model: ForceModel, fitted: Sequence[str],
            fixed: Mapping[str, float], components: Sequence[str],
            weights: Mapping[float, float]) -> _System:
    names = [t.name for t in model.terms]
    idx_fit = [names.index(n) for n in fitted]
    idx_fix = [names.index(n) for n in fixed]
    fix_vals = np.array([fixed[n] for n in fixed])
    scales = {}
    for k in components:
        y = np.concatenate([c.cfd_signal(k) for c in cases])
        scales[k] = float(np.sqrt(np.mean(y**2))) or 1.0
    freqs = np.array([c.frequency for c in cases])
    count = {f: int(np.sum(np.isclose(freqs, f))) for f in weights}
    p = len(fitted)
    grams, rhs = np.zeros((len(cases), p, p)), np.zeros((len(cases), p))
    for i, c in enumerate(cases):
        f = min(weights, key=lambda v, c=c: abs(v - c.frequency))
        w_case = weights[f] / count[f] / c.n_samples
        regs = model.regressors(c.state)
        for k in components:
            a_all = np.column_stack([getattr(regs[t.name], k) for t in model.terms])
            y = c.cfd_signal(k)
            if idx_fix:
                y = y - a_all[:, idx_fix] @ fix_vals
            a = a_all[:, idx_fit] / scales[k]
            yk = y / scales[k]
            grams[i] += w_case * a.T @ a
            rhs[i] += w_case * a.T @ yk
    return _System(grams, rhs, freqs)


def _solve(gram: np.ndarray, rhs: np.ndarray, names: Sequence[str]) -> np.ndarray:
    """min x'Gx - 2 g'x subject to x >= 0 (NNLS on the Cholesky factor).

    A term whose regressor is zero on every sample fitted (a tangential term fitted to the
    moment about the leading edge alone, which the tangential force has no arm for) is not
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


def score(cases: Sequence[CaseData], model: ForceModel,
          signals: Sequence[str] = (*COMPONENTS, *DERIVED)) -> dict[str, dict[str, np.ndarray]]:
    """NRMSE and Pearson of ``model`` against the CFD of every case, per signal."""
    from mfflap.performance import thrust_and_power

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
             excluded: Mapping[str, str] | None = None) -> IdentificationResult:
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
    """
    if not cases:
        raise MfflapError("no usable CFD cases to identify from")
    if n_bootstrap < 0:
        raise ConfigError(f"n_bootstrap must be >= 0 (0: none), got {n_bootstrap!r}",
                          key="n_bootstrap")
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
    weights = frequency_weights([c.frequency for c in cases], strategy)
    system = _system(cases, model, fitted, fixed, components, weights)
    x = _solve(system.grams.sum(axis=0), system.rhs.sum(axis=0), fitted)
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
    return IdentificationResult(
        coefficients=coeffs, standard_error=se, interval=interval, bootstrap=boot,
        fitted_terms=tuple(fitted), strategy=name, weights=weights,
        components=tuple(components), case_names=[c.name for c in cases],
        case_parameters=[dict(c.parameters) for c in cases],
        metrics=score(cases, fitted_model), excluded=dict(excluded or {}),
        notes={c.name: list(c.notes) for c in cases if c.notes},
    )


__all__ = ["HELD_AT_ZERO", "IdentificationResult", "identify", "score"]
