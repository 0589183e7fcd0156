import numpy as np
import pytest

from mfflap.errors import ConfigError
from mfflap.kinematics import HarmonicMotion, KinematicState, harmonic_to_discrete
from mfflap.parameters import MorisonCoefficients, Plate, StripSettings
from mfflap.performance import evaluate_discrete, evaluate_states, thrust_and_power


def rest_state(n=4, theta=0.0):
    z = np.zeros(n)
    return KinematicState(np.arange(n, dtype=float), z + theta, z, z, z, z, z)


def test_plate_at_rest_gives_pure_tangential_drag(model):
    ev = evaluate_states(model, rest_state(), 1.0)
    rho, cdt, d, s, u = 1000.0, 3.12, 0.003, 0.18, 0.3
    np.testing.assert_allclose(ev.thrust, -0.5 * rho * cdt * (d * s) * u**2, rtol=1e-14)
    np.testing.assert_allclose(ev.input_power, 0.0, atol=1e-14)
    np.testing.assert_allclose(ev.loads.normal_force, 0.0, atol=1e-14)


def test_plate_at_rest_at_incidence_hand_value(model):
    # fixed plate at angle a: v_n = U sin a on every strip, v_t = -U cos a
    a = 0.3
    ev = evaluate_states(model, rest_state(3, a), 1.0)
    rho, u, c, s, d = 1000.0, 0.3, 0.16, 0.18, 0.003
    fn = -0.5 * rho * 2.49 * (c * s) * (u * np.sin(a)) ** 2
    ft = 0.5 * rho * 3.12 * (d * s) * (u * np.cos(a)) ** 2
    np.testing.assert_allclose(ev.loads.normal_force, fn, rtol=1e-12)
    np.testing.assert_allclose(ev.loads.tangential_force, ft, rtol=1e-12)
    np.testing.assert_allclose(ev.loads.moment, fn * c / 2, rtol=1e-12)
    # a fixed plate is pure drag: the force acts along +Y0 (downstream)
    np.testing.assert_allclose(ev.thrust, fn * np.sin(a) - ft * np.cos(a))
    assert np.all(ev.thrust < 0)


def test_standard_heave_pitch_sinusoid_gives_thrust_and_takes_power(model):
    """Catches the literal signs of the paper's text (docs/theory.md): phi = 90 deg must give
    positive thrust and positive mean power."""
    d = harmonic_to_discrete(1.0, 0.3, np.deg2rad(20), np.pi / 2, 50)
    s = evaluate_discrete(model, d).summary
    assert s.mean_thrust > 1.0
    assert s.mean_power > 1.0
    assert 0 < s.efficiency < 1


def test_literal_paper_tangential_velocity_breaks_energy_balance(model):
    """With v_t = hdot sin + U cos (the printed sign) a towed plate would get thrust."""
    state = rest_state()
    ev = evaluate_states(model, state, 1.0)
    assert np.all(ev.thrust < 0)  # our signs: pure drag


def test_vectorised_equals_loop(model, rng):
    f = rng.uniform(0.2, 2, 7)
    h = rng.uniform(0.05, 0.5, 7)
    th = rng.uniform(0, 0.8, 7)
    ph = rng.uniform(0, np.pi, 7)
    batch = evaluate_discrete(model, harmonic_to_discrete(f, h, th, ph, 40)).summary
    for i in range(7):
        one = evaluate_discrete(model, harmonic_to_discrete(f[i], h[i], th[i], ph[i], 40))
        assert np.isclose(batch.mean_thrust[i], one.summary.mean_thrust, rtol=1e-12)
        assert np.isclose(batch.mean_power[i], one.summary.mean_power, rtol=1e-12)
        assert np.isclose(batch.max_power[i], one.summary.max_power, rtol=1e-12)


