"""The output correction (multiplicative output space mapping) of the optimisation."""

import numpy as np
import pytest

from mfflap.errors import ConfigError
from mfflap.hydro import MorisonModel
from mfflap.kinematics import DiscreteMotion, harmonic_to_discrete
from mfflap.optimisation import FlappingProblem
from mfflap.optimisation.optimise import optimise_ipopt
from mfflap.optimisation.output_correction import CorrectionPoint, OutputCorrection
from mfflap.optimisation.problem import _positive_part
from mfflap.performance import evaluate_discrete, thrust_and_power

N = 24


def motion(seed=0):
    rng = np.random.default_rng(seed)
    d = harmonic_to_discrete(1.2, 0.45, np.deg2rad(35), 1.4, N)
    return DiscreteMotion(d.pitch_acceleration * (1 + 0.2 * rng.normal(size=N)),
                          d.heave_acceleration * (1 + 0.2 * rng.normal(size=N)), d.time_step)


def problem(beta, **kw):
    # P_max = 30 W, h_max = 0.4 m and a pitch limit of 30 deg make every penalty active
    return FlappingProblem(MorisonModel(), beta=beta, max_power=30.0, max_heave=0.4,
                           smoothing_pitch=1e-5, smoothing_heave=1e-3,
                           max_pitch=np.deg2rad(30), **kw)


def corrected_objective(p: FlappingProblem, d: DiscreteMotion, k_t: float, k_p: float):
    """The corrected J written out from docs/theory.md's stage cost, term by term."""
    state = d.states(p.scheme)
    thrust, power = thrust_and_power(p.model.loads(state), state)
    thrust, power = k_t * thrust, k_p * power
    excess_p = _positive_part(power - p.max_power)
    excess_h = _positive_part(np.abs(state.heave_position) - p.max_heave)
    stage = (-(1 - p.beta) * thrust + p.beta * power + 0.5 * p.penalty_power * excess_p**2
             + 0.5 * p.penalty_heave * excess_h**2 + p.pitch_envelope_cost(state))
    return stage.mean() + p.smoothness(d)


@pytest.mark.parametrize("scheme", ["paper", "midpoint"])
@pytest.mark.parametrize("beta", [0.0, 0.3, 1.0])
@pytest.mark.parametrize("scales", [(1.25, 0.8), (0.7, 1.4)])
def test_the_equivalent_problem_is_the_corrected_objective_over_c(beta, scales, scheme):
    p = problem(beta, scheme=scheme)
    k_t, k_p = scales
    corr = OutputCorrection(k_t, k_p, "test")
    equivalent = corr.problem(p)
    c = corr.objective_factor(beta)
    for seed in range(3):
        d = motion(seed)
        state = d.states(scheme)
        _, power = thrust_and_power(p.model.loads(state), state)
        assert np.max(k_p * power) > p.max_power  # the power penalty is active
        assert np.max(np.abs(state.heave_position)) > p.max_heave
        expected = corrected_objective(p, d, k_t, k_p)
        assert c * float(equivalent.objective(d)) == pytest.approx(float(expected), rel=1e-11)
    # and the gradient: a central difference of the written-out J along a random direction
    d = motion(7)
    g = equivalent.gradient(d).flat()
    rng = np.random.default_rng(3)
    direction = rng.normal(size=g.size) * np.concatenate(
        [np.abs(d.pitch_acceleration), np.abs(d.heave_acceleration), [d.time_step]]) * 1e-6

    def at(step):
        x = np.concatenate([d.pitch_acceleration, d.heave_acceleration, [d.time_step]])
        x = x + step * direction
        return corrected_objective(p, DiscreteMotion(x[:N], x[N:2 * N], x[2 * N]), k_t, k_p)

    fd = (at(1.0) - at(-1.0)) / 2
    assert c * g @ direction == pytest.approx(fd, rel=1e-5)


def test_unit_scales_give_the_same_problem():
    p = problem(0.4)
    same = OutputCorrection(1.0, 1.0, "none").problem(p)
    for name in ("beta", "max_power", "penalty_power", "penalty_heave", "smoothing_pitch",
                 "smoothing_heave", "penalty_pitch", "max_heave", "max_pitch"):
        assert getattr(same, name) == pytest.approx(getattr(p, name), rel=1e-15), name


