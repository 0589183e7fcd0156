"""How the reduced model's error grows with the size of each run's loads.

A least-squares fit over many runs is most accurate when each run's residuals are weighted
by the inverse of their variance. Which residual scaling (:data:`RESIDUAL_SCALINGS`) does
that is a question the data answer: fitting

    log(RMS of the residual in case c) = a + b log(RMS of the CFD load in case c)

over the cases, per component, gives the exponent b. Near 0, the model errs by about the
same amount in every run, and one scale per component over the grid (``"grid"``) weighs the
runs as their errors say. Near 1, the error is a like share of each run's loads (the same
NRMSE in every run), and each run's own range (``"case"``) does. ``mfflap gap blindtest
--noise absolute | relative`` shows what the other choice costs.
"""

from __future__ import annotations

import json
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
from scipy import stats

from mfflap.hydro.base import ForceModel
from mfflap.identification.data import COMPONENTS, CaseData

#: the residual scaling asked for to have the data choose (:func:`choose_scaling`)
AUTO = "auto"
#: the exponent that divides the two scalings: nearer 0, "grid"; nearer 1, "case"
MIDPOINT = 0.5
#: the fewest cases whose slope has a confidence interval (one degree of freedom left)
MIN_CASES = 3


@dataclass(frozen=True)
class ErrorGrowth:
    """The exponent b of residual RMS ~ (load RMS)^b over the cases, for one component.

    Attributes
    ----------
    component : str
    exponent : float
        The least-squares slope in log-log.
    interval : tuple of float
        Its 95 % confidence interval (Student's t on n_cases - 2 degrees of freedom).
    n_cases : int
        The cases it was fitted on (those with a nonzero load and residual).
    log_prefactor : float
        The fit's intercept a: residual RMS = exp(a) (load RMS)^b.
    load_rms, residual_rms : tuple of float
        Each of those cases' CFD load RMS and residual RMS (N or N*m): the points fitted.
    """

    component: str
    exponent: float
    interval: tuple[float, float]
    n_cases: int
    log_prefactor: float = float("nan")
    load_rms: tuple[float, ...] = ()
    residual_rms: tuple[float, ...] = ()

    @property
    def matching_scaling(self) -> str:
        """The residual scaling that weighs the cases as this growth says: "case" from an
        exponent of :data:`MIDPOINT` up, else "grid"."""
        return "case" if self.exponent >= MIDPOINT else "grid"

    def summary(self) -> dict:
        """The exponent, its interval and the scaling it asks for (for JSON output)."""
        return {"exponent": self.exponent, "interval": list(self.interval),
                "matching_scaling": self.matching_scaling}

    def __str__(self) -> str:
        low, high = self.interval
        return f"{self.component} {self.exponent:.2f} [{low:.2f}, {high:.2f}]"


def measure_error_growth(cases: Sequence[CaseData], model: ForceModel,
                         components: Sequence[str] = COMPONENTS) -> dict[str, ErrorGrowth]:
    """Fit the exponent of each component's error growth over ``cases`` for ``model``.

    A component with fewer than :data:`MIN_CASES` cases of nonzero load and residual, or
    whose loads are all of one size, is left out (nothing to fit a slope to).
    """
    loads = [model.loads(c.state) for c in cases]
    out = {}
    for k in components:
        size = np.array([np.sqrt(np.mean(c.cfd_signal(k)**2)) for c in cases])
        error = np.array([np.sqrt(np.mean((c.cfd_signal(k) - getattr(ld, k))**2))
                          for c, ld in zip(cases, loads, strict=True)])
        usable = (size > 0) & (error > 0) & np.isfinite(size) & np.isfinite(error)
        x, y = np.log(size[usable]), np.log(error[usable])
        if len(x) < MIN_CASES or np.ptp(x) == 0:
            continue
        fit = stats.linregress(x, y)
        slope = float(fit.slope)
        half = float(stats.t.ppf(0.975, len(x) - 2) * fit.stderr)
        out[k] = ErrorGrowth(k, slope, (slope - half, slope + half), len(x),
                             float(fit.intercept), tuple(size[usable].tolist()),
                             tuple(error[usable].tolist()))
    return out


def growth_to_json(growth: Mapping[str, ErrorGrowth]) -> str:
    """``growth`` as JSON (an HDF5 attribute), read back by :func:`growth_from_json`."""
    return json.dumps({k: {"exponent": g.exponent, "interval": list(g.interval),
                           "n_cases": g.n_cases, "log_prefactor": g.log_prefactor,
                           "load_rms": list(g.load_rms), "residual_rms": list(g.residual_rms)}
                       for k, g in growth.items()})


def growth_from_json(text: str) -> dict[str, ErrorGrowth]:
    """What :func:`growth_to_json` wrote ("{}": none measured)."""
    return {k: ErrorGrowth(k, v["exponent"], tuple(v["interval"]), int(v["n_cases"]),
                           v["log_prefactor"], tuple(v["load_rms"]), tuple(v["residual_rms"]))
            for k, v in json.loads(text).items()}


def choose_scaling(growth: Mapping[str, ErrorGrowth]) -> str:
    """The residual scaling ``"auto"`` stands for: "case" where every component measured
    asks for it, else "grid" (also where none could be measured, or they disagree)."""
    matching = {g.matching_scaling for g in growth.values()}
    return "case" if matching == {"case"} else "grid"


def scaling_advice(growth: Mapping[str, ErrorGrowth], used: str) -> str:
    """One sentence: how the errors grow, and whether ``used`` weighs the cases so."""
    if not growth:
        return "the error's growth with the runs' loads could not be measured"
    said = "; ".join(map(str, growth.values()))
    matching = {g.matching_scaling for g in growth.values()}
    head = f"residual RMS grows with the run's load RMS as load^b: b = {said} (95 %)"
    if matching != {used} and len(matching) == 1:
        better = matching.pop()
        why = ("errors in proportion to each run's loads" if better == "case"
               else "errors of one size in every run")
        return (f"{head}: {why}, which residual scaling \"{better}\" weighs the runs by, "
                f"not \"{used}\"")
    if matching == {used}:
        return f"{head}, as residual scaling \"{used}\" weighs the runs"
    asking = {m: [k for k, g in growth.items() if g.matching_scaling == m]
              for m in ("grid", "case")}
    asks = "; ".join(f"{', '.join(names)} ask{'s' if len(names) == 1 else ''} for \"{m}\""
                     for m, names in asking.items())
    return f"{head}: the components disagree ({asks}), and \"auto\" keeps \"grid\""


__all__ = ["AUTO", "ErrorGrowth", "choose_scaling", "growth_from_json", "growth_to_json",
           "measure_error_growth", "scaling_advice"]
