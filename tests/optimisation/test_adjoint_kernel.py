import numpy as np
import pytest

from mfflap.errors import ConfigError
from mfflap.hydro import MorisonModel
from mfflap.kinematics import DiscreteMotion, harmonic_to_discrete
from mfflap.metrics import cosine_similarity
from mfflap.optimisation import FlappingProblem

N = 24


def perturbed_motion(seed=0):
    rng = np.random.default_rng(seed)
    d = harmonic_to_discrete(1.2, 0.45, np.deg2rad(35), 1.4, N)
    return DiscreteMotion(d.pitch_acceleration * (1 + 0.2 * rng.normal(size=N)),
                          d.heave_acceleration * (1 + 0.2 * rng.normal(size=N)), d.time_step)


def as_vector(d):
    return np.concatenate([d.pitch_acceleration, d.heave_acceleration, [d.time_step]])


def from_vector(x):
    return DiscreteMotion(x[:N], x[N:2 * N], x[2 * N])


def complex_step(problem, d, h=1e-30):
    x = as_vector(d)
    out = np.empty_like(x)
    for i in range(x.size):
        xc = x.astype(complex)
        xc[i] += 1j * h
        out[i] = np.imag(problem.objective(from_vector(xc))) / h
    return out


@pytest.mark.parametrize("compiled", [True, False], ids=["kernel", "arrays"])
@pytest.mark.parametrize("scheme", ["paper", "midpoint"])
@pytest.mark.parametrize("beta", [0.0, 0.5, 1.0])
def test_adjoint_matches_complex_step(scheme, beta, compiled):
    d = perturbed_motion()
    # P_max = 30 W and h_max = 0.4 m make both penalties active on this motion
    problem = FlappingProblem(MorisonModel(), beta=beta, max_power=30.0, max_heave=0.4,
                              smoothing_pitch=1e-5, smoothing_heave=1e-3, scheme=scheme,
                              compiled=compiled)
    assert (problem._kernel(d) is not None) == compiled
    state = d.states(scheme)
    assert np.max(np.abs(state.heave_position)) > 0.4
    adj = problem.gradient(d).flat()
    cs = complex_step(problem, d)
    assert np.max(np.abs(adj - cs)) <= 1e-10 * np.max(np.abs(cs))
    assert abs(adj[-1] - cs[-1]) <= 1e-10 * abs(cs[-1])  # the time-step component


@pytest.mark.parametrize("scheme", ["paper", "midpoint"])
@pytest.mark.parametrize("n_steps", [2, 3, 24, 301])
def test_compiled_kernel_equals_the_array_code(scheme, n_steps):
    """Objective, gradient and the packed entry point of the numba kernel agree with the
    array implementation (the reference) to rounding, penalties active."""
    rng = np.random.default_rng(n_steps)
    d0 = harmonic_to_discrete(1.2, 0.45, np.deg2rad(35), 1.4, n_steps)
    d = DiscreteMotion(d0.pitch_acceleration * (1 + 0.2 * rng.normal(size=n_steps)),
                       d0.heave_acceleration * (1 + 0.2 * rng.normal(size=n_steps)),
                       d0.time_step)
    kw = dict(beta=0.3, max_power=30.0, max_heave=0.4, smoothing_pitch=1e-5,
              smoothing_heave=1e-3, scheme=scheme)
    fast = FlappingProblem(MorisonModel(), compiled=True, **kw)
    slow = FlappingProblem(MorisonModel(), compiled=False, **kw)
    j_ref, g_ref = float(slow.objective(d)), slow.gradient(d).flat()
    assert np.isclose(fast.objective(d), j_ref, rtol=1e-13)
    np.testing.assert_allclose(fast.gradient(d).flat(), g_ref, rtol=0,
                               atol=1e-12 * np.abs(g_ref).max())
    j, g = fast.packed_value_and_gradient(as_vector_any(d))
    assert np.isclose(j, j_ref, rtol=1e-13)
    np.testing.assert_allclose(g, g_ref, rtol=0, atol=1e-12 * np.abs(g_ref).max())
    j_only, none = fast.packed_value_and_gradient(as_vector_any(d), want_gradient=False)
    assert none is None and np.isclose(j_only, j_ref, rtol=1e-13)