def test_a_measured_correction_makes_the_model_predict_the_cfd_means():
    model = MorisonModel()
    d = harmonic_to_discrete(1.0, 0.3, np.deg2rad(20), np.pi / 2, 50)
    s = evaluate_discrete(model, d).summary
    point = CorrectionPoint(d, 1.2 * float(s.mean_thrust), 0.85 * float(s.mean_power),
                            "round 1, beta = 0")
    corr = OutputCorrection.measured(point, model, "paper")
    assert corr.thrust_scale == pytest.approx(1.2)
    assert corr.power_scale == pytest.approx(0.85)
    assert corr.thrust_scale * corr.model_mean_thrust == pytest.approx(point.cfd_mean_thrust)
    assert corr.power_scale * corr.model_mean_power == pytest.approx(point.cfd_mean_power)
    assert corr.notes == ()
    assert "thrust x 1.200, power x 0.850 (measured on round 1, beta = 0)" == corr.describe()


def test_a_scale_that_means_nothing_is_left_at_one_and_says_why():
    model = MorisonModel()
    d = harmonic_to_discrete(1.0, 0.3, np.deg2rad(20), np.pi / 2, 50)
    s = evaluate_discrete(model, d).summary
    drag = CorrectionPoint(d, -0.5, 2.0 * float(s.mean_power), "a drag")
    corr = OutputCorrection.measured(drag, model, "paper")
    assert corr.thrust_scale == 1.0 and corr.power_scale == pytest.approx(2.0)
    assert "not of one sign" in corr.notes[0]
    # a plate that barely moves makes drag: a CFD drag twice the model's scales it by 2
    still = harmonic_to_discrete(1.0, 0.005, 0.0, 0.0, 50)
    s_still = evaluate_discrete(model, still).summary
    assert float(s_still.mean_thrust) < 0
    corr = OutputCorrection.measured(
        CorrectionPoint(still, 2 * float(s_still.mean_thrust), float(s_still.mean_power),
                        "drag"), model, "paper")
    assert corr.thrust_scale == pytest.approx(2.0) and corr.notes == ()
    small = CorrectionPoint(d, 0.01, float(s.mean_power), "beta 1", thrust_usable=False)
    corr = OutputCorrection.measured(small, model, "paper")
    assert corr.thrust_scale == 1.0 and "too small" in corr.notes[0]


def test_the_filter_moves_the_scales_the_gains_fraction_of_the_way():
    model = MorisonModel()
    d = harmonic_to_discrete(1.0, 0.3, np.deg2rad(20), np.pi / 2, 50)
    s = evaluate_discrete(model, d).summary
    point = CorrectionPoint(d, 1.2 * float(s.mean_thrust), 0.85 * float(s.mean_power),
                            "round 2, beta = 0", scales=(1.4, 1.1))
    measured = OutputCorrection.measured(point, model, "paper")
    half = measured.filtered(point.scales, 0.5)
    # (1 - K) kappa_previous + K kappa_measured, worked by hand
    assert half.thrust_scale == pytest.approx(1.3)
    assert half.power_scale == pytest.approx(0.975)
    assert half.measured_scales == (pytest.approx(1.2), pytest.approx(0.85))
    assert half.previous_scales == (1.4, 1.1) and half.gain == 0.5
    assert half.describe() == ("thrust x 1.300, power x 0.975 (filter gain 0.5 from 1.400, "
                               "1.100 towards 1.200, 0.850 measured on round 2, beta = 0)")
    # filtering again moves from the measured scales, not from the filtered ones
    assert half.filtered((1.0, 1.0), 0.25).thrust_scale == pytest.approx(0.75 + 0.25 * 1.2)
    # gain 1: the measured correction itself, described as before
    same = measured.filtered(point.scales, 1.0)
    assert (same.thrust_scale, same.power_scale) == (measured.thrust_scale,
                                                    measured.power_scale)
    assert same.describe() == measured.describe()
    # the dict written into results.h5 describes the same (a dict from before the filter,
    # without its keys, reads as unfiltered)
    from mfflap.optimisation.output_correction import describe_correction

    assert describe_correction(half.as_dict()) == half.describe()
    old = {k: v for k, v in measured.as_dict().items()
           if k not in ("gain", "measured_scales", "previous_scales")}
    assert describe_correction(old) == measured.describe()


@pytest.mark.parametrize("gain", [0.0, -0.5, 1.5, np.nan])
def test_a_filter_gain_outside_zero_to_one_is_refused(gain):
    from mfflap.pipeline import RunOptions

    corr = OutputCorrection(1.1, 0.9, "x")
    with pytest.raises(ConfigError, match="correction_gain"):
        corr.filtered((1.0, 1.0), gain)
    with pytest.raises(ConfigError, match="correction_gain"):
        RunOptions(correction_gain=gain)
    with pytest.raises(ConfigError, match="previous power scale"):
        corr.filtered((1.0, -1.0), 0.5)


