"""Figures and report sections of the optimisation study (the paper's Figure 4)."""

from __future__ import annotations

from collections.abc import Mapping

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
from matplotlib.figure import Figure

from mfflap.kinematics.discrete import DiscreteMotion
from mfflap.optimisation.optimise import OptimisationResult
from mfflap.optimisation.phase import pitch_phase_rad
from mfflap.optimisation.store import beta_label
from mfflap.optimisation.study import sinusoid_motion
from mfflap.performance import evaluate_discrete
from mfflap.plots import motion_colour
from mfflap.reports.html import Report, figure_html, signed_percent, table_html, text_html
from mfflap.sweep import SweepResult, pareto_front


def pareto_figure(sweep: SweepResult, best: int,
                  optimised: Mapping[float, OptimisationResult] | None = None) -> Figure:
    """(a) mean thrust vs mean power, (b) thrust vs efficiency; feasible set and front."""
    fig, (a, b) = plt.subplots(1, 2, figsize=(11, 4))
    feas = sweep.feasible
    for ax, x in ((a, sweep.mean_power), (b, sweep.efficiency)):
        ax.scatter(x[~feas], sweep.mean_thrust[~feas], s=2, c="0.85", label="infeasible")
        ax.scatter(x[feas], sweep.mean_thrust[feas], s=3, c="C0", label="feasible")
        ax.plot(x[best], sweep.mean_thrust[best], "k*", ms=12, label="best feasible sinusoid")
    idx = np.flatnonzero(feas)
    front = idx[pareto_front(sweep.mean_thrust[idx], sweep.mean_power[idx])]
    a.plot(sweep.mean_power[front], sweep.mean_thrust[front], "C3-", lw=1.5,
           label="constrained Pareto front")
    for beta, r in (optimised or {}).items():
        s = r.summary
        colour = motion_colour(beta_label(beta))
        a.plot(float(s.mean_power), float(s.mean_thrust), "o", ms=8, mec="k", color=colour,
               label=f"optimised β = {beta:g}")
        b.plot(float(s.efficiency), float(s.mean_thrust), "o", ms=8, mec="k", color=colour)
    # the feasible set and the optima fill the axes; the infeasible sinusoids, which reach
    # kilowatts, are clipped
    shown_power = [*sweep.mean_power[feas], *(float(r.summary.mean_power)
                                             for r in (optimised or {}).values())]
    shown_thrust = [*sweep.mean_thrust[feas], *(float(r.summary.mean_thrust)
                                               for r in (optimised or {}).values())]
    if shown_power:
        top_power, top_thrust = max(shown_power), max(shown_thrust)
        low_thrust = min(0.0, min(shown_thrust))
        a.set_xlim(min(0.0, min(shown_power)), 1.15 * top_power if top_power > 0 else 1.0)
        for ax in (a, b):
            ax.set_ylim(low_thrust - 0.05 * abs(top_thrust),
                        1.15 * top_thrust if top_thrust > 0 else 1.0)
    a.set_xlabel("mean input power [W]")
    b.set_xlabel("efficiency η [-]")
    b.set_xlim(-0.2, 1.0)
    for ax in (a, b):
        ax.set_ylabel("mean thrust [N]")
    a.legend(fontsize=7, markerscale=2)
    fig.tight_layout()
    return fig


def cycle_curves(model, motion: DiscreteMotion, scheme: str) -> dict[str, np.ndarray]:
    """Pitch, heave, thrust and power over a full cycle, normalised time t/T."""
    ev = evaluate_discrete(model, motion, scheme)  # type: ignore[arg-type]
    t, pitch, heave = motion.full_cycle_positions()
    period = float(motion.period)
    return {"t": t / period, "pitch_deg": np.rad2deg(pitch), "heave": heave,
            "thrust": np.concatenate([ev.thrust, ev.thrust]),
            "power": np.concatenate([ev.input_power, ev.input_power])}


