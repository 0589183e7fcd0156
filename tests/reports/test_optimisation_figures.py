"""The optimisation figures of the report (mfflap.reports.optimisation) and the colour of
each motion across figures (mfflap.plots.motion_colour)."""

from types import SimpleNamespace

import numpy as np

from mfflap.plots import motion_colour
from mfflap.reports.optimisation import history_figure, pareto_figure
from mfflap.sweep import SweepResult


def _sweep(rng: np.random.Generator) -> SweepResult:
    """Sinusoids whose infeasible part reaches kilowatts, as the paper's sweep does."""
    n = 400
    power = np.concatenate([rng.uniform(0, 40, n // 2), rng.uniform(50, 16_000, n // 2)])
    thrust = np.concatenate([rng.uniform(-5, 15, n // 2), rng.uniform(-100, 600, n // 2)])
    ones = np.ones(n)
    return SweepResult(frequency=ones, heave_amplitude=ones, pitch_amplitude=ones, phase=ones,
                       mean_thrust=thrust, mean_power=power, efficiency=rng.uniform(-1, 1, n),
                       max_power=power * 2, strouhal_number=ones,
                       feasible=np.arange(n) < n // 2)


def _optimum(thrust: float, power: float):
    summary = SimpleNamespace(mean_thrust=thrust, mean_power=power, efficiency=0.3)
    return SimpleNamespace(summary=summary, history=np.array([3.0, 2.0, 1.0]))


def test_the_thrust_power_figure_shows_the_feasible_set_and_the_optima_not_the_kilowatts():
    sweep = _sweep(np.random.default_rng(1))
    optima = {0.0: _optimum(26.0, 45.0), 1.0: _optimum(-1.0, 0.5)}
    fig = pareto_figure(sweep, sweep.best_feasible(), optima)
    power_axes, efficiency_axes = fig.axes
    top_power = max(sweep.mean_power[sweep.feasible].max(), 45.0)
    top_thrust = max(sweep.mean_thrust[sweep.feasible].max(), 26.0)
    assert top_power <= power_axes.get_xlim()[1] <= 1.2 * top_power
    for ax in (power_axes, efficiency_axes):
        low, high = ax.get_ylim()
        assert top_thrust <= high <= 1.2 * top_thrust and low <= -1.0
    assert power_axes.get_xlabel() == "mean input power [W]"
    assert all("[" in ax.get_xlabel() and "[" in ax.get_ylabel() for ax in fig.axes)


def test_each_beta_has_one_colour_in_every_figure():
    optima = {0.0: _optimum(26.0, 45.0), 0.5: _optimum(10.0, 5.0), 1.0: _optimum(-1.0, 0.5)}
    sweep = _sweep(np.random.default_rng(2))
    pareto = pareto_figure(sweep, sweep.best_feasible(), optima)
    history = history_figure(optima)
    marker_colours = {line.get_label(): line.get_color() for line in pareto.axes[0].lines
                      if line.get_label().startswith("optimised")}
    history_colours = {line.get_label(): line.get_color() for line in history.axes[0].lines}
    for beta in optima:
        label = f"β = {beta:g}"
        assert np.allclose(marker_colours[f"optimised {label}"], motion_colour(label))
        assert np.allclose(history_colours[label], motion_colour(label))
    assert len({tuple(motion_colour(f"β = {b:g}")) for b in optima}) == 3