def as_vector_any(d):
    return np.concatenate([d.pitch_acceleration, d.heave_acceleration, [d.time_step]])


def test_complex_inputs_take_the_array_code_and_other_models_are_refused():
    """The adjoint's partials are those of the four Morison terms: a model with another
    term is refused (its gradient would silently miss the term); complex steps and batches
    take the array code."""
    from mfflap.hydro.base import ForceTerm
    from mfflap.hydro.loads import Loads

    class LinearHeaveDamping(ForceTerm):
        name = "linear_heave_damping"

        def regressor(self, state):
            z = 0 * state.heave_velocity
            return Loads(state.time, -state.heave_velocity, z, z)

    with pytest.raises(ConfigError, match="linear_heave_damping"):
        FlappingProblem(MorisonModel() + LinearHeaveDamping())
    d = perturbed_motion(1)
    problem = FlappingProblem(MorisonModel())
    assert problem._kernel(d) is not None
    assert problem._kernel(DiscreteMotion(d.pitch_acceleration + 0j, d.heave_acceleration,
                                          d.time_step)) is None
    batch = DiscreteMotion(np.stack([d.pitch_acceleration] * 2),
                           np.stack([d.heave_acceleration] * 2), np.full(2, d.time_step))
    assert problem._kernel(batch) is None
    np.testing.assert_allclose(problem.gradient(batch).pitch_acceleration[1],
                               problem.gradient(d).pitch_acceleration, rtol=1e-12)


def test_packed_entry_point_refuses_bad_controls():
    from mfflap.errors import MotionError

    problem = FlappingProblem(MorisonModel())
    x = as_vector(perturbed_motion())
    problem.packed_value_and_gradient(x)
    for bad in (np.r_[x[:-1], -1e-3], np.r_[np.nan, x[1:]]):
        with pytest.raises(MotionError):
            problem.packed_value_and_gradient(bad)


def test_adjoint_matches_central_differences_away_from_kinks():
    d = perturbed_motion(3)
    problem = FlappingProblem(MorisonModel(), beta=0.5, max_power=1e4, max_heave=5.0)
    adj = problem.gradient(d).flat()
    x = as_vector(d)
    fd = np.empty_like(x)
    for i in range(x.size):
        step = 1e-6 * max(1.0, abs(x[i]))
        xp, xm = x.copy(), x.copy()
        xp[i] += step
        xm[i] -= step
        fd[i] = (problem.objective(from_vector(xp)) - problem.objective(from_vector(xm))) / (
            2 * step)
    assert cosine_similarity(adj[:-1], fd[:-1]) > 1 - 1e-8
    np.testing.assert_allclose(adj, fd, rtol=1e-4, atol=1e-6 * np.abs(fd).max())


def test_batched_gradient_equals_single():
    ds = [perturbed_motion(s) for s in range(3)]
    batch = DiscreteMotion(np.stack([d.pitch_acceleration for d in ds]),
                           np.stack([d.heave_acceleration for d in ds]),
                           np.array([d.time_step for d in ds]))
    problem = FlappingProblem(MorisonModel(), beta=0.3, max_power=30.0)
    gb = problem.gradient(batch)
    for i, d in enumerate(ds):
        g = problem.gradient(d)
        np.testing.assert_allclose(gb.pitch_acceleration[i], g.pitch_acceleration, rtol=1e-12)
        np.testing.assert_allclose(gb.time_step[i], g.time_step, rtol=1e-12)


@pytest.mark.parametrize(
    "kwargs",
    [{"beta": -0.1}, {"beta": 1.5}, {"max_heave": 0.0}, {"max_power": -1.0},
     {"penalty_power": -1.0}, {"smoothing_heave": -1e-3}, {"scheme": "rk4"}],
)
def test_meaningless_settings_are_refused(kwargs):
    with pytest.raises(ConfigError):
        FlappingProblem(MorisonModel(), **kwargs)


