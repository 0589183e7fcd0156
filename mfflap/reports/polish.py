"""Report section of the polish: each beta's Morison optimum before and after its polish on
the discrete-vortex model."""

from __future__ import annotations

from collections.abc import Mapping

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
from matplotlib.figure import Figure

from mfflap.optimisation.store import beta_label
from mfflap.optimisation.vortex_correction import STEPS_PER_PERIOD
from mfflap.optimisation.vortex_polish import PolishResult
from mfflap.reports.html import Report, figure_html, table_html, text_html


def polish_figure(polished: Mapping[float, PolishResult], max_power: float) -> Figure:
    """The vortex model's input power over the half period at each sample (the largest over
    the sample's share of the cycle), before and after the polish, W against t/T."""
    fig, axes = plt.subplots(1, len(polished), figsize=(3.6 * len(polished) + 0.6, 3.4),
                             squeeze=False)
    for ax, (beta, result) in zip(axes[0], polished.items(), strict=True):
        for samples, name, colour in ((result.start_samples, "start", "tab:red"),
                                      (result.samples, "polished", "tab:blue")):
            n = samples.sample_peaks.size
            phase = np.arange(n) / (2 * n)
            ax.plot(phase, samples.sample_peaks, color=colour, label=name)
        ax.axhline(max_power, color="r", ls=":", label="P_max")
        ax.set_title(beta_label(beta), fontsize=9)
        ax.set_xlabel("t / T")
        ax.set_ylabel("input power, vortex model [W]")
    axes[0][0].legend(fontsize=8)
    fig.tight_layout()
    return fig


def add_polish_section(rep: Report, polished: Mapping[float, PolishResult],
                       morison_optima: Mapping, max_power: float) -> None:
    """Table and figure of the polish; nothing when nothing was polished."""
    if not polished:
        return
    s = rep.section("Polished on the discrete-vortex model")
    s.blocks.append(text_html(
        "Each optimum is polished by Morison corrected sample by sample to the discrete-vortex "
        "model's thrust and power, optimised with its exact adjoint in a trust region that "
        "the vortex model judges (rounds taken when the vortex model confirms the predicted "
        "decrease of J), from the Morison optimum and from the sinusoid the vortex model "
        "ranks best; the better of the two is kept. The 'before' figures are the vortex "
        "model's at the kept polish's start. Vortex-model figures over its settled period at "
        f"{STEPS_PER_PERIOD} steps a period; Morison's over the cycle of its own samples."))
    rows = []
    for beta, result in polished.items():
        summary = morison_optima[beta].summary
        start, end = result.start_samples, result.samples
        rows.append([beta_label(beta), float(summary.mean_thrust), float(summary.mean_power),
                     morison_optima[beta].resampled_max_power, start.mean_thrust,
                     start.peak_power, end.mean_thrust, end.mean_power, end.peak_power,
                     result.start, f"{result.n_accepted} of {len(result.rounds)}",
                     result.message])
    s.blocks.append(table_html(
        ["β", "Morison: thrust [N]", "mean power [W]", "peak power [W]",
         "vortex model, before: thrust [N]", "peak power [W]",
         "polished: thrust [N]", "mean power [W]", "peak power [W]", "started from",
         "rounds taken", "stopped"], rows))
    s.blocks.append(figure_html(polish_figure(polished, max_power),
                                "Input power over the half period on the vortex model, "
                                "before and after the polish"))