def test_strip_sum_against_direct_loop(model, rng):
    state = HarmonicMotion(0.8, 0.2, 0.5, 1.2).sample(np.linspace(0, 1, 9))
    loads = model.loads(state)
    g = model.geometry
    rho, u, c = 1000.0, 0.3, model.morison_coefficients
    for i in range(9):
        th, td, tdd = state.pitch_angle[i], state.pitch_rate[i], state.pitch_acceleration[i]
        hd, hdd = state.heave_velocity[i], state.heave_acceleration[i]
        fn = mo = 0.0
        for lk in g.positions:
            vn = hd * np.cos(th) + u * np.sin(th) + td * lk
            an = hdd * np.cos(th) - hd * td * np.sin(th) + u * td * np.cos(th) + tdd * lk
            fk = (-c.normal_added_mass * rho * g.volume_normal / g.n_strips * an
                  - 0.5 * rho * c.normal_drag * g.area_normal / g.n_strips * abs(vn) * vn)
            fn += fk
            mo += fk * lk
        assert np.isclose(loads.normal_force[i], fn, rtol=1e-12)
        assert np.isclose(loads.moment[i], mo, rtol=1e-12)


def test_energy_residual_equals_discrete_added_mass_work(model, rng):
    for _ in range(3):
        d = harmonic_to_discrete(rng.uniform(0.3, 2), rng.uniform(0.05, 0.5),
                                 rng.uniform(0.1, 0.7), rng.uniform(0, np.pi), 50)
        ev = evaluate_discrete(model, d, "paper")
        work = model.added_mass_work(d.states("paper")).mean()
        assert abs(ev.summary.energy_residual - work) < 1e-10 * abs(ev.summary.mean_power)
        assert abs(work) > 1e-3  # the identity is not trivially zero


def test_energy_consistent_variant_is_second_order(model):
    # docs/theory.md's case: f = 1 Hz, h = 0.3 m, theta = 20 deg, phi = 90 deg
    res = {}
    for n in (50, 100, 200):
        d = harmonic_to_discrete(1.0, 0.3, np.deg2rad(20), np.pi / 2, n)
        res[n] = (evaluate_discrete(model, d, "paper").summary.energy_residual,
                  evaluate_discrete(model, d, "midpoint").summary.energy_residual)
    paper = np.array([res[n][0] for n in (50, 100, 200)])
    mid = np.array([res[n][1] for n in (50, 100, 200)])
    # halving dt halves the paper's residual (first order) and quarters the midpoint's
    np.testing.assert_allclose(paper[:-1] / paper[1:], 2.0, rtol=0.02)
    np.testing.assert_allclose(mid[:-1] / mid[1:], 4.0, rtol=0.05)
    assert np.all(np.abs(mid) < 1e-3 * np.abs(paper))


def test_added_mass_leading_order_estimate(model):
    d = harmonic_to_discrete(1.0, 0.3, np.deg2rad(20), np.pi / 2, 50)
    st = d.states()
    g, dt = model.geometry, d.time_step
    pos = np.asarray(g.positions)
    from mfflap.hydro import RelativeFlow

    flow = RelativeFlow.of(st, 0.3)
    an = flow.normal_acceleration[:, None] + st.pitch_acceleration[:, None] * pos
    estimate = -1 / (2 * 50 * dt) * (1.02 * 1000 * g.volume_normal / g.n_strips
                                     * (dt * an) ** 2).sum()
    r = evaluate_discrete(model, d).summary.energy_residual
    assert abs(r - estimate) < 0.2 * abs(r)  # docs/theory.md: within about 20 % at N = 50


def test_thrust_power_projection_consistency(model, rng):
    # P_in - U F_thrust = -sum_k F_k . v_k (work done by the fluid on the moving strips)
    state = HarmonicMotion(1.1, 0.3, 0.4, 1.0).sample(np.linspace(0, 1, 11))
    loads = model.loads(state)
    thrust, power = thrust_and_power(loads, state)
    from mfflap.hydro import RelativeFlow

    flow = RelativeFlow.of(state, 0.3)
    work = (loads.normal_force * flow.normal_velocity + loads.moment * state.pitch_rate
            + loads.tangential_force * flow.tangential_velocity)
    np.testing.assert_allclose(power - 0.3 * thrust, -work, atol=1e-10)


