"""CFD in the loop: `mfflap run` with [rounds] count above 1 (mfflap.rounds)."""

from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest
from shipped_settings import SHIPPED_IDENTIFICATION, SHIPPED_SETTINGS

from mfflap.rounds import (
    THRUST_FLOOR,
    MotionCheck,
    RoundSummary,
    motion_checks,
    stop_reason,
)

CASE = Path(__file__).parents[2] / "cases" / "paper2026.toml"


def _outcome(key, cfd_thrust, model_thrust, cfd_power, model_power):
    comparison = SimpleNamespace(
        cfd_mean_thrust=cfd_thrust, model_mean_thrust=model_thrust, cfd_mean_power=cfd_power,
        model_mean_power=model_power,
        mean_thrust_error=(model_thrust - cfd_thrust) / abs(cfd_thrust),
        mean_power_error=(model_power - cfd_power) / abs(cfd_power))
    return SimpleNamespace(key=key, comparison=comparison,
                           record=SimpleNamespace(name=f"backtest_{key}"))


def test_motion_checks_count_thrust_only_where_there_is_thrust_and_only_unseen_motions():
    backtests = {
        "β = 0": _outcome("a", 30.0, 24.0, 50.0, 55.0),  # -20 % thrust, +10 % power
        "β = 1": _outcome("b", -1.0, -2.0, 1.0, 1.05),  # +100 % of almost no thrust
        "β = 0.5": _outcome("c", 10.0, 10.5, 8.0, 6.0),  # +5 % thrust, -25 % power
        "lost": SimpleNamespace(key="d", comparison=None, record=None),
    }
    checks = motion_checks(backtests, in_fit={"backtest_c"})
    assert set(checks) == {"β = 0", "β = 1", "β = 0.5"}
    assert checks["β = 0"].thrust_counted and checks["β = 0"].error == pytest.approx(0.2)
    assert abs(-1.0) < THRUST_FLOOR * 30.0  # below the floor: the thrust error is not counted
    assert not checks["β = 1"].thrust_counted
    assert checks["β = 1"].error == pytest.approx(0.05)  # its power error counts
    assert checks["β = 0.5"].in_fit and not checks["β = 0"].in_fit
    assert checks["β = 0.5"].error == pytest.approx(0.25)
    from mfflap.rounds import RoundSummary

    assert not any(c.cfd_of_neighbour for c in checks.values())
    assert checks["β = 0"].cfd_record == "backtest_a"
    summary = RoundSummary(1, Path("r"), 43, 0, {}, checks)
    # the motion whose CFD was in the fit is not counted: its error is in-sample
    assert summary.largest_error == pytest.approx(0.2)
    assert np.isfinite(summary.as_dict()["largest_error"])


def test_a_motion_checked_on_a_neighbours_cfd_says_so():
    """The back-test look-up takes a record whose motion lies within its tolerance: the
    check names that record, and the round's lines say whose CFD it is."""
    from mfflap.rounds import describe_round

    near = _outcome("a", 30.0, 24.0, 50.0, 55.0)
    near.record = SimpleNamespace(name="backtest_b")  # run for a motion 0.1 % away
    checks = motion_checks({"β = 0": near}, set())
    assert checks["β = 0"].cfd_of_neighbour
    assert checks["β = 0"].as_dict()["cfd_record"] == "backtest_b"
    text = describe_round(RoundSummary(3, Path("r"), 43, 0, {}, checks), 0.1)
    assert "the CFD of backtest_b, a motion within the back-test look-up's tolerance" in text
    assert not MotionCheck("x", "k", 1, 1, 1, 1, 0, 0, True, False).cfd_of_neighbour


def test_the_first_order_slopes_take_a_neighbours_cfd_once_per_beta():
    """A motion checked on its own CFD always gives the secants a point; one checked on a
    neighbour's (as every optimum made with the phase fixed is on the shipped free series'
    records, found shifted in time) gives one only where that record has not given the beta
    a point before: a trust region's short step that reuses an earlier run adds no second
    point with the same CFD."""
    from mfflap.rounds.steps import secant_points

    def check(key: str, record: str) -> MotionCheck:
        return MotionCheck("β = 0", key, 30.0, 25.0, 50.0, 45.0, -0.2, -0.1, True, False,
                           cfd_record=f"backtest_{record}")

    used: dict[float, set[str]] = {}
    rounds = [("a", "a"), ("b", "a"), ("c", "c"), ("c", "c"), ("d", "e"), ("f", "e")]
    kept = [bool(secant_points({0.0: f"point {k}"}, {"β = 0": check(k, r)}, used))
            for k, r in rounds]
    # own CFD: kept, even a repeat (round 3's motion again); a neighbour's: kept once
    assert kept == [True, False, True, True, True, False]
    assert used == {0.0: {"backtest_a", "backtest_c", "backtest_e"}}
    assert secant_points({0.0: "p"}, {"β = 0": check("g", "g")}, used) == {0.0: "p"}


