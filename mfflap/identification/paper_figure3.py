"""The identified model's agreement with CFD against what the paper's Figure 3 reports.

The paper (Table 1 grid, the Morison model identified with uniform weighting) reports a
Pearson correlation of F_n above 0.78 for every case, an NRMSE of at most 10 % for f = 0.2 Hz
with h_amp >= 0.4 m, f = 0.5 Hz with h_amp >= 0.2 m and generally the highest frequency, and
a Strouhal range St = 2 f A / U of 0.35-8.17 for those cases (A the trailing edge's half
excursion). :func:`figure3_comparison` measures the same on an identification result.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from mfflap.identification.data import CaseData
from mfflap.identification.fit import IdentificationResult
from mfflap.performance import strouhal_number

#: the paper's lowest Pearson correlation of F_n over its grid
PAPER_MIN_PEARSON = 0.78
#: the NRMSE at or below which the paper calls a case's agreement reasonable
PAPER_NRMSE_BAR = 0.10
#: the paper's Strouhal range of those cases, St = 2 f A / U
PAPER_STROUHAL_RANGE = (0.35, 8.17)
#: the paper's Strouhal range of its whole grid
PAPER_GRID_STROUHAL_RANGE = (0.01, 8.17)


@dataclass(frozen=True)
class Figure3Comparison:
    """Figure 3's measures on an identification result.

    Attributes
    ----------
    case_names : the cases compared
    pearson, nrmse : per case, of F_n (NRMSE as a fraction of the CFD range)
    strouhal : per case, St = 2 f A / U with A the trailing edge's half excursion over the
        compared samples
    """

    case_names: tuple[str, ...]
    pearson: np.ndarray
    nrmse: np.ndarray
    strouhal: np.ndarray

    @property
    def min_pearson(self) -> float:
        """The lowest Pearson correlation of F_n over the cases."""
        return float(np.min(self.pearson))

    @property
    def below_paper_pearson(self) -> list[str]:
        """The cases whose Pearson correlation is at or below the paper's 0.78."""
        return [n for n, r in zip(self.case_names, self.pearson, strict=True)
                if r <= PAPER_MIN_PEARSON]

    @property
    def within_bar(self) -> np.ndarray:
        """Per case: F_n NRMSE at most the paper's 10 %."""
        return self.nrmse <= PAPER_NRMSE_BAR

    def strouhal_range_within_bar(self) -> tuple[float, float]:
        """The Strouhal range of the cases within the 10 % bar (NaN, NaN when none is)."""
        st = self.strouhal[self.within_bar]
        return (float(st.min()), float(st.max())) if st.size else (np.nan, np.nan)

    def rows(self) -> list[list[object]]:
        """(measure, here, the paper) rows for a report table."""
        low, high = self.strouhal_range_within_bar()
        return [
            ["cases compared", len(self.case_names), 125],
            ["lowest Pearson r of F_n", f"{self.min_pearson:.3f}",
             f"> {PAPER_MIN_PEARSON}"],
            [f"cases with Pearson r ≤ {PAPER_MIN_PEARSON}", len(self.below_paper_pearson), 0],
            [f"cases with F_n NRMSE ≤ {PAPER_NRMSE_BAR:.0%}", int(self.within_bar.sum()), "–"],
            ["their St = 2 f A / U", f"{low:.2f}-{high:.2f}",
             "{:.2f}-{:.2f}".format(*PAPER_STROUHAL_RANGE)],
            ["St of all cases", f"{self.strouhal.min():.2f}-{self.strouhal.max():.2f}",
             "{:.2f}-{:.2f}".format(*PAPER_GRID_STROUHAL_RANGE)],
        ]


def figure3_comparison(result: IdentificationResult, cases: Sequence[CaseData],
                       chord: float, velocity: float) -> Figure3Comparison:
    """Figure 3's measures of ``result`` on its ``cases`` (those it was fitted to, by name;
    chord m, velocity m/s: the plate's and the stream's), over its Table 1 grid cases only
    (the pitch-ramp motions, ``kind = "ramp_harmonic"``: not pooled back-tests or harmonic
    motions).

    Examples
    --------
    >>> from types import SimpleNamespace
    >>> from mfflap.kinematics.continuous import HarmonicMotion
    >>> state = HarmonicMotion(1.0, 0.3, 0.0).sample(np.linspace(0.0, 1.0, 101))
    >>> case = SimpleNamespace(name="c", state=state, frequency=1.0, parameters={})
    >>> result = SimpleNamespace(case_names=["c"], metrics={"normal_force": {
    ...     "pearson": np.array([0.9]), "nrmse": np.array([0.05])}})
    >>> cmp = figure3_comparison(result, [case], chord=0.16, velocity=0.3)
    >>> round(float(cmp.strouhal[0]), 3), cmp.below_paper_pearson
    (2.0, [])
    """
    by_name = {c.name: c for c in cases}
    kept = [i for i, name in enumerate(result.case_names)
            if by_name[name].parameters.get("kind", "ramp_harmonic") == "ramp_harmonic"]
    names = tuple(result.case_names[i] for i in kept)
    strouhal = []
    for name in names:
        case = by_name[name]
        te = np.real(np.asarray(case.state.trailing_edge_position(chord), dtype=float))
        strouhal.append(float(strouhal_number(case.frequency, 0.5 * (te.max() - te.min()),
                                              velocity)))
    metrics = result.metrics["normal_force"]
    return Figure3Comparison(names, np.asarray(metrics["pearson"], dtype=float)[kept],
                             np.asarray(metrics["nrmse"], dtype=float)[kept],
                             np.asarray(strouhal))


__all__ = ["PAPER_MIN_PEARSON", "PAPER_NRMSE_BAR", "PAPER_STROUHAL_RANGE",
           "Figure3Comparison", "figure3_comparison"]
