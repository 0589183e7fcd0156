"""The [backtest], [rounds] and [harmonic_set] tables, the [optimisation] keys of the main
job and ``--set`` (mfflap.study_tables, mfflap.config.apply_settings)."""

import itertools
import math
from pathlib import Path

import pytest
from click.testing import CliRunner

from mfflap.campaign.cases import harmonic_set_cases
from mfflap.cli.main import cli
from mfflap.config import CaseConfig, apply_settings, load_case
from mfflap.errors import ConfigError
from mfflap.pipeline import RunOptions
from mfflap.rounds import check_rounds
from mfflap.study_tables import BacktestSettings, HarmonicSet, RoundsSettings

CASE = Path(__file__).parents[1] / "cases" / "paper2026.toml"


def test_the_main_job_optimises_with_identified_coefficients_and_a_fixed_phase():
    config = CaseConfig()
    assert config.optimisation.coefficients == "uniform"
    assert config.optimisation.phase == "fixed"
    assert config.identification.residual_scaling == "auto"
    options = RunOptions.for_case(config, Path("out"))
    assert options.coefficients == "identified:uniform"
    assert options.work_dir == Path("out/cfd_cases") and options.vtk_dir == Path("out/vtk")


def test_a_back_test_runs_three_periods_after_its_ramp_and_averages_the_last_two():
    backtest = BacktestSettings()
    assert (backtest.cycles, backtest.average_cycles) == (3.0, 2)
    assert backtest.simulated_periods == 3.5
    options = RunOptions.for_case(CaseConfig(), Path("out"))
    assert (options.backtest_cycles, options.average_cycles) == (3.5, 2)
    assert options.retries_from_start


@pytest.mark.parametrize(("kwargs", "key"), [
    ({"average_cycles": 3, "cycles": 2.0}, "backtest.average_cycles"),
    ({"average_cycles": 0}, "backtest.average_cycles"),
    ({"cycles": 0.5}, "backtest.cycles"),
])
def test_a_back_test_that_cannot_hold_its_averaged_cycles_is_refused(kwargs, key):
    with pytest.raises(ConfigError) as err:
        BacktestSettings(**kwargs)
    assert err.value.key.startswith(key)


@pytest.mark.parametrize(("kwargs", "key"), [
    ({"count": 0}, "rounds.count"),
    ({"count": 2, "tolerance": 0.0}, "rounds.tolerance"),
    ({"count": 2, "tolerance": 1.0}, "rounds.tolerance"),
    ({"count": 2, "tolerance": float("nan")}, "rounds.tolerance"),
    ({"trust_radius": 0.25}, "rounds.trust_radius"),  # one round: nothing to bound
    ({"correct_outputs": True}, "rounds.correct_outputs"),
    ({"count": 2, "refit": False}, "rounds.refit"),  # nothing would learn
    ({"count": 2, "correction_gain": 0.5}, "rounds.correction_gain"),  # no correction
    ({"count": 2, "correct_outputs": True, "correction_gain": 0.0}, "rounds.correction_gain"),
    ({"count": 2, "correct_outputs": True, "trust_radius": 3.0}, "rounds.trust_radius"),
    ({"count": 2, "correct_outputs": True, "cfd_repeatability": 0.03},
     "rounds.cfd_repeatability"),
    ({"count": 2, "correct_outputs": True, "trust_radius": 0.25, "cfd_repeatability": 1.0},
     "rounds.cfd_repeatability"),
    ({"count": 2, "first_order": True, "correct_outputs": True}, "rounds.first_order"),
    ({"count": 2, "first_order": True, "trust_radius": 0.25}, "rounds.first_order"),
    ({"count": 2, "first_order": True, "correct_outputs": True, "trust_radius": 0.25,
      "correction_gain": 0.5}, "rounds.first_order"),
])
def test_rounds_that_cannot_run_or_learn_are_refused_naming_the_key(kwargs, key):
    with pytest.raises(ConfigError) as err:
        RoundsSettings(**kwargs)
    assert err.value.key.startswith(key)