@pytest.mark.parametrize("scheme", ["paper", "midpoint"])
def test_adjoint_matches_casadi_reverse_mode(scheme):
    from mfflap.optimisation.casadi_objective import build_objective, casadi_gradient

    d = perturbed_motion(5)
    problem = FlappingProblem(MorisonModel(), beta=0.5, max_power=30.0, max_heave=0.4,
                              scheme=scheme)
    f, _ = build_objective(problem, N)
    assert np.isclose(float(f(as_vector(d))), problem.objective(d), rtol=1e-13)
    adj = problem.gradient(d).flat()
    ca_grad = casadi_gradient(problem, d)
    assert np.max(np.abs(adj - ca_grad)) <= 1e-10 * np.max(np.abs(ca_grad))


def _envelope_at(motion, scheme, share=0.7):
    """Pitch limits at ``share`` of the motion's own peaks: all three penalties active."""
    st = motion.states(scheme)
    return {"max_pitch": share * np.max(np.abs(st.pitch_angle)),
            "max_pitch_rate": share * np.max(np.abs(st.pitch_rate)),
            "max_pitch_acceleration": share * np.max(np.abs(st.pitch_acceleration))}


@pytest.mark.parametrize("compiled", [True, False], ids=["kernel", "arrays"])
@pytest.mark.parametrize("scheme", ["paper", "midpoint"])
def test_the_pitch_envelope_adds_its_penalty_and_its_exact_gradient(scheme, compiled):
    d = perturbed_motion(3)
    limits = _envelope_at(d, scheme)
    kw = dict(beta=0.5, max_power=30.0, max_heave=0.4, smoothing_pitch=1e-5,
              smoothing_heave=1e-3, scheme=scheme, compiled=compiled)
    free = FlappingProblem(MorisonModel(), **kw)
    sigma = 1.0e5
    held = FlappingProblem(MorisonModel(), penalty_pitch=sigma, **limits, **kw)
    # the penalty by hand: 1/2 sigma (excess / limit)^2, summed over the states, mean over j
    st = d.states(scheme)
    by_hand = 0.0
    for name, limit in zip(("pitch_angle", "pitch_rate", "pitch_acceleration"),
                           limits.values(), strict=True):
        excess = np.maximum(np.abs(getattr(st, name)) - limit, 0) / limit
        assert excess.max() > 0
        by_hand += 0.5 * sigma * np.mean(excess**2)
    assert float(held.objective(d)) == pytest.approx(float(free.objective(d)) + by_hand,
                                                     rel=1e-12)
    adj = held.gradient(d).flat()
    cs = complex_step(held, d)
    assert np.max(np.abs(adj - cs)) <= 1e-10 * np.max(np.abs(cs))
    assert abs(adj[-1] - cs[-1]) <= 1e-10 * abs(cs[-1])
    # and the envelope changes the pitch controls' gradient: the test could fail
    change = np.abs(adj - free.gradient(d).flat())[:N]
    assert change.max() > 1e-2 * np.max(np.abs(cs[:N]))


@pytest.mark.parametrize("scheme", ["paper", "midpoint"])
def test_the_pitch_envelope_in_casadi_and_the_kernel_equals_the_array_code(scheme):
    from mfflap.optimisation.casadi_objective import build_objective, casadi_gradient

    d = perturbed_motion(7)
    kw = dict(beta=0.2, max_power=30.0, max_heave=0.4, scheme=scheme,
              **_envelope_at(d, scheme, 0.8))
    slow = FlappingProblem(MorisonModel(), compiled=False, **kw)
    fast = FlappingProblem(MorisonModel(), compiled=True, **kw)
    g_ref = slow.gradient(d).flat()
    np.testing.assert_allclose(fast.gradient(d).flat(), g_ref, rtol=0,
                               atol=1e-12 * np.abs(g_ref).max())
    f, _ = build_objective(slow, N)
    assert np.isclose(float(f(as_vector(d))), slow.objective(d), rtol=1e-13)
    assert np.max(np.abs(casadi_gradient(slow, d) - g_ref)) <= 1e-10 * np.max(np.abs(g_ref))


