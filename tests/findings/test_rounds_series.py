"""Replays of the shipped series of rounds (`mfflap run --rounds N` on the shipped
fixtures, each round's optima back-tested in real OpenFOAM when the series was measured):
each checks the numbers docs/findings/optimised_motions.md and docs/findings/phase_of_optima.md
give for its series, round by round.

They test shipped research data, not code, and take 2-6 minutes each: the replay tier,
``pytest --replays``, runs them (see docs/development.md). The series with a free phase
follow steps that round-off steers (docs/findings/known_limits.md), so they find their
shipped CFD where OpenBLAS runs what they were computed with: its SkylakeX kernels on
two threads (``OPENBLAS_CORETYPE=SkylakeX OPENBLAS_NUM_THREADS=2``); the series with the
phase fixed find theirs on any kernels.
"""

import json
from pathlib import Path

import pytest
from click.testing import CliRunner
from rounds_series import fixed_phase_series
from shipped_settings import as_shipped

from mfflap.cli.main import cli

pytestmark = [pytest.mark.findings, pytest.mark.replay]

CASE = Path(__file__).parents[2] / "cases" / "paper2026.toml"


def _series(out, n_rounds, *flags):
    """`mfflap run` of the shipped case in ``n_rounds`` rounds of the series the shipped
    back-tests were run for (identified coefficients, kept within the data, no IPOPT or
    gain table) with ``flags``: the result and its JSON summary."""

    res = CliRunner().invoke(cli, ["run", str(CASE), "--out", str(out), *as_shipped(
        "--set", f"rounds.count={n_rounds}", "--set", "optimisation.coefficients=uniform",
        "--set", "optimisation.within_data=true", *flags, "--set", "optimisation.ipopt=false",
        "--set", "optimisation.gain_table=false"), "--json"])
    assert res.exit_code == 0, res.output
    return res, json.loads(res.stdout[res.stdout.index("{"):])


def _against_one_set_up(check: dict) -> tuple[float, float]:
    """The relative errors of a round's prediction for a motion (thrust, power) against
    eight periods of one set-up of that motion (cycles 3-8; shipped in cfd_repeatability for
    the four beta = 0 optima whose compared cycle mixes two set-ups)."""
    from mfflap.backtest.cycles import cycle_means
    from mfflap.records.record import fixture_dir, read_record

    eight = read_record(fixture_dir("cfd_repeatability")
                        / f"backtest_{check['key']}_from_start_8_cycles.h5")
    settled = cycle_means(eight, float(eight.parameters["period"])).after(1)
    return (check["predicted_thrust"] / settled.mean_thrust - 1,
            check["predicted_power"] / settled.mean_power - 1)


@pytest.mark.shipped_kernels
def test_rounds_refit_on_their_back_tests_and_stop_when_a_motion_has_no_cfd(tmp_path):
    """`mfflap run --rounds 4` on the shipped fixtures: round 1 is the main job with the
    identified coefficients kept within the data (its back-tests ship in
    backtest_within_data); rounds 2 and 3 fit with the back-tests of the rounds before
    pooled in (their records kept in loop_records) and optimise other motions, back-tested
    in real OpenFOAM (backtest_rounds); their errors are measured on motions their fits have
    not seen. Round 4's motions have no CFD here, so the rounds stop there and say why. What
    docs/findings/optimised_motions.md says of it: the refit moves the coefficients but not the
    model's error on its
    new optima (beta = 0 about -18 % thrust, -20 % power in every round)."""

    import h5py

    from mfflap.results import ResultsFile

    out = tmp_path / "loop"
    _, summary = _series(out, 4)
    loop = summary["rounds"]
    rounds = loop["rounds"]
    assert [r["round"] for r in rounds] == [1, 2, 3, 4]
    assert [r["n_cases"] for r in rounds] == [43, 47, 50, 53]
    assert [r["loop_records_in_fit"] for r in rounds] == [0, 4, 7, 10]
    first, second, third = rounds[0], rounds[1], rounds[2]
    # the refit moves the coefficients (the back-tests weigh as frequencies of their own)
    assert second["coefficients"]["tangential_added_mass"] < \
        0.8 * first["coefficients"]["tangential_added_mass"]
    assert set(first["checks"]) == set(second["checks"]) == {"best sinusoid", "β = 0",
                                                            "β = 0.5", "β = 1"}
    assert not any(c["in_fit"] for c in first["checks"].values())
    # the best sinusoid is round 1's (its CFD in round 2's fit, not counted); the optima new
    assert second["checks"]["best sinusoid"]["in_fit"]
    assert second["checks"]["best sinusoid"]["key"] == first["checks"]["best sinusoid"]["key"]
    for label in ("β = 0", "β = 0.5", "β = 1"):
        assert not second["checks"][label]["in_fit"]
        assert second["checks"][label]["key"] != first["checks"][label]["key"]
    assert second["largest_error"] == pytest.approx(max(
        c["error"] for c in second["checks"].values() if not c["in_fit"]))
    assert set(third["checks"]) == set(second["checks"])
    assert {c["key"] for c in third["checks"].values() if not c["in_fit"]}.isdisjoint(
        c["key"] for c in second["checks"].values())
    assert not loop["converged"] and second["largest_error"] > loop["tolerance"]
    for r in (first, second, third):  # the refit does not close the beta = 0 gap
        assert -0.25 < r["checks"]["β = 0"]["thrust_error"] < -0.1
        assert -0.25 < r["checks"]["β = 0"]["power_error"] < -0.1
    assert third["coefficients"]["tangential_drag"] > first["coefficients"]["tangential_drag"]
    assert rounds[3]["not_backtested"]
    assert loop["stopped_because"].startswith("round 4: ")
    assert "was not back-tested" in loop["stopped_because"]
    assert loop["stopped_because"].endswith("(--live runs its CFD in OpenFOAM)")
    assert summary["last_round"]["backtest"]  # the last round's own summary
    # one record per motion: round 1's four, rounds 2 and 3's three new ones each
    assert len(list((out / "loop_records").glob("backtest_*.h5"))) == 10
    for k in (1, 2, 3, 4):
        assert (out / f"round_{k}" / "report.html").is_file()
    with ResultsFile(out / "rounds.h5", kinds=("rounds",)) as rf:
        assert "residual_scaling" in rf.config_toml
    with h5py.File(out / "rounds.h5") as f:
        thrust = f["rounds/round_2/cfd_mean_thrust"][()]
        labels = json.loads(f["rounds/round_2"].attrs["labels"])
        assert f["rounds/round_2/cfd_mean_thrust"].attrs["units"] == "N"
    assert thrust[labels.index("β = 0")] == pytest.approx(
        second["checks"]["β = 0"]["cfd_mean_thrust"])
    # read back as a study's results: every round, in order, with its numbers
    import mfflap

    back = mfflap.open_results(out / "rounds.h5")
    assert back.kind == "rounds" and [r.index for r in back.rounds] == [1, 2, 3, 4]
    assert back.rounds[1].labels == labels
    assert back.rounds[1].values["cfd_mean_thrust"] == pytest.approx(thrust)
    assert back.config.rounds.count == 4
    assert (out / "rounds.png").stat().st_size > 10_000
    assert "Not converged: round 4: " in (out / "rounds.html").read_text()


