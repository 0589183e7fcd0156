"""The figure of how the model's error grows with each run's loads (which residual scaling
the errors ask for)."""

from __future__ import annotations

from collections.abc import Mapping

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
from matplotlib.figure import Figure
from matplotlib.ticker import LogFormatter

from mfflap.hydro.loads import LOAD_UNITS
from mfflap.identification.error_growth import ErrorGrowth

#: the components' symbols, for the axes (their units: LOAD_UNITS)
_SYMBOLS = {"normal_force": "F_n", "tangential_force": "F_t", "moment": "M"}


def error_growth_figure(growth: Mapping[str, ErrorGrowth], title: str) -> Figure | None:
    """Each run's residual RMS against its CFD load RMS, log-log, one panel per component:
    the fitted power law (its exponent b in the legend) and, through the runs' centre, the
    two the residual scalings weigh the runs for: errors of one size (b = 0, "grid") and in
    proportion to the loads (b = 1, "case"). None where nothing was measured or the points
    were not kept (an older file)."""
    shown = {k: g for k, g in growth.items() if g.load_rms}
    if not shown:
        return None
    fig, axes = plt.subplots(1, len(shown), figsize=(3.6 * len(shown) + 0.6, 3.6),
                             squeeze=False)
    for ax, (k, g) in zip(axes[0], shown.items(), strict=True):
        size, error = np.asarray(g.load_rms), np.asarray(g.residual_rms)
        ax.loglog(size, error, "o", ms=3, color="C0", label="runs")
        span = np.geomspace(size.min(), size.max(), 50)
        low, high = g.interval
        ax.loglog(span, np.exp(g.log_prefactor) * span**g.exponent, color="C0",
                  label=f"fit: b = {g.exponent:.2f} [{low:.2f}, {high:.2f}]")
        centre_x, centre_y = np.exp(np.mean(np.log(size))), np.exp(np.mean(np.log(error)))
        for b, style, said in ((0.0, ":", 'b = 0 ("grid")'), (1.0, "--", 'b = 1 ("case")')):
            ax.loglog(span, centre_y * (span / centre_x)**b, style, color="0.4", lw=1,
                      label=said)
        symbol, unit = _SYMBOLS.get(k, k), LOAD_UNITS.get(k, "")
        ax.set_xlabel(f"{symbol} RMS of the CFD ({unit})")
        ax.set_ylabel(f"{symbol} RMS of the residual ({unit})")
        ax.legend(fontsize=7, loc="upper left")
        for axis in (ax.xaxis, ax.yaxis):  # plain-text labels: a third of the drawing time
            axis.set_major_formatter(LogFormatter())  # of mathtext powers of ten
            axis.set_minor_formatter(LogFormatter(minor_thresholds=(2, 0.5)))
    fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    return fig


__all__ = ["error_growth_figure"]