@pytest.mark.parametrize("kwargs", [{"max_pitch": 0.0}, {"max_pitch_rate": -1.0},
                                    {"max_pitch_acceleration": float("nan")},
                                    {"penalty_pitch": -1.0}])
def test_a_meaningless_pitch_envelope_is_refused_naming_its_key(kwargs):
    name = next(iter(kwargs))
    with pytest.raises(ConfigError, match=rf"optimisation\.{name}"):
        FlappingProblem(MorisonModel(), **kwargs)


def _modifier(seed=0, size=1.0):
    """A linear modifier about another motion, g . (z - z_c) = ``size`` at perturbed_motion."""
    from mfflap.optimisation.problem import LinearModifier

    rng = np.random.default_rng(seed)
    centre = as_vector(perturbed_motion(seed + 1))
    g = rng.normal(size=2 * N + 1) * np.r_[np.full(2 * N, 0.01), 10.0]
    return LinearModifier(g * size / (g @ (as_vector(perturbed_motion()) - centre)), centre)


@pytest.mark.parametrize("compiled", [True, False], ids=["kernel", "arrays"])
@pytest.mark.parametrize("scheme", ["paper", "midpoint"])
def test_a_linear_modifier_adds_its_value_and_its_exact_gradient(scheme, compiled):
    """g . (z - z_c) (the first-order output correction): J grows by it, the adjoint by g,
    checked against complex steps, CasADi's reverse mode and the packed entry point."""
    from mfflap.optimisation.casadi_objective import build_objective, casadi_gradient

    d = perturbed_motion()
    kw = dict(beta=0.5, max_power=30.0, max_heave=0.4, scheme=scheme, compiled=compiled)
    plain = FlappingProblem(MorisonModel(), **kw)
    mod = _modifier(size=-0.1 * abs(plain.objective(d)))
    problem = FlappingProblem(MorisonModel(), linear_modifier=mod, **kw)
    shift = mod.gradient @ (as_vector(d) - mod.centre)
    assert shift == pytest.approx(-0.1 * abs(plain.objective(d)))  # a term that shows
    assert problem.objective(d) == pytest.approx(plain.objective(d) + shift, rel=1e-12)
    adj = problem.gradient(d).flat()
    assert np.max(np.abs(adj - plain.gradient(d).flat() - mod.gradient)) <= 1e-9 * np.max(
        np.abs(adj))
    cs = complex_step(problem, d)
    assert np.max(np.abs(adj - cs)) <= 1e-10 * np.max(np.abs(cs))
    value, packed = problem.packed_value_and_gradient(as_vector(d))
    assert value == pytest.approx(problem.objective(d), rel=1e-12)
    assert np.max(np.abs(packed - adj)) <= 1e-10 * np.max(np.abs(adj))
    f, _ = build_objective(problem, N)
    assert float(f(as_vector(d))) == pytest.approx(problem.objective(d), rel=1e-12)
    assert np.max(np.abs(casadi_gradient(problem, d) - adj)) <= 1e-10 * np.max(np.abs(adj))
    # batches (array code) carry it per motion
    batch = DiscreteMotion(np.stack([d.pitch_acceleration] * 2),
                           np.stack([d.heave_acceleration] * 2), np.array([d.time_step] * 2))
    assert np.allclose(problem.objective(batch), problem.objective(d), rtol=1e-12)