def test_a_corrected_motion_is_checked_by_its_corrected_prediction():
    """Optimised with thrust x 1.25 and power x 1.1, the beta = 0 motion's prediction is the
    model's means times those: 24 N x 1.25 = 30 N is CFD's (0 %), 55 W x 1.1 against 50 W
    is +21 %; the motion without a correction keeps the model's own error."""
    from mfflap.rounds import RoundSummary, correction_points

    backtests = {"β = 0": _outcome("a", 30.0, 24.0, 50.0, 55.0),
                 "β = 0.5": _outcome("c", 10.0, 10.5, 8.0, 6.0)}
    checks = motion_checks(backtests, set(), {"β = 0": (1.25, 1.1)})
    a = checks["β = 0"]
    assert (a.model_mean_thrust, a.predicted_thrust) == (24.0, pytest.approx(30.0))
    assert a.thrust_error == pytest.approx(0.0)
    assert a.power_error == pytest.approx(55 * 1.1 / 50 - 1)
    assert checks["β = 0.5"].thrust_error == pytest.approx(0.05)
    assert (checks["β = 0.5"].thrust_scale, checks["β = 0.5"].power_scale) == (1.0, 1.0)
    assert a.as_dict()["predicted_power"] == pytest.approx(60.5)
    summary = RoundSummary(2, Path("r"), 47, 4, {}, checks, {}, {0.0: {"thrust_scale": 1.25}})
    assert summary.as_dict()["corrections"] == {"0": {"thrust_scale": 1.25}}
    # the next round's correction points: each back-tested optimum with its CFD means
    motion0, motion1 = object(), object()
    study = SimpleNamespace(sqp={0.0: SimpleNamespace(motion=motion0),
                                 0.5: SimpleNamespace(motion=object()),
                                 1.0: SimpleNamespace(motion=motion1)})
    points = correction_points(SimpleNamespace(study=study), checks, 2)
    assert set(points) == {0.0, 0.5}  # beta = 1 was not back-tested
    assert points[0.0].motion is motion0
    assert (points[0.0].cfd_mean_thrust, points[0.0].cfd_mean_power) == (30.0, 50.0)
    assert points[0.0].source == "round 2's beta = 0 (back-test a)"
    assert points[0.0].thrust_usable
    assert correction_points(SimpleNamespace(study=None), checks, 2) == {}


def test_a_prediction_is_made_of_the_optimisers_own_means_where_they_are_known():
    """The scales were measured with the optimiser's discrete means, so the corrected
    prediction multiplies those, not the model's means on the kinematics CFD imposed (the
    paper scheme's energy error is 8-9 % of the beta = 1 optimum's power); at the motion the
    scales were measured on, the prediction is then CFD's own."""
    from mfflap.config import load_case
    from mfflap.kinematics.convert import harmonic_to_discrete
    from mfflap.optimisation.output_correction import CorrectionPoint, OutputCorrection
    from mfflap.performance import discrete_means, evaluate_discrete
    from mfflap.rounds import optimised_means

    config = load_case(CASE)
    model, scheme = config.morison_model(), config.optimisation.scheme
    motion = harmonic_to_discrete(0.3, 0.2, 0.3, 1.5, config.optimisation.n_steps)
    own = discrete_means(model, motion, scheme)
    s = evaluate_discrete(model, motion, scheme).summary
    assert own == (float(s.mean_thrust), float(s.mean_power))
    # CFD 20 % over the optimiser's means; the back-test's model means 3 % off them
    cfd = (1.2 * own[0], 1.2 * own[1])
    backtest = {"β = 0": _outcome("a", cfd[0], 1.03 * own[0], cfd[1], 1.03 * own[1])}
    corr = OutputCorrection.measured(CorrectionPoint(motion, *cfd, "a"), model, scheme)
    scales = {"β = 0": (corr.thrust_scale, corr.power_scale)}
    outcome = SimpleNamespace(model=model, config=None, backtest_motions={"β = 0": motion})
    assert optimised_means(outcome, config) == {"β = 0": own}
    check = motion_checks(backtest, set(), scales, optimised_means(outcome, config))["β = 0"]
    assert (check.predicted_thrust, check.predicted_power) == (pytest.approx(cfd[0]),
                                                               pytest.approx(cfd[1]))
    assert check.thrust_error == pytest.approx(0.0, abs=1e-12)
    assert check.as_dict()["optimised_mean_power"] == pytest.approx(own[1])
    # without them, the back-test's model means stand in (3 % high here)
    stand_in = motion_checks(backtest, set(), scales)["β = 0"]
    assert stand_in.power_error == pytest.approx(0.03, rel=1e-9)
    assert stand_in.as_dict()["optimised_mean_power"] is None
    assert optimised_means(SimpleNamespace(model=None), config) == {}