def test_forces_are_linear_in_each_coefficient(model):
    d = harmonic_to_discrete(1.0, 0.3, np.deg2rad(20), np.pi / 2, 50)
    st = d.states()
    base = model.loads(st)
    parts = model.regressors(st)
    total = sum(model.coefficients[k] * parts[k].normal_force for k in parts)
    np.testing.assert_allclose(base.normal_force, total, rtol=1e-12)
    doubled = model.with_coefficients({"normal_drag": 2 * model.coefficients["normal_drag"]})
    diff = doubled.loads(st).normal_force - base.normal_force
    np.testing.assert_allclose(diff, model.coefficients["normal_drag"]
                               * parts["normal_drag"].normal_force, rtol=1e-10, atol=1e-12)
    zero = model.with_coefficients({k: 0.0 for k in model.coefficients})
    np.testing.assert_allclose(zero.loads(st).normal_force, 0.0)


@pytest.mark.parametrize(
    "make",
    [
        lambda: Plate(chord=0.0),
        lambda: Plate(span=-1.0),
        lambda: Plate(thickness=0.2),
        lambda: StripSettings(n_strips=0),
        lambda: StripSettings(n_strips=2.5),
        lambda: MorisonCoefficients(normal_drag=float("nan")),
    ],
)
def test_bad_parameters_are_refused(make):
    with pytest.raises(ConfigError):
        make()


def test_nan_state_is_refused(model):
    from mfflap.errors import MotionError

    st = rest_state()
    bad = KinematicState(st.time, st.pitch_angle, st.pitch_rate, st.pitch_acceleration,
                         st.heave_position, np.array([0, np.nan, 0, 0.0]),
                         st.heave_acceleration)
    with pytest.raises(MotionError, match="heave_velocity"):
        evaluate_states(model, bad, 1.0)


def test_strouhal_uses_trailing_edge_amplitude(model):
    d = harmonic_to_discrete(1.0, 0.3, 0.0, np.pi / 2, 200)
    s = evaluate_discrete(model, d).summary
    assert np.isclose(s.trailing_edge_amplitude, 0.3, rtol=1e-3)
    assert np.isclose(s.strouhal_number, 2 * 1.0 * 0.3 / 0.3, rtol=1e-3)


def test_complex_step_through_model(model):
    d = harmonic_to_discrete(1.0, 0.3, 0.3, np.pi / 2, 20)
    h = 1e-30
    pa = d.pitch_acceleration.astype(complex)
    pa[3] += 1j * h
    from mfflap.kinematics import DiscreteMotion

    cs = evaluate_discrete(model, DiscreteMotion(pa, d.heave_acceleration, d.time_step))
    thrust_cs = np.mean(model.loads(DiscreteMotion(pa, d.heave_acceleration,
                                                   d.time_step).states()).normal_force)
    assert np.isfinite(thrust_cs)
    eps = 1e-4
    pp = d.pitch_acceleration.copy()
    pp[3] += eps
    pm = d.pitch_acceleration.copy()
    pm[3] -= eps
    fp = evaluate_discrete(model, DiscreteMotion(pp, d.heave_acceleration, d.time_step))
    fm = evaluate_discrete(model, DiscreteMotion(pm, d.heave_acceleration, d.time_step))
    fd = (fp.summary.mean_thrust - fm.summary.mean_thrust) / (2 * eps)
    cs_grad = np.imag(np.mean(cs.thrust)) / h
    assert np.isclose(cs_grad, fd, rtol=1e-5)
    assert abs(cs_grad) > 0


