"""Report section of the model ladder: CFD, Morison and the discrete-vortex model on every
back-tested motion."""

from __future__ import annotations

from collections.abc import Mapping

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
from matplotlib.figure import Figure

from mfflap.backtest.model_ladder import STEPS_PER_PERIOD, LadderComparison
from mfflap.reports.html import Report, figure_html, table_html, text_html

#: the ladder's levels as the report names them, lowest fidelity first
LEVELS = {"morison": "Morison", "vortex": "discrete-vortex model", "cfd": "CFD"}
#: one colour per level
LEVEL_COLOURS = {"morison": "tab:red", "vortex": "tab:blue", "cfd": "0.2"}


def ladder_figure(ladders: Mapping[str, LadderComparison], max_power: float) -> Figure:
    """Mean and peak input power of the three levels per back-tested motion, W."""
    labels = list(ladders)
    x = np.arange(len(labels))
    width = 0.27
    fig, axes = plt.subplots(1, 2, figsize=(max(6.0, 2.2 * len(labels) + 2), 3.8))
    for ax, figure, title in ((axes[0], "mean_power", "mean input power [W]"),
                              (axes[1], "peak_power", "peak input power [W]")):
        for i, (level, name) in enumerate(LEVELS.items()):
            values = [getattr(getattr(ladders[k], level), figure) for k in labels]
            ax.bar(x + (i - 1) * width, values, width, label=name,
                   color=LEVEL_COLOURS[level])
        ax.set_xticks(x, labels, fontsize=8)
        ax.set_ylabel(title)
        ax.axhline(0, color="0.5", lw=0.8)
    axes[1].axhline(max_power, color="r", ls=":", label="P_max")
    axes[1].legend(fontsize=8)
    fig.tight_layout()
    return fig


def add_ladder_section(rep: Report, ladders: Mapping[str, LadderComparison],
                       max_power: float) -> None:
    """Table and figure of the ladder; nothing without a back-tested motion."""
    if not ladders:
        return
    s = rep.section("Three levels: Morison, the discrete-vortex model and CFD")
    periods = sorted({f"{x.periods:g}" for x in ladders.values()})
    s.blocks.append(text_html(
        "Morison (the coefficients the optimisation used) and the discrete-vortex model (its "
        "defaults, no parameter fitted) run through the motion each back-test imposed, ramp "
        f"included, at {STEPS_PER_PERIOD} steps a period; means and peaks over the run's "
        f"last {', '.join(periods)} periods. F_n NRMSE against CFD on CFD's samples; CFD's "
        "own figure is its last period against the one before, the yardstick for the "
        "models'. On "
        "large motions the vortex model's means are not converged at this step: at 600 "
        "steps a period they can be 10-35 % higher (docs: Findings, The discrete-vortex "
        "model)."))
    rows = []
    for label, x in ladders.items():
        for level, name in LEVELS.items():
            fig = getattr(x, level)
            rows.append([label, name, fig.mean_thrust, fig.mean_power, fig.peak_power,
                         100 * fig.normal_force_nrmse])
    s.blocks.append(table_html(["motion", "level", "mean thrust [N]", "mean power [W]",
                                "peak power [W]",
                                "F_n NRMSE [%] (CFD: its last period against the one "
                                "before)"], rows))
    s.blocks.append(figure_html(ladder_figure(ladders, max_power),
                                "Mean and peak input power, three levels"))
