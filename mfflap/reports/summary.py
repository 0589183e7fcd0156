"""The run report's first screen: what the run found and whether CFD confirmed it.

One headline (the beta = 0 thrust gain over the best feasible sinusoid in CFD and in the
model, whether P_max held in CFD, the gap verdict), one table of the motions with their
model and CFD figures side by side, and the coefficients the optimisation used with their
spread over the weightings.
"""

from __future__ import annotations

import numpy as np

from mfflap.backtest.baseline import best_motion_within
from mfflap.backtest.workflow import gain_in_cfd
from mfflap.config import CaseConfig
from mfflap.optimisation.store import beta_label
from mfflap.performance import thrust_gain
from mfflap.pipeline import RunOutcome
from mfflap.reports.html import Section, signed_percent, table_html, text_html


def _efficiency(thrust_n: float, power_w: float, velocity_m_s: float) -> str:
    """Froude efficiency T U / P in percent, or a dash where the motion makes no thrust or
    takes no power (a propulsive efficiency means nothing there)."""
    if not (thrust_n > 0 and power_w > 0):
        return "–"
    return f"{thrust_n * velocity_m_s / power_w:.0%}"


def motion_rows(config: CaseConfig, outcome: RunOutcome) -> list[list]:
    """One row per back-tested or optimised motion: model and CFD mean thrust, mean and
    peak power, efficiency, and whether the CFD's power stayed under P_max."""
    velocity = config.flow.velocity
    rows = []
    for label, o in outcome.backtests.items():
        c = o.comparison
        if c is None:
            rows.append([label, "-", "-", "-", "-", "-", "-", "-", "-",
                         f"not back-tested ({o.status})"])
            continue
        model_peak = float(np.max(c.model_power))
        rows.append([label, c.model_mean_thrust, c.cfd_mean_thrust, c.model_mean_power,
                     c.cfd_mean_power, model_peak, c.cfd_max_power,
                     _efficiency(c.model_mean_thrust, c.model_mean_power, velocity),
                     _efficiency(c.cfd_mean_thrust, c.cfd_mean_power, velocity),
                     "yes" if c.max_power_ok else "NO"])
    if not rows and outcome.study is not None:  # optimised, nothing back-tested
        for beta, r in outcome.study.sqp.items():
            s = r.summary
            rows.append([beta_label(beta), float(s.mean_thrust), "-", float(s.mean_power),
                         "-", float(s.max_power), "-",
                         _efficiency(float(s.mean_thrust), float(s.mean_power), velocity),
                         "-", "not back-tested"])
    return rows


def cfd_pair_said(config: CaseConfig, outcome: RunOutcome) -> str | None:
    """The answer a user came for, in one sentence: the best motion within P_max in CFD
    against the best sinusoid within P_max in CFD, with the gain's standard error."""
    baseline = outcome.cfd_baseline
    if baseline is None:
        return None
    p_max = config.optimisation.max_power
    if baseline.best is None:
        return (f"No sinusoid run in CFD holds P_max = {p_max:g} W: the CFD baseline is "
                "missing.")
    pair = best_motion_within(outcome.backtests, p_max, baseline)
    sinusoid = f"the best sinusoid within it in CFD ({baseline.best.said()})"
    if pair is None:
        return (f"Within P_max = {p_max:g} W in CFD: no back-tested motion holds it; "
                f"{sinusoid[0].upper()}{sinusoid[1:]}.")
    efficiency = _efficiency(pair.mean_thrust_n, pair.mean_power_w, config.flow.velocity)
    return (f"Within P_max = {p_max:g} W in CFD: {pair.label} gives "
            f"{pair.mean_thrust_n:.3g} N at {pair.peak_power_w:.3g} W peak (efficiency "
            f"{efficiency}), {signed_percent(pair.gain)} ± {pair.gain_standard_error:.0%} "
            f"mean thrust against {sinusoid}.")


