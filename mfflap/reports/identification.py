"""Identification and weighting-sensitivity reports (the paper's Figure 3 and Table 2 kind)."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
from matplotlib.figure import Figure

from mfflap.cfd.case_inputs import kept_wall_treatment
from mfflap.hydro.base import ForceModel
from mfflap.identification.data import BURST_NOTE, CaseData, motion_frequency
from mfflap.identification.error_growth import scaling_advice
from mfflap.identification.fit import (
    HELD_AT_ZERO,
    IdentificationResult,
    most_influential,
    scalings_said,
)
from mfflap.identification.paper_figure3 import figure3_comparison
from mfflap.identification.repeatability import cycle_nrmse
from mfflap.performance import thrust_and_power
from mfflap.reports.error_growth_plot import error_growth_figure
from mfflap.reports.html import (
    Report,
    figure_html,
    folded_html,
    signed_percent,
    table_html,
    text_html,
)

SIGNAL_LABELS = {"normal_force": "F_n", "tangential_force": "F_t", "moment": "M",
                 "thrust": "thrust", "input_power": "input power"}
APPLICABLE_NRMSE = 0.10
METRIC_NAMES = {"nrmse": "NRMSE [%]", "pearson": "Pearson r"}


def uncertainty_weighting_said(model_nrmse: list[float], cfd_nrmse: list[float]) -> str:
    """Why the fit weighs these cases alike whatever their CFD's uncertainty: the
    inverse-variance weights 1 / (e^2 + u_c^2) (e the model's median NRMSE, u_c each
    case's CFD cycle-to-cycle NRMSE) and how far they would spread, in words.

    Examples
    --------
    >>> uncertainty_weighting_said([0.17, 0.2], [0.01, 0.05])[:38]
    'The cases are weighed alike whatever t'
    """
    e = float(np.median(model_nrmse))
    u = np.asarray(cfd_nrmse, dtype=float)
    w = 1.0 / (e**2 + u**2)
    w = w / w.mean()
    return (f"The cases are weighed alike whatever their CFD's uncertainty: inverse-variance "
            f"weights 1 / (e² + u²), e the model's median NRMSE ({100 * e:.1f} %) and u a "
            f"case's CFD cycle-to-cycle NRMSE (median {100 * float(np.median(u)):.1f} %), "
            f"would range {w.min():.2f}-{w.max():.2f} of their mean; the model's misfit, "
            f"{e / max(float(np.median(u)), 1e-12):.0f} times CFD's in the median, is what "
            "each case's residual holds.")


def cfd_own_nrmse_rows(case_names: Sequence[str], model_nrmse: np.ndarray,
                       cases_by_name: dict[str, CaseData]) -> list[tuple[str, ...]]:
    """(case, model NRMSE %, CFD cycle-to-cycle NRMSE %, CFD mesh NRMSE %, CFD time-step
    NRMSE %) of F_n for each case whose CFD uncertainty is known in any part (NaN for a part
    not measured): the rows that set the model's misfit beside CFD's own.

    Examples
    --------
    >>> cfd_own_nrmse_rows(["a"], np.array([0.2]), {})
    []
    """
    rows = []
    for name, e in zip(case_names, model_nrmse, strict=True):
        case = cases_by_name.get(name)
        if case is None:
            continue
        parts = [cycle_nrmse(case)] + [
            case.refinement[k].normal_force_nrmse if k in case.refinement else np.nan
            for k in ("mesh", "time_step")]
        if np.isfinite(parts).any():
            rows.append((name, 100 * float(e), *(100 * float(v) for v in parts)))
    return rows


def _param(result: IdentificationResult, key: str) -> np.ndarray:
    """A motion parameter of every case (NaN where its record has none); the frequency as
    identification weighs it (:func:`~mfflap.identification.data.motion_frequency`)."""
    if key == "frequency":
        return np.array([motion_frequency(p) for p in result.case_parameters])
    return np.array([float(p.get(key, np.nan)) for p in result.case_parameters])


def heave_strouhal(result: IdentificationResult, velocity: float) -> np.ndarray:
    """St_h = 2 f h_amp / U of every case (the heave-based Strouhal number)."""
    return 2 * _param(result, "frequency") * _param(result, "heave_amplitude") / velocity


def map_figure(result: IdentificationResult, signal: str = "normal_force",
               metric: str = "nrmse") -> Figure:
    """Heat maps of a metric over (f, h_amp), one panel per phase.

    A value marked * is of a case whose CFD had numerical bursts bridged
    (:mod:`mfflap.records.bursts`). Cases without a heave amplitude and phase (back-tests of
    optimised motions pooled in) are not on the grid and not drawn.
    """
    f, h, p = (_param(result, k) for k in ("frequency", "heave_amplitude", "phase_deg"))
    values = np.asarray(result.metrics[signal][metric], dtype=float)
    if metric == "nrmse":  # NRMSE in percent, as everywhere in the report
        values = 100.0 * values
    bridged = [any(BURST_NOTE in n for n in result.notes.get(name, ()))
               for name in result.case_names]
    grid_case = np.isfinite(f) & np.isfinite(h) & np.isfinite(p)  # not a pooled back-test
    fs, hs, ps = (np.unique(a[grid_case]) for a in (f, h, p))
    fig, axes = plt.subplots(1, len(ps), figsize=(3.2 * len(ps) + 1, 3.2), squeeze=False,
                             layout="constrained")
    cmap = "viridis_r" if metric == "nrmse" else "viridis"
    vmin, vmax = (0, max(30.0, float(np.nanmax(values)))) if metric == "nrmse" else (0, 1)
    im = None
    for ax, phase in zip(axes[0], ps, strict=True):
        grid = np.full((len(hs), len(fs)), np.nan)
        marks = np.full(grid.shape, "", dtype=object)
        for i in np.flatnonzero(p == phase):
            cell = np.searchsorted(hs, h[i]), np.searchsorted(fs, f[i])
            grid[cell] = values[i]
            marks[cell] = "*" if bridged[i] else ""
        im = ax.imshow(grid, origin="lower", cmap=cmap, vmin=vmin, vmax=vmax, aspect="auto")
        for (r, c), v in np.ndenumerate(grid):
            if np.isfinite(v):
                text = f"{v:.0f}" if metric == "nrmse" else f"{v:.2f}"
                ax.text(c, r, f"{text}{marks[r, c]}", ha="center", va="center", fontsize=7,
                        color="w" if (v > 0.5 * vmax) == (metric == "nrmse") else "k")
        ax.set_xticks(range(len(fs)), [f"{v:g}" for v in fs])
        ax.set_yticks(range(len(hs)), [f"{v:g}" for v in hs])
        ax.set_xlabel("f [Hz]")
        ax.set_title(f"φ = {phase:g}°")
    axes[0][0].set_ylabel("h_amp [m]")
    if any(bridged):
        fig.text(0.01, 0.99, "* numerical bursts in the CFD bridged", fontsize=7, va="top")
    label = (f"NRMSE of {SIGNAL_LABELS[signal]} [%]" if metric == "nrmse"
             else f"Pearson r of {SIGNAL_LABELS[signal]}")
    fig.colorbar(im, ax=axes[0].tolist(), label=label)
    return fig


def overlay_figure(cases: Sequence[CaseData], model: ForceModel, names: Sequence[str],
                   signals: Sequence[str] = ("normal_force", "thrust")) -> Figure:
    """CFD and model time histories of chosen cases."""
    by_name = {c.name: c for c in cases}
    chosen = [by_name[n] for n in names if n in by_name]
    fig, axes = plt.subplots(len(signals), max(len(chosen), 1),
                             figsize=(4 * max(len(chosen), 1), 2.6 * len(signals)),
                             squeeze=False)
    for j, c in enumerate(chosen):
        pred = model.loads(c.state)
        thrust, power = thrust_and_power(pred, c.state)
        for i, s in enumerate(signals):
            ax = axes[i][j]
            model_signal = {"thrust": thrust, "input_power": power}.get(s)
            if model_signal is None:
                model_signal = getattr(pred, s)
            ax.plot(c.state.time, c.cfd_signal(s), "k-", lw=1, label="CFD")
            ax.plot(c.state.time, model_signal, "C1--", lw=1.2, label="model")
            ax.set_ylabel(SIGNAL_LABELS[s])
            if i == 0:
                ax.set_title(c.name, fontsize=9)
            if i == len(signals) - 1:
                ax.set_xlabel("t [s]")
    axes[0][0].legend(fontsize=8)
    fig.tight_layout()
    return fig


def applicability_figure(result: IdentificationResult, velocity: float,
                         signal: str = "normal_force",
                         threshold: float = APPLICABLE_NRMSE) -> Figure:
    """NRMSE against the heave Strouhal number, and the share of phases that pass per (f, h)."""
    st = heave_strouhal(result, velocity)
    err = result.metrics[signal]["nrmse"]
    f, h = _param(result, "frequency"), _param(result, "heave_amplitude")
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(10, 3.6))
    sc = a1.scatter(st, 100 * err, c=np.log10(f), cmap="plasma", s=18)
    a1.axhline(100 * threshold, color="k", ls=":", label=f"NRMSE = {threshold:.0%}")
    a1.set_xscale("log")
    a1.set_xlabel("St_h = 2 f h_amp / U [-]")
    a1.set_ylabel(f"NRMSE of {SIGNAL_LABELS[signal]} [%]")
    a1.legend(fontsize=8)
    fig.colorbar(sc, ax=a1, label="log10 f [Hz]")
    fs, hs = (np.unique(a[np.isfinite(f) & np.isfinite(h)]) for a in (f, h))
    share = np.full((len(hs), len(fs)), np.nan)
    for r, hv in enumerate(hs):
        for c, fv in enumerate(fs):
            sel = (f == fv) & (h == hv)
            if sel.any():
                share[r, c] = np.mean(err[sel] <= threshold)
    im = a2.imshow(share, origin="lower", cmap="RdYlGn", vmin=0, vmax=1, aspect="auto")
    a2.set_xticks(range(len(fs)), [f"{v:g}" for v in fs])
    a2.set_yticks(range(len(hs)), [f"{v:g}" for v in hs])
    a2.set_xlabel("f [Hz]")
    a2.set_ylabel("h_amp [m]")
    a2.set_title(f"share of phases with NRMSE ≤ {threshold:.0%}")
    fig.colorbar(im, ax=a2, label="share of phases [-]")
    fig.tight_layout()
    return fig


def coefficient_figure(results: Mapping[str, IdentificationResult]) -> Figure:
    """Coefficients with bootstrap 95 % intervals, per weighting strategy."""
    names = list(next(iter(results.values())).coefficients)
    fig, ax = plt.subplots(figsize=(7, 3.6))
    width = 0.8 / len(results)
    for k, (label, res) in enumerate(results.items()):
        x = np.arange(len(names)) + (k - (len(results) - 1) / 2) * width
        v = np.array([res.coefficients[n] for n in names])
        lo = np.array([res.interval[n][0] for n in names])
        hi = np.array([res.interval[n][1] for n in names])
        ax.bar(x, v, width, label=label)
        ax.errorbar(x, v, yerr=[np.maximum(v - lo, 0), np.maximum(hi - v, 0)], fmt="none",
                    ecolor="k", capsize=2)
    ax.set_xticks(range(len(names)), names, rotation=15)
    ax.set_ylabel("coefficient [-]")
    ax.legend(title="weighting", fontsize=8)
    fig.tight_layout()
    return fig


def strategy_error_figure(results: Mapping[str, IdentificationResult],
                          signal: str = "normal_force") -> Figure:
    """Mean NRMSE per frequency for each weighting strategy."""
    fig, ax = plt.subplots(figsize=(6, 3.4))
    for label, res in results.items():
        f = _param(res, "frequency")
        fs = np.unique(f[np.isfinite(f)])
        err = res.metrics[signal]["nrmse"]
        ax.plot(fs, [100 * err[f == v].mean() for v in fs], "o-", label=label)
    ax.set_xscale("log")
    ax.set_xlabel("f [Hz]")
    ax.set_ylabel(f"mean NRMSE of {SIGNAL_LABELS[signal]} [%]")
    ax.axhline(100 * APPLICABLE_NRMSE, color="k", ls=":")
    ax.legend(title="weighting", fontsize=8)
    fig.tight_layout()
    return fig


def influence_figure(result: IdentificationResult) -> Figure | None:
    """Each fitted coefficient refitted without each case in turn (dots), against its value
    with every case (line) and its bootstrap standard error (band); the case that moves it
    most is named. None when the refits were not stored or no case moves any coefficient."""
    found = most_influential(result)
    if not found:
        return None
    rows = np.asarray(result.leave_one_out, dtype=float)
    x = np.arange(len(result.case_names))
    width_in, height_in = max(7.0, 0.17 * len(x) + 2), 2.0 * len(found) + 1.2
    fig, axes = plt.subplots(len(found), 1, figsize=(width_in, height_in), sharex=True,
                             squeeze=False)
    for ax, inf in zip(axes[:, 0], found, strict=True):
        j = result.fitted_terms.index(inf.term)
        se = inf.standard_error
        if np.isfinite(se):
            ax.axhspan(inf.value - se, inf.value + se, color="0.9", label="± 1 bootstrap s.e.")
        ax.axhline(inf.value, color="k", lw=1, label="with every case")
        ax.plot(x, rows[:, j], "o", ms=3, label="without the case")
        i = result.case_names.index(inf.case)
        ax.annotate(inf.case, (i, rows[i, j]), fontsize=7, xytext=(4, 4),
                    textcoords="offset points")
        ax.set_ylabel(inf.term.replace("_", " "), fontsize=8)
        ax.margins(y=0.2)  # room for the name above the point that moves it most
    axes[0, 0].legend(fontsize=7, loc="best")
    axes[-1, 0].set_xticks(x, result.case_names, rotation=90, fontsize=6)
    fig.suptitle(f"Coefficients refitted without each case ({result.strategy} weighting)")
    fig.tight_layout()
    return fig


def _influence_rows(results: Mapping[str, IdentificationResult]) -> list[list[object]]:
    rows = []
    for label, res in results.items():
        for inf in most_influential(res):
            rows.append([label, inf.term, float(inf.value), inf.case, float(inf.value_without),
                         signed_percent(inf.relative_change),
                         float(inf.in_standard_errors) if np.isfinite(inf.in_standard_errors)
                         else None])
    return rows


def _coefficient_rows(results: Mapping[str, IdentificationResult]) -> list[list[object]]:
    """A row per strategy and term; a spread not estimated (no bootstrap) is a dash."""
    def shown(value: float) -> float | None:
        return float(value) if np.isfinite(value) else None

    rows = []
    for label, res in results.items():
        for n, v in res.coefficients.items():
            lo, hi = res.interval[n]
            rows.append([label, n, float(v), shown(res.standard_error[n]), shown(lo), shown(hi)])
    return rows


def identification_report(path: str | Path, results: Mapping[str, IdentificationResult],
                          cases: Sequence[CaseData], base_model: ForceModel, velocity: float,
                          source: str = "") -> Path:
    """Write the identification and weighting-sensitivity report (HTML)."""
    first = next(iter(results.values()))
    rep = Report("Identification of the Morison coefficients",
                 f"{len(first.case_names)} CFD cases{f' from {source}' if source else ''}; "
                 f"fitted components: {', '.join(first.components)}")
    add_identification_sections(rep, results, cases, base_model, velocity, source)
    return rep.write(path)


def weights_table_html(results: Mapping[str, IdentificationResult]) -> str:
    """Each weighting's weight per frequency, as the fit used them (summing to one)."""
    frequencies = sorted({f for res in results.values() for f in res.weights})
    rows = [[label, *(res.weights.get(f) for f in frequencies)]
            for label, res in results.items()]
    return table_html(["weighting", *(f"f = {f:g} Hz" for f in frequencies)], rows)


def add_identification_sections(rep: Report, results: Mapping[str, IdentificationResult],
                                cases: Sequence[CaseData], base_model: ForceModel,
                                velocity: float, source: str = "",
                                mapped: str | None = None) -> None:
    """Coefficients, agreement maps, overlays, applicability and weighting sensitivity.

    The agreement maps, overlays and applicability region are drawn for one weighting:
    ``mapped`` (the one the optimisation used), else the first; the others are compared in
    the weighting-sensitivity table, which counts each one's cases within NRMSE 10 %.
    """
    first = next(iter(results.values()))
    s = rep.section(f"Identified coefficients ({len(first.case_names)} CFD cases"
                    f"{f' from {source}' if source else ''})")
    s.blocks.append(text_html(f"Residuals scaled {scalings_said(results)}."))
    if first.error_growth:
        s.blocks.append(text_html(
            f"How the fitted model's error grows with each run's loads ({first.strategy} "
            f"weighting): {scaling_advice(first.error_growth, first.residual_scaling)}. "
            "Weighted least squares weighs the runs best by their errors' size: near b = 0, "
            "one scale per component over the grid (\"grid\"); near b = 1, each run's own "
            "range (\"case\")."))
        fig = error_growth_figure(first.error_growth, f"How the fitted model's error grows "
                                  f"with each run's loads ({first.strategy} weighting)")
        if fig is not None:
            s.blocks.append(figure_html(fig, "Each run's residual against its loads, with "
                                             "the fitted power law and the two the "
                                             "scalings assume"))
    s.blocks.append(table_html(["weighting", "term", "value", "bootstrap s.e.", "2.5 %",
                                "97.5 %"], _coefficient_rows(results)))
    s.blocks.append(weights_table_html(results))
    s.blocks.append(figure_html(coefficient_figure(results),
                                "Coefficients and bootstrap 95 % intervals per strategy"))
    held: dict[str, list[str]] = {}
    for label, r in results.items():
        for n in r.at_lower_bound:
            held.setdefault(n, []).append(label)
    if held:
        which = "; ".join(f"{n} ({', '.join(labels)})" for n, labels in held.items())
        s.blocks.append(text_html(f"Held at 0: {which}: {HELD_AT_ZERO}.", warn=True))
    if any(not np.isfinite(r.standard_error[n]) for r in results.values()
           for n in r.fitted_terms):
        s.blocks.append(text_html("The coefficients' uncertainty is not estimated: the "
                                  "identification ran with fewer than 2 bootstrap replicates, "
                                  "or with no frequency that has two cases to resample.",
                                  warn=True))
    influence = _influence_rows(results)
    if influence:
        s.blocks.append(text_html(
            "The case each coefficient rests on most: every case left out in turn and the "
            "coefficients refitted without it (the others weighted as before). A change of "
            "one bootstrap standard error or more means one CFD run decides that value: "
            "check that run (its mesh, time step, numerical bursts) before trusting it."))
        s.blocks.append(table_html(["weighting", "term", "value", "most influential case",
                                    "value without it", "relative change",
                                    "change / bootstrap s.e."], influence))
        fig = influence_figure(first)
        if fig is not None:
            s.blocks.append(figure_html(fig, f"Coefficients refitted without each case "
                                             f"({first.strategy} weighting)"))
    n_per_f = {}
    for p in first.case_parameters:
        n_per_f[p.get("frequency")] = n_per_f.get(p.get("frequency"), 0) + 1
    if min(n_per_f.values()) < 2:
        s.blocks.append(text_html("Some frequencies have a single case: the case bootstrap "
                                  "cannot resample them and understates the uncertainty.",
                                  warn=True))
    by_name = {c.name: c for c in cases}
    own_by_name = {r[0]: max(v for v in r[2:] if np.isfinite(v)) for r in cfd_own_nrmse_rows(
        first.case_names, first.metrics["normal_force"]["nrmse"], by_name)}
    rows = []
    for i, name in enumerate(first.case_names):
        c = by_name.get(name)
        prov = c.provenance if c is not None else {}
        par = first.case_parameters[i]
        rows.append([name, float(par.get("frequency", np.nan)),
                     float(par.get("heave_amplitude", np.nan)),
                     float(par.get("phase_deg", np.nan)), str(prov.get("mesh", "-")),
                     prov.get("n_cells", "-"), prov.get("solver_max_courant", "-"),
                     str(prov.get("solver_far_field", "-")),
                     prov.get("as_run_max_courant", "-"), str(prov.get("as_run_far_field", "-")),
                     kept_wall_treatment(prov) or "-",
                     float(prov.get("cpu_time_s", np.nan)),
                     str(prov.get("retries", "")) or "-",
                     100 * float(first.metrics["normal_force"]["nrmse"][i]),
                     own_by_name.get(name, "-"),
                     float(first.metrics["normal_force"]["pearson"][i])])
    s.blocks.append(folded_html(
        f"CFD cases used: {len(rows)} runs, how each was run and its agreement with the "
        f"{first.strategy}-weighted fit",
        table_html(["case", "f [Hz]", "h_amp [m]", "φ [deg]", "mesh", "cells",
                    "set-up max Co", "set-up far field", "max Co at end", "far field at end",
                    "wall treatment", "CPU [s]", "solver retries", "NRMSE F_n [%]",
                    "CFD's own NRMSE F_n [%] (largest part known)", "Pearson F_n"], rows)))
    if first.notes:
        s.blocks.append(text_html("Data cleaning (numerical bursts of the CFD bridged, "
                                  "one-step glitches replaced; marked * in the maps):"))
        s.blocks.append(table_html(["case", "what was done"],
                                   [(k, "; ".join(v)) for k, v in sorted(first.notes.items())]))
    if first.excluded:
        s.blocks.append(text_html("Cases left out of the fit:", warn=True))
        s.blocks.append(table_html(["case", "reason"], sorted(first.excluded.items())))
    label = mapped if mapped in results else next(iter(results))
    res = results[label]
    model = res.model(base_model)
    sec = rep.section(f"Agreement maps ({label} weighting)")
    for sig in ("normal_force", "thrust"):
        for metric in ("pearson", "nrmse"):
            sec.blocks.append(figure_html(map_figure(res, sig, metric),
                                          f"{METRIC_NAMES[metric]} of {SIGNAL_LABELS[sig]} "
                                          "over (f, h_amp) per phase"))
    err = res.metrics["normal_force"]["nrmse"]
    order = np.argsort(err)
    pick = [res.case_names[order[0]], res.case_names[order[len(order) // 2]],
            res.case_names[order[-1]]]
    sec.blocks.append(figure_html(overlay_figure(cases, model, pick),
                                  "Best, median and worst case by NRMSE of F_n"))
    sec.blocks.append(figure_html(applicability_figure(res, velocity),
                                  "Applicability region: NRMSE ≤ 10 %"))
    ok = err <= APPLICABLE_NRMSE
    sec.blocks.append(text_html(f"{ok.sum()} of {len(err)} cases within NRMSE ≤ 10 % on "
                                f"F_n; median Pearson of F_n "
                                f"{np.median(res.metrics['normal_force']['pearson']):.3f}."))
    against = figure3_comparison(res, cases, base_model.plate.chord, velocity)
    if against.case_names:
        sec.blocks.append(text_html(
            f"Against the paper's Figure 3 (its Table 1 grid cases here, {label} weighting; "
            "St = 2 f A / U with A the trailing edge's half excursion):"))
        sec.blocks.append(table_html(["measure", "here", "the paper"], against.rows()))
    by_name = {c.name: c for c in cases}
    own = cfd_own_nrmse_rows(res.case_names, err, by_name)
    repeat = [(r[1], r[2]) for r in own if np.isfinite(r[2])]
    if own:
        said = ("The model's NRMSE of F_n beside CFD's own on the same case: its "
                "cycle-to-cycle NRMSE (each whole cycle's F_n against the case's mean cycle, "
                "periodic cases) and, where a refined run of its motion exists, the NRMSE of "
                "its F_n against the medium mesh's and the halved Courant limit's "
                "(`mfflap campaign refinement`; - where not measured). The model cannot be "
                "asked to follow a run more closely than the run repeats itself or holds "
                "under refinement. ")
        if repeat:
            said += uncertainty_weighting_said([r[0] / 100 for r in repeat],
                                               [r[1] / 100 for r in repeat])
        sec.blocks.append(text_html(said))
        sec.blocks.append(table_html(
            ["case", "model NRMSE of F_n [%]", "CFD cycle-to-cycle NRMSE of F_n [%]",
             "CFD mesh NRMSE of F_n [%]", "CFD time-step NRMSE of F_n [%]"],
            [[r[0], *(v if np.isfinite(v) else "-" for v in r[1:])] for r in own]))
    if len(results) > 1:
        sec = rep.section("Sensitivity to the frequency weighting")
        sec.blocks.append(figure_html(strategy_error_figure(results),
                                      "Mean NRMSE of F_n per frequency, per strategy"))
        rows = []
        for label, res in results.items():
            err = res.metrics["normal_force"]["nrmse"]
            rows.append([label] + [100 * float(np.median(res.metrics[s]["nrmse"])) for s in
                                   ("normal_force", "tangential_force", "moment", "thrust",
                                    "input_power")]
                        + [f"{int((err <= APPLICABLE_NRMSE).sum())} of {len(err)}"])
        sec.blocks.append(table_html(["weighting", "median NRMSE F_n [%]", "F_t [%]", "M [%]",
                                      "thrust [%]", "power [%]", "cases with NRMSE F_n ≤ 10 %"],
                                     rows))