def motion_figure(model, motions: Mapping[str, DiscreteMotion], scheme: str,
                  max_power: float | None = None) -> Figure:
    """Figure 4c-e: pitch, heave, thrust and input power over one cycle per motion."""
    fig, axes = plt.subplots(2, 2, figsize=(11, 6), sharex=True)
    for label, m in motions.items():
        c = cycle_curves(model, m, scheme)
        ls = "--" if "sinusoid" in label else "-"
        colour = motion_colour(label)
        axes[0, 0].plot(c["t"], c["pitch_deg"], ls, color=colour, label=label)
        axes[0, 1].plot(c["t"], c["heave"], ls, color=colour)
        axes[1, 0].plot(c["t"], c["thrust"], ls, color=colour)
        axes[1, 1].plot(c["t"], c["power"], ls, color=colour)
    if max_power is not None:
        axes[1, 1].axhline(max_power, color="k", ls=":", label="P_max")
        axes[1, 1].legend(fontsize=8)
    for ax, lab in zip(axes.flat, ("pitch θ [deg]", "heave h [m]", "thrust [N]",
                                   "input power [W]"), strict=True):
        ax.set_ylabel(lab)
    for ax in axes[1]:
        ax.set_xlabel("t / T")
    axes[0, 0].legend(fontsize=8)
    fig.tight_layout()
    return fig


def history_figure(results: Mapping[float, OptimisationResult]) -> Figure:
    """Objective over the SQP iterations (all continuation stages) for each beta."""
    fig, ax = plt.subplots(figsize=(6, 3.4))
    for beta, r in results.items():
        h = r.history
        if len(h):
            ax.plot(np.arange(1, len(h) + 1), h - h.min() + 1e-12,
                    color=motion_colour(beta_label(beta)), label=f"β = {beta:g}")
    ax.set_yscale("log")
    ax.set_xlabel("SQP iteration")
    ax.set_ylabel("J − min J [N, W as weighted]")
    ax.legend(fontsize=8)
    fig.tight_layout()
    return fig


def result_rows(label: str, r: OptimisationResult) -> list[object]:
    """One table row of an optimised motion."""
    s = r.summary
    return [label, r.method, float(s.mean_thrust), float(s.mean_power), float(s.efficiency),
            float(s.strouhal_number), float(r.motion.period), float(s.max_power),
            r.resampled_max_power, "yes" if r.converged else f"NO: {r.message}",
            "; ".join(r.flags) or "none"]


RESULT_HEADER = ["motion", "method", "mean thrust [N]", "mean power [W]", "η", "St",
                 "period [s]", "max power [W]", "max power at 10N [W]", "converged", "flags"]


def phase_text(phase: str, results: Mapping[float, OptimisationResult]) -> str:
    """What the report says of the optimised motions' phase (``optimisation.phase``) and
    each one's pitch phase against sin(2 pi t / T) (:mod:`mfflap.optimisation.phase`)."""
    measured = ", ".join(f"β = {b:g}: {pitch_phase_rad(r.motion):+.3f} rad"
                         for b, r in results.items())
    if phase == "fixed":
        return ("Phase fixed (optimisation.phase = \"fixed\"): each motion's pitch first "
                f"harmonic is in phase with sin(2πt/T) ({measured}).")
    return ("Phase free (the paper's problem): a motion shifted in time is the same motion, "
            "so nothing fixes the optima's phase, and where J is flat (β = 1) round-off "
            "decides it; optimisation.phase = \"fixed\" (the default) fixes it. Pitch first "
            f"harmonic's phase against sin(2πt/T): {measured}.")