def headline(config: CaseConfig, outcome: RunOutcome) -> list[str]:
    """The run's findings in a few sentences: the CFD-confirmed pair within P_max first,
    then the model's optimum and its CFD."""
    said = []
    pair = cfd_pair_said(config, outcome)
    if pair is not None:
        said.append(pair)
    if outcome.study is not None:
        sweep, i = outcome.study.sweep, outcome.study.best_sinusoid
        said.append(f"The model's best feasible sinusoid: f = {sweep.frequency[i]:.3g} Hz, "
                    f"h = {sweep.heave_amplitude[i]:.3g} m, "
                    f"θ = {np.degrees(sweep.pitch_amplitude[i]):.3g}°, "
                    f"φ = {np.degrees(sweep.phase[i]):.3g}°.")
    cfd_gain = gain_in_cfd(outcome.backtests)
    best, optimum = (outcome.backtests.get(k) for k in ("best sinusoid", "β = 0"))
    model_gain = None
    if best is not None and optimum is not None and None not in (best.comparison,
                                                                 optimum.comparison):
        model_gain = thrust_gain(optimum.comparison.model_mean_thrust,
                                 best.comparison.model_mean_thrust)
    if cfd_gain is not None:
        said.append(f"On the model's terms: β = 0 gives {signed_percent(cfd_gain)} mean "
                    f"thrust over the model's best feasible sinusoid in CFD (the model "
                    f"predicted {signed_percent(model_gain)}); both are within P_max in the "
                    "model, not necessarily in CFD.")
    elif outcome.study is not None:
        said.append("β = 0's thrust gain over the best feasible sinusoid is not confirmed "
                    "in CFD (see the back-test below).")
    p_max = config.optimisation.max_power
    polished = outcome.backtests.get("β = 0 polished")
    if polished is not None and polished.comparison is not None and 0.0 in outcome.polished:
        c, v = polished.comparison, outcome.polished[0.0].samples
        said.append(f"Polished on the discrete-vortex model, β = 0 gives {c.cfd_mean_thrust:.3g} "
                    f"N mean thrust in CFD at a peak power of {c.cfd_max_power:.3g} W "
                    f"({'within' if c.max_power_ok else 'over'} P_max; the vortex model "
                    f"predicted {v.mean_thrust:.3g} N at {v.peak_power:.3g} W).")
    tested = {k: o.comparison for k, o in outcome.backtests.items() if o.comparison is not None}
    if tested:
        over = [k for k, c in tested.items() if not c.max_power_ok]
        said.append(f"P_max = {p_max:g} W held in CFD by every back-tested motion."
                    if not over else
                    f"P_max = {p_max:g} W did not hold in CFD for {', '.join(over)} "
                    f"(peak {', '.join(f'{tested[k].cfd_max_power:.3g} W' for k in over)}).")
    if outcome.gap is not None:
        said.append(f"Gap diagnosis: {outcome.gap[0].verdict}.")
    return said


def coefficient_rows(outcome: RunOutcome) -> list[list]:
    """The optimisation's coefficients (those identified with its weighting), each with its
    bootstrap standard error and its range over the weightings the run identified."""
    if not outcome.identification:
        return []
    used = outcome.optimised_with or next(iter(outcome.identification))
    fit = outcome.identification[used]
    rows = []
    for term in fit.fitted_terms:
        values = [r.coefficients[term] for r in outcome.identification.values()]
        rows.append([term, fit.coefficients[term], fit.standard_error[term],
                     f"{min(values):.3g}-{max(values):.3g}"])
    return rows


def add_run_summary(s: Section, config: CaseConfig, outcome: RunOutcome) -> None:
    """Fill the report's summary section ``s``: headline, motions, coefficients."""
    for line in headline(config, outcome):
        s.blocks.append(text_html(line))
    rows = motion_rows(config, outcome)
    if rows:
        s.blocks.append(table_html(
            ["motion", "model thrust [N]", "CFD thrust [N]", "model mean power [W]",
             "CFD mean power [W]", "model peak power [W]", "CFD peak power [W]",
             "model efficiency", "CFD efficiency", "CFD power ≤ P_max"], rows))
    used = ("the case file's coefficients" if outcome.optimised_with is None else
            f"the coefficients identified with the {outcome.optimised_with} weighting")
    s.blocks.append(text_html(f"The β optima used {used}."))
    coefficients = coefficient_rows(outcome)
    if coefficients:
        s.blocks.append(table_html(["coefficient", "value", "bootstrap s.e.",
                                    "range over the weightings"], coefficients))


__all__ = ["add_run_summary", "cfd_pair_said", "coefficient_rows", "headline", "motion_rows"]