@pytest.mark.parametrize("bad", [0.0, -1.0, np.nan, np.inf])
def test_an_impossible_scale_is_refused(bad):
    with pytest.raises(ConfigError, match="thrust_scale"):
        OutputCorrection(bad, 1.0, "x")


def test_a_power_scale_moves_the_hard_power_limit_of_the_optimum():
    """IPOPT holds P_in,j <= P_max at every step: corrected by kappa_P, the model's own peak
    power at the optimum is P_max / kappa_P (the limit is active at beta = 0)."""
    p = FlappingProblem(MorisonModel(), beta=0.0, max_power=20.0, max_heave=0.5)
    start = harmonic_to_discrete(1.0, 0.3, np.deg2rad(20), np.pi / 2, 30)
    plain = optimise_ipopt(p, start, min_period=0.5, max_period=3.0)
    corrected = optimise_ipopt(OutputCorrection(1.0, 1.25, "x").problem(p), start,
                               min_period=0.5, max_period=3.0)
    peak = [float(np.max(evaluate_discrete(p.model, r.motion).input_power))
            for r in (plain, corrected)]
    assert peak[0] == pytest.approx(20.0, rel=1e-4)
    assert peak[1] == pytest.approx(16.0, rel=1e-4)
    assert corrected.summary.mean_thrust < plain.summary.mean_thrust


def _small_sweep(config, model):
    from mfflap.sweep import sinusoid_sweep

    o = config.optimisation
    return sinusoid_sweep(model, np.linspace(0.5, 2.0, 4), np.linspace(0.1, 0.4, 4),
                          np.deg2rad([20, 40]), np.deg2rad([90]), n_steps=o.n_steps,
                          max_power=o.max_power)


@pytest.mark.slow
def test_a_beta_study_with_a_correction_optimises_the_corrected_outputs(tmp_path):
    """beta = 0 with the power scaled by 1.3: the optimum keeps the model's own power at
    P_max / 1.3 (the penalty's limit moves), is labelled beta = 0 with the corrected J, and
    its correction is stored beside it in HDF5 and said in the report."""
    import json
    from pathlib import Path

    from mfflap.config import load_case
    from mfflap.optimisation.store import read_result
    from mfflap.optimisation.study import beta_study, problem_for
    from mfflap.optimisation.workflow import write_study
    from mfflap.reports.html import Report
    from mfflap.reports.optimisation import add_optimisation_sections
    from mfflap.results import ResultsFile

    config = load_case(Path(__file__).parents[2] / "cases" / "paper2026.toml")
    model = config.morison_model()
    sweep = _small_sweep(config, model)
    corr = OutputCorrection(1.1, 1.3, "a test")
    lines = []
    plain = beta_study(config, [0.0], n_starts=1, with_ipopt=False, model=model, sweep=sweep)
    study = beta_study(config, [0.0], n_starts=1, with_ipopt=False, model=model, sweep=sweep,
                       corrections={0.0: corr}, progress=lines.append)
    p_max = config.optimisation.max_power
    result = study.sqp[0.0]
    assert result.beta == 0.0 and study.corrections == {0.0: corr}
    peak = float(np.max(evaluate_discrete(model, result.motion, config.optimisation.scheme)
                        .input_power))
    assert peak < 1.01 * p_max / 1.3 < 0.8 * p_max  # the corrected limit holds
    assert float(result.summary.mean_power) < float(plain.sqp[0.0].summary.mean_power)
    # the stored objective is the corrected J: c J' with c = kappa_T at beta = 0
    equivalent = corr.problem(problem_for(config, 0.0, model))
    assert result.objective == pytest.approx(1.1 * float(equivalent.objective(result.motion)))
    assert any(line.startswith("beta 0 (outputs corrected; J over c) from") for line in lines)
    assert any("thrust x 1.100, power x 1.300 (measured on a test)" in line for line in lines)
    assert "corrected from CFD" in study.thrust_gain_caveat
    with ResultsFile(tmp_path / "r.h5", "w", kind="optimisation") as rf:
        write_study(rf, config, study, model=model)
    with ResultsFile(tmp_path / "r.h5") as rf:
        back = read_result(rf, "optimisation/sqp/beta_0.00")
        attrs = dict(rf.h5["optimisation/sqp/beta_0.00"].attrs)
    assert back.beta == 0.0
    assert attrs["setting_output_power_scale"] == 1.3
    assert attrs["setting_max_power"] == p_max  # the case's, the correction beside it
    assert json.loads(attrs["setting_output_correction"])["source"] == "a test"
    rep = Report("t", "")
    add_optimisation_sections(rep, study, model, config.optimisation.scheme, p_max)
    rep.write(tmp_path / "r.html")
    html = (tmp_path / "r.html").read_text().replace("&#x27;", "'")
    assert "β = 0 was optimised with the model's outputs corrected from CFD" in html
    with pytest.raises(ConfigError, match=r"output corrections for beta \[0.5\]"):
        beta_study(config, [0.0], n_starts=1, with_ipopt=False, model=model, sweep=sweep,
                   corrections={0.5: corr})


