"""Gap-diagnosis report (HTML) and storage (HDF5)."""

from __future__ import annotations

from typing import TYPE_CHECKING

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

from mfflap.gap.diagnose import CFD_OWN, CONFOUNDED_VIF, Diagnosis
from mfflap.gap.transfer import BASE, TransferCheck
from mfflap.identification.error_growth import scaling_advice
from mfflap.identification.fit import scaling_said
from mfflap.reports.error_growth_plot import error_growth_figure
from mfflap.reports.html import Report, figure_html, table_html, text_html

if TYPE_CHECKING:
    from mfflap.gap.levels import LevelComparison

SIGNALS = ("normal_force", "tangential_force", "moment", "thrust", "input_power")


def _where_figure(where: dict):
    fig, axes = plt.subplots(2, 2, figsize=(11, 7))
    comp = where["by_component"]
    axes[0, 0].bar(list(comp), list(comp.values()))
    axes[0, 0].set_title("share of squared error by component")
    ph = where["by_phase"]
    axes[0, 1].bar(ph["bin_centres_deg"], ph["squared_share"], width=25)
    axes[0, 1].set_xlabel("phase in the carrier cycle [deg]")
    axes[0, 1].set_title("share of squared F_n residual by phase")
    st = {**where["by_state"], **where["by_regime"]}
    axes[1, 0].barh(list(st), list(st.values()))
    axes[1, 0].set_xlabel("η² (share of the residual a variable organises)")
    hv = where["by_harmonic"]
    axes[1, 1].bar(list(hv), list(hv.values()))
    axes[1, 1].set_title("residual power by harmonic of the carrier")
    for ax in (axes[0, 0], axes[1, 1]):
        ax.tick_params(axis="x", rotation=20)
    fig.tight_layout()
    return fig


def _regime_figure(where: dict, diag: Diagnosis):
    rv = where["regime_values"]
    keys = [k for k in ("Strouhal number 2 f h / U", "reduced frequency k = pi f c / U",
                        "peak effective angle of attack") if k in rv]
    fig, axes = plt.subplots(1, len(keys), figsize=(4 * len(keys), 3.4), squeeze=False)
    before = 100 * np.asarray(diag.gap["before"]["normal_force"]["nrmse"])
    after = diag.gap.get("after", {}).get("normal_force", {}).get("nrmse")
    for ax, k in zip(axes[0], keys, strict=True):
        ax.scatter(rv[k], before, s=14, label="model")
        if after is not None:
            ax.scatter(rv[k], 100 * np.asarray(after), s=14, marker="x",
                       label="model + chosen effect")
        ax.set_xlabel(k + (" [rad]" if "angle" in k else " [-]"))
        ax.set_ylabel("held-out NRMSE of F_n [%]")
    axes[0][0].legend(fontsize=8)
    fig.tight_layout()
    return fig


def _median_known(metric: dict | None) -> str:
    """The median in % of a CFD-own NRMSE over the cases that have it, and how many; "-"
    where none has it."""
    values = np.asarray(metric["nrmse"], dtype=float) if metric else np.zeros(0)
    known = values[np.isfinite(values)]
    if not known.size:
        return "-"
    return f"{100 * float(np.median(known)):.1f} ({known.size} of {values.size})"


def candidate_figure(diag: Diagnosis):
    """Each candidate's held-out error reduction against the base model, the significant
    ones in green."""
    fig, ax = plt.subplots(figsize=(8, 0.35 * len(diag.scores) + 1.5))
    labels = [s.label for s in diag.scores]
    gains = [100 * s.gain for s in diag.scores]
    colours = ["C2" if s.significant else "0.6" for s in diag.scores]
    ax.barh(labels, gains, color=colours)
    ax.invert_yaxis()
    ax.set_xlabel("held-out error reduction vs the base model [%] (green: significant)")
    fig.tight_layout()
    return fig


def _transfer_figure(check: TransferCheck):
    """Per held-out motion, each component's NRMSE without and with the checked effect."""
    motions = check.motions
    comps = list(motions[0].nrmse[BASE])
    fig, axes = plt.subplots(1, len(comps), figsize=(3.6 * len(comps), 3.4), squeeze=False)
    x = np.arange(len(motions))
    for ax, comp in zip(axes[0], comps, strict=True):
        ax.bar(x - 0.2, [100 * m.nrmse[BASE][comp] for m in motions], 0.4, label="base model")
        ax.bar(x + 0.2, [100 * m.nrmse[check.label][comp] for m in motions], 0.4,
               label=f"+ {check.label}")
        ax.set_xticks(x, [m.label for m in motions], rotation=20, fontsize=8)
        ax.set_ylabel(f"NRMSE of {comp} [%]")
    axes[0][0].legend(fontsize=8)
    fig.tight_layout()
    return fig


