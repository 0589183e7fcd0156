"""Report section: where the optimised motions lie against the identification data."""

from __future__ import annotations

from collections.abc import Mapping

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

from mfflap.identification.coverage import FEATURE_UNITS, Coverage
from mfflap.reports.html import Report, figure_html, table_html, text_html


def coverage_figure(coverage: Mapping[str, Coverage]):
    """Per variable, the identification data's range (grey) and each motion's value, over
    the data's largest (log scale), with the leverage ratio as the last row."""
    ranges = next(iter(coverage.values())).ranges
    names = [n for n in FEATURE_UNITS if n in ranges]
    fig, ax = plt.subplots(figsize=(8, 0.45 * (len(names) + 1) + 1.4))
    y = np.arange(len(names) + 1)
    for i, name in enumerate(names):
        lo, hi = ranges[name]
        if hi > 0:
            ax.plot([max(lo / hi, 1e-4), 1.0], [i, i], color="0.75", lw=8,
                    solid_capstyle="butt")
    ax.plot([1e-4, 1.0], [len(names)] * 2, color="0.75", lw=8, solid_capstyle="butt")
    for j, (label, cov) in enumerate(coverage.items()):
        xs = [cov.features[n] / ranges[n][1] if ranges[n][1] > 0 else np.nan for n in names]
        xs.append(cov.leverage_ratio)
        ax.scatter(np.clip(xs, 1e-4, None), y + 0.12 * (j - (len(coverage) - 1) / 2),
                   s=28, label=label, zorder=3)
    ax.set_xscale("log")
    ax.axvline(1.0, color="k", lw=0.8)
    ax.set_yticks(y, [f"{n} [{FEATURE_UNITS[n]}]" for n in names] + ["leverage"])
    ax.invert_yaxis()
    ax.set_xlabel("value over the identification data's largest (grey: the data's range)")
    ax.legend(fontsize=8, loc="lower left")
    fig.tight_layout()
    return fig


def add_coverage_section(rep: Report, coverage: Mapping[str, Coverage], n_cases: int) -> None:
    """Table and figure of each motion against the identification data."""
    s = rep.section("Do the motions lie within the identification data?")
    s.blocks.append(text_html(
        f"Each motion as CFD imposes it, against the {n_cases} identification cases: a "
        "variable beyond their range, or a leverage above theirs (the fit's regressors "
        "outside the ellipsoid that holds every identification sample), means the model is "
        "extrapolated there and its prediction, and the optimum it found, rest on no CFD."))
    rows = [[label, "no: extrapolated" if cov.extrapolated else "yes",
             cov.leverage_ratio, cov.describe()] for label, cov in coverage.items()]
    s.blocks.append(table_html(["motion", "within the data", "leverage / data's largest",
                                "where"], rows))
    out = [label for label, cov in coverage.items() if cov.extrapolated]
    if out:
        s.blocks.append(text_html(f"Extrapolated: {', '.join(out)}. Add identification cases "
                                  "that reach these motions (or back-test them: the "
                                  "back-test below is the check).", warn=True))
    if coverage and next(iter(coverage.values())).ranges:
        s.blocks.append(figure_html(coverage_figure(coverage),
                                    "Each motion's variables over the identification data's "
                                    "largest"))