def _round(k, error, not_backtested=None, corrections=None):
    check = MotionCheck("β = 0", "a", 30.0, 30.0 * (1 + error), 50.0, 50.0 * (1 + error),
                        error, error, True, False)
    return RoundSummary(k, Path("."), 43, 0, {}, {"β = 0": check}, not_backtested or {},
                        corrections or {})


def test_the_rounds_stop_for_the_first_reason_that_holds():
    done = SimpleNamespace(interrupted=None, identification={"uniform": 1}, study=object())
    assert stop_reason(_round(2, 0.2), done, {"b"}, {"a"}, 0.1) is None  # go on
    # converged: every unseen motion within the tolerance
    converged, why = stop_reason(_round(2, 0.08), done, {"b"}, {"a"}, 0.1)
    assert converged and why == ("round 2: the model predicts every back-tested motion's CFD "
                                 "mean thrust and power within 10% (largest 8.0%)")
    assert "the corrected model" in stop_reason(
        _round(2, 0.08, corrections={0.0: {}}), done, {"b"}, set(), 0.1)[1]
    # a fixed point: the motions of earlier rounds, unless a filter still moves the scales
    converged, why = stop_reason(_round(3, 0.2), done, {"a", "b"}, {"a", "b", "c"}, 0.1)
    assert not converged and why.startswith("round 3 optimised the motions of an earlier")
    assert why.endswith("would fit the same data")
    assert stop_reason(_round(3, 0.2), done, {"a"}, {"a"}, 0.1,
                       corrected=True)[1].endswith("and measure the same corrections")
    assert stop_reason(_round(3, 0.2), done, {"a"}, {"a"}, 0.1, corrected=True,
                       filtered=True) is None
    # a motion without CFD comes before convergence; live it does not suggest --live
    no_cfd = _round(2, 0.05, not_backtested={"β = 1": "no CFD fixture\nmore"})
    converged, why = stop_reason(no_cfd, done, {"b"}, set(), 0.1)
    assert not converged
    assert why == ("round 2: β = 1 was not back-tested (no CFD fixture\nmore); the next round "
                   "would not learn where the model is wrong (--live runs its CFD in OpenFOAM)")
    assert stop_reason(no_cfd, done, {"b"}, set(), 0.1, live=True)[1].endswith("is wrong")
    failed = SimpleNamespace(interrupted=None, identification={}, study=None)
    assert "identification or optimisation failed" in stop_reason(
        _round(2, 0.05), failed, set(), set(), 0.1)[1]
    stopped = SimpleNamespace(interrupted="back-test", identification={}, study=None)
    assert stop_reason(_round(2, 0.05), stopped, set(), set(), 0.1) == (
        False, "round 2 was stopped (Ctrl-C) in its back-test stage")


@pytest.mark.slow
def test_a_stop_in_a_round_ends_the_rounds_and_keeps_what_was_done(tmp_path):
    """Ctrl-C in round 2's back-test: round 2 is written with the stages before it, round 1's
    records stay in loop_records for the next call, and the rounds say where they stopped."""
    from mfflap.config import load_case
    from mfflap.pipeline import RunOptions
    from mfflap.rounds import run_rounds

    def progress(message: str) -> None:
        if message == "[round 2] [back-test] started":
            raise KeyboardInterrupt

    from mfflap.records.record import fixture_dir

    options = RunOptions(fixtures=(fixture_dir(SHIPPED_IDENTIFICATION),),
                         coefficients="identified:uniform", within_data=True,
                         with_ipopt=False, sensitivity=False, work_dir=tmp_path / "cases")
    out = tmp_path / "loop"
    # the settings the shipped back-tests of round 1 were optimised with
    result, outcome = run_rounds(load_case(CASE, SHIPPED_SETTINGS), options, 3, 0.1, out,
                                 progress=progress)
    assert [r.index for r in result.rounds] == [1, 2]
    assert outcome.interrupted is not None and not outcome.backtests
    assert result.stopped_because.startswith("round 2 was stopped (Ctrl-C)")
    assert not result.converged
    assert (out / "round_2" / "results.h5").is_file() and (out / "rounds.h5").is_file()
    assert len(list((out / "loop_records").glob("*.h5"))) == 4  # round 1's, for the next call