def levels_figure(levels: LevelComparison):
    """Each record's F_n NRMSE, the vortex model's against Morison's, with CFD's own as
    the grey band's edge: below the diagonal the vortex model is nearer CFD."""
    fig, ax = plt.subplots(figsize=(5.2, 4.6))
    top = 0.0
    for group, marker in (("diagnosed", "o"), ("held out", "^")):
        rows = [r for r in levels.rows if r.group == group]
        if not rows:
            continue
        m = 100 * np.array([r.morison_nrmse for r in rows])
        v = 100 * np.array([r.vortex_nrmse for r in rows])
        ax.scatter(m, v, s=16, marker=marker, label=f"{group} ({len(rows)})")
        top = max(top, float(np.nanmax(m)), float(np.nanmax(v)))
    own = np.array([r.cfd_repeat_nrmse for r in levels.rows], dtype=float)
    top = 1.05 * top if top > 0 else 1.0
    ax.plot([0, top], [0, top], color="0.4", lw=0.8)
    if np.isfinite(own).any():
        ax.axhspan(0, 100 * float(np.nanmedian(own)), color="0.85", zorder=0,
                   label="below CFD's own (median)")
    ax.set_xlim(0, top)
    ax.set_ylim(0, top)
    ax.set_xlabel("F_n NRMSE, Morison [%]")
    ax.set_ylabel("F_n NRMSE, discrete-vortex model [%]")
    ax.legend(fontsize=8)
    fig.tight_layout()
    return fig


def add_levels_section(rep: Report, levels: LevelComparison) -> None:
    """The discrete-vortex model as a level: what its F_n residual leaves of Morison's."""
    s = rep.section("The discrete-vortex level")
    s.blocks.append(text_html(
        "Morison as the case file configures it and the discrete-vortex model as its "
        "[vortex] table does, each run through every record's motion from rest, against CFD "
        "over the record's last two periods. The share removed is 1 - SSE_vortex / "
        "SSE_Morison of F_n: what a model with a wake and leading-edge shedding explains of "
        "the residual the candidates above work on (negative where it does worse). No "
        "coefficient of either model is fitted here; CFD's own is its last period against "
        "the one before."))
    rows = []
    for group in ("diagnosed", "held out"):
        summary = levels.summary(group)
        if summary["n_records"]:
            rows.append([group, summary["n_records"], 100 * summary["median_morison_nrmse"],
                         100 * summary["median_vortex_nrmse"],
                         100 * summary["median_cfd_repeat_nrmse"],
                         100 * summary["median_explained_share"],
                         f"{summary['records_explained']} of {summary['n_records']}"])
    if rows:
        s.blocks.append(table_html(
            ["records", "n", "median F_n NRMSE Morison [%]", "vortex [%]", "CFD's own [%]",
             "median share removed [%]", "records with a share > 0"], rows))
        s.blocks.append(figure_html(levels_figure(levels), "F_n NRMSE per record, the "
                                                           "discrete-vortex model against "
                                                           "Morison"))
        s.blocks.append(table_html(
            ["record", "set", "F_n NRMSE Morison [%]", "vortex [%]", "CFD's own [%]",
             "share removed [%]"],
            [[r.record, r.group, 100 * r.morison_nrmse, 100 * r.vortex_nrmse,
              "-" if np.isnan(r.cfd_repeat_nrmse) else 100 * r.cfd_repeat_nrmse,
              "-" if np.isnan(r.explained_share) else 100 * r.explained_share]
             for r in levels.rows]))
    if levels.excluded:
        s.blocks.append(text_html(f"Not compared ({len(levels.excluded)} records): "
                                  + "; ".join(levels.excluded.values()), warn=True))


