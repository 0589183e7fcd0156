"""The reverse sweep of the discrete-vortex model against finite differences of the forward
model: directional derivatives over every step's motion and the time step, a Taylor test of
the remainder's second order, and single entries with and without leading-edge shedding."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from mfflap.errors import ConfigError
from mfflap.hydro.discrete_vortex import ATTACHED_FLOW, VortexModelSettings, vortex_loads
from mfflap.hydro.discrete_vortex_adjoint import vortex_loads_vjp
from mfflap.kinematics.continuous import HarmonicMotion
from mfflap.parameters import Plate

N_STEPS, TIME_STEP = 160, 0.01
KINEMATICS = ("heave_position", "heave_velocity", "pitch_angle", "pitch_rate")
#: a wake of half a chord and a core of a tenth of a chord keep the forward model smooth
#: enough for central differences to resolve its derivative to 1e-8
SMOOTH = {"wake_chords": 0.5, "chord_points": 16, "core_radius_chords": 0.1}


def _state():
    # started a little after t = 0 s, where the first leading-edge sheet would lie on the
    # plate (zero pitch and heave rate), a point where the model is not differentiable
    time = 0.013 + np.arange(N_STEPS) * TIME_STEP
    return HarmonicMotion(frequency=1.0, heave_amplitude=0.2, pitch_amplitude=0.6).sample(time)


def _weights(seed=1):
    return np.random.default_rng(seed).normal(size=(3, N_STEPS))


def _objective(state, weights, settings, plate=None):
    loads = vortex_loads(state, plate, settings=settings)
    return (weights[0] @ loads.normal_force + weights[1] @ loads.tangential_force
            + weights[2] @ loads.moment)


def _moved(state, direction, dt_direction, eps):
    moved = replace(state, **{k: getattr(state, k) + eps * direction[k] for k in KINEMATICS})
    start = state.time[0]
    return replace(moved, time=start + (state.time - start) * (1 + eps * dt_direction
                                                                / TIME_STEP))


@pytest.mark.parametrize("pivot_chord_fraction", [0.0, 0.3])
@pytest.mark.parametrize("critical_lesp", [ATTACHED_FLOW, 0.2])
def test_the_directional_derivative_matches_central_differences(critical_lesp,
                                                                pivot_chord_fraction):
    """Along a random direction of all 4 x 160 samples and the time step, pivot at the
    leading edge and behind it: the reverse sweep against a Richardson-extrapolated central
    difference, within 1e-7."""
    settings = VortexModelSettings(critical_lesp=critical_lesp, **SMOOTH)
    plate = Plate(pivot_chord_fraction=pivot_chord_fraction)
    state, weights = _state(), _weights()
    rng = np.random.default_rng(2)
    direction = {k: rng.normal(size=N_STEPS) for k in KINEMATICS}
    dt_direction = float(rng.normal())
    grad = vortex_loads_vjp(state, *weights, plate=plate, settings=settings)
    exact = sum(getattr(grad, k) @ direction[k] for k in KINEMATICS) \
        + grad.time_step * dt_direction

    def along(eps):
        return _objective(_moved(state, direction, dt_direction, eps), weights, settings,
                          plate)

    h = 1e-6
    coarse = (along(h) - along(-h)) / (2 * h)
    fine = (along(h / 2) - along(-h / 2)) / h
    difference = (4 * fine - coarse) / 3
    assert abs(exact - difference) < 1e-7 * abs(difference), (exact, difference)


@pytest.mark.parametrize("critical_lesp", [ATTACHED_FLOW, 0.2])
def test_the_remainder_of_the_linearisation_is_second_order(critical_lesp):
    """J(x + eps d) - J(x) - eps g.d shrinks as eps^2: 100-fold for each tenfold eps (eps
    small enough that no step's shedding switches)."""
    settings = VortexModelSettings(critical_lesp=critical_lesp, **SMOOTH)
    state, weights = _state(), _weights()
    rng = np.random.default_rng(3)
    direction = {k: rng.normal(size=N_STEPS) for k in KINEMATICS}
    grad = vortex_loads_vjp(state, *weights, settings=settings)
    slope = sum(getattr(grad, k) @ direction[k] for k in KINEMATICS)
    base = _objective(state, weights, settings)
    remainder = [abs(_objective(_moved(state, direction, 0.0, eps), weights, settings)
                     - base - eps * slope) for eps in (1e-4, 1e-5)]
    assert 50 < remainder[0] / remainder[1] < 200, remainder


@pytest.mark.parametrize("pivot_chord_fraction", [0.0, 0.5])
@pytest.mark.parametrize("name", KINEMATICS)
def test_single_entries_match_central_differences_with_shedding(name, pivot_chord_fraction):
    """Entries early, mid-way and at the end of the run, leading-edge shedding on, pivot at
    the leading edge and at mid-chord: within 1e-5 of a Richardson-extrapolated difference
    (single entries carry the forward model's round-off relative to a much smaller
    derivative than a whole direction does)."""
    settings = VortexModelSettings(critical_lesp=0.2, **SMOOTH)
    plate = Plate(pivot_chord_fraction=pivot_chord_fraction)
    state, weights = _state(), _weights()
    grad = getattr(vortex_loads_vjp(state, *weights, plate=plate, settings=settings), name)
    for index in (3, N_STEPS // 2, N_STEPS - 1):
        def at(eps, index=index):
            step = np.zeros(N_STEPS)
            step[index] = eps
            moved = replace(state, **{name: getattr(state, name) + step})
            return _objective(moved, weights, settings, plate)

        h = 1e-5
        difference = (4 * (at(h / 2) - at(-h / 2)) / h - (at(h) - at(-h)) / (2 * h)) / 3
        assert abs(grad[index] - difference) < 1e-5 * max(abs(difference), 1.0), \
            (index, grad[index], difference)


def test_the_gradient_run_returns_the_forward_loads():
    settings = VortexModelSettings(**SMOOTH)
    state, weights = _state(), _weights()
    grad = vortex_loads_vjp(state, *weights, settings=settings)
    np.testing.assert_array_equal(grad.loads.normal_force,
                                  vortex_loads(state, settings=settings).normal_force)


def test_weights_of_the_wrong_length_are_refused():
    state, weights = _state(), _weights()
    with pytest.raises(ConfigError, match="moment_weight") as caught:
        vortex_loads_vjp(state, weights[0], weights[1], weights[2][:-1],
                         settings=VortexModelSettings(**SMOOTH))
    assert caught.value.key == "moment_weight"
