"""Back-tests over several cycles: real coarse-mesh pimpleFoam runs of the trust series'
round 2 optima run for 10 (beta = 0, key f85edc06d9cf46a0) and 8 periods (beta = 0.5, key
34cd2b07c53664ae), shipped in ``cfd_repeatability`` beside the three-period copies of the
beta = 0 one (docs/findings/optimised_motions.md, "How long a back-test runs")."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner
from shipped_settings import as_shipped

from mfflap.backtest.compare import compare_last_cycle
from mfflap.backtest.cycles import cycle_means
from mfflap.cli.main import cli
from mfflap.errors import ConfigError
from mfflap.hydro.morison import MorisonModel
from mfflap.records.record import fixture_dir, read_record

BETA0 = "backtest_f85edc06d9cf46a0"
BETA05 = "backtest_34cd2b07c53664ae"


def _record(name: str):
    rec = read_record(fixture_dir("cfd_repeatability") / f"{name}.h5")
    return rec, float(rec.parameters["period"])


def test_the_last_cycle_mean_is_the_back_tests_own():
    """cycle_means counts cycles back from the end as the back-test counts its last one, and
    bridges the same bursts (three in the ten-period run)."""
    for name in (f"{BETA0}_10_cycles", f"{BETA05}_8_cycles", f"{BETA0}_copy0"):
        rec, period = _record(name)
        means = cycle_means(rec, period)
        last = compare_last_cycle(rec, MorisonModel(), period, 50.0)
        assert means.thrust[-1] == pytest.approx(last.cfd_mean_thrust, rel=1e-12)
        assert means.power[-1] == pytest.approx(last.cfd_mean_power, rel=1e-12)
        # whole cycles after the start-up ramp of half a period, one period apart
        assert means.n_cycles == int(rec.parameters["n_cycles"] - 0.5)
        np.testing.assert_allclose(np.diff(means.start_s), period, rtol=1e-12)
        assert means.start_s[0] >= rec.parameters["ramp_time"]
        assert means.start_s[-1] + period == pytest.approx(rec.time[-1], rel=1e-12)


def test_one_cycle_of_a_long_beta_0_run_is_one_draw_of_a_9_percent_scatter():
    """After its start-up (cycle 2: 20.1 N), the beta = 0 optimum's cycles make 24.7-32.6 N:
    a single cycle's mean scatters by 8.7 % of the mean, where the three copies of the
    three-period run spread 0.7 % (they part only in their third cycle)."""
    rec, period = _record(f"{BETA0}_10_cycles")
    means = cycle_means(rec, period)
    assert means.thrust[0] < 0.85 * means.thrust[1:].min()  # cycle 2 is still start-up
    settled = means.last(8)  # cycles 3-10
    assert settled.thrust.min() < 25.0 and settled.thrust.max() > 32.0
    assert 0.07 < settled.thrust_scatter < 0.10 and 0.07 < settled.power_scatter < 0.10
    assert settled.mean_thrust == pytest.approx(28.66, abs=0.01)
    assert settled.thrust_standard_error == pytest.approx(
        np.std(settled.thrust, ddof=1) / np.sqrt(8), rel=1e-12)
    # the run's last cycle lies four standard errors of the eight-cycle mean above it
    assert (means.thrust[-1] - settled.mean_thrust) / settled.thrust_standard_error > 4
    copies = [cycle_means(*_record(f"{BETA0}_copy{k}")).thrust[-1] for k in range(3)]
    assert np.ptp(copies) / np.mean(copies) < 0.01
    # and the three-period back-test's value lies within the scatter, not within the copies'
    assert abs(copies[0] - settled.mean_thrust) < 2 * np.std(settled.thrust, ddof=1)


def test_a_back_test_averaged_over_cycles_gives_means_and_standard_errors():
    rec, period = _record(f"{BETA0}_10_cycles")
    model = MorisonModel()
    one = compare_last_cycle(rec, model, period, 50.0)
    eight = compare_last_cycle(rec, model, period, 50.0, average_cycles=8)
    settled = cycle_means(rec, period).last(8)
    assert eight.cycles_averaged == 8 and one.cycles_averaged == 1
    assert eight.cfd_mean_thrust == pytest.approx(settled.mean_thrust, rel=1e-12)
    assert eight.cfd_power_standard_error == pytest.approx(settled.power_standard_error)
    # the model is periodic after its ramp: its mean is the same over one cycle or eight
    assert eight.model_mean_thrust == pytest.approx(one.model_mean_thrust, rel=1e-3)
    # the curves and NRMSE stay the last cycle's
    np.testing.assert_array_equal(eight.cfd_thrust, one.cfd_thrust)
    assert eight.nrmse == one.nrmse
    assert np.isnan(one.cfd_thrust_standard_error) and np.isnan(one.cycle_scatter)
    assert eight.cycle_scatter == pytest.approx(max(settled.thrust_scatter,
                                                    settled.power_scatter), rel=1e-9)
    data = eight.as_dict()
    assert data["cycles_averaged"] == 8 and data["cfd_thrust_standard_error"] > 0
    assert one.as_dict()["cfd_thrust_standard_error"] is None  # JSON has no NaN
    json.dumps(one.as_dict())


def test_more_cycles_averaged_than_a_run_holds_is_refused_naming_it():
    rec, period = _record(f"{BETA0}_copy0")
    with pytest.raises(ConfigError, match=f"{BETA0}_copy0.*holds 2 whole cycle") as err:
        compare_last_cycle(rec, MorisonModel(), period, 50.0, average_cycles=3)
    assert err.value.key == "average_cycles"
    with pytest.raises(ConfigError):
        cycle_means(rec, period).last(0)
    with pytest.raises(ConfigError, match="no whole cycle"):
        cycle_means(rec, period, after_s=rec.time[-1] - 0.5 * period)
    with pytest.raises(ConfigError, match="period must be > 0"):
        cycle_means(rec, 0.0)


def test_a_shorter_run_is_not_the_cfd_a_longer_live_run_asks_for():
    from mfflap.backtest.run import _other_set_up

    rec, _ = _record(f"{BETA0}_copy0")
    assert _other_set_up(rec, "coarse", None) is None
    assert _other_set_up(rec, "coarse", None, 2.5) is None  # its cycles hold those asked
    assert _other_set_up(rec, "coarse", None, 10) == "for 3 periods, not 10 as asked"


@pytest.mark.slow
def test_backtest_command_averages_cycles_and_refuses_what_a_run_cannot_hold(
        optimisation_file):
    """On the shipped three-period fixtures: two cycles averaged by default (each a whole
    cycle after the ramp), three not back-tested with the reason; a [backtest] that a live
    run cannot hold refused by its key."""
    res = CliRunner().invoke(cli, ["backtest", str(optimisation_file), "--json"])
    assert res.exit_code == 0, res.output
    motions = json.loads(res.stdout)["motions"]
    for d in motions.values():
        assert d["cycles_averaged"] == 2 and d["cfd_thrust_standard_error"] > 0
    text = CliRunner().invoke(cli, ["backtest", str(optimisation_file)])
    assert text.exit_code == 0 and text.stdout.count("means over the last 2 cycles") == 2
    assert " ± " in text.stdout
    res = CliRunner().invoke(cli, ["backtest", str(optimisation_file), "--set",
                                   "backtest.average_cycles=3"])
    assert res.exit_code == 1 and res.stdout.count("NOT BACK-TESTED") == 2
    assert "holds 2 whole cycle(s)" in res.stdout
    for args, says in ((["--set", "backtest.cycles=10"],
                        "--set backtest.cycles applies only to live runs"),
                       (["--set", "backtest.average_cycles=0"], "backtest.average_cycles"),
                       (["--live", "--set", "backtest.cycles=0.5"], "backtest.cycles"),
                       (["--live", "--set", "backtest.average_cycles=4"],
                        "4 whole cycles need cycles >= 4")):
        res = CliRunner().invoke(cli, ["backtest", str(optimisation_file), *args])
        assert res.exit_code == 2 and says in res.output, (args, res.output)


def test_two_long_copies_agree_in_their_means_though_not_in_their_cycles():
    """Copy 1 (every time step a millionth longer) of the ten-period beta = 0 run: its
    cycles scatter 2.2 %, copy 0's 8.7 % (two low cycles, 24.7 and 26.0 N, then two high,
    31.9 and 32.6 N), and their last cycles lie 11 % apart; yet the means of cycles 3-10,
    28.66 +- 0.93 and 28.67 +- 0.22 N, agree within 0.1 %: the mean over cycles is what
    the motion makes, one cycle is not."""
    zero = cycle_means(*_record(f"{BETA0}_10_cycles")).last(8)
    one = cycle_means(*_record(f"{BETA0}_copy1_10_cycles")).last(8)
    assert one.thrust_scatter < 0.03 < 0.07 < zero.thrust_scatter
    assert abs(zero.thrust[-1] - one.thrust[-1]) / one.mean_thrust > 0.1
    assert abs(zero.mean_thrust - one.mean_thrust) / one.mean_thrust < 1e-3
    assert abs(zero.mean_power - one.mean_power) < np.hypot(zero.power_standard_error,
                                                            one.power_standard_error)
    # up to their second cycle the copies are one run (they part in the vortex shedding)
    first = cycle_means(*_record(f"{BETA0}_10_cycles"))
    again = cycle_means(*_record(f"{BETA0}_copy1_10_cycles"))
    assert first.thrust[0] == pytest.approx(again.thrust[0], rel=1e-3)


@pytest.mark.slow
@pytest.mark.openfoam
def test_a_live_back_test_runs_the_cycles_asked_and_averages_them(tmp_path,
                                                                  optimisation_file):
    """Real pimpleFoam, coarse mesh: the beta = 0.5 optimum (period 0.46 s) for 2.5 periods,
    its two whole cycles after the ramp averaged; the case is named for its periods, the
    record says how many it ran, and the same command takes the saved record."""
    from mfflap.records.record import read_record_parameters

    work, saved = tmp_path / "work", tmp_path / "saved"
    args = ["backtest", str(optimisation_file), "--live", "--motion", "0.5", "--set",
            "backtest.cycles=2", "--work", str(work), "--save-to", str(saved), "--json"]
    res = CliRunner().invoke(cli, args)
    assert res.exit_code == 0, res.output
    d = json.loads(res.stdout)["motions"]["β = 0.5"]
    assert d["source"] == "live OpenFOAM" and d["cycles_averaged"] == 2
    assert d["cfd_thrust_standard_error"] > 0 and d["cfd_power_standard_error"] > 0
    key = d["motion_key"]
    assert (work / f"backtest_{key}_2.5cycles").is_dir()
    assert not (work / f"backtest_{key}").exists()
    assert read_record_parameters(saved / f"backtest_{key}.h5")["n_cycles"] == 2.5
    assert read_record(saved / f"backtest_{key}.h5").name == f"backtest_{key}"
    again = CliRunner().invoke(cli, args)
    assert again.exit_code == 0, again.output
    d2 = json.loads(again.stdout)["motions"]["β = 0.5"]
    assert d2["source"].startswith("live OpenFOAM, run before")
    assert d2["cfd_mean_thrust"] == pytest.approx(d["cfd_mean_thrust"], rel=1e-5)


def test_cfd_cycles_command_gives_each_runs_cycles_and_settled_mean(tmp_path):
    folder = fixture_dir("cfd_repeatability")
    ten, short = folder / f"{BETA0}_10_cycles.h5", folder / f"{BETA0}_copy0.h5"
    figure = tmp_path / "cycles.png"
    res = CliRunner().invoke(cli, ["cfd", "cycles", str(ten), str(short), "--figure",
                                   str(figure), "--json"])
    assert res.exit_code == 0, res.output
    runs = json.loads(res.stdout)["runs"]
    long_run = runs[str(ten)]
    assert long_run["cycle_numbers"] == list(range(2, 11))
    assert long_run["settled"]["mean_thrust"] == pytest.approx(28.66, abs=0.01)
    assert len(long_run["settled"]["cycle_mean_thrust"]) == 8  # cycle 2 left out
    assert runs[str(short)]["settled"]["thrust_standard_error"] is None  # cycle 3 alone
    assert figure.stat().st_size > 10_000
    assert long_run["retries"] is None
    retried = CliRunner().invoke(cli, ["cfd", "cycles", str(folder / f"{BETA05}_8_cycles.h5")])
    assert "retried part-way, so not one set-up throughout" in retried.stdout
    assert "with maxCo 2" in retried.stdout
    text = CliRunner().invoke(cli, ["cfd", "cycles", str(ten), str(short), "--skip-cycles",
                                    "0"])
    assert text.exit_code == 0 and "settled (cycles 2-10)" in text.stdout
    assert "settled (cycles 2-3)" in text.stdout
    one = CliRunner().invoke(cli, ["cfd", "cycles", str(short)])
    assert "cycle 3 alone: no cycle-to-cycle scatter" in one.stdout


def test_the_cycles_figure_names_each_run_by_its_file_in_a_colour_of_its_own():
    """Records of one motion share a name (the ten-period run and the medium-mesh run of
    round 2's beta = 0 optimum): the figure names them by file, each in its own colour."""
    from mfflap.backtest.cycles import cycle_means, cycles_figure, record_period

    paths = sorted(fixture_dir("cfd_repeatability").glob("*_cycles.h5"))
    assert len(paths) > 10
    runs = []
    for path in paths:
        rec = read_record(path)
        every = cycle_means(rec, record_period(rec))
        runs.append((every, every.after(1)))
    assert len({every.record for every, _ in runs}) < len(runs)  # names shared
    fig = cycles_figure(runs, [p.stem for p in paths])
    handles, labels = fig.axes[1].get_legend_handles_labels()
    assert labels == [p.stem for p in paths]
    assert len({tuple(h.get_color()) for h in handles}) == len(paths)


def test_cfd_cycles_refuses_pitch_ramp_runs_and_cycles_skipped_past_the_end():
    ramp = sorted(fixture_dir("table1_coarse").glob("*.h5"))[0]
    res = CliRunner().invoke(cli, ["cfd", "cycles", str(ramp)])
    assert res.exit_code == 2 and "pitch ramp" in res.output and ramp.stem in res.output
    short = fixture_dir("cfd_repeatability") / f"{BETA0}_copy0.h5"
    res = CliRunner().invoke(cli, ["cfd", "cycles", str(short), "--skip-cycles", "2"])
    assert res.exit_code == 2 and "skip_cycles" in res.output and "leave none" in res.output


@pytest.mark.slow
def test_run_and_its_rounds_judge_the_means_over_the_cycles_asked(tmp_path):
    """`mfflap run` of two rounds averaging two cycles on the shipped three-period fixtures:
    round 1's back-tests (the main job's) and the rounds' checks take the means of the last
    two cycles, not the last cycle's; a live run too short for them is refused."""
    from mfflap.records.record import backtest_fixture_dirs

    case = Path(__file__).parents[2] / "cases" / "paper2026.toml"
    out = tmp_path / "loop"
    res = CliRunner().invoke(cli, [
        "run", str(case), "--out", str(out), *as_shipped(
            "--set", "rounds.count=2", "--set", "optimisation.coefficients=uniform",
            "--set", "optimisation.within_data=true", "--set", "rounds.correct_outputs=true",
            "--set", "rounds.refit=false", "--set", "rounds.trust_radius=0.25",
            "--set", "optimisation.ipopt=false", "--set", "optimisation.gain_table=false",
            "--set", "backtest.average_cycles=2"), "--json"])
    assert res.exit_code == 0, res.output
    checks = json.loads(res.stdout[res.stdout.index("{"):])["rounds"]["rounds"][0]["checks"]
    assert checks
    for check in checks.values():
        path = next(f / f"{check['cfd_record']}.h5" for f in backtest_fixture_dirs()
                    if (f / f"{check['cfd_record']}.h5").exists())
        rec = read_record(path)
        means = cycle_means(rec, float(rec.parameters["period"])).last(2)
        assert check["cfd_mean_thrust"] == pytest.approx(means.mean_thrust, rel=1e-9)
        assert check["cfd_mean_power"] == pytest.approx(means.mean_power, rel=1e-9)
        assert check["cfd_mean_thrust"] != pytest.approx(means.thrust[-1], rel=1e-3)
    import h5py

    with h5py.File(out / "round_1" / "results.h5") as f:
        metrics = json.loads(f["backtest/beta__0"].attrs["metrics"])
        assert metrics["cycles_averaged"] == 2 and f["backtest/beta__0"].attrs[
            "cfd_n_cycles"] == 3
    assert "Means over the last 2 whole cycles" in (out / "round_1" / "report.html").read_text()
    for args, says in ((["--set", "backtest.average_cycles=0"], "out of range"),
                       (["--live", "--set", "backtest.cycles=3", "--set",
                         "backtest.average_cycles=4"], "4 whole cycles need cycles >= 4")):
        res = CliRunner().invoke(cli, ["run", str(case), "--out", str(tmp_path / "x"), *args])
        assert res.exit_code == 2 and says in res.output, (args, res.output)
        assert "backtest.average_cycles" in res.output and not (tmp_path / "x").exists()


def test_a_retry_at_half_the_courant_limit_moves_the_beta_05_optimum_by_7_percent():
    """The two eight-period beta = 0.5 runs are not copies: the time step collapsed in both
    (freestream far field) and run_motion's retries left run A at max Co 2 from 6.08 s and
    run B at 4. Cycles 3-8 make 8.52 +- 0.14 N (A) and 9.13 +- 0.10 N (B), 3.5 combined
    standard errors apart (power 6.46 and 6.95 W); the trust series' three-period run, at
    max Co 2 too, read 9.14 N in its cycle 3, four standard errors above A's mean."""
    from mfflap.backtest.repeat import repeatability_of

    a_rec, period = _record(f"{BETA05}_8_cycles")
    b_rec, _ = _record(f"{BETA05}_copy1_8_cycles")
    assert a_rec.provenance["as_run_max_courant"] == 2.0
    assert "with maxCo 2" in a_rec.provenance["retries"]
    assert b_rec.provenance["as_run_max_courant"] == pytest.approx(4.0, rel=1e-5)
    assert "maxCo" not in b_rec.provenance["retries"]
    a = cycle_means(a_rec, period).last(6)
    b = cycle_means(b_rec, period).last(6)
    apart = abs(b.mean_thrust - a.mean_thrust)
    assert apart / np.hypot(a.thrust_standard_error, b.thrust_standard_error) > 3
    assert 0.06 < apart / a.mean_thrust < 0.08
    assert abs(b.mean_power - a.mean_power) / a.mean_power > 0.06
    # both start alike: their second cycles (the last of the start-up) agree within 0.3 %
    assert cycle_means(a_rec, period).thrust[0] == pytest.approx(
        cycle_means(b_rec, period).thrust[0], rel=3e-3)
    three = read_record(fixture_dir("backtest_trust_region") / f"{BETA05}.h5")
    assert three.provenance["as_run_max_courant"] == 2.0
    read = compare_last_cycle(three, MorisonModel(), period, 50.0).cfd_mean_thrust
    assert read == pytest.approx(9.137, abs=1e-3)
    assert (read - a.mean_thrust) / a.thrust_standard_error > 4
    # --repeat's measure over cycles: at beta = 0 (true copies, no retry) 0.05 %, against
    # 11 % between their last cycles
    b0 = [_record(f"{BETA0}_10_cycles")[0], _record(f"{BETA0}_copy1_10_cycles")[0]]
    assert not any(r.provenance.get("retries") for r in b0)
    settled = repeatability_of(b0, "β = 0", MorisonModel(), b0[0].parameters["period"], 50.0,
                               average_cycles=8)
    assert settled.thrust_spread < 1e-3 < 0.1 < repeatability_of(
        b0, "β = 0", MorisonModel(), b0[0].parameters["period"], 50.0).thrust_spread


def test_cycles_are_numbered_by_the_period_they_start_in():
    from mfflap.backtest.cycles import CycleMeans

    period = 0.46
    # a run of 2.5 periods whose written end fell a hair short: starts 0.5 P and 1.5 P less
    # 3e-9 s; one of 3 periods: starts at P and 2P
    half = CycleMeans("x", period, np.array([0.5, 1.5]) * period - 3e-9, np.ones(2),
                      np.ones(2))
    whole = CycleMeans("x", period, np.array([1.0, 2.0]) * period - 3e-9, np.ones(2),
                       np.ones(2))
    assert list(half.numbers) == [1, 2] and list(whole.numbers) == [2, 3]


def test_as_run_differences_name_what_a_retry_changed():
    from mfflap.records.as_run import as_run_differences

    run_a, _ = _record(f"{BETA05}_8_cycles")  # inletOutlet, max Co 2 after its retries
    run_b, _ = _record(f"{BETA05}_copy1_8_cycles")  # inletOutlet, max Co 4.000004
    clean, _ = _record(f"{BETA0}_10_cycles")  # freestream, max Co 4
    copy, _ = _record(f"{BETA0}_copy1_10_cycles")  # max Co 4.000004: a copy, alike
    assert as_run_differences(run_a, run_b) == ["max Co 2 against 4"]
    assert as_run_differences(clean, copy) == []
    assert as_run_differences(clean, run_a) == ["max Co 4 against 2",
                                                "far field freestream against inletOutlet"]
    # a record that does not say is not taken as different
    bare = type(clean)(clean.name, clean.state, clean.loads, clean.parameters, {})
    assert as_run_differences(bare, run_a) == []


def test_the_beta_0_optimum_with_a_retrys_set_up_from_the_start_is_not_resolved_apart():
    """Round 2's beta = 0 optimum run for eight periods with the inletOutlet far field from
    t = 0 s (the far field a retry switches to): its time step collapsed at 10.97 s at max
    Co 4, where the freestream far field ran ten periods through, and it was rerun from
    t = 0 s at max Co 2. Cycles 3-8 of that set-up (27.35 N, 42.1 W) lie 4.6 % (thrust) and
    4-5 % (power) below the freestream copies' 28.66-28.67 N, 1.3 combined standard errors:
    not resolved from the noise, and still climbing (cycles 6-8: 29.2 N). So a retry's
    set-up moves this optimum by less than 5 %, where it moved beta = 0.5 by 7 %
    (docs/findings/optimised_motions.md, "How long a back-test runs")."""
    other, period = _record(f"{BETA0}_inlet_outlet_8_cycles")
    assert other.parameters["motion_key"] == BETA0.removeprefix("backtest_")
    assert other.provenance["solver_far_field"] == "inletOutlet"
    assert other.provenance["retries"] == ("time step collapsed at t = 10.9651 s; resumed "
                                           "from t = 0 s with maxCo 2")
    assert other.provenance["as_run_max_courant"] == 2.0
    settled = cycle_means(other, period).after(1)
    assert list(settled.numbers) == [3, 4, 5, 6, 7, 8]
    assert settled.mean_thrust == pytest.approx(27.35, abs=0.01)
    assert settled.mean_power == pytest.approx(42.09, abs=0.01)
    for copy in (f"{BETA0}_10_cycles", f"{BETA0}_copy1_10_cycles"):
        free = cycle_means(_record(copy)[0], period).after(1)
        assert free.mean_thrust == pytest.approx(28.66, abs=0.02)
        below = 1 - settled.mean_thrust / free.mean_thrust
        assert 0.04 < below < 0.05
        assert 0.04 < 1 - settled.mean_power / free.mean_power < 0.06
        combined = np.hypot(settled.thrust_standard_error, free.thrust_standard_error)
        assert (free.mean_thrust - settled.mean_thrust) / combined < 1.5  # not resolved
    assert settled.last(3).mean_thrust > free.mean_thrust  # still climbing


def test_the_beta_0_optimum_on_the_medium_mesh_reads_the_coarse_meshs_means_over_cycles_3_to_5():
    """Round 2's beta = 0 optimum on the medium mesh (12,880 cells) with the set-up the
    coarse mesh's eight-period run above ended with (inletOutlet far field, max Co 2, from
    t = 0 s), five periods decomposed on two ranks (`[cfd] procs = 2`), with no retry. Over cycles
    3-5 it reads 25.18 N / 38.28 W, 1.2 % and 2.5 % below the coarse mesh's same cycles
    (25.48 N / 39.25 W), a quarter of their combined standard error; cycle by cycle the two
    meshes lie up to 12 % apart, within the coarse mesh's 9 % cycle scatter, and the medium
    mesh scatters less (3.7 %). So the coarse back-tests' means hold on the medium mesh for
    this optimum, as far as three cycles tell (docs/findings/optimised_motions.md, "How long a
    back-test
    runs")."""
    medium, period = _record(f"{BETA0}_medium_5_cycles")
    coarse, _ = _record(f"{BETA0}_inlet_outlet_8_cycles")
    assert medium.parameters["motion_key"] == BETA0.removeprefix("backtest_")
    assert medium.provenance["mesh"] == "medium" and medium.provenance["n_cells"] == 12880
    assert coarse.provenance["mesh"] == "coarse"
    assert medium.provenance["n_processes"] == 2
    assert medium.provenance.get("retries") is None  # one set-up throughout
    for key in ("as_run_far_field", "as_run_max_courant"):
        assert medium.provenance[key] == coarse.provenance[key]
    fine = cycle_means(medium, period).after(1)
    assert list(fine.numbers) == [3, 4, 5]
    assert fine.mean_thrust == pytest.approx(25.18, abs=0.01)
    assert fine.mean_power == pytest.approx(38.28, abs=0.01)
    assert fine.thrust_scatter < 0.04
    both = cycle_means(coarse, period).after(1)
    same = np.isin(both.numbers, [3, 4, 5])
    thrust, power = both.thrust[same].mean(), both.power[same].mean()
    assert thrust == pytest.approx(25.48, abs=0.01) and power == pytest.approx(39.25, abs=0.01)
    assert -0.015 < fine.mean_thrust / thrust - 1 < -0.01
    assert -0.03 < fine.mean_power / power - 1 < -0.02
    combined = np.hypot(fine.thrust_standard_error,
                        both.thrust[same].std(ddof=1) / np.sqrt(same.sum()))
    assert abs(fine.mean_thrust - thrust) / combined < 0.3
    per_cycle = np.abs(fine.thrust / both.thrust[same] - 1)
    assert 0.10 < per_cycle.max() < 0.13 and both.thrust_scatter > 0.09


def test_the_beta_0_optimum_on_the_medium_mesh_reads_the_coarse_meshs_means_over_six_cycles():
    """The same motion and set-up on the medium mesh for eight periods (two ranks, no
    retry): cycles 3-8 read 27.88 N / 43.12 W, 1.9 % and 2.4 % above the coarse mesh's
    eight-period run, 0.4 of their combined standard error. Its cycles 3-5 lie 14 % from
    the five-period medium run's, which differs only in its write times: copies part on
    the medium mesh too. The coarse run's late rise (cycles 6-8) does not come on it
    (docs/findings/optimised_motions.md, "How long a back-test runs")."""
    medium, period = _record(f"{BETA0}_medium_8_cycles")
    five, _ = _record(f"{BETA0}_medium_5_cycles")
    coarse, _ = _record(f"{BETA0}_inlet_outlet_8_cycles")
    assert medium.parameters["motion_key"] == BETA0.removeprefix("backtest_")
    assert medium.parameters["n_cycles"] == 8 and five.parameters["n_cycles"] == 5
    assert medium.provenance["mesh"] == "medium" and medium.provenance["n_cells"] == 12880
    assert medium.provenance["n_processes"] == 2 and medium.provenance.get("retries") is None
    for key in ("as_run_far_field", "as_run_max_courant"):
        assert medium.provenance[key] == coarse.provenance[key] == five.provenance[key]
    fine = cycle_means(medium, period).after(1)
    both = cycle_means(coarse, period).after(1)
    assert list(fine.numbers) == list(both.numbers) == [3, 4, 5, 6, 7, 8]
    assert fine.mean_thrust == pytest.approx(27.88, abs=0.01)
    assert fine.mean_power == pytest.approx(43.12, abs=0.01)
    assert 0.015 < fine.mean_thrust / both.mean_thrust - 1 < 0.02
    assert 0.02 < fine.mean_power / both.mean_power - 1 < 0.025
    combined = np.hypot(fine.thrust_standard_error, both.thrust_standard_error)
    assert abs(fine.mean_thrust - both.mean_thrust) / combined < 0.5
    assert fine.thrust_scatter < both.thrust_scatter
    # the two medium runs' cycles 3-5 part by 14 %
    early = cycle_means(five, period).after(1)
    assert list(early.numbers) == [3, 4, 5]
    assert fine.thrust[:3].mean() / early.mean_thrust - 1 == pytest.approx(0.14, abs=0.005)
    # the coarse run's rise in cycles 6-8 is not the medium mesh's
    assert both.last(3).mean_thrust > both.mean_thrust > fine.last(3).mean_thrust
    per_cycle = np.abs(fine.thrust / both.thrust - 1)
    assert 0.14 < per_cycle.max() < 0.15


def test_procs_applies_only_to_live_runs(optimisation_file):
    res = CliRunner().invoke(cli, ["backtest", str(optimisation_file), "--set", "cfd.procs=2"])
    assert res.exit_code == 2 and "--set cfd.procs applies only to live runs" in res.output
    res = CliRunner().invoke(cli, ["backtest", str(optimisation_file), "--live", "--set",
                                   "cfd.procs=0"])
    assert res.exit_code == 2 and "cfd.procs" in res.output


@pytest.mark.slow
@pytest.mark.openfoam
def test_a_live_back_test_on_two_processes_runs_the_serial_runs_flow(tmp_path,
                                                                     optimisation_file):
    """Real pimpleFoam decomposed on two ranks under mpirun (`[cfd] procs = 2`), coarse mesh: the
    beta = 0.5 optimum for 1.5 periods. Its record says it ran on two processes, and its
    forces follow the shipped serial run of the same motion and set-up (backtest/) within
    1 % NRMSE over that time: the decomposition changes round-off, not the flow, before
    the wake's chaos parts the two runs (docs/findings/optimised_motions.md, 'How long a back-test
    runs')."""
    from mfflap.cfd.openfoam.time_folders import processor_folders
    from mfflap.metrics import nrmse

    work, saved = tmp_path / "work", tmp_path / "saved"
    res = CliRunner().invoke(cli, ["backtest", str(optimisation_file), "--live", "--motion",
                                   "0.5", "--set", "backtest.cycles=1",
                                   "--set", "backtest.average_cycles=1",
                                   # the serial run's set-up
                                   "--set", "cfd.max_courant=4.0",
                                   "--set", 'cfd.far_field="freestream"',
                                   "--set", "cfd.procs=2", "--work",
                                   str(work), "--save-to", str(saved), "--json"])
    assert res.exit_code == 0, res.output
    d = json.loads(res.stdout)["motions"]["β = 0.5"]
    assert d["source"] == "live OpenFOAM"
    key = d["motion_key"]
    assert len(processor_folders(work / f"backtest_{key}_1.5cycles")) == 2
    record = read_record(saved / f"backtest_{key}.h5")
    assert record.provenance["n_processes"] == 2
    serial = read_record(fixture_dir("backtest") / f"backtest_{key}.h5")
    assert "n_processes" not in serial.provenance  # run before the option (serial)
    assert serial.provenance["solver_max_courant"] == record.provenance["solver_max_courant"]
    t = record.loads.time
    for name in ("normal_force", "moment"):
        along = np.interp(t, serial.loads.time, getattr(serial.loads, name))
        assert nrmse(getattr(record.loads, name), along) < 0.01, name


def test_a_back_test_gives_the_cfds_own_repeat_beside_the_models_nrmse(tmp_path):
    """The last cycle of a real run against its cycle before, as an NRMSE over the same
    range as the model's: it is the CFD's last cycle against a copy of itself shifted by
    one period (computed here directly), below the model's error on the beta = 0 optimum
    (16 % against 30 % of thrust: this motion's CFD hardly repeats), and it survives the
    round trip through HDF5."""
    from mfflap.backtest.run import BacktestOutcome
    from mfflap.backtest.store import read_backtests, write_backtests
    from mfflap.metrics import nrmse
    from mfflap.performance import thrust_and_power
    from mfflap.results import ResultsFile

    rec, period = _record(f"{BETA0}_10_cycles")
    c = compare_last_cycle(rec, MorisonModel(), period, 50.0)
    t = rec.time
    last = t >= t[-1] - period
    thrust = thrust_and_power(rec.loads, rec.state)[0]
    direct = nrmse(np.interp(t[last] - period, t, thrust), thrust[last])
    assert c.cfd_repeat_nrmse["thrust"] == pytest.approx(float(direct), rel=1e-2)
    assert 0.0 < c.cfd_repeat_nrmse["thrust"] < c.nrmse["thrust"]
    assert set(c.cfd_repeat_nrmse) == set(c.nrmse)
    path = tmp_path / "backtest.h5"
    with ResultsFile(path, "w", kind="backtest") as rf:
        write_backtests(rf, {"beta 0": BacktestOutcome("beta 0", "k", "ok", "test",
                                                       comparison=c)})
    with ResultsFile(path, "r") as rf:
        back = read_backtests(rf)["beta 0"].comparison
    assert back.cfd_repeat_nrmse == pytest.approx(c.cfd_repeat_nrmse)