def add_transfer_section(rep: Report, check: TransferCheck) -> None:
    """Whether the effect predicts runs outside the diagnosed cases better."""
    s = rep.section("Does it carry over to runs outside the cases?")
    s.blocks.append(text_html(f"Verdict: {check.verdict}.", warn=not check.carries_over))
    s.blocks.append(text_html(
        "The base terms alone, with each candidate and with the checked effect, are fitted on "
        "every diagnosed case and compared with CFD runs none of the fits saw (the back-tested "
        "motions in a run), each over its last period. A motion's error is the mean over F_n, "
        "F_t and M of the squared NRMSE; every motion weighs alike. An effect that lowers the "
        "diagnosed cases' held-out error but not these runs' is confined to the identification "
        "grid's motions: a model with it is no better for optimising."))
    for name, why in check.excluded.items():
        s.blocks.append(text_html(f"Not checked on {name}: {why}", warn=True))
    if not check.motions:
        return
    lab = check.label
    rows = []
    for m in check.motions:
        rows.append([m.label, m.name]
                    + [f"{100 * m.nrmse[BASE][k]:.1f} → {100 * m.nrmse[lab][k]:.1f}"
                       for k in m.nrmse[BASE]]
                    + [f"{m.mean_thrust['cfd']:.3g} / {m.mean_thrust[BASE]:.3g} / "
                       f"{m.mean_thrust[lab]:.3g}",
                       f"{m.mean_power['cfd']:.3g} / {m.mean_power[BASE]:.3g} / "
                       f"{m.mean_power[lab]:.3g}",
                       " / ".join("-" if np.isnan(m.cfd_repeat_nrmse.get(k, np.nan))
                                  else f"{100 * m.cfd_repeat_nrmse[k]:.1f}"
                                  for k in m.nrmse[BASE])])
    comps = list(check.motions[0].nrmse[BASE])
    s.blocks.append(table_html(
        ["motion", "record"] + [f"NRMSE {k} [%], base → + {lab}" for k in comps]
        + ["mean thrust [N]: CFD / base / + effect", "mean input power [W]: CFD / base / "
           "+ effect", "CFD's own NRMSE [%] " + " / ".join(comps)
           + " (the period before against the compared one)"], rows))
    s.blocks.append(figure_html(_transfer_figure(check), f"NRMSE per held-out motion, base "
                                                          f"model and + {lab}"))
    s.blocks.append(table_html(
        ["terms added", "error on the held-out runs vs the base model's", "runs improved",
         "coefficients (fitted on every diagnosed case)"],
        [[label, -gain, f"{check.n_better[label]} of {len(check.motions)}",
          "; ".join(f"{n} = {v:.3g}" for n, v in check.coefficients[label].items())]
         for label, gain in sorted(check.gains.items(), key=lambda kv: -kv[1])]))


def gap_report(path, diag: Diagnosis, where: dict, source: str = "",
               snapshots: list[tuple[object, str]] | None = None):
    """Write the HTML report of a diagnosis."""
    rep = Report("Sim-to-real gap diagnosis", f"{len(diag.case_names)} cases"
                 f"{f' from {source}' if source else ''}; base model: "
                 f"{', '.join(diag.base_names)}")
    add_gap_sections(rep, diag, where, snapshots)
    return rep.write(path)


