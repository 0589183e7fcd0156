"""Whether a model's residual is noise: the Ljung-Box test of each case's and component's
residual, its noise taken as first-order autoregressive.

A model that misses an effect leaves a residual that follows the motion; what is left once
the model holds is measurement or solver noise. Noise sampled as densely as force records
are is itself correlated from sample to sample, so the test takes the noise model to be
AR(1), x[t] = rho x[t-1] + e[t] with white innovations e (white noise is rho = 0): each
residual is whitened with its own lag-1 autocorrelation, and the innovations are tested
with the Ljung-Box statistic (Ljung & Box 1978, *Biometrika* 65, 297)

    Q = n (n + 2) sum_{k=1}^{K} r_k^2 / (n - k),

chi-squared with K - 1 degrees of freedom (one for the fitted rho) when the residual is
AR(1) noise. A deterministic residual (a missed effect, periodic in the motion) is not
AR(1) and leaves its innovations correlated. The statistics of every series add up: their
sum is chi-squared with the summed degrees of freedom, so an effect too weak to show in
one case shows across many.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
from scipy.stats import chi2

from mfflap.hydro.loads import LOAD_COMPONENTS as COMPONENTS
from mfflap.identification.data import CaseData

#: autocorrelation lags the test sums over (fewer for a series shorter than 5 of them)
MAX_LAG = 20


def ar1_innovations(residual: np.ndarray) -> np.ndarray:
    """``residual`` whitened by its own AR(1) fit: x[t] - rho x[t-1], rho its lag-1
    autocorrelation.

    Examples
    --------
    >>> rng = np.random.default_rng(0)
    >>> e = rng.normal(size=5000)
    >>> x = np.empty_like(e); x[0] = e[0]
    >>> for i in range(1, len(e)):
    ...     x[i] = 0.9 * x[i - 1] + e[i]
    >>> bool(abs(np.corrcoef(ar1_innovations(x)[1:], ar1_innovations(x)[:-1])[0, 1]) < 0.05)
    True
    """
    x = np.asarray(residual, dtype=float)
    x = x - x.mean()
    energy = float(x @ x)
    rho = 0.0 if energy == 0.0 else float(np.clip(x[:-1] @ x[1:] / energy, -0.999, 0.999))
    return x[1:] - rho * x[:-1]


def ljung_box(series: np.ndarray, max_lag: int = MAX_LAG) -> tuple[float, int]:
    """The Ljung-Box statistic Q of ``series`` and its lags K (``max_lag``, fewer for a
    series shorter than 5 K).

    Examples
    --------
    >>> q, lags = ljung_box(np.random.default_rng(0).normal(size=600))
    >>> lags, bool(q < 40)
    (20, True)
    """
    x = np.asarray(series, dtype=float)
    x = x - x.mean()
    n = len(x)
    lags = min(max_lag, max(1, n // 5))
    energy = float(x @ x)
    if n < 3 or energy == 0.0:
        return 0.0, lags
    r = np.array([float(x[:-k] @ x[k:]) / energy for k in range(1, lags + 1)])
    return float(n * (n + 2) * np.sum(r**2 / (n - np.arange(1, lags + 1)))), lags


@dataclass(frozen=True)
class WhitenessTest:
    """The Ljung-Box test of every case's and component's AR(1)-whitened residual.

    Attributes
    ----------
    statistics
        Per case name, per component: the Ljung-Box Q of its innovations.
    degrees_of_freedom
        Per case name, per component: the lags less the fitted rho.
    alpha
        The significance level.
    """

    statistics: dict[str, dict[str, float]]
    degrees_of_freedom: dict[str, dict[str, int]]
    alpha: float

    def _pairs(self) -> list[tuple[str, str, float, int]]:
        return [(case, comp, q, self.degrees_of_freedom[case][comp])
                for case, qs in self.statistics.items() for comp, q in qs.items()]

    @property
    def n_series(self) -> int:
        """How many residual series were tested."""
        return len(self._pairs())

    @property
    def p_value(self) -> float:
        """The probability of a summed statistic this large were every residual AR(1)
        noise."""
        pairs = self._pairs()
        return float(chi2.sf(sum(q for *_, q, _ in pairs), sum(d for *_, d in pairs)))

    @property
    def within_noise(self) -> bool:
        """Whether the residual is indistinguishable from noise at ``alpha``."""
        return self.p_value > self.alpha

    @property
    def least_white(self) -> tuple[str, str, float]:
        """The case, component and p-value of the least white series."""
        return min(((case, comp, float(chi2.sf(q, d))) for case, comp, q, d in self._pairs()),
                   key=lambda item: item[2])

    @property
    def share_structured(self) -> float:
        """The share of series that reject AR(1) noise on their own at ``alpha``."""
        return float(np.mean([chi2.sf(q, d) <= self.alpha for *_, q, d in self._pairs()]))

    def said(self) -> str:
        """The test and its outcome in words."""
        case, comp, p = self.least_white
        return (f"Ljung-Box test of the held-out residual against AR(1) noise "
                f"({self.n_series} series, {MAX_LAG} lags each): p = {self.p_value:.2g}, "
                f"{self.share_structured:.0%} of the series autocorrelated on their own "
                f"(least white: {case} {comp}, p = {p:.2g})")

    def as_dict(self) -> dict:
        """Plain numbers (for JSON and HDF5 attributes)."""
        case, comp, p = self.least_white
        return {"test": "Ljung-Box of AR(1) innovations", "max_lag": MAX_LAG,
                "alpha": self.alpha, "n_series": self.n_series, "p_value": self.p_value,
                "within_noise": self.within_noise, "share_structured": self.share_structured,
                "least_white": {"case": case, "component": comp, "p_value": p}}


def residual_whiteness(cases: Sequence[CaseData], predictions: Sequence[Mapping[str, np.ndarray]],
                   alpha: float) -> WhitenessTest:
    """The Ljung-Box test of each case's AR(1)-whitened residual, CFD minus
    ``predictions`` (one mapping of component to predicted series per case).

    Examples
    --------
    >>> from mfflap.hydro.loads import Loads
    >>> from mfflap.kinematics.state import KinematicState
    >>> t = np.linspace(0.0, 2.0, 400)
    >>> z = np.zeros_like(t)
    >>> rng = np.random.default_rng(1)
    >>> cfd = Loads(t, *(rng.normal(size=t.size) for _ in range(3)))
    >>> case = CaseData("c", {}, KinematicState(t, z, z, z, z, z, z), cfd)
    >>> residual_whiteness([case], [{k: z for k in COMPONENTS}], 0.01).within_noise
    True
    """
    statistics: dict[str, dict[str, float]] = {}
    dof: dict[str, dict[str, int]] = {}
    for case, predicted in zip(cases, predictions, strict=True):
        statistics[case.name], dof[case.name] = {}, {}
        for k in COMPONENTS:
            q, lags = ljung_box(ar1_innovations(case.cfd_signal(k) - predicted[k]))
            statistics[case.name][k], dof[case.name][k] = q, max(lags - 1, 1)
    return WhitenessTest(statistics, dof, alpha)