def test_corrected_rounds_predict_their_new_optima_far_better(tmp_path):
    """`mfflap run --rounds 6 --correct-outputs --loop-tolerance 0.05` on the shipped
    fixtures: round 1 is the plain loop's; from round 2 on each beta is optimised with the
    outputs scaled to round k - 1's CFD of that beta (rounds 2-5 back-tested in real
    OpenFOAM, backtest_corrected). The corrected predictions of rounds 2 and 3's new optima
    come within 1.4-13.3 % where the model alone was 16-49 % off (round 2 within the default
    tolerance of 10 %: 6.1 %), and beta = 0 then holds a mean power below P_max in CFD,
    which round 1's optimum did not; rounds 4 and 5 widen again, beta = 0 predicted low,
    then high (docs/findings/optimised_motions.md, "Output correction"). Round 6's motions have no
    CFD here,
    so the rounds stop there."""

    import h5py

    out = tmp_path / "loop"
    res, summary = _series(out, 6, "--set", "rounds.correct_outputs=true", "--set",
                           "rounds.tolerance=0.05")
    loop = summary["rounds"]
    rounds = loop["rounds"]
    assert [r["round"] for r in rounds] == [1, 2, 3, 4, 5, 6]
    assert 0.05 < rounds[1]["largest_error"] < 0.1  # the default tolerance stops there
    first, second = rounds[0], rounds[1]
    assert first["corrections"] == {}
    assert set(second["corrections"]) == {"0", "0.5", "1"}
    for beta, label in (("0", "β = 0"), ("0.5", "β = 0.5"), ("1", "β = 1")):
        corr = second["corrections"][beta]
        before = first["checks"][label]
        # measured on round 1's back-test of that beta, with round 2's refitted model
        assert corr["source"] == f"round 1's beta = {beta} (back-test {before['key']})"
        assert corr["cfd_mean_thrust"] == pytest.approx(before["cfd_mean_thrust"])
        assert corr["thrust_scale"] == pytest.approx(
            corr["cfd_mean_thrust"] / corr["model_mean_thrust"])
        assert corr["power_scale"] == pytest.approx(
            corr["cfd_mean_power"] / corr["model_mean_power"])
        check = second["checks"][label]
        assert (check["thrust_scale"], check["power_scale"]) == (
            pytest.approx(corr["thrust_scale"]), pytest.approx(corr["power_scale"]))
        # the prediction: the scale times the optimiser's own mean, which the scale was
        # measured with (the back-test's model mean differs by the discretisation)
        assert check["predicted_thrust"] == pytest.approx(
            corr["thrust_scale"] * check["optimised_mean_thrust"])
        assert check["optimised_mean_thrust"] == pytest.approx(check["model_mean_thrust"],
                                                               rel=0.03)
        assert not check["in_fit"]
    # the model alone was 16-49 % off round 1's optima; corrected, rounds 2 and 3 come
    # within 1.4-13.3 % ...
    assert first["largest_error"] > 0.45
    for r in rounds[1:3]:
        assert r["largest_error"] < 0.2
        assert abs(r["checks"]["β = 0"]["thrust_error"]) < 0.1
        assert abs(r["checks"]["β = 0"]["power_error"]) < 0.1
        assert abs(r["checks"]["β = 0.5"]["power_error"]) < 0.13
        # the corrected power limit: beta = 0's CFD mean power under P_max = 50 W
        assert r["checks"]["β = 0"]["cfd_mean_power"] < 45.0
    assert first["checks"]["β = 0"]["cfd_mean_power"] > 50.0
    # ... but the rounds do not converge: the optima of rounds 4 and 5 move to where the
    # ratio of CFD to model differs again, beta = 0 predicted low (-14 %), then high (+16 %)
    for r in rounds[3:5]:
        assert max(rounds[1]["largest_error"], rounds[2]["largest_error"]) < \
            r["largest_error"] < first["largest_error"]
    assert rounds[3]["checks"]["β = 0"]["thrust_error"] < -0.05
    assert rounds[4]["checks"]["β = 0"]["thrust_error"] > 0.05
    # round 1's and round 4's beta = 0 back-tests compare a cycle that mixes two set-ups:
    # over eight periods of one set-up round 1's model is 10-12 % low, not 16-18 %, and
    # round 4's correction within 3 %, not 14 % (docs/findings/optimised_motions.md, "Retries and
    # one
    # set-up")
    assert all(-0.12 < e < -0.10 for e in _against_one_set_up(first["checks"]["β = 0"]))
    assert all(abs(e) < 0.03 for e in _against_one_set_up(rounds[3]["checks"]["β = 0"]))
    assert not loop["converged"]
    assert second["checks"]["best sinusoid"]["thrust_scale"] == 1.0  # not corrected
    assert rounds[5]["not_backtested"]
    assert loop["stopped_because"].startswith("round 6: ")
    assert summary["last_round"]["output_corrections"]["0"]["source"].startswith(
        "round 5's beta = 0")
    with h5py.File(out / "round_2" / "results.h5") as f:
        attrs = f["optimisation/sqp/beta_0.00"].attrs
        assert attrs["beta"] == 0.0
        assert attrs["setting_output_thrust_scale"] == pytest.approx(
            second["corrections"]["0"]["thrust_scale"])
    with h5py.File(out / "rounds.h5") as f:
        g = f["rounds/round_2"]
        labels = json.loads(g.attrs["labels"])
        i = labels.index("β = 0")
        assert g["predicted_power"][i] == pytest.approx(
            g["power_scale"][i] * g["optimised_mean_power"][i])
    # `mfflap backtest` of a round's results compares with the coefficients it optimised with
    res = CliRunner().invoke(cli, ["backtest", str(out / "round_2" / "results.h5"), "--json"])
    assert res.exit_code == 0, res.output
    again = json.loads(res.stdout[res.stdout.index("{"):])["motions"]["β = 0"]
    assert again["model_mean_thrust"] == pytest.approx(
        second["checks"]["β = 0"]["model_mean_thrust"], rel=1e-9)
    assert again["corrected_prediction"]["mean_thrust"] == pytest.approx(
        second["checks"]["β = 0"]["predicted_thrust"], rel=1e-9)
    res = CliRunner().invoke(cli, ["backtest", str(out / "round_2" / "results.h5"),
                                   "--motion", "0.5"])
    assert res.exit_code == 0, res.output
    assert "optimised with corrected outputs (thrust x " in res.stdout
    html = (out / "rounds.html").read_text()
    assert "output correction (thrust, power)" in html
    assert "corrected from CFD" in (out / "round_2" / "report.html").read_text().replace(
        "&#x27;", "'")