def add_optimisation_sections(rep: Report, study, model, scheme: str, max_power: float,
                              gain: Mapping[str, np.ndarray] | None = None,
                              phase: str = "free") -> None:
    """Sections of the optimisation study (sweep, beta sweep, IPOPT, gain table);
    ``phase``: the case's ``optimisation.phase``, said beside the optimised motions."""
    sw, best = study.sweep, study.best_sinusoid
    s = rep.section("Sinusoidal sweep and constrained Pareto front")
    s.blocks.append(text_html(
        f"{len(sw.frequency)} sinusoids, {int(sw.feasible.sum())} feasible under P_max = "
        f"{max_power:g} W. Best feasible: f = {sw.frequency[best]:.3g} Hz, h_amp = "
        f"{sw.heave_amplitude[best]:.3g} m, θ_amp = {np.rad2deg(sw.pitch_amplitude[best]):.0f}°"
        f", φ = {np.rad2deg(sw.phase[best]):.0f}°, mean thrust {sw.mean_thrust[best]:.3g} N."))
    s.blocks.append(figure_html(pareto_figure(sw, best, study.sqp),
                                "Mean thrust against mean power and efficiency (Fig. 4a,b)"))
    s = rep.section("Optimised motions (β sweep)")
    if study.interruption is not None:
        s.blocks.append(text_html(f"Incomplete: {study.interruption}.", warn=True))
    rows = [result_rows(f"β = {b:g}", r) for b, r in study.sqp.items()]
    rows += [result_rows(f"β = {b:g}", r) for b, r in study.ipopt.items()]
    s.blocks.append(table_html(RESULT_HEADER, rows))
    if study.sqp:
        s.blocks.append(text_html(phase_text(phase, study.sqp)))
    for b, corr in study.corrections.items():
        if b in study.sqp:
            m = study.sqp[b].summary
            s.blocks.append(text_html(
                f"β = {b:g} was optimised with the model's outputs corrected from CFD: "
                f"{corr.describe()}. The table gives the model's own means; corrected, its "
                f"mean thrust is {corr.thrust_scale * float(m.mean_thrust):.3g} N and mean "
                f"power {corr.power_scale * float(m.mean_power):.3g} W, and P_max holds for "
                f"the corrected power (the model's own at most {max_power / corr.power_scale:.3g}"
                " W)."))
    for b, region in study.trust_regions.items():
        if b in study.sqp:
            fraction = region.step_fraction(study.sqp[b].motion)
            s.blocks.append(text_html(
                f"β = {b:g} was kept in a trust region of radius {region.radius:.3g} about "
                f"{region.source or 'an earlier motion'} (started there alone): its step is "
                f"{fraction:.2f} of the radius, "
                + ("on the boundary (the model would go further)." if region.on_boundary(
                    study.sqp[b].motion) else "inside it.")))
    if study.thrust_gain is not None:
        s.blocks.append(text_html(f"β = 0 thrust gain over the best feasible sinusoid: "
                                  f"{study.thrust_gain:+.1%} (the paper: +50.29 %)."))
        if study.thrust_gain_caveat is not None:
            s.blocks.append(text_html(f"Caution: {study.thrust_gain_caveat}.", warn=True))
    else:
        s.blocks.append(text_html(f"β = 0 thrust gain over the best feasible sinusoid: not "
                                  f"given: {study.no_thrust_gain_reason}.", warn=True))
    if study.refined is not None:
        r = study.refined
        s.blocks.append(text_html(
            f"Refined best feasible sinusoid (continuous search from the grid point): f = "
            f"{r.frequency:.4g} Hz, h_amp = {r.heave_amplitude:.4g} m, θ_amp = "
            f"{np.rad2deg(r.pitch_amplitude):.1f}°, φ = {np.rad2deg(r.phase):.1f}°, mean "
            f"thrust {r.mean_thrust:.4g} N (grid {r.grid_thrust:.4g} N); β = 0 gain over it: "
            f"{signed_percent(study.thrust_gain_refined)}."))
    for b, r in study.sqp.items():
        if float(r.summary.mean_power) < 0:
            s.blocks.append(text_html(
                f"β = {b:g}: mean input power {float(r.summary.mean_power):.3g} W < 0 with mean "
                f"thrust {float(r.summary.mean_thrust):.3g} N: a generator-like regime (the "
                "flow drives the plate), as the paper reports for β = 1."))
        if r.flags:
            s.blocks.append(text_html(f"β = {b:g}: " + " ".join(r.flags), warn=True))

    motions = {"best sinusoid": sinusoid_motion(sw, best, next(iter(study.sqp.values()))
                                                .motion.n_steps)}
    motions.update({beta_label(b): r.motion for b, r in study.sqp.items()})
    s.blocks.append(figure_html(motion_figure(model, motions, scheme, max_power),
                                "Motion, thrust and power over a cycle (Fig. 4c-e)"))
    s.blocks.append(figure_html(history_figure(study.sqp), "SQP convergence"))
    if gain is not None:
        s = rep.section("β = 0 gain against N and the smoothing weights")
        header = ["N"] + [f"ε × {f:g}" for f in gain["smoothing_factors"]]
        rows = [[int(n)] + [f"{signed_percent(g)}{' (flagged)' if fl else ''}" for g, fl in
                            zip(gain["gain"][i], gain["flagged"][i], strict=True)]
                for i, n in enumerate(gain["n_steps"])]
        s.blocks.append(table_html(header, rows))
