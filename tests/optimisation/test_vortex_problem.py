"""The optimisation problem on the discrete-vortex model: its objective against the loads
computed directly, its exact gradient against central differences with and without
leading-edge shedding, and its inputs checked."""

from __future__ import annotations

import numpy as np
import pytest

from mfflap.errors import ConfigError
from mfflap.hydro.discrete_vortex import ATTACHED_FLOW, VortexModelSettings, vortex_loads
from mfflap.kinematics.discrete import DiscreteMotion
from mfflap.optimisation.vortex_problem import VortexFlappingProblem
from mfflap.performance import thrust_and_power

N_STEPS = 20
#: a short wake and a wide core keep the model smooth enough for central differences
SMOOTH = {"wake_chords": 0.5, "chord_points": 16, "core_radius_chords": 0.1}


def _motion():
    phase = (np.arange(N_STEPS) + 0.5) * np.pi / N_STEPS
    return DiscreteMotion(-20 * np.sin(phase), -4 * np.sin(phase + 1.2), 0.025)


def _problem(critical_lesp=ATTACHED_FLOW, cycles=2):
    # P_max low enough that the power penalty is active on part of the cycle
    return VortexFlappingProblem(VortexModelSettings(critical_lesp=critical_lesp, **SMOOTH),
                                 cycles=cycles, beta=0.3, max_power=0.5, penalty_power=1.0)


def test_the_repeated_states_are_the_half_period_and_its_negative():
    motion = _motion()
    state = _problem().repeated_states(motion)
    half = motion.states()
    assert state.time.size == 4 * N_STEPS
    np.testing.assert_allclose(state.pitch_angle[:N_STEPS], half.pitch_angle)
    np.testing.assert_allclose(state.pitch_angle[N_STEPS:2 * N_STEPS], -half.pitch_angle)
    np.testing.assert_allclose(state.heave_velocity[2 * N_STEPS:],
                               state.heave_velocity[:2 * N_STEPS])
    np.testing.assert_allclose(np.diff(state.time), motion.time_step)


def test_the_objective_is_the_last_periods_mean_stage_cost():
    problem, motion = _problem(), _motion()
    state = problem.repeated_states(motion)
    thrust, power = thrust_and_power(vortex_loads(state, settings=problem.settings), state)
    last = slice(-2 * N_STEPS, None)
    expected = np.mean(-0.7 * thrust[last] + 0.3 * power[last]
                       + 0.5 * np.maximum(power[last] - 0.5, 0) ** 2)
    smooth = 0.5 * 1e-4 * (np.sum(np.diff(motion.pitch_acceleration) ** 2)
                           + (motion.pitch_acceleration[0] + motion.pitch_acceleration[-1]) ** 2)
    smooth += 0.5 * 1e-2 * (np.sum(np.diff(motion.heave_acceleration) ** 2)
                            + (motion.heave_acceleration[0] + motion.heave_acceleration[-1]) ** 2)
    assert problem.objective(motion) == pytest.approx(expected + smooth, rel=1e-12)


@pytest.mark.parametrize("critical_lesp", [ATTACHED_FLOW, 0.2])
def test_the_gradient_matches_central_differences(critical_lesp):
    """Along a random direction of the 2N accelerations and the time step: within 1e-8 of a
    Richardson-extrapolated central difference."""
    problem, motion = _problem(critical_lesp), _motion()
    z = motion.controls()
    value, grad = problem.packed_value_and_gradient(z)
    assert value == pytest.approx(problem.objective(motion), rel=1e-14)
    direction = np.random.default_rng(0).normal(size=z.size)
    direction[-1] *= 1e-3  # the time step is 0.025 s

    def along(eps):
        return problem.packed_value_and_gradient(z + eps * direction, False)[0]

    h = 1e-3
    difference = (4 * (along(h / 2) - along(-h / 2)) / h - (along(h) - along(-h)) / (2 * h)) / 3
    assert abs(grad @ direction - difference) < 1e-8 * abs(difference)


def test_a_step_against_the_gradient_lowers_the_objective():
    problem, motion = _problem(0.2), _motion()
    z = motion.controls()
    value, grad = problem.packed_value_and_gradient(z)
    step = 1e-3 * np.abs(z).max() / np.abs(grad).max()
    assert problem.packed_value_and_gradient(z - step * grad, False)[0] < value


def test_impossible_settings_and_batches_are_refused():
    with pytest.raises(ConfigError) as caught:
        _problem(cycles=1)
    assert caught.value.key == "optimisation.cycles"
    batch = DiscreteMotion(np.ones((2, N_STEPS)), np.ones((2, N_STEPS)), np.array([0.02, 0.02]))
    with pytest.raises(ConfigError, match="batch"):
        _problem().objective(batch)
