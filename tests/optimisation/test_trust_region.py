"""The rounds' trust region: its box, the optimisers kept in it, and the step's judgement."""

import math
from pathlib import Path

import numpy as np
import pytest

from mfflap.config import load_case
from mfflap.errors import ConfigError
from mfflap.kinematics.convert import harmonic_to_discrete
from mfflap.kinematics.discrete import DiscreteMotion
from mfflap.optimisation.optimise import optimise_ipopt, optimise_sqp
from mfflap.optimisation.study import beta_study, problem_for
from mfflap.optimisation.trust_region import (
    MAX_RADIUS,
    TrustRegion,
    TrustStep,
    check_radius,
    check_repeatability,
    noise_of_objective,
    step_ratio,
    updated_radius,
)

CASE = Path(__file__).parents[2] / "cases" / "paper2026.toml"


def test_cfds_noise_relaxes_the_ratio_and_settles_a_step_it_cannot_judge():
    """rho = (CFD decrease + eps) / (predicted + eps) (Sun and Nocedal's relaxation); a step
    predicted to gain no more than eps is within CFD's noise."""
    c = DiscreteMotion(np.ones(4), np.ones(4), 0.1)
    optimum = DiscreteMotion(np.ones(4), np.ones(4), 0.1 * 1.1)  # inside, half the radius
    region = TrustRegion(c, 0.2, "round 2's beta = 0")
    # eps of J at beta = 0.5 from a CFD of 9 N and 7 W, two runs 3 % apart: 0.24
    eps = noise_of_objective(0.03, 0.5, 9.0, -7.0)
    assert eps == pytest.approx(0.03 * (0.5 * 9.0 + 0.5 * 7.0))
    # predicted 0.1, CFD -0.1 (worse): refused without the noise, within it with
    exact = TrustStep.judged(region, 0.5, optimum, 5.0, 5.1, 5.0, 4.9)
    assert exact.ratio == pytest.approx(-1.0) and not exact.accepted
    assert not exact.within_noise and exact.noise == 0.0
    noisy = TrustStep.judged(region, 0.5, optimum, 5.0, 5.1, 5.0, 4.9, noise=eps)
    assert noisy.ratio == pytest.approx((-0.1 + eps) / (0.1 + eps))
    assert noisy.accepted and noisy.within_noise
    assert "CFD's noise 0.24; ratio relaxed by it 0.412; within CFD's noise" in noisy.describe()
    assert noisy.as_dict()["within_noise"] and noisy.as_dict()["noise"] == eps
    # a gain well above the noise is judged as before: CFD's -3 for a predicted 3, refused
    big = TrustStep.judged(region, 0.5, optimum, 5.0, 8.0, 5.0, 2.0, noise=eps)
    assert not big.within_noise and not big.accepted
    assert big.ratio == pytest.approx((-3 + eps) / (3 + eps))
    with pytest.raises(ConfigError, match="noise of J") as err:
        TrustStep.judged(region, 0.5, optimum, 5.0, 5.1, 5.0, 4.9, noise=-0.1)
    assert err.value.key == "cfd_repeatability"


@pytest.mark.parametrize("share", [0.0, 1.0, -0.03, math.nan, True, "0.03"])
def test_a_repeatability_outside_zero_to_one_is_refused_by_name(share):
    with pytest.raises(ConfigError) as err:
        check_repeatability(share)
    assert err.value.key == "cfd_repeatability"


@pytest.fixture(scope="module")
def config():
    return load_case(CASE)


@pytest.fixture(scope="module")
def centre(config):
    """A sinusoid of the paper's range, not an optimum of any beta."""
    return harmonic_to_discrete(0.6, 0.3, np.deg2rad(30.0), np.deg2rad(90.0),
                                config.optimisation.n_steps)


@pytest.mark.parametrize("radius", [0.0, -0.1, math.nan, math.inf, MAX_RADIUS * 1.01, True,
                                    "0.2"])
def test_a_radius_outside_its_range_is_refused_by_name(radius):
    with pytest.raises(ConfigError, match="trust region's radius must be a fraction") as err:
        check_radius(radius)
    assert err.value.key == "trust_region"


