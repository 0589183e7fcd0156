"""The rounds' report: ``rounds.png`` (model against CFD per motion over the rounds) and
``rounds.html`` beside the rounds' ``rounds.h5``."""

from __future__ import annotations

from pathlib import Path

from matplotlib.figure import Figure

from mfflap.config import CaseConfig
from mfflap.optimisation.output_correction import describe_correction
from mfflap.plots import motion_colour
from mfflap.reports.html import Report, figure_html, table_html, text_html
from mfflap.rounds.checks import MotionCheck
from mfflap.rounds.output import write_rounds_results
from mfflap.rounds.summary import LoopResult


def write_rounds(result: LoopResult, config: CaseConfig, out_dir: Path) -> None:
    """``out_dir/rounds.h5`` (every round's numbers, the case file beside them),
    ``rounds.png`` (model against CFD per motion over the rounds) and ``rounds.html``."""
    write_rounds_results(result, config, out_dir)
    fig = rounds_figure(result)
    fig.savefig(out_dir / "rounds.png", dpi=110)
    learns = ("refits the model with the back-tests of the rounds before" if result.refit
              else "keeps round 1's coefficients")
    if result.correct_outputs:
        learns += ", corrects its outputs to the CFD of the round before"
    if result.trust_radius is not None:
        learns += (f", keeps each optimum in a trust region (first radius "
                   f"{result.trust_radius:g}) about the last one CFD confirmed")
    if result.cfd_repeatability is not None:
        learns += (f", counts CFD's noise ({result.cfd_repeatability:.1%} of the means "
                   "between two runs) in judging each step")
    if result.first_order:
        learns += (", and gives the corrected objective a slope that makes it CFD's at the "
                   "earlier motions near the centre")
    rep = Report("mfflap run: rounds of CFD in the loop",
                 f"{config.study.name}: each round {learns}, optimises and back-tests again")
    s = rep.section("Rounds")
    s.blocks.append(text_html(f"{'Converged' if result.converged else 'Not converged'}: "
                              f"{result.stopped_because}.", warn=not result.converged))
    rows = []
    for r in result.rounds:
        for c in r.checks.values():
            shown = c.label + (f" (CFD of {c.cfd_record}, within the look-up's tolerance)"
                               if c.cfd_of_neighbour else "")
            rows.append([r.index, shown, f"{c.predicted_thrust:.3g}",
                         f"{c.cfd_mean_thrust:.3g}",
                         f"{c.thrust_error:+.1%}" + ("" if c.thrust_counted else " (n.c.)"),
                         f"{c.predicted_power:.3g}", f"{c.cfd_mean_power:.3g}",
                         f"{c.power_error:+.1%}", "yes" if c.in_fit else "no",
                         _scales_text(c)])
        for label, reason in r.not_backtested.items():
            rows.append([r.index, label, "", "", "not back-tested: " + reason.splitlines()[0],
                         "", "", "", "", ""])
    s.blocks.append(table_html(["round", "motion", "thrust predicted N", "CFD N", "error",
                                "power predicted W", "CFD W", "error", "CFD in the fit",
                                "output correction (thrust, power)"], rows))
    if result.answers:
        s.blocks.append(text_html(
            "The last motion of each β that CFD confirmed (its trust region's centre when the "
            "rounds stopped; each round's own report holds it): " + "; ".join(
                f"β = {b:g}: {a}" for b, a in result.answers.items()) + "."))
    corrected = [f"round {r.index}, beta {b:g}: {describe_correction(c)}"
                 for r in result.rounds for b, c in r.corrections.items()]
    if corrected:
        s.blocks.append(text_html(
            "Output corrections (" + ("measured scales" if result.correction_gain == 1.0
                                      else f"filtered, gain {result.correction_gain:g}")
            + "): " + "; ".join(corrected) + "."))
    steps = [[r.index, f"{b:g}", f"{t.radius:.3g}", t.centre, f"{t.step_fraction:.2f}",
              "yes" if t.on_boundary else "no", f"{t.cfd_decrease:.4g}",
              f"{t.predicted_decrease:.4g}", f"{t.ratio:.3g}" if t.moved else "–",
              ("accepted" if t.accepted else "rejected") if t.moved else "no step",
              f"{t.next_radius:.3g}", "; ".join(t.ran_otherwise) or "alike"]
             for r in result.rounds for b, t in r.trust_steps.items()]
    if steps:
        s.blocks.append(text_html(
            "Trust-region steps: the ratio is CFD's decrease of the objective J from the "
            "centre to the optimum over the decrease the round's optimisation predicted (J "
            "with the model's thrust and power scaled to each motion's own CFD means, against "
            "J as the round optimised it); a step of ratio below 0.1 is rejected (the centre "
            "stays), below 0.25 the radius halves, above 0.75 on the boundary it doubles."))
        s.blocks.append(table_html(["round", "beta", "radius", "centre", "step / radius",
                                    "on the boundary", "CFD decrease of J",
                                    "predicted decrease", "ratio", "step", "next radius",
                                    "CFD runs (centre against optimum)"],
                                   steps))
        if any(t.ran_otherwise for r in result.rounds for t in r.trust_steps.values()):
            s.blocks.append(text_html(
                "Some steps compare CFD runs that did not run alike: a retry of a run whose "
                "time step collapsed changed its far field or Courant limit, and its CFD "
                "decrease holds that change as well as the motion's (at the trust series' "
                "beta = 0.5 optimum, max Co 2 instead of 4 moves the mean thrust by 7 %); "
                "a run resumed part-way by a retry may mix two set-ups in the cycles "
                "compared. --retries-from-start reruns a retried run from t = 0 s.",
                warn=True))
    s.blocks.append(table_html(["round", "CFD runs in the fit", "of them from rounds before",
                                *(result.rounds[0].coefficients if result.rounds else [])],
                               [[r.index, r.n_cases, r.loop_records_in_fit,
                                 *(f"{v:.3g}" for v in r.coefficients.values())]
                                for r in result.rounds]))
    s.blocks.append(figure_html(fig, "Mean thrust and input power of each back-tested "
                                     "motion, predicted (open: the model's, or the corrected "
                                     "model's where the motion was optimised with corrected "
                                     "outputs) and CFD (filled), by round, and the "
                                     "prediction's largest counted error of the two (grey: "
                                     "its CFD was in the round's fit, not counted); each "
                                     "round's own report: round_<k>/report.html"))
    rep.write(out_dir / "rounds.html")



