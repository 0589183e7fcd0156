"""Time histories of one motion as two campaigns ran it: the forces, moment and thrust of
both records over each other, the compared window shaded, the comparison's numbers in the
title. The figure to look at when ``mfflap campaign compare`` says two set-ups differ: is it
a phase shift, a missed vortex, a burst, a drift after the first cycle?"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.figure import Figure

from mfflap.campaign.compare import CampaignComparison, CaseComparison
from mfflap.errors import MfflapError
from mfflap.performance import thrust_and_power
from mfflap.plots import save_figure
from mfflap.records.record import CfdRecord, read_record

#: (record attribute or "thrust", axis label) per panel, top to bottom
PANELS = (("normal_force", "F_n [N]"), ("tangential_force", "F_t [N]"),
          ("moment", "M about LE [N m]"), ("thrust", "thrust [N]"))


def _series(record: CfdRecord, key: str) -> np.ndarray:
    if key == "thrust":
        return thrust_and_power(record.loads, record.state)[0]
    return np.asarray(getattr(record.loads, key))


def history_figure(a: CfdRecord, b: CfdRecord, comparison: CaseComparison,
                   labels: Sequence[str] = ("A", "B")) -> Figure:
    """F_n, F_t, M and thrust of records ``a`` and ``b`` (the reference) against time.

    The loads are drawn as recorded (a numerical burst or a lost stretch shows as what it
    is; the comparison bridged it); the comparison's window is shaded and its NRMSE, mean
    thrust and bridged counts are in the titles.

    Parameters
    ----------
    a, b : CfdRecord
        The same motion from campaign A and campaign B.
    comparison : CaseComparison
        :func:`mfflap.campaign.compare.compare_records` of the two.
    labels : (str, str)
        Names of campaigns A and B for the legend.
    """
    fig, axes = plt.subplots(len(PANELS), 1, figsize=(10, 9), sharex=True)
    nrmse = {"normal_force": comparison.nrmse_normal_force,
             "tangential_force": comparison.nrmse_tangential_force,
             "moment": comparison.nrmse_moment}
    for ax, (key, axis_label) in zip(axes, PANELS, strict=True):
        ax.plot(b.time, _series(b, key), color="k", lw=1.2, label=labels[1])
        ax.plot(a.time, _series(a, key), color="tab:red", lw=1.0, alpha=0.85, label=labels[0])
        ax.axvspan(comparison.start_s, comparison.end_s, color="0.9", zorder=0)
        ax.set_ylabel(axis_label)
        ax.grid(alpha=0.3)
        if key in nrmse:
            ax.set_title(f"NRMSE {100 * nrmse[key]:.1f} %", fontsize=8, loc="right")
        else:
            ax.set_title(f"mean thrust {comparison.mean_thrust_a_n:.3g} N ({labels[0]}) "
                         f"against {comparison.mean_thrust_b_n:.3g} N ({labels[1]})",
                         fontsize=8, loc="right")
    axes[0].legend(fontsize=8, loc="upper left")
    axes[-1].set_xlabel("t [s] (shaded: the compared window)")
    fig.suptitle(f"{comparison.case_id}: {labels[0]} against {labels[1]}; bursts "
                 f"{comparison.n_bursts_a}/{comparison.n_bursts_b}, lost "
                 f"{comparison.lost_a_s:.3g}/{comparison.lost_b_s:.3g} s", fontsize=9)
    fig.tight_layout()
    return fig


def plot_histories(folder: str | Path, comparison: CampaignComparison,
                   labels: Sequence[str] = ("A", "B"),
                   case_ids: Sequence[str] | None = None) -> list[Path]:
    """One PNG per compared case, ``<folder>/<case_id>.png`` (:func:`history_figure`).

    Raises
    ------
    MfflapError
        If a case asked for in ``case_ids`` is not among the compared ones, naming it, why
        (not run by both, or outside the window compared) and the compared cases.
    """
    chosen = {c.case_id: c for c in comparison.cases}
    if case_ids:
        missing = [c for c in case_ids if c not in chosen]
        if missing:
            why = [f"{comparison.outside_window[c]}: outside the window compared"
                   if c in comparison.outside_window
                   else f"{c}: not run by both {comparison.folder_a} and {comparison.folder_b}"
                   for c in missing]
            raise MfflapError(f"{'; '.join(why)}; compared: {', '.join(chosen) or 'none'}")
        chosen = {c: chosen[c] for c in case_ids}
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    written = []
    for case_id, case in chosen.items():
        a = read_record(Path(comparison.folder_a) / f"{case_id}.h5")
        b = read_record(Path(comparison.folder_b) / f"{case_id}.h5")
        fig = history_figure(a, b, case, labels)
        path = folder / f"{case_id}.png"
        save_figure(fig, path, dpi=100)
        plt.close(fig)
        written.append(path)
    return written