def test_rounds_learn_by_a_refit_an_output_correction_or_both():
    assert RoundsSettings(count=3).refit
    RoundsSettings(count=3, correct_outputs=True, refit=False, trust_radius=0.25,
                   first_order=True, cfd_repeatability=0.03)
    assert check_rounds(3, 0.1, "identified:uniform").count == 3
    check_rounds(3, 0.1, "case", correct_outputs=True)
    with pytest.raises(ConfigError, match="every round would optimise the same motions") as err:
        check_rounds(3, 0.1, "case")
    assert err.value.key == "rounds.count"


def test_rounds_with_the_case_files_coefficients_and_no_correction_are_refused(tmp_path):
    case = tmp_path / "c.toml"
    case.write_text('[study]\nname = "c"\n[optimisation]\ncoefficients = "case"\n'
                    "[rounds]\ncount = 2\n")
    with pytest.raises(ConfigError) as err:
        load_case(case)
    assert err.value.key == "rounds.count" and str(case) in str(err.value)


def test_set_overrides_a_key_as_toml_reads_it_and_a_bare_word_as_text():
    data = {"optimisation": {"betas": [0.0]}}
    out = apply_settings(data, ["optimisation.betas=[0.5, 1]", "optimisation.coefficients=case",
                                "rounds.count=3", "model.coefficients.normal_drag=2.5",
                                "backtest.retries_from_start=false"])
    assert out["optimisation"] == {"betas": [0.5, 1], "coefficients": "case"}
    assert out["rounds"] == {"count": 3} and out["backtest"] == {"retries_from_start": False}
    assert out["model"]["coefficients"]["normal_drag"] == 2.5
    assert data == {"optimisation": {"betas": [0.0]}}  # the file's mapping is left as read


@pytest.mark.parametrize(("setting", "says"), [
    ("rounds.count", "is not table.key=value"),
    ("count=3", "is not table.key=value"),
    ("rounds.=3", "is not table.key=value"),
    ("study.name.x=1", "study.name is a value, not a table"),
])
def test_a_malformed_setting_is_refused_naming_it(setting, says):
    with pytest.raises(ConfigError, match=says) as err:
        apply_settings({"study": {"name": "c"}}, [setting])
    assert err.value.source == "--set"


@pytest.mark.parametrize(("setting", "key"), [
    ("rounds.trust_radius=0.25", "rounds.trust_radius"),
    ("rounds.count=2", "rounds.count"),  # with the case's coefficients below
    ("optimisation.coefficients=identified", "optimisation.coefficients"),
    ("backtest.retries_from_start=1", "backtest.retries_from_start"),
    ("rounds.counts=2", "rounds.counts"),
    ("optimisation.starts=0", "optimisation.starts"),
    ("roundz.count=2", "roundz"),
])
def test_the_cli_refuses_an_impossible_setting_before_anything_is_written(tmp_path, setting,
                                                                          key):
    out = tmp_path / "run"
    res = CliRunner().invoke(cli, ["run", str(CASE), "--out", str(out), "--set",
                                   "optimisation.coefficients=case", "--set", setting])
    assert res.exit_code == 2, res.output
    assert key in res.output and "--set" in res.output and str(CASE) in res.output
    assert "Traceback" not in res.output and not out.exists()


def test_case_show_marks_what_set_gives_as_given(tmp_path):
    res = CliRunner().invoke(cli, ["case", "show", str(CASE), "--set", "rounds.count=3",
                                   "--set", "rounds.correct_outputs=true"])
    assert res.exit_code == 0, res.output
    lines = res.output.splitlines()
    count = next(line for line in lines if line.startswith("count = "))
    assert count.startswith("count = 3  #") and "(default)" not in count
    tolerance = next(line for line in lines if line.startswith("tolerance = "))
    assert "(default)" in tolerance


def test_run_help_fits_one_screen_and_every_command_has_at_most_ten_options():
    import click

    res = CliRunner().invoke(cli, ["run", "--help"], terminal_width=100)
    assert res.exit_code == 0 and len(res.output.splitlines()) <= 40, res.output

    def commands(group, name):
        for sub_name, sub in group.commands.items():
            if isinstance(sub, click.Group):
                yield from commands(sub, f"{name} {sub_name}")
            else:
                yield f"{name} {sub_name}", sub

    for name, command in commands(cli, "mfflap"):
        if name.split()[1] in ("run", "optimise", "case", "init", "evaluate", "gradcheck"):
            options = [p for p in command.params if isinstance(p, click.Option)]
            assert len(options) <= 10, (name, [o.name for o in options])