def test_rounds_without_a_refit_keep_round_ones_model_and_filter_its_correction(tmp_path):
    """`--rounds 6 --correct-outputs --no-refit --correction-gain 0.5` on the shipped
    fixtures (rounds 2-5 back-tested in real OpenFOAM, backtest_fixed_model): every round
    fits the identification data alone (round 1's coefficients, no back-test pooled in), so
    round 2's correction measured on round 1's optima is CFD's mean over round 1's own
    model mean (1 / (1 + error)), the filter taking half of the way from 1 to it. The errors
    keep their sign and shrink for three rounds as the scales climb; in round 5 the beta = 0
    optimum moves (its corrected power limit tighter) to a motion where the ratio of CFD to
    the model is another, and is 15-17 % high (docs/findings/optimised_motions.md, "Filtered output
    correction"). Round 6's motions have no CFD here."""
    import itertools

    import h5py

    out = tmp_path / "loop"
    res, summary = _series(out, 6, "--set", "rounds.correct_outputs=true", "--set",
                           "rounds.refit=false", "--set", "rounds.correction_gain=0.5")
    loop = summary["rounds"]
    rounds = loop["rounds"]
    first, second = rounds[:2]
    assert [r["round"] for r in rounds] == [1, 2, 3, 4, 5, 6]
    assert loop["refit"] is False and loop["correction_gain"] == 0.5
    for r in rounds[1:]:
        assert r["loop_records_in_fit"] == 0 and r["n_cases"] == first["n_cases"]
        assert r["coefficients"] == first["coefficients"]
        assert not r["checks"].get("best sinusoid", {}).get("in_fit", False)  # counted
    assert "(nothing refitted: the coefficients of round 1)" in res.stderr
    for beta, label in (("0", "β = 0"), ("0.5", "β = 0.5")):
        corr, before = second["corrections"][beta], first["checks"][label]
        # the same model on the same motion: the correction's model mean is round 1's
        # optimiser's (the discrete motion, what the scale multiplies), the back-test's is
        # the model on the kinematics CFD imposed; they differ by the discretisation only
        assert corr["model_mean_thrust"] == pytest.approx(before["model_mean_thrust"],
                                                          rel=0.03)
        assert corr["model_mean_power"] == pytest.approx(before["model_mean_power"],
                                                         rel=0.03)
        measured = corr["cfd_mean_thrust"] / corr["model_mean_thrust"]
        assert measured == pytest.approx(1 / (1 + before["thrust_error"]), rel=0.03)
        assert corr["cfd_mean_thrust"] == before["cfd_mean_thrust"]
        assert corr["measured_scales"][0] == pytest.approx(measured, rel=1e-12)
        assert corr["previous_scales"] == [1.0, 1.0] and corr["gain"] == 0.5
        assert corr["thrust_scale"] == pytest.approx(0.5 + 0.5 * measured, rel=1e-12)
        assert corr["power_scale"] == pytest.approx(
            0.5 + 0.5 * corr["cfd_mean_power"] / corr["model_mean_power"], rel=1e-12)
    # round 1's own optimiser gave the discrete means the correction was measured with
    from mfflap.optimisation.store import read_result
    from mfflap.results import ResultsFile

    with ResultsFile(out / "round_1" / "results.h5") as rf:
        optimum = read_result(rf, "optimisation/sqp/beta_0.00")
    assert float(optimum.summary.mean_thrust) == pytest.approx(
        second["corrections"]["0"]["model_mean_thrust"], rel=1e-9)
    assert "filter gain 0.5 from 1.000, 1.000 towards" in res.stderr
    # rounds 2-4: one sign, shrinking, the scales climbing towards the measured ratios
    for r in rounds[1:4]:
        for label in ("β = 0", "β = 0.5"):
            assert r["checks"][label]["thrust_error"] < 0
    beta_half = [-r["checks"]["β = 0.5"]["thrust_error"] for r in rounds[1:4]]
    assert beta_half[0] > beta_half[1] > beta_half[2] > 0  # 33.3, 22.7, 10.0 %
    # round 2's beta = 0 back-test compares a cycle that mixes two set-ups: over eight
    # periods of one set-up the prediction is within 4 %, not 11 % low
    assert second["checks"]["β = 0"]["thrust_error"] < -0.11
    assert all(abs(e) < 0.04 for e in _against_one_set_up(second["checks"]["β = 0"]))
    largest = [r["largest_error"] for r in rounds[:4]]
    assert largest[0] > largest[1] > largest[2] > largest[3] > 0.1  # beta = 1's power
    scales = [r["corrections"]["0"]["thrust_scale"] for r in rounds[1:]]
    assert all(b > a for a, b in itertools.pairwise(scales[:4]))  # 1.10 ... 1.30
    assert scales[4] < scales[3]  # measured on round 5's optimum: the ratio fell
    # round 5: beta = 0 moved where the corrected model is high
    assert rounds[4]["checks"]["β = 0"]["thrust_error"] > 0.15
    assert abs(rounds[4]["checks"]["β = 0.5"]["thrust_error"]) < 0.05
    assert rounds[5]["not_backtested"] and not loop["converged"]
    assert loop["stopped_because"].startswith("round 6: ")
    with h5py.File(out / "rounds.h5") as f:
        assert f.attrs["refit"] == 0 and f.attrs["correction_gain"] == 0.5
    assert "keeps round 1&#x27;s coefficients, corrects its outputs" in (
        out / "rounds.html").read_text()