def test_the_box_spans_the_radius_of_the_centres_peak_accelerations_and_time_step():
    n = 4
    c = DiscreteMotion(np.array([1.0, -4.0, 2.0, 0.0]), np.array([0.5, 0.5, -1.0, 0.0]), 0.1)
    region = TrustRegion(c, 0.25, "test")
    lower, upper = region.bounds(n, (0.0, 1.0))
    x_c = np.real(c.controls())
    np.testing.assert_allclose(upper[:n] - x_c[:n], 0.25 * 4.0)  # the pitch peak 4
    np.testing.assert_allclose(x_c[n:2 * n] - lower[n:2 * n], 0.25 * 1.0)
    assert (lower[-1], upper[-1]) == pytest.approx((0.075, 0.125))
    # dt is also held to the period bounds
    assert region.bounds(n, (0.09, 0.11))[0][-1] == pytest.approx(0.09)
    with pytest.raises(ConfigError, match="misses the time steps") as err:
        region.bounds(n, (0.2, 0.3))
    assert err.value.key == "trust_region"
    with pytest.raises(ConfigError, match="centre \\(test\\) has 4 steps, the optimisation 5"):
        region.bounds(5, (0.0, 1.0))
    # the step's share of the radius: the largest over the variables
    assert region.step_fraction(c) == 0.0 and not region.on_boundary(c)
    moved = DiscreteMotion(c.pitch_acceleration + np.array([0.0, 0.5, 0.0, 0.0]),
                           c.heave_acceleration, 0.1)
    assert region.step_fraction(moved) == pytest.approx(0.5)  # 0.5 of the half width 1
    edge = DiscreteMotion(c.pitch_acceleration, c.heave_acceleration, 0.125)
    assert region.step_fraction(edge) == pytest.approx(1.0) and region.on_boundary(edge)


def test_the_step_ratio_and_the_radius_update_follow_the_textbook_rule():
    assert step_ratio(1.0, 2.0) == 0.5
    assert step_ratio(-1.0, 2.0) == -0.5
    assert step_ratio(0.1, 0.0) == math.inf and step_ratio(-0.1, -1.0) == -math.inf
    with pytest.raises(ConfigError, match="finite decreases"):
        step_ratio(math.nan, 1.0)
    assert updated_radius(0.2, 0.1, True) == pytest.approx(0.1)  # poor: halves
    assert updated_radius(0.2, 0.5, True) == 0.2  # fair: kept
    assert updated_radius(0.2, 0.9, False) == 0.2  # good, but the box did not bind
    assert updated_radius(0.2, 0.9, True) == pytest.approx(0.4)  # good and bound: doubles
    assert updated_radius(1.5, 0.9, True) == MAX_RADIUS
    # a poor step inside the region: half the step, so its optimum is not found again
    assert updated_radius(0.2, 0.1, False, 0.3) == pytest.approx(0.03)
    assert updated_radius(0.2, 0.5, False, 0.3) == 0.2


def test_a_step_is_judged_by_the_decrease_cfd_confirms_of_the_one_predicted():
    c = DiscreteMotion(np.ones(4), np.ones(4), 0.1)
    optimum = DiscreteMotion(np.ones(4), np.ones(4), 0.1 * (1 + 0.2))  # on the boundary
    region = TrustRegion(c, 0.2, "round 1's beta = 0.5")
    # J: CFD 5 -> 4 (decrease 1), predicted 5 -> 3 (decrease 2)
    step = TrustStep.judged(region, 0.5, optimum, 5.0, 4.0, 5.0, 3.0)
    assert (step.cfd_decrease, step.predicted_decrease, step.ratio) == (1.0, 2.0, 0.5)
    assert step.accepted and step.on_boundary and step.next_radius == 0.2
    assert "(ratio 0.5): accepted, next radius 0.2" in step.describe()
    # CFD worse at the optimum than at the centre: rejected, and the radius halves
    bad = TrustStep.judged(region, 0.5, optimum, 5.0, 5.5, 5.0, 3.0)
    assert bad.ratio == -0.25 and not bad.accepted and bad.next_radius == pytest.approx(0.1)
    assert "rejected" in bad.describe()
    # nothing predicted, CFD better: a bonus; the dict keeps an infinite ratio as text
    free = TrustStep.judged(region, 1.0, optimum, 5.0, 4.9, 5.0, 5.0)
    assert free.ratio == math.inf and free.as_dict()["ratio"] == "inf"
    assert free.accepted and free.next_radius == pytest.approx(0.4)
    # an optimum that did not leave the centre: nothing judged, centre and radius kept
    still = TrustStep.judged(region, 1.0, c, 5.0, 5.0 + 1e-9, 5.0, 5.0 - 1e-12)
    assert not still.moved and still.accepted and still.next_radius == 0.2
    assert math.isnan(still.ratio) and still.as_dict()["ratio"] == "nan"
    assert still.describe().endswith("no step (the centre is the optimum); centre and radius "
                                     "kept")