def test_a_case_without_a_set_up_runs_the_wall_treatment_valid_at_the_plates_y_plus():
    from mfflap.cfd.openfoam.setups import case_mesh_and_solver
    from mfflap.study_tables import CfdSettings

    _, solver = case_mesh_and_solver(CfdSettings())
    assert solver.wall_treatment == "all_y_plus"
    _, solver = case_mesh_and_solver(CfdSettings(wall_treatment="log_law"))
    assert solver.wall_treatment == "log_law"
    # a named set-up keeps the wall treatment it was measured with
    _, solver = case_mesh_and_solver(CfdSettings(setup="affordable"))
    assert solver.wall_treatment == "log_law"
    assert CfdSettings().retries_from_start


@pytest.mark.parametrize(("settings", "key"), [
    ({"max_courant": float("nan")}, "cfd.max_courant"),
    ({"max_courant": 1e9}, "cfd.max_courant"),
    ({"writes": 1_000_000_000}, "cfd.writes"),
    ({"timeout_s": -5.0}, "cfd.timeout_s"),
    ({"far_field": "outlet"}, "cfd.far_field"),
    ({"procs": 0}, "cfd.procs"),
])
def test_an_impossible_cfd_setting_is_refused_by_its_key(settings, key):
    from mfflap.study_tables import CfdSettings

    with pytest.raises(ConfigError) as err:
        CfdSettings(**settings)
    assert err.value.key.startswith(key)


def test_the_harmonic_set_spans_each_axis_at_every_frequency_and_pitch_amplitude():
    hs = HarmonicSet()
    motions = hs.motions()
    assert len(motions) >= 30 and len(set(motions)) == len(motions)
    for f, theta in itertools.product(hs.frequencies, hs.pitch_amplitudes_deg):
        runs = [(h, phi) for f_, h, th, phi in motions if (f_, th) == (f, theta)]
        assert sorted(h for h, _ in runs) == sorted(hs.heave_amplitudes)
        assert sorted(phi for _, phi in runs) == sorted(hs.phases_deg)
    # the set reaches the pitch rates of optimised motions (15 rad/s), the grid does not
    peak_rate = max(2 * math.pi * f * math.radians(th) for f, _, th, _ in motions)
    assert peak_rate > 15.0
    assert motions[:len(hs.frequencies)] == sorted(motions[:len(hs.frequencies)])


def test_harmonic_set_cases_run_their_periods_and_have_distinct_ids():
    hs = HarmonicSet(n_cycles=4.0)
    cases = harmonic_set_cases(hs)
    assert len({c.case_id for c in cases}) == len(cases)
    for c in cases:
        assert math.isclose(c.duration * c.frequency, 4.0)
        assert 0 < c.ramp_time < c.duration / 4
        assert c.motion().pitch_amplitude == pytest.approx(math.radians(c.pitch_amplitude_deg))


@pytest.mark.parametrize(("kwargs", "key"), [
    ({"pitch_amplitudes_deg": (30.0, 95.0)}, "harmonic_set.pitch_amplitudes_deg"),
    ({"frequencies": (1.0, 1.0)}, "harmonic_set.frequencies"),
    ({"n_cycles": 0.5}, "harmonic_set.n_cycles"),
])
def test_an_impossible_harmonic_set_is_refused_naming_the_key(kwargs, key):
    with pytest.raises(ConfigError) as err:
        HarmonicSet(**kwargs)
    assert err.value.key.startswith(key)


def test_campaign_run_lists_the_harmonic_set_in_its_own_folder(tmp_path):
    case = Path(__file__).parents[1] / "cases" / "paper2026.toml"
    res = CliRunner().invoke(cli, ["campaign", "run", str(case), "--out", str(tmp_path / "h"),
                                   "--cases", "harmonic", "--set", "harmonic_set.n_cycles=3",
                                   "--dry-run"])
    assert res.exit_code == 0, res.output
    lines = res.output.strip().splitlines()
    assert len(lines) == len(HarmonicSet().motions())
    assert all(line.startswith("harmonic_f") and line.endswith("pending") for line in lines)
    assert "duration 3 s" in lines[0]
