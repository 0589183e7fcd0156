"""Per-case least-squares blocks over the base terms and every candidate.

For case c and component k the rows are (y - A x) / s_ck, weighted 1 / n_samples(c) so that
every case counts equally. With ``residual_scaling="grid"`` (the default) s_ck is the
component's RMS over all cases, so the cases of large forces weigh most; with ``"case"`` it
is the component's range in case c, NRMSE's denominator, so the fits minimise the mean
square NRMSE and every case weighs alike (as in identification, :data:`RESIDUAL_SCALINGS`).
Keeping each case's Gram matrix G_c = A'A, g_c = A'y and y'y makes any fit on any subset of
terms and cases a sum of small blocks, and any case's squared error a quadratic form:
cross-validation of every candidate set costs almost nothing once the regressors are
evaluated.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from mfflap.errors import ConfigError, MfflapError
from mfflap.hydro.base import ForceTerm
from mfflap.hydro.loads import LOAD_COMPONENTS
from mfflap.identification.data import CaseData
from mfflap.identification.fit import RESIDUAL_SCALINGS

COMPONENTS = LOAD_COMPONENTS
#: the fewest cases a diagnosis can hold cases out of
MIN_CASES = 3


@dataclass
class GapSystem:
    """Regressors of every case for the base terms followed by the candidates.

    Attributes
    ----------
    names : list of str
        Column names: base terms, then candidates.
    n_base : int
    grams : (n_cases, p, p); rhs : (n_cases, p); yy : (n_cases,)
    scales : per case, dict component -> the divisor of its residuals (N or N*m)
    columns : per case, per component, (n_samples, p) regressor matrices (unscaled)
    residual_scaling : str
        A key of :data:`~mfflap.identification.fit.RESIDUAL_SCALINGS`: what ``scales`` are.
    """

    names: list[str]
    n_base: int
    grams: np.ndarray
    rhs: np.ndarray
    yy: np.ndarray
    scales: list[dict[str, float]]
    columns: list[dict[str, np.ndarray]]
    cases: list[CaseData]
    residual_scaling: str = "grid"

    @classmethod
    def build(cls, cases: Sequence[CaseData], base: Sequence[ForceTerm],
              candidates: Sequence[ForceTerm],
              components: Sequence[str] = COMPONENTS,
              residual_scaling: str = "grid") -> GapSystem:
        """Evaluate every regressor of every case once.

        Raises
        ------
        MfflapError
            If there are fewer than :data:`MIN_CASES` cases.
        ConfigError
            If ``residual_scaling`` is not a key of ``RESIDUAL_SCALINGS``.
        """
        if len(cases) < MIN_CASES:
            raise MfflapError(f"gap diagnosis needs at least {MIN_CASES} cases (it holds cases "
                              f"out to test each effect), got {len(cases)}")
        if residual_scaling not in RESIDUAL_SCALINGS:
            raise ConfigError(f"residual scaling {residual_scaling!r}: choose one of "
                              f"{', '.join(RESIDUAL_SCALINGS)}",
                              key="identification.residual_scaling")
        terms = list(base) + list(candidates)
        names = [t.name for t in terms]
        scales = _residual_scales(cases, components, residual_scaling)
        p = len(terms)
        grams, rhs, yy = np.zeros((len(cases), p, p)), np.zeros((len(cases), p)), np.zeros(
            len(cases))
        columns = []
        for i, c in enumerate(cases):
            regs = [t.regressor(c.state) for t in terms]
            cols = {}
            w = 1.0 / c.n_samples
            for k in components:
                a = np.column_stack([getattr(r, k) for r in regs])
                y = c.cfd_signal(k)
                cols[k] = a
                a_s, y_s = a / scales[i][k], y / scales[i][k]
                grams[i] += w * a_s.T @ a_s
                rhs[i] += w * a_s.T @ y_s
                yy[i] += w * y_s @ y_s
            columns.append(cols)
        return cls(names, len(base), grams, rhs, yy, scales, columns, list(cases),
                   residual_scaling)

    def fit(self, cols: Sequence[int], train: np.ndarray) -> np.ndarray:
        """Unconstrained least squares on ``cols`` over the ``train`` cases."""
        cols = list(cols)
        g = self.grams[train][:, cols][:, :, cols].sum(axis=0)
        b = self.rhs[train][:, cols].sum(axis=0)
        return _solve_normal_equations(g, b)

    def fit_held(self, cols: Sequence[int], held: Sequence[int], held_values: np.ndarray,
                 train: np.ndarray) -> np.ndarray:
        """Least squares on ``cols`` with the ``held`` columns fixed at ``held_values``.

        The fit of the free terms to what the held terms leave unexplained (the residual of
        the base model with its coefficients as configured), over the ``train`` cases.
        """
        cols, held = list(cols), list(held)
        g = self.grams[train].sum(axis=0)
        b = self.rhs[train].sum(axis=0)
        g_free = g[np.ix_(cols, cols)]
        rhs = b[cols] - g[np.ix_(cols, held)] @ np.asarray(held_values, dtype=float)
        return _solve_normal_equations(g_free, rhs)

    def correlation(self, cols: Sequence[int]) -> np.ndarray:
        """Uncentred correlation (cosine) between the regressor columns ``cols``, in the
        inner product of the fit (components scaled, cases weighted), over all cases.

        Zero columns (a term that produces no load on these cases) get zero correlation.
        """
        cols = list(cols)
        g = self.grams.sum(axis=0)[np.ix_(cols, cols)]
        norm = np.sqrt(np.clip(np.diag(g), 0.0, None))
        safe = np.where(norm > 0, norm, 1.0)
        r = g / np.outer(safe, safe)
        r[norm == 0, :] = 0.0
        r[:, norm == 0] = 0.0
        return r

    def variance_inflation(self, cols: Sequence[int]) -> np.ndarray:
        """Variance inflation factor of each column of ``cols`` among the others:
        1 / (1 - R²) with R² the share of the column explained by the other columns.

        1 for a column orthogonal to the rest; large (conventionally above 10) where the fit
        cannot tell the column's coefficient from the others'; inf for an exact dependence or
        a zero column.
        """
        cols = list(cols)
        g = self.grams.sum(axis=0)[np.ix_(cols, cols)]
        out = np.empty(len(cols))
        for j in range(len(cols)):
            others = [i for i in range(len(cols)) if i != j]
            own = g[j, j]
            if own <= 0:
                out[j] = np.inf
                continue
            if not others:
                out[j] = 1.0
                continue
            coef, *_ = np.linalg.lstsq(g[np.ix_(others, others)], g[others, j], rcond=None)
            unexplained = (own - g[j, others] @ coef) / own
            out[j] = 1.0 / unexplained if unexplained > 1e-14 else np.inf
        return out

    def case_sse(self, cols: Sequence[int], x: np.ndarray, cases: np.ndarray) -> np.ndarray:
        """Weighted scaled squared error of each case in ``cases`` for coefficients ``x``."""
        cols = list(cols)
        g = self.grams[cases][:, cols][:, :, cols]
        b = self.rhs[cases][:, cols]
        return self.yy[cases] - 2 * b @ x + np.einsum("i,cij,j->c", x, g, x)

    def predict(self, case: int, cols: Sequence[int], x: np.ndarray, component: str
                ) -> np.ndarray:
        """Prediction of one component for one case."""
        return self.columns[case][component][:, list(cols)] @ x

    def cross_validate(self, cols: Sequence[int], folds: Sequence[np.ndarray]
                       ) -> tuple[np.ndarray, list[np.ndarray]]:
        """Held-out squared error per case and the coefficients fitted for each fold."""
        sse = np.empty(len(self.cases))
        coefs = []
        every = np.arange(len(self.cases))
        for held in folds:
            train = np.setdiff1d(every, held)
            x = self.fit(cols, train)
            sse[held] = self.case_sse(cols, x, held)
            coefs.append(x)
        return sse, coefs


def _residual_scales(cases: Sequence[CaseData], components: Sequence[str],
                     residual_scaling: str) -> list[dict[str, float]]:
    """Each case's divisor of each component's residual: the RMS over every case ("grid")
    or the range in the case ("case"); 1 where that is 0 (a component that stays 0)."""
    if residual_scaling == "case":
        return [{k: float(np.ptp(c.cfd_signal(k))) or 1.0 for k in components} for c in cases]
    grid = {k: float(np.sqrt(np.mean(np.concatenate([c.cfd_signal(k) for c in cases])**2)))
            or 1.0 for k in components}
    return [dict(grid) for _ in cases]


def _solve_normal_equations(gram: np.ndarray, rhs: np.ndarray) -> np.ndarray:
    """Solve G x = b with a ridge of 1e-10 of G's mean diagonal (nearly dependent terms)."""
    ridge = 1e-10 * np.trace(gram) / len(rhs)
    return np.linalg.solve(gram + ridge * np.eye(len(rhs)), rhs)


def group_folds(labels: Sequence[object], n_folds: int | None = None,
                seed: int = 0) -> list[np.ndarray]:
    """Folds that keep each group (case, frequency, amplitude...) together."""
    labels = list(labels)
    groups = sorted(set(labels), key=str)
    rng = np.random.default_rng(seed)
    order = rng.permutation(len(groups))
    k = len(groups) if n_folds is None else min(n_folds, len(groups))
    folds = [[] for _ in range(k)]
    for pos, gi in enumerate(order):
        folds[pos % k].extend(i for i, lab in enumerate(labels) if lab == groups[gi])
    return [np.array(sorted(f)) for f in folds if f]