def test_a_linear_modifier_of_another_length_is_refused_naming_its_key():
    from mfflap.optimisation.problem import LinearModifier

    with pytest.raises(ConfigError) as err:
        LinearModifier(np.ones(2 * N + 1), np.ones(2 * N))
    assert err.value.key == "linear_modifier"
    with pytest.raises(ConfigError, match="finite"):
        LinearModifier(np.r_[np.ones(2 * N), np.nan], np.ones(2 * N + 1))
    problem = FlappingProblem(MorisonModel(), linear_modifier=_modifier())
    short = harmonic_to_discrete(1.2, 0.45, np.deg2rad(35), 1.4, N - 2)
    with pytest.raises(ConfigError, match="N = 24 steps, the motion has 22"):
        problem.objective(short)
    with pytest.raises(ConfigError, match="N = 24 steps"):
        problem.packed_value_and_gradient(as_vector(short))


@pytest.mark.parametrize("scheme", ["paper", "midpoint"])
def test_adjoint_matches_complex_step_with_the_pivot_at_mid_chord(scheme):
    from mfflap.parameters import Plate

    d = perturbed_motion(3)
    model = MorisonModel(plate=Plate(pivot_chord_fraction=0.5))
    problem = FlappingProblem(model, beta=0.5, max_power=30.0, max_heave=0.4,
                              smoothing_pitch=1e-5, smoothing_heave=1e-3, scheme=scheme)
    assert problem._kernel(d) is None  # the compiled kernel serves leading-edge pivots only
    adj = problem.gradient(d).flat()
    cs = complex_step(problem, d)
    assert np.max(np.abs(adj - cs)) <= 1e-10 * np.max(np.abs(cs))
    assert abs(adj[-1] - cs[-1]) <= 1e-10 * abs(cs[-1])
    # the pivot changes the objective: moment arms, and so power, differ
    le = FlappingProblem(MorisonModel(), beta=0.5, max_power=30.0, max_heave=0.4,
                         smoothing_pitch=1e-5, smoothing_heave=1e-3, scheme=scheme)
    assert not np.isclose(float(problem.objective(d)), float(le.objective(d)), rtol=1e-3)


@pytest.mark.parametrize("scheme", ["paper", "midpoint"])
def test_sample_offsets_give_one_objective_and_gradient_in_the_kernel_arrays_and_casadi(
        scheme):
    """Per-sample thrust, power and peak offsets (the vortex polish's correction) with the
    power limit biting on part of the cycle: the compiled kernel, the array code, CasADi and
    complex steps agree."""
    from mfflap.optimisation.casadi_objective import build_objective, casadi_gradient
    from mfflap.optimisation.problem import SampleOffsets

    d = perturbed_motion()
    rng = np.random.default_rng(7)
    offsets = SampleOffsets(rng.normal(0, 2, N), rng.normal(0, 3, N), rng.normal(8, 4, N))
    kw = dict(beta=0.3, max_power=30.0, max_heave=0.4, scheme=scheme, sample_offsets=offsets)
    kernel = FlappingProblem(MorisonModel(), compiled=True, **kw)
    arrays = FlappingProblem(MorisonModel(), compiled=False, **kw)
    assert kernel._kernel(d) is not None
    value = kernel.objective(d)
    assert value == pytest.approx(arrays.objective(d), rel=1e-12)
    assert value != pytest.approx(FlappingProblem(MorisonModel(), beta=0.3, max_power=30.0,
                                                  max_heave=0.4, scheme=scheme).objective(d),
                                  rel=1e-3)
    adj = kernel.gradient(d).flat()
    assert np.max(np.abs(adj - arrays.gradient(d).flat())) <= 1e-10 * np.max(np.abs(adj))
    cs = complex_step(arrays, d)
    assert np.max(np.abs(adj - cs)) <= 1e-10 * np.max(np.abs(cs))
    packed_value, packed = kernel.packed_value_and_gradient(as_vector(d))
    assert packed_value == pytest.approx(value, rel=1e-12)
    assert np.max(np.abs(packed - adj)) <= 1e-10 * np.max(np.abs(adj))
    f, _ = build_objective(kernel, N)
    assert float(f(as_vector(d))) == pytest.approx(value, rel=1e-12)
    assert np.max(np.abs(casadi_gradient(kernel, d) - adj)) <= 1e-10 * np.max(np.abs(adj))