def test_a_step_within_cfds_noise_does_not_keep_the_rounds_from_converging():
    from mfflap.optimisation.trust_region import TrustStep

    done = SimpleNamespace(interrupted=None, identification={"uniform": 1}, study=object())
    refused = _round(3, 0.05)
    # predicted to gain 0.3 where CFD's noise is 0.8, CFD found -0.04: not a refusal
    refused.trust_steps = {0.0: TrustStep(0.0, 0.25, "c", 0.03, False, -0.04, 0.3, -0.13,
                                          False, 0.004)}
    assert stop_reason(refused, done, {"b"}, {"a"}, 0.1, bounded=True) is None  # goes on
    refused.trust_steps = {0.0: TrustStep(0.0, 0.25, "c", 0.03, False, -0.04, 0.3, 0.69,
                                          True, 0.25, noise=0.8)}
    converged, why = stop_reason(refused, done, {"b"}, {"a"}, 0.1, bounded=True)
    assert converged and why.endswith("or predicted to gain less than CFD's noise")


def _step(beta, on_boundary, next_radius=0.25):
    from mfflap.optimisation.trust_region import TrustStep

    return TrustStep(beta, 0.25, "round 1's beta = 0", 1.0 if on_boundary else 0.4,
                     on_boundary, 1.0, 1.2, 0.83, True, next_radius)


def test_rounds_in_trust_regions_converge_only_inside_them_and_stop_when_one_collapses():
    done = SimpleNamespace(interrupted=None, identification={"uniform": 1}, study=object())
    inside = _round(3, 0.05)
    inside.trust_steps = {0.0: _step(0.0, False)}
    converged, why = stop_reason(inside, done, {"b"}, {"a"}, 0.1, bounded=True)
    assert converged and why.endswith("(largest 5.0%) with every optimum inside its trust "
                                      "region and its step confirmed by CFD")
    # inside, but CFD rejected the step: its centre, not the optimum, is the answer so far
    from dataclasses import replace as replaced

    refused = _round(3, 0.05)
    refused.trust_steps = {0.0: replaced(_step(0.0, False), ratio=-0.1, accepted=False)}
    assert stop_reason(refused, done, {"b"}, {"a"}, 0.1, bounded=True) is None
    # within the tolerance, but an optimum is on its boundary: the model wants to go on
    edge = _round(3, 0.05)
    edge.trust_steps = {0.0: _step(0.0, True), 0.5: _step(0.5, False)}
    assert stop_reason(edge, done, {"b"}, {"a"}, 0.1, bounded=True) is None
    # a repeated motion is no fixed point: the radius still moves
    assert stop_reason(edge, done, {"a"}, {"a"}, 0.1, bounded=True) is None
    # ... unless no optimum left its centre
    from mfflap.optimisation.trust_region import TrustStep

    still = _round(3, 0.2)
    still.trust_steps = {0.0: TrustStep(0.0, 0.25, "c", 0.0, False, 0.0, 0.0, float("nan"),
                                        True, 0.25)}
    converged, why = stop_reason(still, done, {"a"}, {"a"}, 0.1, bounded=True)
    assert not converged and why.startswith("round 3 optimised the motions of an earlier")
    collapsed = _round(4, 0.3)
    collapsed.trust_steps = {0.5: _step(0.5, True, next_radius=4e-4)}
    converged, why = stop_reason(collapsed, done, {"c"}, {"a"}, 0.1, bounded=True)
    assert not converged and why.startswith("round 4: the trust region of beta 0.5 "
                                            "collapsed (radius below 0.001)")
    assert collapsed.as_dict()["trust_steps"]["0.5"]["next_radius"] == 4e-4


