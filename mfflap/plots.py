"""Figures. Every function returns a matplotlib Figure and never calls ``show()``."""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.figure import Figure


def full_cycle(time: np.ndarray, values: np.ndarray, antisymmetric: bool, period: float
               ) -> tuple[np.ndarray, np.ndarray]:
    """Extend half-cycle samples to a full cycle (sign flipped for antisymmetric signals)."""
    sign = -1.0 if antisymmetric else 1.0
    return np.concatenate([time, time + period / 2]), np.concatenate([values, sign * values])


def cycle_figure(evaluation, period: float, half_cycle: bool, title: str = "") -> Figure:
    """Thrust, input power, F_n, F_t and M over one cycle.

    Parameters
    ----------
    evaluation
        A :class:`~mfflap.performance.Evaluation` of one motion.
    period : s
    half_cycle
        True if the evaluation holds the half cycle of an antisymmetric motion.
    """
    panels = [
        ("thrust", "thrust [N]", evaluation.thrust, False),
        ("input_power", "input power [W]", evaluation.input_power, False),
        ("normal_force", "F_n [N]", evaluation.loads.normal_force, True),
        ("tangential_force", "F_t [N]", evaluation.loads.tangential_force, False),
        ("moment", "M about LE [N m]", evaluation.loads.moment, True),
    ]
    fig, axes = plt.subplots(len(panels), 1, figsize=(7, 10), sharex=True)
    t = np.real(np.asarray(evaluation.state.time))
    for ax, (_, label, y, anti) in zip(axes, panels, strict=True):
        y = np.real(np.asarray(y))
        tt, yy = full_cycle(t, y, anti, period) if half_cycle else (t, y)
        ax.plot(tt / period, yy, lw=1.5)
        ax.axhline(yy.mean(), color="0.5", ls="--", lw=1, label=f"mean {yy.mean():.4g}")
        ax.set_ylabel(label)
        ax.grid(alpha=0.3)
        ax.legend(loc="upper right", fontsize=8)
    axes[-1].set_xlabel("t / T")
    if title:
        fig.suptitle(title)
    fig.tight_layout()
    return fig