def test_filtered_corrected_rounds_close_in_then_part_again_with_the_refit(tmp_path):
    """`mfflap run --rounds 7 --correct-outputs --correction-gain 0.5` on the shipped
    fixtures (rounds 2-6 back-tested in real OpenFOAM, backtest_filtered): each round's
    scales move half of the way from those of the round before to the measured ones. The
    largest counted error falls round by round to 12.9 % in round 5, with beta = 0 within
    3.5 % in rounds 4 and 5 (the undamped rounds: 6-27 %, signs alternating); then the
    refit, its tangential added mass driven to zero, moves round 6's optima where the
    corrected model is 15-25 % high (docs/findings/optimised_motions.md, "Filtered output
    correction")."""
    import itertools

    out = tmp_path / "loop"
    _, summary = _series(out, 7, "--set", "rounds.correct_outputs=true", "--set",
                         "rounds.correction_gain=0.5")
    loop = summary["rounds"]
    rounds = loop["rounds"]
    assert [r["round"] for r in rounds] == [1, 2, 3, 4, 5, 6, 7]
    assert loop["correction_gain"] == 0.5 and loop["refit"] is True
    for before, now in itertools.pairwise(rounds):
        for beta, label in (("0", "β = 0"), ("0.5", "β = 0.5"), ("1", "β = 1")):
            corr, check = now["corrections"][beta], before["checks"][label]
            # the filter moves from the scales the previous optimum was optimised with
            assert corr["previous_scales"] == [pytest.approx(check["thrust_scale"]),
                                               pytest.approx(check["power_scale"])]
            for i, name in enumerate(("thrust_scale", "power_scale")):
                assert corr[name] == pytest.approx(
                    0.5 * corr["previous_scales"][i] + 0.5 * corr["measured_scales"][i],
                    rel=1e-12)
            assert corr["measured_scales"][1] == pytest.approx(
                corr["cfd_mean_power"] / corr["model_mean_power"])
    largest = [r["largest_error"] for r in rounds[:6]]
    assert all(b < a for a, b in itertools.pairwise(largest[:5]))
    assert largest[0] > 0.45 and 0.12 < largest[4] < 0.14  # 49.2 % ... 12.9 %
    # round 3's beta = 0 back-test compares a cycle that mixes two set-ups: over eight
    # periods of one set-up the prediction is within 2.5 %, not 16-18 % low
    assert rounds[2]["checks"]["β = 0"]["thrust_error"] < -0.15
    assert all(abs(e) < 0.025 for e in _against_one_set_up(rounds[2]["checks"]["β = 0"]))
    for r in rounds[3:5]:  # beta = 0 within 3.5 % in rounds 4 and 5
        assert abs(r["checks"]["β = 0"]["thrust_error"]) < 0.035
        assert abs(r["checks"]["β = 0"]["power_error"]) < 0.035
        assert r["checks"]["β = 0"]["cfd_mean_power"] < 45.0  # P_max = 50 W held in CFD
    sixth = rounds[5]
    assert sixth["coefficients"]["tangential_added_mass"] < 0.01  # driven to zero
    assert sixth["largest_error"] > 0.2 and sixth["checks"]["β = 0"]["power_error"] > 0.2
    assert not loop["converged"] and rounds[6]["not_backtested"]
    assert loop["stopped_because"].startswith("round 7: ")