def test_a_rounds_step_is_judged_by_the_objective_with_each_motions_own_cfd_means():
    """Predicted: J of the round's corrected problem at the centre and at the optimum. CFD:
    J with the model's outputs scaled to each motion's own CFD means; a power that CFD finds
    over the model's is penalised there beyond P_max."""
    from mfflap.config import load_case
    from mfflap.kinematics.convert import harmonic_to_discrete
    from mfflap.optimisation.output_correction import CorrectionPoint, OutputCorrection
    from mfflap.optimisation.study import problem_for
    from mfflap.optimisation.trust_region import TrustRegion
    from mfflap.performance import evaluate_discrete
    from mfflap.rounds import trust_steps

    config = load_case(CASE)
    model, n = config.morison_model(), config.optimisation.n_steps
    scheme = config.optimisation.scheme
    centre = harmonic_to_discrete(0.6, 0.3, 0.5, 1.5, n)
    optimum = harmonic_to_discrete(0.62, 0.31, 0.5, 1.5, n)
    own = evaluate_discrete(model, optimum, scheme).summary
    cfd_t, cfd_p = 1.2 * float(own.mean_thrust), 1.5 * float(own.mean_power)
    checks = motion_checks({"β = 0": _outcome("u", cfd_t, float(own.mean_thrust), cfd_p,
                                              float(own.mean_power))}, set(),
                           {"β = 0": (1.1, 1.2)})
    at_centre = CorrectionPoint(centre, 11.0, 31.0, "c")
    correction = OutputCorrection.measured(at_centre, model, scheme)
    outcome = SimpleNamespace(
        study=SimpleNamespace(sqp={0.0: SimpleNamespace(motion=optimum),
                                   0.5: SimpleNamespace(motion=centre)}),
        model=model, config=None, corrections={0.0: correction})
    region = TrustRegion(centre, 0.25, "round 1's beta = 0")
    steps = trust_steps(outcome, checks, {0.0: region, 0.5: TrustRegion(centre, 0.25)},
                        {0.0: at_centre, 0.5: None}, config)
    assert set(steps) == {0.0}  # beta = 0.5 was not back-tested
    base = problem_for(config, 0.0, model)
    # beta = 0: J = -kappa_T mean thrust + penalties, so c = kappa_T
    predicted = [correction.thrust_scale * float(correction.problem(base).objective(m))
                 for m in (centre, optimum)]
    at_optimum = OutputCorrection.measured(CorrectionPoint(optimum, cfd_t, cfd_p, "u"), model,
                                           scheme)
    assert (at_optimum.thrust_scale, at_optimum.power_scale) == (pytest.approx(1.2),
                                                                 pytest.approx(1.5))
    measured = [correction.thrust_scale * float(correction.problem(base).objective(centre)),
                1.2 * float(at_optimum.problem(base).objective(optimum))]
    step = steps[0.0]
    assert step.predicted_decrease == pytest.approx(predicted[0] - predicted[1])
    assert step.cfd_decrease == pytest.approx(measured[0] - measured[1])
    # at the centre, corrected there, the predicted J is CFD's
    assert predicted[0] == pytest.approx(measured[0])
    # J with the CFD means: -1.2 T and the penalties and smoothing, which are positive
    assert measured[1] > -1.2 * float(own.mean_thrust)
    assert step.step_fraction == pytest.approx(region.step_fraction(optimum))
    assert step.centre == "round 1's beta = 0"


def test_the_rounds_files_keep_the_trust_regions_steps(tmp_path):
    import json

    import h5py

    from mfflap.config import load_case
    from mfflap.reports.rounds import write_rounds
    from mfflap.rounds import LoopResult

    first, second = _round(1, 0.3), _round(2, 0.12)
    second.trust_steps = {0.0: _step(0.0, True)}
    result = LoopResult([first, second], 0.1, False, "ran the 2 round(s) asked for",
                        correct_outputs=True, refit=False, trust_radius=0.25,
                        answers={0.0: "round 1's beta = 0 (back-test a): CFD mean thrust 30 N"})
    write_rounds(result, load_case(CASE), tmp_path)
    with h5py.File(tmp_path / "rounds.h5") as f:
        assert f.attrs["trust_radius"] == 0.25 and not f.attrs["refit"]
        kept = json.loads(f["rounds/round_2"].attrs["summary"])["trust_steps"]["0"]
        assert kept["on_boundary"] and kept["ratio"] == pytest.approx(0.83)
        assert json.loads(f["rounds/round_1"].attrs["summary"])["trust_steps"] == {}
    html = (tmp_path / "rounds.html").read_text()
    assert "keeps each optimum in a trust region (first radius 0.25)" in html
    assert "Trust-region steps" in html and "<td>0.83</td>" in html
    assert "β = 0: round 1&#x27;s beta = 0 (back-test a): CFD mean thrust 30 N." in html
    assert (tmp_path / "rounds.png").stat().st_size > 0
    unbounded = LoopResult([first], 0.1, False, "x")
    write_rounds(unbounded, load_case(CASE), tmp_path)
    with h5py.File(tmp_path / "rounds.h5") as f:
        assert np.isnan(f.attrs["trust_radius"])
    assert "Trust-region steps" not in (tmp_path / "rounds.html").read_text()



