"""Report sections of the main job: gradient check, back-test (model vs CFD) and
coefficient sensitivity."""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
from matplotlib.figure import Figure

from mfflap.backtest.run import BacktestOutcome
from mfflap.backtest.workflow import gain_in_cfd, no_gain_in_cfd_reason
from mfflap.config import CaseConfig
from mfflap.optimisation.gradcheck import FD_NOTE, GradCheck, scatter_figure
from mfflap.pipeline import RunOutcome, write_results
from mfflap.records.as_run import describe_as_run
from mfflap.reports.coverage import add_coverage_section
from mfflap.reports.gap import add_gap_sections
from mfflap.reports.html import Report, figure_html, table_html, text_html
from mfflap.reports.identification import add_identification_sections
from mfflap.reports.ladder import add_ladder_section
from mfflap.reports.optimisation import add_optimisation_sections, cycle_curves
from mfflap.reports.polish import add_polish_section
from mfflap.reports.summary import add_run_summary


def backtest_figure(outcomes: Mapping[str, BacktestOutcome], max_power: float) -> Figure:
    """Thrust and input power over the last CFD cycle, model vs CFD, per motion."""
    done = {k: o for k, o in outcomes.items() if o.comparison is not None}
    fig, axes = plt.subplots(2, max(len(done), 1), figsize=(4 * max(len(done), 1), 5.5),
                             squeeze=False)
    for j, (label, o) in enumerate(done.items()):
        c = o.comparison
        t = (c.time - c.time[0]) / (c.time[-1] - c.time[0])
        axes[0][j].plot(t, c.cfd_thrust, "k-", lw=1, label="CFD")
        axes[0][j].plot(t, c.model_thrust, "C1--", label="model")
        axes[1][j].plot(t, c.cfd_power, "k-", lw=1)
        axes[1][j].plot(t, c.model_power, "C1--")
        axes[1][j].axhline(max_power, color="r", ls=":", label="P_max")
        axes[0][j].set_title(label)
        axes[1][j].set_xlabel("t / T (last cycle)")
    axes[0][0].set_ylabel("thrust [N]")
    axes[1][0].set_ylabel("input power [W]")
    axes[0][0].legend(fontsize=8)
    axes[1][0].legend(fontsize=8)
    fig.tight_layout()
    return fig


def add_backtest_sections(rep: Report, outcomes: Mapping[str, BacktestOutcome],
                          max_power: float) -> None:
    """Back-test table, figure and the CFD thrust gain."""
    s = rep.section("Back-test against CFD")
    if not outcomes:
        s.blocks.append(text_html("No back-test was run.", warn=True))
        return

    rows = []
    for label, o in outcomes.items():
        if o.comparison is None:
            rows.append([label, o.status, o.source] + ["-"] * 10)
            continue
        c = o.comparison
        rows.append([label, o.status, o.source, describe_as_run(o.record) or "-",
                     c.cfd_mean_thrust, c.model_mean_thrust,
                     c.cfd_mean_power, c.model_mean_power, 100 * c.nrmse["thrust"],
                     100 * c.cfd_repeat_nrmse.get("thrust", float("nan")),
                     c.pearson["thrust"], c.cfd_max_power,
                     "yes" if c.max_power_ok else "NO"])
    averaged = {label: o.comparison for label, o in outcomes.items()
                if o.comparison is not None and o.comparison.cycles_averaged > 1}
    if averaged:
        s.blocks.append(text_html(
            "Means over the last "
            + ", ".join(sorted({str(c.cycles_averaged) for c in averaged.values()}))
            + " whole cycles of each run (curves, NRMSE and maximum power: the last cycle's; "
            "CFD's own repeat NRMSE: its last cycle against the one before, the closest a "
            "model can be asked to follow it); "
            "CFD's standard errors from its cycle means: " + "; ".join(
                f"{label} thrust ± {c.cfd_thrust_standard_error:.2g} N, power ± "
                f"{c.cfd_power_standard_error:.2g} W" for label, c in averaged.items()) + "."))
    s.blocks.append(table_html(["motion", "status", "CFD from", "CFD as run", "CFD thrust [N]",
                                "model thrust [N]", "CFD power [W]", "model power [W]",
                                "NRMSE thrust [%]", "CFD's own repeat NRMSE thrust [%]",
                                "Pearson thrust", "CFD max power [W]",
                                "CFD power ≤ P_max"], rows))
    if any(o.comparison is not None for o in outcomes.values()):
        s.blocks.append(figure_html(backtest_figure(outcomes, max_power),
                                    "Last simulated cycle: model against CFD"))
    gain = gain_in_cfd(outcomes)
    if gain is not None:
        s.blocks.append(text_html(f"β = 0 thrust gain over the best feasible sinusoid in CFD: "
                                  f"{gain:+.1%}."))
    elif outcomes:
        s.blocks.append(text_html(f"β = 0 thrust gain in CFD: not given: "
                                  f"{no_gain_in_cfd_reason(outcomes)}.", warn=True))
    for label, o in outcomes.items():
        if o.comparison is None:
            s.blocks.append(text_html(f"{label}: not back-tested ({o.source}).", warn=True))
            continue
        if o.comparison.compared_cycles_mixed_set_up:
            s.blocks.append(text_html(f"{label}: {o.comparison.describe_mixed_set_up()}.",
                                      warn=True))
        if not np.isnan(o.comparison.cycle_to_cycle_thrust_change) and \
                o.comparison.cycle_to_cycle_thrust_change > 0.05:
            s.blocks.append(text_html(
                f"{label}: CFD mean thrust changed by "
                f"{o.comparison.cycle_to_cycle_thrust_change:.0%} between the last two cycles; "
                "the flow is not yet periodic.", warn=True))