def test_rounds_in_a_trust_region_take_the_steps_cfd_confirms_until_one_collapses(tmp_path):
    """`--rounds 6 --correct-outputs --no-refit --trust-region 0.25` on the shipped fixtures
    (rounds 2-5 back-tested in real OpenFOAM, backtest_trust_region): round 2's bounded steps
    are all confirmed by CFD (beta = 0 gives up thrust to come back under P_max, predicted
    within 3 %, its decrease of J confirmed with a ratio of 1.00); in round 3 CFD refuses the
    steps of beta = 0 and 0.5 although every prediction is within 10 %, so the rounds go on
    about the same centres with the radius cut to half the step; beta = 1's optimum stays at
    its centre (no step), predicted within 1 %; in round 5 beta = 0's radius collapses:
    CFD confirms no step of the corrected model about round 2's optimum
    (docs/findings/optimised_motions.md,
    "Trust region")."""

    import h5py

    out = tmp_path / "loop"
    res, summary = _series(out, 6, "--set", "rounds.correct_outputs=true", "--set",
                           "rounds.refit=false", "--set", "rounds.trust_radius=0.25")
    loop = summary["rounds"]
    rounds = loop["rounds"]
    assert [r["round"] for r in rounds] == [1, 2, 3, 4, 5]
    assert loop["trust_radius"] == 0.25 and not loop["converged"]
    assert loop["stopped_because"].startswith("round 5: the trust region of beta 0 collapsed")
    # the rounds' answer: the last motion of each beta CFD confirmed
    assert loop["answers"]["0"].startswith("round 2's beta = 0 (back-test")
    assert loop["answers"]["0.5"].startswith("round 4's beta = 0.5 (back-test")
    assert "beta 0's last motion CFD confirmed: round 2's beta = 0" in res.stderr
    assert rounds[0]["trust_steps"] == {}
    for r in rounds[1:]:
        assert set(r["trust_steps"]) == {"0", "0.5", "1"}
        for step in r["trust_steps"].values():
            assert step["step_fraction"] <= 1 + 1e-6
    second, third, fourth, fifth = rounds[1:]
    # round 2: every step confirmed; beta = 0 predicted within 3 %, its J decrease by CFD's
    assert all(t["accepted"] for t in second["trust_steps"].values())
    assert float(second["trust_steps"]["0"]["ratio"]) == pytest.approx(1.0, abs=0.01)
    assert second["trust_steps"]["1"]["on_boundary"]
    assert second["trust_steps"]["1"]["next_radius"] == 0.5  # doubled
    # the runs round 2 compares were retried differently (docs/findings/optimised_motions.md, "How
    # long a
    # back-test runs"): the centres' with the inletOutlet far field (beta = 0) and at max Co 4
    # (beta = 0.5), the optima's with the freestream one and at max Co 2; round 3's alike.
    # beta = 0's centre was resumed with the inletOutlet far field a quarter into its last
    # cycle (docs/findings/optimised_motions.md, "Retries and one set-up"): that cycle mixes two
    # set-ups
    assert second["trust_steps"]["0"]["ran_otherwise"] == [
        "far field inletOutlet against freestream",
        "the centre's compared cycles mix two set-ups (its settings changed at t = 3.896 s, "
        "after t = 3.464 s)"]
    assert second["trust_steps"]["0.5"]["ran_otherwise"] == ["max Co 4 against 2"]
    assert second["trust_steps"]["1"]["ran_otherwise"] == []
    assert "did not run alike (centre against optimum: max Co 4 against 2)" in res.stderr
    assert all(t["ran_otherwise"] == [] for t in third["trust_steps"].values())
    html = (out / "rounds.html").read_text()
    assert "max Co 4 against 2" in html and "did not run alike" in html
    b0 = second["checks"]["β = 0"]
    assert abs(b0["thrust_error"]) < 0.03 and abs(b0["power_error"]) < 0.03
    assert b0["cfd_mean_power"] < 45.0 < rounds[0]["checks"]["β = 0"]["cfd_mean_power"]
    assert 0.13 < second["largest_error"] < 0.14  # beta = 0.5 (unbounded, --no-refit: 40 %)
    # round 3: within 10 %, but CFD refuses beta = 0 and 0.5's steps: not converged
    assert third["largest_error"] < 0.1
    for beta in ("0", "0.5"):
        step = third["trust_steps"][beta]
        assert not step["accepted"] and float(step["ratio"]) < 0
        assert not step["on_boundary"]
        assert step["next_radius"] == pytest.approx(0.5 * step["step_fraction"] * 0.25)
    assert third["trust_steps"]["1"]["step_fraction"] < 1e-3  # no step, centre kept
    assert abs(third["checks"]["β = 1"]["power_error"]) < 0.01
    # round 4 is optimised about the same centres, the corrections measured there
    assert fourth["corrections"]["0"]["source"].startswith("round 2's beta = 0")
    # beta = 0's shorter steps find round 3's run within the look-up's tolerance, and say so
    assert not third["checks"]["β = 0"]["cfd_of_neighbour"]
    for r in (fourth, fifth):
        assert r["checks"]["β = 0"]["cfd_of_neighbour"]
        assert r["checks"]["β = 0"]["cfd_record"] == f"backtest_{third['checks']['β = 0']['key']}"
    assert fourth["trust_steps"]["0.5"]["accepted"]
    assert abs(fourth["checks"]["β = 0.5"]["thrust_error"]) < 0.02
    assert fifth["corrections"]["0.5"]["source"].startswith("round 4's beta = 0.5")
    assert fifth["trust_steps"]["0"]["next_radius"] < 1e-3
    with h5py.File(out / "rounds.h5") as f:
        assert f.attrs["trust_radius"] == 0.25
    with h5py.File(out / "round_3" / "results.h5") as f:
        attrs = f["optimisation/sqp/beta_0.00"].attrs
        assert attrs["setting_trust_region_radius"] == 0.25
        assert attrs["setting_trust_region_centre"].startswith("round 2's beta = 0")
    html = (out / "rounds.html").read_text()
    assert "Trust-region steps" in html and "no step" in html and "rejected" in html