def test_a_corrected_optimums_peak_power_flag_is_in_corrected_watts_against_the_case_p_max():
    """The optimiser flags a peak over P_max' = P_max / kappa_P in model watts; the result
    of the corrected problem says it in corrected watts against the case's P_max (the same
    test), and keeps its other flags."""
    from dataclasses import replace

    from mfflap.optimisation.optimise import OptimisationResult, assess, peak_power_flag
    from mfflap.optimisation.study import _corrected

    model = MorisonModel()
    d = harmonic_to_discrete(1.0, 0.3, np.deg2rad(20), np.pi / 2, 50)
    corr = OutputCorrection(1.1, 2.0, "a test")
    # a limit the motion's peak passes by far: the equivalent problem's P_max' = 5 / 2 W
    equivalent = corr.problem(FlappingProblem(model, beta=0.0, max_power=5.0))
    summary, peak, flags = assess(equivalent, d)
    assert peak_power_flag(peak, 500, 2.5) in flags
    result = OptimisationResult(0.0, d, "sqp-penalty", "s", True, "", 1.0, np.ones(2),
                                summary, peak, [*flags, "another flag"])
    out = _corrected(result, 0.0, corr, equivalent)
    assert out.flags[0] == "another flag"
    assert out.flags[1].startswith(f"corrected peak power {2 * peak:.3g} W after resampling "
                                   "to 500 steps exceeds P_max 5 W by more than")
    assert len(out.flags) == 2
    # under the limit, corrected or not, no flag (nor one added to a result without it)
    assert peak_power_flag(peak, 500, peak) is None
    fine = replace(result, flags=["another flag"])
    assert _corrected(fine, 0.0, corr, equivalent).flags == ["another flag"]


def _cfd_stand_in():
    """A "CFD" unlike the model in shape: other coefficients, so its means are not a fixed
    multiple of the model's (the secants then have something to correct)."""
    from mfflap.parameters import MorisonCoefficients

    return MorisonModel(coefficients=MorisonCoefficients(
        normal_drag=1.6, tangential_drag=0.2, normal_added_mass=1.4, tangential_added_mass=0.3))


def _point(cfd_model, motion, source):
    from mfflap.performance import discrete_means

    thrust, power = discrete_means(cfd_model, motion, "paper")
    return CorrectionPoint(motion, thrust, power, source)


@pytest.mark.parametrize("beta", [0.0, 0.5, 1.0])
def test_a_slope_makes_the_corrected_objective_cfds_at_every_earlier_motion(beta):
    """J_0(u) + lambda . (u - c) is CFD's objective (the outputs scaled to each motion's own
    CFD means, power penalty active) at the centre and at each earlier motion; lambda is
    minimum-norm: it lies in the span of the scaled secants; the optimisers' problem, times
    c, is that objective."""
    from mfflap.optimisation.output_correction import cfd_objective

    model, cfd = MorisonModel(), _cfd_stand_in()
    p = problem(beta)
    centre = _point(cfd, motion(0), "centre")
    others = [_point(cfd, motion(seed), f"round {seed}") for seed in (1, 2)]
    corr = OutputCorrection.measured(centre, model, "paper")
    assert corr.thrust_scale != pytest.approx(1.0, abs=0.05)
    sloped = corr.with_slopes(centre.motion, [*others, centre], p)
    assert sloped.slopes.sources == ("round 1", "round 2")  # the centre itself left out
    equivalent, c = sloped.problem(p), sloped.objective_factor(beta)
    zeroth = corr.problem(p)
    for q in (centre, *others):
        target = cfd_objective(q, p)
        assert c * float(equivalent.objective(q.motion)) == pytest.approx(target, rel=1e-9)
        if q is not centre:  # the scales alone miss it
            assert abs(c * float(zeroth.objective(q.motion)) - target) > 1e-3 * abs(target)
    # CFD's objective by hand at one point: the scales measured there, power penalty active
    q = others[0]
    own = OutputCorrection.measured(q, model, "paper")
    st = q.motion.states("paper")
    _, power = thrust_and_power(model.loads(st), st)
    assert np.max(own.power_scale * power) > p.max_power
    assert cfd_objective(q, p) == pytest.approx(float(corrected_objective(
        p, q.motion, own.thrust_scale, own.power_scale)), rel=1e-11)
    w = centre.motion.control_scales()
    x_c = np.real(centre.motion.controls())
    secants = np.array([(np.real(x.motion.controls()) - x_c) / w for x in others])
    scaled = sloped.slopes.objective * w
    in_span = secants.T @ np.linalg.lstsq(secants.T, scaled, rcond=None)[0]
    assert np.allclose(in_span, scaled, rtol=1e-9, atol=1e-12 * np.abs(scaled).max())
    assert p.linear_modifier is None and equivalent.linear_modifier is not None
    assert "a slope of J through 2 earlier motion(s)" in sloped.describe()
    assert sloped.as_dict()["slopes"]["sources"] == ["round 1", "round 2"]
    assert sloped.shift(others[1].motion) == pytest.approx(
        c * float(equivalent.objective(others[1].motion))
        - c * float(zeroth.objective(others[1].motion)), rel=1e-9)