def test_closed_form_strip_sums_equal_the_strip_by_strip_sums(model):
    """sum |v|v, sum |v|v l and sum |v|^3 in O(1): exact against the strip loop, including
    no pitch rate (b = 0) and a zero of v exactly at a strip centre."""
    from mfflap.hydro.base import signed_square

    drag = next(t for t in model.terms if t.name == "normal_drag")
    rng = np.random.default_rng(8)
    a = rng.normal(size=3000) * 2
    b = rng.normal(size=3000) * 20
    b[:20] = 0.0
    a[20:40] = -b[20:40] * drag.positions[7]
    v = a[:, None] + b[:, None] * drag.positions
    q = signed_square(v)
    f, g = drag.strip_sums(a, b)
    np.testing.assert_allclose(f, q.sum(-1), rtol=1e-12, atol=1e-12 * np.abs(q).sum(-1).max())
    np.testing.assert_allclose(g, q @ drag.positions, rtol=1e-12,
                               atol=1e-12 * np.abs(q).sum(-1).max())
    np.testing.assert_allclose(drag.strip_abs_cubes(a, b), (np.abs(v) ** 3).sum(-1),
                               rtol=1e-12)


@pytest.mark.parametrize("pivot_fraction", [0.25, 0.5, 1.0])
def test_pivot_on_the_chord_against_rigid_body_point_kinematics(pivot_fraction):
    """Each strip's relative velocity from its own lab-frame path (pivot at (0, h), a point
    s along the chord at (s cos theta, h + s sin theta)), differentiated numerically; the
    loads summed strip by strip, the moment taken about the pivot."""
    from mfflap.hydro import MorisonModel

    plate = Plate(pivot_chord_fraction=pivot_fraction)
    model = MorisonModel(plate=plate)
    motion = HarmonicMotion(0.9, 0.25, 0.6, 1.3)
    t = np.linspace(0.05, 1.0, 7)
    loads = model.loads(motion.sample(t))
    rho, u, c = 1000.0, 0.3, model.morison_coefficients
    n, chord, dt = model.geometry.n_strips, plate.chord, 1e-4
    span, thick = plate.span, plate.thickness
    vol_n = np.pi * (chord / 2) ** 2 * span / n

    def relative_velocity(time, s):
        """(v_n, v_t) of the point s behind the pivot, by central differences of its path."""
        def path(tt):
            st = motion.sample(np.atleast_1d(tt))
            th, h = st.pitch_angle[0], st.heave_position[0]
            return np.array([s * np.cos(th), h + s * np.sin(th)]), th
        (p1, _), (p0, _) = path(time + dt), path(time - dt)
        _, th = path(time)
        # the point's velocity relative to the fluid, which moves at U along +x
        v = (p1 - p0) / (2 * dt) - np.array([u, 0.0])
        normal, tangent = np.array([-np.sin(th), np.cos(th)]), np.array([np.cos(th), np.sin(th)])
        return v @ normal, v @ tangent

    for i, ti in enumerate(t):
        fn = mo = ft = 0.0
        for k in range(1, n + 1):
            s = chord * (2 * k - 1) / (2 * n) - plate.pivot_m
            vn, vt = relative_velocity(ti, s)
            an = (relative_velocity(ti + dt, s)[0] - relative_velocity(ti - dt, s)[0]) / (2 * dt)
            f = -c.normal_added_mass * rho * vol_n * an - 0.5 * rho * c.normal_drag * (
                chord * span / n) * abs(vn) * vn
            fn, mo = fn + f, mo + f * s
            if k == 1:
                at = (relative_velocity(ti + dt, s)[1]
                      - relative_velocity(ti - dt, s)[1]) / (2 * dt)
                ft = (-c.tangential_added_mass * rho * chord * span * thick * at
                      - 0.5 * rho * c.tangential_drag * thick * span * abs(vt) * vt)
        scale = np.max(np.abs(loads.normal_force))
        assert abs(loads.normal_force[i] - fn) < 1e-5 * scale
        assert abs(loads.moment[i] - mo) < 1e-5 * scale * chord
        assert abs(loads.tangential_force[i] - ft) < 1e-5 * np.max(np.abs(loads.tangential_force))