def test_first_order_rounds_predict_gains_on_the_boxs_faces_that_cfd_refuses(tmp_path):
    """`--rounds 5 --correct-outputs --no-refit --trust-region 0.25 --first-order` on the
    shipped fixtures (rounds 3-5 back-tested in real OpenFOAM, backtest_first_order; rounds
    1-2 are the trust series'): from round 3 on the corrected objective meets CFD's at the
    earlier motions near the centre, but each optimum goes to a face of the box where the
    slope's share makes most of the predicted decrease, and CFD refuses every step of
    beta = 0 and 0.5 while predicting their means within 10 % in rounds 3-4
    (docs/findings/optimised_motions.md, "First-order corrections")."""

    import h5py

    out = tmp_path / "loop"
    _, summary = _series(out, 5, "--set", "rounds.correct_outputs=true", "--set",
                         "rounds.refit=false", "--set", "rounds.trust_radius=0.25", "--set",
                         "rounds.first_order=true")
    loop = summary["rounds"]
    rounds = loop["rounds"]
    assert loop["first_order"] and not loop["converged"]
    assert [r["round"] for r in rounds] == [1, 2, 3, 4, 5]
    assert loop["stopped_because"] == "ran the 5 round(s) asked for"
    assert 0.49 < rounds[0]["largest_error"] < 0.5 and 0.13 < rounds[1]["largest_error"] < 0.14
    # round 2: no earlier motion near, a zero slope: the trust series' round
    for corr in rounds[1]["corrections"].values():
        assert corr["slopes"]["sources"] == [] and corr["slopes"]["scaled_norm"] == 0.0
    assert all(t["accepted"] for t in rounds[1]["trust_steps"].values())
    n_secants = []
    for r in rounds[2:]:
        n_secants.append([len(r["corrections"][b]["slopes"]["sources"]) for b in ("0", "0.5")])
        for beta in ("0", "0.5"):
            step = r["trust_steps"][beta]
            assert not step["accepted"] and step["on_boundary"]
            assert step["predicted_decrease"] > 0 > step["cfd_decrease"] or (
                step["cfd_decrease"] < 0.1 * step["predicted_decrease"])
        assert r["trust_steps"]["1"]["step_fraction"] < 1e-3  # beta = 1: no step
    assert n_secants == [[1, 1], [2, 2], [1, 2]]  # within two radii of the centre
    third, fourth, fifth = rounds[2:]
    assert third["largest_error"] < 0.1 and fourth["largest_error"] < 0.1
    assert fifth["largest_error"] > 0.1  # beta = 0.5, 17 %
    # rounds 3-4: the slope's term makes the whole predicted decrease (beta = 0: 59.5 and
    # 45.8); the scales' part alone foretells what CFD finds (a rise of J: 3.20 and 2.40
    # against CFD's 3.19 and 2.53)
    assert third["trust_steps"]["0"]["predicted_decrease"] > 50
    for k, r in ((3, third), (4, fourth)):
        with h5py.File(out / f"round_{k}" / "results.h5") as f:
            for beta, key in (("0", "beta_0.00"), ("0.5", "beta_0.50")):
                attrs = f[f"optimisation/sqp/{key}"].attrs
                shift = attrs["setting_output_objective_shift"]
                step = r["trust_steps"][beta]
                assert shift < -step["predicted_decrease"] < 0
                assert abs(step["predicted_decrease"] + shift - step["cfd_decrease"]) < (
                    0.15 * abs(shift))
                if beta == "0":
                    assert abs(shift) > 5 * abs(step["cfd_decrease"])
    with h5py.File(out / "round_3" / "results.h5") as f:
        attrs = f["optimisation/sqp/beta_0.00"].attrs
        assert attrs["setting_output_objective_slope"].shape == (101,)
        kept = json.loads(attrs["setting_output_correction"])["slopes"]
        assert kept["sources"][0].startswith("round 1's beta = 0")
    for beta in ("0", "0.5"):  # the answer: round 2's optimum, the last step CFD confirmed
        assert loop["answers"][beta].startswith(f"round 2's beta = {beta} (back-test")
    with h5py.File(out / "rounds.h5") as f:
        assert f.attrs["first_order"]
    assert "a slope that makes it CFD" in (out / "rounds.html").read_text()