def _scales_text(check: MotionCheck) -> str:
    """The output correction of a motion in a table cell ("none": the model's own)."""
    if (check.thrust_scale, check.power_scale) == (1.0, 1.0):
        return "none"
    return f"x {check.thrust_scale:.3f}, x {check.power_scale:.3f}"


def rounds_figure(result: LoopResult):
    """Predicted (open; the corrected model's where a motion was optimised with corrected
    outputs) and CFD (filled) mean thrust and power of each motion over the rounds, and each
    motion's counted error against the tolerance (a motion whose CFD was in the
    round's fit is drawn grey there)."""
    fig = Figure(figsize=(12, 3.6), layout="constrained")
    axes = fig.subplots(1, 3)
    labels = sorted({lbl for r in result.rounds for lbl in r.checks})
    for i, label in enumerate(labels):
        colour = motion_colour(label) or f"C{i % 10}"
        pts = [(r.index, r.checks[label]) for r in result.rounds if label in r.checks]
        x = [p[0] for p in pts]
        for ax, cfd, mod in ((axes[0], "cfd_mean_thrust", "predicted_thrust"),
                             (axes[1], "cfd_mean_power", "predicted_power")):
            ax.plot(x, [getattr(c, cfd) for _, c in pts], "o-", color=colour, label=label)
            ax.plot(x, [getattr(c, mod) for _, c in pts], "o--", color=colour,
                    markerfacecolor="none")
        axes[2].plot(x, [100 * c.error for _, c in pts], "o-", color=colour, label=label)
        seen = [(k, c) for k, c in pts if c.in_fit]
        if seen:
            axes[2].plot([k for k, _ in seen], [100 * c.error for _, c in seen], "o",
                         color="0.6")
    axes[2].axhline(100 * result.tolerance, color="k", ls=":", label="tolerance")
    axes[0].set_ylabel("mean thrust (N)")
    axes[1].set_ylabel("mean input power (W)")
    axes[2].set_ylabel("prediction's error of the means (%)")
    for ax in axes:
        ax.set_xlabel("round")
        ax.set_xticks([r.index for r in result.rounds])
    if labels:
        axes[0].legend(fontsize=8)
    return fig


__all__ = ["rounds_figure", "write_rounds"]