def test_a_slope_with_nothing_to_meet_is_zero_and_a_filtered_correction_refuses_it():
    model, cfd = MorisonModel(), _cfd_stand_in()
    centre = _point(cfd, motion(0), "centre")
    corr = OutputCorrection.measured(centre, model, "paper")
    alone = corr.with_slopes(centre.motion, [centre], problem(0.0))
    assert alone.slopes.sources == () and not alone.slopes.objective.any()
    assert alone.shift(motion(3)) == 0.0 and corr.shift(motion(3)) == 0.0
    assert "a slope of J: no earlier motion near (zero)" in alone.describe()
    with pytest.raises(ConfigError, match="filter gain 1") as err:
        corr.filtered((1.0, 1.0), 0.5).with_slopes(centre.motion, [], problem(0.0))
    assert err.value.key == "correction_gain"
    other_n = harmonic_to_discrete(1.2, 0.45, np.deg2rad(35), 1.4, N + 2)
    with pytest.raises(ConfigError, match="slopes are for N = 24"):
        alone.shift(other_n)


def test_ipopt_and_sqp_follow_a_linear_modifier_within_a_trust_region():
    """A modifier that rewards a longer time step takes both optimisers' dt to the trust
    region's upper face; the same modifier reversed takes it to the lower face."""
    from mfflap.optimisation.optimise import optimise_sqp
    from mfflap.optimisation.problem import LinearModifier
    from mfflap.optimisation.trust_region import TrustRegion

    start = harmonic_to_discrete(1.0, 0.3, np.deg2rad(20), np.pi / 2, 30)
    region = TrustRegion(start, 0.1, "test")
    z_c = np.r_[start.pitch_acceleration, start.heave_acceleration, start.time_step]
    for sign in (1.0, -1.0):
        g = np.zeros(61)
        g[-1] = -sign * 1e7  # J falls by 1e7 per second of dt (1700 per % of dt here)
        p = FlappingProblem(MorisonModel(), beta=0.0, max_power=500.0, max_heave=1.0,
                            linear_modifier=LinearModifier(g, z_c))  # IPOPT: feasible box
        for optimiser in (optimise_sqp, optimise_ipopt):
            r = optimiser(p, start, min_period=0.5, max_period=3.0, trust_region=region)
            assert r.motion.time_step == pytest.approx(start.time_step * (1 + sign * 0.1),
                                                       rel=1e-6), optimiser.__name__


def test_secants_within_a_reach_keep_the_near_motions_and_drop_the_far_ones():
    """The largest scaled control change decides (the trust region's own measure)."""
    from mfflap.optimisation.output_correction import secants_within

    centre = motion(0)
    near, far = (DiscreteMotion(centre.pitch_acceleration * f, centre.heave_acceleration,
                                centre.time_step) for f in (1.1, 1.3))
    other_n = harmonic_to_discrete(1.2, 0.45, np.deg2rad(35), 1.4, N + 2)
    points = [CorrectionPoint(m, 1.0, 1.0, name) for m, name in
              ((near, "near"), (far, "far"), (other_n, "other N"))]
    # near moves the peak pitch acceleration by 10 % of itself, far by 30 %
    assert [p.source for p in secants_within(centre, points, 0.2)] == ["near"]
    assert [p.source for p in secants_within(centre, points, 0.3)] == ["near", "far"]
    assert secants_within(centre, points, 0.05) == []