def add_gap_sections(rep: Report, diag: Diagnosis, where: dict,
                     snapshots: list[tuple[object, str]] | None = None) -> None:
    """Verdict, where the model departs, candidates, gap before/after, validation."""
    s = rep.section("Sim-to-real gap: verdict")
    s.blocks.append(text_html(diag.headline(),
                              warn=not diag.finding.startswith(("explained", "within"))))
    claim = diag.claim_said()
    if claim is not None:
        s.blocks.append(text_html(f"{claim[0].upper()}{claim[1:]}."))
    scaled = scaling_said(diag.residual_scaling, diag.scaling_asked)
    s.blocks.append(text_html(f"Residuals scaled {scaled}, in the fits, the held-out errors and "
                              "the significance test; the base model's (refitted over "
                              "every case) "
                              f"{scaling_advice(diag.error_growth, diag.residual_scaling)}."))
    fig = error_growth_figure(diag.error_growth, "How the base model's error (refitted over "
                                                 "every case) grows with each run's loads")
    if fig is not None:
        s.blocks.append(figure_html(fig, "Each run's residual against its loads: b near 0 asks "
                                         "for the grid's scale, near 1 for each case's"))
    s = rep.section("Where the model departs from CFD")
    s.blocks.append(table_html(["factor", "share / η²"], [(k, float(v)) for k, v in
                                                          where["ranking"][:15]]))
    s.blocks.append(figure_html(_where_figure(where), "Residual by component, phase, state, "
                                                      "regime and harmonic"))
    s.blocks.append(figure_html(_regime_figure(where, diag), "Per-case error against regime"))
    lag = where["phase_lag_deg"]
    if np.any(np.isfinite(lag)):
        s.blocks.append(text_html(f"Phase of the model's first harmonic of F_n relative to "
                                  f"CFD's: median {np.nanmedian(lag):+.1f}° "
                                  f"(positive: the model leads)."))
    for fig, caption in snapshots or []:
        s.blocks.append(figure_html(fig, caption))
    s = rep.section("Which unmodelled effect")
    rows = []
    for sc in diag.scores:
        coefs = "; ".join(f"{n} = {v:.3g} ± {sc.coefficient_spread[n]:.2g}"
                          f"{'' if sc.plausible[n] else ' (implausible)'}"
                          for n, v in sc.coefficients.items())
        held = "; ".join(f"{v:.3g}" for v in sc.held_coefficients.values())
        separable = "; ".join(
            f"{sc.variance_inflation[n]:.3g} ({sc.confounded_with[n][0]}, r = "
            f"{sc.confounded_with[n][1]:+.2f})"
            f"{' confounded' if sc.variance_inflation[n] > CONFOUNDED_VIF else ''}"
            for n in sc.names)
        what = " + ".join(diag.descriptions.get(n, {}).get("physical_name", n)
                          for n in sc.names)
        rows.append([sc.label, what, sc.gain, sc.p_value, "yes" if sc.significant else "no",
                     coefs, held, separable])
    s.blocks.append(table_html(["candidate(s)", "what it is", "held-out gain", "p (Wilcoxon)",
                                "significant", "coefficients, base terms refitted (mean ± "
                                "spread over folds)", "coefficients, base terms held",
                                "variance inflation (most correlated term)"], rows))
    s.blocks.append(text_html(
        "The refitted coefficients are those the claim rests on. Where the base model is "
        "misspecified its refitted terms absorb part of an effect, so a candidate's "
        "coefficient is then better read from its fit to the residual of the base model "
        "with the base coefficients held as configured. A variance inflation factor above "
        f"{CONFOUNDED_VIF:g} means the fit cannot tell the candidate's coefficient from the "
        "named term's."))
    s.blocks.append(figure_html(candidate_figure(diag), "Held-out gain per candidate"))
    s = rep.section("How far the gap shrinks (held-out cases)")
    rows = []
    for sig in SIGNALS:
        b = diag.gap["before"][sig]
        a = diag.gap.get("after", {}).get(sig)
        rows.append([sig, 100 * float(np.median(b["nrmse"])),
                     100 * float(np.median(a["nrmse"])) if a else "-",
                     float(np.median(b["pearson"])), float(np.median(a["pearson"])) if a else "-",
                     *(_median_known(diag.gap.get(key, {}).get(sig)) for key in CFD_OWN)])
    for key in ("mean_thrust_error", "mean_power_error"):
        b = diag.gap["before"][key]
        a = diag.gap.get("after", {}).get(key)
        rows.append([key + " (mean |.|)", 100 * float(np.mean(np.abs(b))),
                     100 * float(np.mean(np.abs(a))) if a is not None else "-", "", "",
                     "", "", ""])
    s.blocks.append(text_html(
        "Beside the model's NRMSE, CFD's own over the same cases (median over the cases where "
        "it is known, with how many): each case's cycles against its mean cycle, and its F_n "
        "against the run of its motion on the medium mesh and at half the Courant limit where "
        "the record holds one (mfflap campaign refinement). A model NRMSE at or below these "
        "is within what the CFD can tell."))
    s.blocks.append(table_html(["signal", "median NRMSE before [%]", "after [%]",
                                "median Pearson before", "after",
                                "CFD cycle-to-cycle NRMSE [%]", "CFD mesh NRMSE [%]",
                                "CFD time-step NRMSE [%]"], rows))
    if diag.validation:
        s = rep.section("Validation on withheld groups")
        s.blocks.append(table_html(["validation", "candidate", "claimed", "held-out gain", "p",
                                    "gain per withheld group"],
                                   [(k, v["candidate"], "yes" if v["claimed"] else
                                     "no (best candidate only)", v["gain"], v["p_value"],
                                     "; ".join(f"{g}: {x:+.1%}" for g, x in
                                               v["per_group_gain"].items()))
                                    for k, v in diag.validation.items()]))
    if diag.validation_skipped:
        s = (rep.section("Validation on withheld groups") if not diag.validation else s)
        for key, why in diag.validation_skipped.items():
            s.blocks.append(text_html(f"Not checked by {key}: {why}.", warn=True))
    if diag.transfer is not None:
        add_transfer_section(rep, diag.transfer)
    if diag.levels is not None:
        add_levels_section(rep, diag.levels)