def add_sensitivity_section(rep: Report, sensitivity: Mapping[str, tuple], scheme: str) -> None:
    """Figure 5: beta = 0 re-optimised with each strategy's coefficients."""
    s = rep.section("Coefficient sensitivity (β = 0 re-optimised per weighting strategy)")
    fig, axes = plt.subplots(2, 2, figsize=(11, 6))
    rows = []
    for label, (model, r) in sensitivity.items():
        m = r.motion
        tt = np.arange(m.n_steps) / m.n_steps / 2
        axes[0, 0].plot(tt, m.pitch_acceleration, label=label)
        axes[0, 1].plot(tt, m.heave_acceleration)
        c = cycle_curves(model, m, scheme)
        axes[1, 0].plot(c["t"], c["thrust"])
        axes[1, 1].plot(c["t"], c["power"])
        rows.append([label, float(r.summary.mean_thrust), float(r.summary.max_power),
                     float(m.period), float(r.summary.strouhal_number)])
    for ax, lab in zip(axes.flat, ("pitch acceleration [rad/s²]", "heave acceleration [m/s²]",
                                   "thrust [N]", "input power [W]"), strict=True):
        ax.set_ylabel(lab)
        ax.set_xlabel("t / T")
    axes[0, 0].legend(fontsize=8)
    fig.tight_layout()
    s.blocks.append(figure_html(fig, "Optimised controls, thrust and power per strategy "
                                     "(Fig. 5)"))
    s.blocks.append(table_html(["coefficients from", "mean thrust [N]", "max power [W]",
                                "period [s]", "St"], rows))


def add_gradient_section(rep: Report, checks: Mapping[float, GradCheck]) -> None:
    """Fig. 6: the adjoint gradient against central differences per beta, and its errors
    against complex step, CasADi's AD and central differences, controls and dt apart."""
    s = rep.section("Gradient check (Fig. 6)")
    s.blocks.append(text_html(
        "The adjoint's gradient of J at the case's sinusoid (perturbed, scaled until the "
        "penalties make at most a tenth of J), against three other derivatives. The "
        "controls dJ/du_j and dJ/dΔt are compared apart: |dJ/dΔt| is about 1e4 times the "
        "controls', so one ratio over both would hide an error in the thrust and power "
        "part. Errors are the largest difference over the largest complex-step component."))
    s.blocks.append(figure_html(scatter_figure(dict(checks)),
                                "Adjoint against central differences (Fig. 6)"))
    s.blocks.append(table_html(
        ["β", "penalties [% of J]", "controls vs complex step", "dt vs complex step",
         "controls vs CasADi", "dt vs CasADi", "controls vs central differences",
         "dt vs central differences"],
        [[f"{b:g}", 100 * c.penalty_share, f"{c.controls_error_complex_step:.1e}",
          f"{c.time_step_error_complex_step:.1e}", f"{c.controls_error_casadi:.1e}",
          f"{c.time_step_error_casadi:.1e}", f"{c.controls_error_finite_difference:.1e}",
          f"{c.time_step_error_finite_difference:.1e}"] for b, c in checks.items()]))
    s.blocks.append(text_html(FD_NOTE))


def write_run_report(config: CaseConfig, outcome: RunOutcome, html_path: Path,
                     source: str) -> None:
    """The run's self-contained HTML report (``source``: where its CFD records came from)."""
    rep = Report(f"mfflap run: {config.study.name}", config.study.description)
    s = rep.section("Summary")
    add_run_summary(s, config, outcome)
    if outcome.problems:
        s.blocks.append(text_html("What is missing and why:", warn=True))
        for p in outcome.problems:
            s.blocks.append(text_html(p, warn=True))
    else:
        s.blocks.append(text_html("Every stage ran."))
    s.blocks.append(text_html("Stage times: " + ", ".join(f"{k} {v:.1f} s" for k, v in
                                                          outcome.timings.items())))
    if outcome.identification:
        add_identification_sections(rep, outcome.identification, outcome.cases,
                                    config.morison_model(), config.flow.velocity, source,
                                    mapped=outcome.optimised_with)
    if outcome.study is not None:
        add_optimisation_sections(rep, outcome.study, outcome.model, config.optimisation.scheme,
                                  config.optimisation.max_power, outcome.gain,
                                  config.optimisation.phase)
    if outcome.study is not None:
        add_polish_section(rep, outcome.polished, outcome.study.sqp,
                           config.optimisation.max_power)
    if outcome.gradient_checks:
        add_gradient_section(rep, outcome.gradient_checks)
    if outcome.coverage:
        add_coverage_section(rep, outcome.coverage, len(outcome.cases))
    add_backtest_sections(rep, outcome.backtests, config.optimisation.max_power)
    add_ladder_section(rep, outcome.ladder, config.optimisation.max_power)
    if outcome.gap is not None:
        add_gap_sections(rep, *outcome.gap)
    if outcome.sensitivity:
        add_sensitivity_section(rep, outcome.sensitivity, config.optimisation.scheme)
    rep.write(html_path)


def write_run_outputs(config: CaseConfig, outcome: RunOutcome, h5_path: Path, html_path: Path,
                      source: str) -> None:
    """One HDF5 file with every number and the inputs
    (:func:`mfflap.pipeline.write_results`); one self-contained HTML report beside it."""
    write_results(config, outcome, h5_path)
    write_run_report(config, outcome, html_path, source)


def write_round_outputs(config: CaseConfig, outcome: RunOutcome, round_dir: Path,
                        source: str) -> None:
    """A round's ``results.h5`` and ``report.html`` in its folder (the rounds'
    ``write_round``, :func:`mfflap.rounds.run_rounds`)."""
    write_run_outputs(config, outcome, round_dir / "results.h5", round_dir / "report.html",
                      source)