def test_first_order_rounds_with_the_phase_fixed_take_slopes_through_shifted_records(tmp_path):
    """The first-order series with `--fix-phase` on the shipped fixtures: rounds 1-2 find the
    free series' records shifted in time, and the secants take each once per beta
    (mfflap.rounds.steps.secant_points), so from round 3 on its optima leave the free
    series' and are back-tested on their own runs (real OpenFOAM,
    backtest_first_order_fixed_phase). CFD refuses rounds 3 and 4's steps of beta = 0 and
    0.5 and confirms round 5's, at a quarter of the first radius; beta = 1 keeps its
    centre from round 3 on (docs/findings/phase_of_optima.md)."""
    out = tmp_path / "loop"
    _, summary = _series(out, 5, "--set", "rounds.correct_outputs=true", "--set",
                         "rounds.refit=false", "--set", "rounds.trust_radius=0.25", "--set",
                         "rounds.first_order=true", "--set", "optimisation.phase=fixed")
    loop = summary["rounds"]
    rounds = loop["rounds"]
    assert [r["round"] for r in rounds] == [1, 2, 3, 4, 5]
    assert loop["stopped_because"] == "ran the 5 round(s) asked for"
    for r in rounds[:2]:  # the free series' runs, found shifted
        assert all(c["cfd_of_neighbour"] for c in r["checks"].values()
                   if c["label"] != "best sinusoid")
    own = {"backtest_5329c3324f32e161", "backtest_5e9d900e669b668f",
           "backtest_ac4de2b2334065d7", "backtest_548f9c5cc3aa25be",
           "backtest_ec8f26d2a076fb37", "backtest_1bbea7efd9e4e35b"}
    seen = {r["checks"][label]["cfd_record"] for r in rounds[2:] for label in ("β = 0",
                                                                               "β = 0.5")}
    assert seen == own
    third, fourth, fifth = rounds[2:]
    for beta in ("0", "0.5"):
        assert third["corrections"][beta]["slopes"]["sources"]  # slopes through round 1-2
        assert not third["trust_steps"][beta]["accepted"]
        assert not fourth["trust_steps"][beta]["accepted"]
        assert fifth["trust_steps"][beta]["accepted"]
        assert fifth["trust_steps"][beta]["radius"] == pytest.approx(0.0625)
    assert all(r["trust_steps"]["1"]["step_fraction"] < 1e-3 for r in rounds[2:])