def test_sqp_keeps_its_optimum_in_the_box_and_improves_on_the_centre(config, centre):
    o = config.optimisation
    problem = problem_for(config, 0.0)
    region = TrustRegion(centre, 0.05)
    found = optimise_sqp(problem, centre, min_period=o.min_period, max_period=o.max_period,
                         trust_region=region)
    lower, upper = region.bounds(centre.n_steps, (0.0, np.inf))
    x = np.real(found.motion.controls())
    width = upper - lower
    assert np.all(x >= lower - 1e-9 * width) and np.all(x <= upper + 1e-9 * width)
    # the sinusoid is no optimum: the small box binds, and J falls within it
    assert region.on_boundary(found.motion)
    assert found.objective < problem.objective(centre)
    # a start outside the box is moved into it
    far = optimise_sqp(problem, harmonic_to_discrete(1.2, 0.2, 0.3, 1.5, centre.n_steps),
                       min_period=o.min_period, max_period=o.max_period, trust_region=region,
                       max_iterations=2)
    assert region.step_fraction(far.motion) <= 1 + 1e-9


def test_a_box_about_an_optimum_leaves_it_where_it_is(config, centre):
    o = config.optimisation
    problem = problem_for(config, 0.0)
    free = optimise_sqp(problem, centre, min_period=o.min_period, max_period=o.max_period)
    region = TrustRegion(free.motion, 0.1)
    kept = optimise_sqp(problem, free.motion, min_period=o.min_period,
                        max_period=o.max_period, trust_region=region, continuation=(1.0,))
    assert free.converged and not region.on_boundary(kept.motion)
    assert region.step_fraction(kept.motion) < 1e-3
    assert kept.objective == pytest.approx(free.objective, rel=1e-9)


def test_ipopt_keeps_its_optimum_in_the_box(config, centre):
    o = config.optimisation
    region = TrustRegion(centre, 0.05)
    found = optimise_ipopt(problem_for(config, 0.0), centre, min_period=o.min_period,
                           max_period=o.max_period, trust_region=region)
    assert region.step_fraction(found.motion) <= 1 + 1e-6
    assert region.on_boundary(found.motion)


@pytest.mark.slow
def test_a_beta_study_starts_a_trust_region_from_its_centre_alone(config, centre, tmp_path):
    from mfflap.optimisation.workflow import write_study
    from mfflap.reports.html import Report
    from mfflap.reports.optimisation import add_optimisation_sections
    from mfflap.results import ResultsFile

    messages = []
    study = beta_study(config, betas=[0.0], with_ipopt=False, progress=messages.append,
                       trust_regions={0.0: TrustRegion(centre, 0.05, "a sinusoid")})
    assert [r.start for r in study.sqp_all[0.0]] == [
        "trust-region centre (a sinusoid, radius 0.05)"]
    assert study.trust_regions[0.0].radius == 0.05
    assert study.trust_regions[0.0].step_fraction(study.sqp[0.0].motion) <= 1 + 1e-9
    assert any("beta 0 (trust region 0.05) from trust-region centre" in m for m in messages)
    assert "kept in a trust region about an earlier optimum" in study.thrust_gain_caveat
    with ResultsFile(tmp_path / "r.h5", "w", kind="optimisation") as rf:
        write_study(rf, config, study)
    with ResultsFile(tmp_path / "r.h5") as rf:
        attrs = dict(rf.h5["optimisation/sqp/beta_0.00"].attrs)
    assert attrs["setting_trust_region_radius"] == 0.05
    assert attrs["setting_trust_region_centre"] == "a sinusoid"
    assert attrs["setting_trust_region_step_fraction"] == pytest.approx(1.0, abs=1e-3)
    rep = Report("t", "")
    add_optimisation_sections(rep, study, config.morison_model(), config.optimisation.scheme,
                              config.optimisation.max_power)
    rep.write(tmp_path / "r.html")
    assert ("β = 0 was kept in a trust region of radius 0.05 about a sinusoid (started there "
            "alone): its step is 1.00 of the radius, on the boundary") in (
        tmp_path / "r.html").read_text()
    with pytest.raises(ConfigError, match=r"trust regions for beta \[0.5\]") as err:
        beta_study(config, betas=[0.0], trust_regions={0.5: TrustRegion(centre, 0.1)})
    assert err.value.key == "trust_regions"
