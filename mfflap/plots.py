"""Figures. Every function returns a matplotlib Figure and never calls ``show()``."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.figure import Figure

#: the colour of the best feasible sinusoid in every figure
SINUSOID_COLOUR = "0.35"


def motion_colour(label: str) -> str | tuple[float, float, float, float]:
    """The colour of a motion in every figure of a report: one colour per β, the same in
    each figure (viridis at 0.85 β), grey for the best sinusoid, matplotlib's next colour
    (None) for anything else.

    Parameters
    ----------
    label
        ``"β = 0.5"``, ``"best sinusoid"`` or another label.

    Examples
    --------
    >>> motion_colour("β = 0") == motion_colour("β = 0.0")
    True
    >>> motion_colour("best sinusoid")
    '0.35'
    """
    if "sinusoid" in label:
        return SINUSOID_COLOUR
    text = label.replace("β", "").replace("=", "").strip()
    try:
        beta = float(text)
    except ValueError:
        return None  # type: ignore[return-value]
    return plt.cm.viridis(0.85 * min(max(beta, 0.0), 1.0))


def save_figure(figure: Figure, path: str | Path, dpi: int = 120) -> Path:
    """Save ``figure`` to ``path`` (its format from the suffix), making the folders it lies
    in, so that a figure asked for in a new folder does not fail after the work is done.

    Returns
    -------
    Path
        ``path``.
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    figure.savefig(path, dpi=dpi)
    return path


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


def model_comparison_figure(comparison, title: str = "") -> Figure:
    """A CFD run's F_n, F_t, M, thrust and input power beside the model's over time.

    Parameters
    ----------
    comparison
        A :class:`~mfflap.cfd.model_comparison.ModelComparison`. The discarded start is
        shaded and left off the scale; the load panels' titles give the NRMSE and Pearson
        of the compared samples.
    """
    cfd, model, summary = comparison.cfd_loads, comparison.model_loads, comparison.summary
    panels = [
        ("normal_force", "F_n [N]", cfd.normal_force, model.normal_force),
        ("tangential_force", "F_t [N]", cfd.tangential_force, model.tangential_force),
        ("moment", "M about LE [N m]", cfd.moment, model.moment),
        ("thrust", "thrust [N]", comparison.cfd_thrust_n, comparison.model_thrust_n),
        ("input_power", "input power [W]", comparison.cfd_power_w, comparison.model_power_w),
    ]
    t = np.asarray(cfd.time, dtype=float)
    compared = np.asarray(comparison.compared, dtype=bool)
    fig, axes = plt.subplots(len(panels), 1, figsize=(8, 11), sharex=True)
    for ax, (name, label, cfd_y, model_y) in zip(axes, panels, strict=True):
        cfd_y, model_y = np.real(np.asarray(cfd_y)), np.real(np.asarray(model_y))
        ax.plot(t, cfd_y, lw=1.2, label="CFD")
        ax.plot(t, model_y, lw=1.2, ls="--", label="model")
        if not compared.all():  # the scale of the compared samples, not of the start-up
            ax.axvspan(t[0], t[compared][0], color="0.85", zorder=0)
            shown = np.concatenate([cfd_y[compared], model_y[compared]])
            low, high = float(shown.min()), float(shown.max())
            pad = 0.1 * (high - low) or 0.1 * max(abs(high), 1e-12)
            ax.set_ylim(low - pad, high + pad)
        if f"nrmse_{name}" in summary:
            ax.set_title(f"NRMSE {100 * summary[f'nrmse_{name}']:.1f} %, Pearson "
                         f"{summary[f'pearson_{name}']:.3f}", fontsize=9, loc="right")
        ax.set_ylabel(label)
        ax.grid(alpha=0.3)
    axes[0].legend(loc="upper left", fontsize=8)
    axes[-1].set_xlabel("t [s] (shaded: discarded start, off the scale of the compared "
                        "samples)" if not compared.all() else "t [s]")
    fig.suptitle(title or str(summary.get("source", "")), fontsize=10)
    fig.tight_layout()
    return fig