def test_trust_region_rounds_that_know_cfds_noise_converge_in_round_3(tmp_path):
    """The trust series with `--cfd-repeatability 0.03` (two runs of one motion differ by
    2.8 % of the mean thrust, tests/backtest/test_repeat.py): round 3's steps, which CFD
    refused without it, were predicted to gain less than CFD's noise (beta = 0: 0.31 of J
    against 0.84), so they settle nothing and refuse nothing, and the rounds converge with
    every prediction within 10 % (docs/findings/optimised_motions.md, "First-order corrections")."""
    import h5py

    out = tmp_path / "loop"
    res, summary = _series(out, 6, "--set", "rounds.correct_outputs=true", "--set",
                           "rounds.refit=false", "--set", "rounds.trust_radius=0.25", "--set",
                           "rounds.cfd_repeatability=0.03")
    loop = summary["rounds"]
    assert loop["converged"] and loop["cfd_repeatability"] == 0.03
    assert [r["round"] for r in loop["rounds"]] == [1, 2, 3]
    assert loop["stopped_because"].endswith("or predicted to gain less than CFD's noise")
    second, third = loop["rounds"][1:]
    assert second["trust_steps"]["0"]["accepted"] and not second["trust_steps"]["0"][
        "within_noise"]  # 493 of J, far above the noise
    assert second["trust_steps"]["0.5"]["within_noise"]  # 0.011 predicted, noise 0.23
    assert third["largest_error"] < 0.1
    b0 = third["trust_steps"]["0"]
    assert b0["within_noise"] and 0.8 < b0["noise"] < 0.9 and b0["predicted_decrease"] < 0.4
    assert b0["cfd_decrease"] < 0  # what refused it without the noise
    assert "CFD's noise 0.837" in res.stderr
    with h5py.File(out / "rounds.h5") as f:
        assert f.attrs["cfd_repeatability"] == 0.03
    assert "counts CFD&#x27;s noise (3.0% of the means" in (out / "rounds.html").read_text()
    # the repeatability of round 2's beta = 0 optimum, from its three shipped copies (taken,
    # not run again: `--repeat` finds them in --save-to)
    import shutil

    from mfflap.records.record import fixture_dir

    # the optima whose shipped copies the repeats take (on other OpenBLAS kernels beta =
    # 0.5's comes out within the look-up's tolerance of it, and its copies are taken as its
    # back-test was): checked first, so that other optima fail here instead of running their
    # copies in OpenFOAM (--live) for twenty minutes
    assert second["checks"]["β = 0"]["cfd_record"].startswith("backtest_f85edc06d9cf46a0")
    assert second["checks"]["β = 0.5"]["cfd_record"].startswith("backtest_34cd2b07c53664ae")
    saved = tmp_path / "copies"
    shutil.copytree(fixture_dir("cfd_repeatability"), saved)
    rep = CliRunner().invoke(cli, ["backtest", str(out / "round_2" / "results.h5"), "--live",
                                   "--repeat", "3", "--motion", "0", "--save-to", str(saved),
                                   "--work", str(tmp_path / "w"), "--json"])
    assert rep.exit_code == 0, rep.output
    assert rep.stderr.count("taken from") == 3 and "pimpleFoam" not in rep.stderr
    found = json.loads(rep.stdout[rep.stdout.index("{"):])["repeatability"]["β = 0"]
    assert found["motion_key"] == "f85edc06d9cf46a0" and len(found["mean_thrust"]) == 3
    assert found["mean_thrust"][0] == pytest.approx(27.894, abs=1e-3)  # the series' own run
    # copies 1 and 2 (every time step a millionth longer, two millionths) part from copy 0:
    # thrust 27.89, 28.05, 28.09 N, power 43.69, 43.76, 44.08 W
    assert 0.005 < found["thrust_spread"] < 0.01 and 0.005 < found["power_spread"] < 0.012
    assert found["alike"] is True and found["ran_otherwise"] == []
    # beta = 0.5's two eight-period runs as copies 0 and 1: a retry left copy 0 at max Co 2,
    # so their 7 % is no repeatability, and none is suggested (docs/findings/optimised_motions.md,
    # "Retries
    # and one set-up")
    for k, name in enumerate(("backtest_34cd2b07c53664ae_8_cycles",
                              "backtest_34cd2b07c53664ae_copy1_8_cycles")):
        shutil.copy(saved / f"{name}.h5", saved / f"backtest_34cd2b07c53664ae_copy{k}.h5")
    rep = CliRunner().invoke(cli, ["backtest", str(out / "round_2" / "results.h5"), "--live",
                                   "--repeat", "2", "--motion", "0.5", "--save-to", str(saved),
                                   "--work", str(tmp_path / "w"), "--cycles", "8",
                                   "--set", "backtest.average_cycles=6"])
    assert rep.exit_code == 0, rep.output
    assert rep.stderr.count("taken from") == 2 and "pimpleFoam" not in rep.stderr
    assert ("not a repeatability: the runs did not run alike (backtest_34cd2b07c53664ae_copy1:"
            " max Co 2 against 4)") in rep.stdout
    assert "CFD's repeatability: not measured: no motion's runs ran alike" in rep.stdout
    assert "--cfd-repeatability" not in rep.stdout


def test_the_first_order_series_with_a_fixed_phase_asks_for_the_same_cfd_on_one_thread(
        tmp_path):
    """The first-order series (`--trust-region 0.25 --first-order`) with --fix-phase on one
    OpenBLAS thread and whatever kernels OpenBLAS picks: every motion of its five rounds
    finds the record the shipped series found (the free series' records
    shifted in rounds 1-2, for beta = 0 and 0.5 its own runs of
    backtest_first_order_fixed_phase in rounds 3-5), and CFD refuses and confirms the same
    steps. Its secants run through those records, so the CFD it needs does not turn on the
    CPU it runs on."""
    loop, _ = fixed_phase_series(tmp_path / "loop", 5, "--set", "rounds.trust_radius=0.25", "--set",
                                 "rounds.first_order=true")
    rounds = loop["rounds"]
    assert loop["stopped_because"] == "ran the 5 round(s) asked for"
    shipped = [("598a5388e592df63", "c91660e722b01742", "fb22156550965a86"),
               ("f85edc06d9cf46a0", "34cd2b07c53664ae", "1a923f3083e54ac4"),
               ("5329c3324f32e161", "5e9d900e669b668f", "1a923f3083e54ac4"),
               ("ac4de2b2334065d7", "548f9c5cc3aa25be", "1a923f3083e54ac4"),
               ("ec8f26d2a076fb37", "1bbea7efd9e4e35b", "1a923f3083e54ac4")]
    assert [tuple(r["checks"][f"β = {b}"]["cfd_record"].removeprefix("backtest_")
                  for b in ("0", "0.5", "1")) for r in rounds] == shipped
    accepted = [{beta: step["accepted"] for beta, step in r["trust_steps"].items()
                 if beta != "1"} for r in rounds[2:]]
    assert accepted == [{"0": False, "0.5": False}, {"0": False, "0.5": False},
                        {"0": True, "0.5": True}]
