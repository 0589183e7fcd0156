"""Realistic misuse, found by running every command with wrong, odd and borderline input:
impossible numbers and lists are refused before any work by the option's or key's name,
files of the wrong kind or from other runs are refused by name, outputs go to folders that
do not exist yet, numbers that were not computed are NaN (and ``null`` in strict ``--json``
output), never a false 0."""

import json
import math
import re
from pathlib import Path

import h5py
import numpy as np
import pytest
from click.testing import CliRunner

from mfflap.campaign.cases import grid_cases
from mfflap.campaign.execute import CampaignSetup, run_campaign
from mfflap.cfd.fluent.udf import write_fluent_case
from mfflap.cfd.imposed_motion import check_end_time
from mfflap.cfd.openfoam.runner import run_application
from mfflap.cfd.openfoam.writer import table_times
from mfflap.cli.json_output import strict_json_value
from mfflap.cli.main import cli
from mfflap.config import IdentificationGrid, load_case
from mfflap.errors import ConfigError, MfflapError, MotionError
from mfflap.gap.blindtest import NULL, blind_test, synthesize
from mfflap.gap.diagnose import diagnose
from mfflap.hydro import MorisonModel
from mfflap.hydro.loads import Loads
from mfflap.identification import identify, prepare_cases
from mfflap.kinematics.continuous import HarmonicMotion
from mfflap.optimisation.study import beta_study
from mfflap.records.record import CfdRecord

CASE = Path(__file__).parents[2] / "cases" / "paper2026.toml"


def _strict_loads(text: str):
    """json.loads that refuses NaN and Infinity, as jq and JavaScript do."""
    def refuse(word):
        raise ValueError(f"not JSON: {word}")
    return json.loads(text, parse_constant=refuse)


# (command after `mfflap`, with OUT as the folder it would write, the option refused, and
# the words of click's message)
REFUSED = [
    (["cfd", "write", str(CASE), "OUT", "--cycles", "0"], "--cycles", "finite number > 0"),
    (["cfd", "write", str(CASE), "OUT", "--cycles", "inf"], "--cycles", "finite number > 0"),
    (["cfd", "write", str(CASE), "OUT", "--cycles", "nan"], "--cycles", "finite number > 0"),
    (["cfd", "write", str(CASE), "OUT", "--cycles", "three"], "--cycles", "is not a number"),
    (["cfd", "write", str(CASE), "OUT", "--ramp-time", "-1"], "--ramp-time",
     "finite number >= 0"),
    (["cfd", "fluent", str(CASE), "OUT", "--time-step", "0"], "--time-step",
     "finite number > 0"),
    (["cfd", "fluent", str(CASE), "OUT", "--cycles", "0"], "--cycles", "finite number > 0"),
    (["cfd", "convergence", str(CASE), "OUT", "--cycles", "inf"], "--cycles",
     "finite number > 0"),
    (["campaign", "run", str(CASE), "--out", "OUT", "--workers", "0"], "--workers", "x>=1"),
    (["gradcheck", str(CASE), "--n-steps", "1", "--out", "OUT"], "--n-steps", "x>=2"),
    # a figure format matplotlib cannot write: refused before the work, not after it
    (["evaluate", str(CASE), "--figure", "OUT/f.txt"], "--figure", "written as .png, .pdf"),
    (["campaign", "compare", "OUT", "OUT", "--figure", "OUT/c.gif"], "--figure",
     "written as .png, .pdf"),
    (["identify", str(CASE), "--bootstrap", "-1", "--output", "OUT/i.h5"], "--bootstrap",
     "x>=0"),
    (["campaign", "compare", "OUT", "OUT", "--start", "nan"], "--start", "finite number >= 0"),
    (["campaign", "compare", "OUT", "OUT", "--end", "-1"], "--end", "finite number > 0"),
    (["optimise", str(CASE), "--betas", "0,0.5,0", "--output", "OUT/o.h5"], "--betas",
     "0 given twice"),
    (["identify", str(CASE), "--weights", "1,x", "--output", "OUT/i.h5"], "--weights",
     "expected comma-separated numbers"),
    (["cfd", "convergence", str(CASE), "OUT", "--courant", "4,x"], "--courant",
     "expected comma-separated numbers"),
    (["backtest", str(CASE), "--fixtures", "OUT/typo"], "--fixtures", "does not exist"),
    (["run", str(CASE), "--out", "OUT", "--backtest-fixtures", "OUT/typo"],
     "--backtest-fixtures", "does not exist"),
    (["gap", "blindtest", "--trials", "0"], "--trials", "x>=1"),
    (["gap", "blindtest", "--snr", "nan"], "--snr", "finite number > 0"),
    # sizes beyond this machine or any flapping motion
    (["cfd", "write", str(CASE), "OUT", "--cycles", "1e9"], "--cycles", "<= 1000"),
    # a huge value is repeated cut short, not whole
    (["cfd", "write", str(CASE), "OUT", "--cycles", "7" * 100_000], "--cycles", "777..."),
]


@pytest.mark.parametrize(("args", "option", "words"), REFUSED,
                         ids=[" ".join(a[:2] + a[-2:])[:80] for a, _, _ in REFUSED])
def test_an_impossible_option_is_refused_by_name_before_anything_is_written(
        tmp_path, args, option, words):
    out = tmp_path / "out"
    args = [str(a).replace("OUT", str(out)) for a in args]
    res = CliRunner().invoke(cli, args)
    assert res.exit_code == 2, res.output
    assert f"Invalid value for '{option}'" in res.output and words in res.output
    assert len(res.output) < 1000
    assert not out.exists()


# (command after `mfflap`, a --set that cannot run, the key refused and the words said)
SET_REFUSED = [
    (["cfd", "write", str(CASE), "OUT"], "cfd.max_courant=nan", "cfd.max_courant",
     "out of range; allowed: (0, 100]"),
    (["cfd", "write", str(CASE), "OUT"], "cfd.max_courant=1e9", "cfd.max_courant",
     "out of range; allowed: (0, 100]"),
    (["cfd", "write", str(CASE), "OUT"], "cfd.writes=1000000000", "cfd.writes",
     "allowed: [1, 100000]"),
    (["campaign", "run", str(CASE), "--out", "OUT"], "cfd.timeout_s=-5", "cfd.timeout_s",
     "allowed: (0, 2.592e+06] s"),
    (["campaign", "run", str(CASE), "--out", "OUT"], "cfd.timeout_s=1e300", "cfd.timeout_s",
     "allowed: (0, 2.592e+06] s"),
    (["campaign", "run", str(CASE), "--out", "OUT"], "identification.frequencies=[1, 1]",
     "identification.frequencies[1]", "given twice"),
    (["campaign", "run", str(CASE), "--out", "OUT"], "identification.phases_deg=[90, nan]",
     "identification.phases_deg[1]", "value nan is out of range"),
    (["campaign", "run", str(CASE), "--out", "OUT"], 'cfd.frame="moving"', "cfd.frame",
     "one of 'inertial', 'plate'"),
    (["cfd", "convergence", str(CASE), "OUT"], "cfd.procs=0", "cfd.procs",
     "allowed: [1, 4096]"),
    (["cfd", "convergence", str(CASE), "OUT"], 'cfd.far_field="outlet"', "cfd.far_field",
     "one of"),
]


@pytest.mark.parametrize(("args", "setting", "key", "words"), SET_REFUSED,
                         ids=[f"{a[0]} {a[1]} {s}" for a, s, _, _ in SET_REFUSED])
def test_an_impossible_setting_is_refused_by_its_key_before_anything_is_written(
        tmp_path, args, setting, key, words):
    out = tmp_path / "out"
    args = [str(a).replace("OUT", str(out)) for a in args]
    res = CliRunner().invoke(cli, [*args, "--set", setting])
    assert res.exit_code == 2, res.output
    said = " ".join(res.output.split())
    assert f"{CASE} with --set {setting}: {key}" in said and words in said, said
    assert len(res.output) < 1000
    assert not out.exists()


@pytest.mark.parametrize("end_time", [0.0, -1.0, math.inf, math.nan])
def test_a_run_of_no_or_endless_length_is_refused(tmp_path, end_time):
    with pytest.raises(MotionError, match="end_time must be a finite time > 0 s"):
        check_end_time(end_time)
    with pytest.raises(MotionError, match="end_time must be a finite time > 0 s"):
        table_times(end_time)
    # the analytic UDF of a sinusoid does not tabulate the motion: it used to write a
    # journal of one time step for end_time 0, and divide by a time step of 0
    motion = HarmonicMotion(1.0, 0.3, 0.3, np.pi / 2)
    with pytest.raises(MotionError, match="end_time"):
        write_fluent_case(tmp_path / "udf", motion, end_time)
    assert not (tmp_path / "udf").exists()
    assert check_end_time(2) == 2.0


@pytest.mark.parametrize("time_step", [0.0, -1e-3, math.nan, math.inf])
def test_a_fluent_time_step_that_is_not_a_finite_positive_time_is_refused(tmp_path,
                                                                        time_step):
    motion = HarmonicMotion(1.0, 0.3, 0.3, np.pi / 2)
    with pytest.raises(ConfigError, match="time_step must be a finite time > 0 s") as err:
        write_fluent_case(tmp_path / "udf", motion, 1.0, time_step=time_step)
    assert err.value.key == "time_step"
    assert not (tmp_path / "udf").exists()


def test_a_fluent_time_step_too_long_for_the_run_is_refused_and_a_coarse_one_warned(
        tmp_path):
    motion = HarmonicMotion(1.0, 0.3, 0.3, np.pi / 2)
    with pytest.raises(ConfigError, match=r"time_step 0.2 s leaves fewer than 10 steps in the "
                                          r"1 s run") as err:
        write_fluent_case(tmp_path / "udf", motion, 1.0, time_step=0.2)
    assert err.value.key == "time_step" and not (tmp_path / "udf").exists()
    assert write_fluent_case(tmp_path / "udf", motion, 1.0, time_step=0.1).is_dir()
    runner = CliRunner()
    res = runner.invoke(cli, ["cfd", "fluent", str(CASE), str(tmp_path / "coarse"),
                              "--time-step", "0.05"])
    assert res.exit_code == 0 and "gives 20 steps per period of the 1 Hz motion" in res.output
    res = runner.invoke(cli, ["cfd", "fluent", str(CASE), str(tmp_path / "fine"),
                              "--time-step", "0.005"])
    assert res.exit_code == 0 and "warning: --time-step" not in res.output


def test_an_impossible_beta_or_no_start_is_refused_before_the_sweep():
    case = load_case(CASE)
    said = []
    with pytest.raises(ConfigError, match=r"value 2.0 is not allowed; allowed: \[0, 1\]"):
        beta_study(case, [0.0, 2.0], n_starts=1, with_ipopt=False, progress=said.append)
    with pytest.raises(ConfigError, match="n_starts must be >= 1") as err:
        beta_study(case, [0.0], n_starts=0, with_ipopt=False, progress=said.append)
    assert err.value.key == "n_starts"
    assert said == []  # neither the sweep nor the refined sinusoid ran


def _model_records(rng: np.random.Generator) -> list[CfdRecord]:
    """Forces of the Morison model itself, with 5 % noise, on nine cases of the grid."""
    model = MorisonModel()
    records = []
    for c in grid_cases(IdentificationGrid(), frequencies=[0.5, 1.0, 2.0],
                        heave_amplitudes=[0.1, 0.3, 0.5], phases_deg=[90]):
        t = np.linspace(0.0, c.duration, 400)
        state = c.motion().sample(t)
        clean = model.loads(state)
        loads = Loads(*(t, *(a + 0.05 * np.std(a) * rng.standard_normal(a.shape) for a in
                             (clean.normal_force, clean.tangential_force, clean.moment))))
        records.append(CfdRecord(c.case_id, state, loads, c.as_dict()))
    return records


def test_without_bootstrap_the_spread_is_not_estimated_rather_than_zero():
    cases, _ = prepare_cases(_model_records(np.random.default_rng(3)))
    res = identify(cases, MorisonModel(), fixed={"tangential_drag": 4.0}, n_bootstrap=0)
    for name in res.fitted_terms:
        assert math.isnan(res.standard_error[name])
        assert all(math.isnan(v) for v in res.interval[name])
    assert res.standard_error["tangential_drag"] == 0.0  # fixed: known exactly
    assert res.interval["tangential_drag"] == (4.0, 4.0)
    with pytest.raises(ConfigError, match="n_bootstrap must be >= 0") as err:
        identify(cases, MorisonModel(), n_bootstrap=-1)
    assert err.value.key == "n_bootstrap"


@pytest.mark.slow
def test_identify_without_bootstrap_prints_strict_json_and_no_false_zero(tmp_path):
    out = tmp_path / "i.h5"
    runner = CliRunner()
    res = runner.invoke(cli, ["identify", str(CASE), "--bootstrap", "0", "--strategy",
                              "uniform", "--output", str(out), "--json"])
    assert res.exit_code == 0, res.output
    summary = _strict_loads(res.output)["uniform"]
    assert set(summary["standard_error"]) == set(summary["coefficients"])
    assert all(v is None for v in summary["standard_error"].values())
    text = runner.invoke(cli, ["identify", str(CASE), "--bootstrap", "0", "--strategy",
                               "uniform", "--output", str(out)])
    assert text.exit_code == 0, text.output
    assert "normal_drag = " in text.output and "±" not in text.output
    html = tmp_path / "i.html"
    rep = runner.invoke(cli, ["report", "identification", str(out), "--out", str(html)])
    assert rep.exit_code == 0, rep.output
    page = html.read_text()
    assert "uncertainty is not estimated" in page and ">nan<" not in page
    # with records other than the ones it was fitted to, the report would draw their maps
    # beside these coefficients' metrics
    from mfflap.records.record import fixture_dir

    other = runner.invoke(cli, ["report", "identification", str(out), "--fixtures",
                                str(fixture_dir("small_motion_coarse")), "--out",
                                str(tmp_path / "other.html")])
    assert other.exit_code == 2
    assert "small_motion_coarse lacks 161 of the 161 records" in other.output
    assert not (tmp_path / "other.html").exists()


def test_strict_json_value_makes_every_non_finite_number_null():
    value = {"a": math.nan, "b": [1.0, math.inf, np.float64(-np.inf)], "c": np.array(
        [[0.5, np.nan]]), "d": (np.int64(3), "x", None, True), "e": {"f": np.float32(2.5)}}
    plain = strict_json_value(value)
    assert plain == {"a": None, "b": [1.0, None, None], "c": [[0.5, None]],
                     "d": [3, "x", None, True], "e": {"f": 2.5}}
    json.dumps(plain, allow_nan=False)  # raises on any NaN left


def test_blind_test_and_diagnosis_refuse_impossible_settings():
    with pytest.raises(ConfigError, match="at least one trial") as err:
        blind_test(0)
    assert err.value.key == "n_trials"
    for snr in (0.0, -3.0, math.nan, math.inf):
        with pytest.raises(ConfigError, match="signal-to-noise ratio") as err:
            blind_test(2, snr)
        assert err.value.key == "snr"
    data = synthesize(np.random.default_rng(5), NULL, 0.0)
    for alpha in (0.0, 1.0, 2.0, math.nan):
        with pytest.raises(ConfigError, match="significance level must be in") as err:
            diagnose(data, MorisonModel(), alpha=alpha)
        assert err.value.key == "alpha"
    for gain in (-0.1, math.nan):
        with pytest.raises(ConfigError, match="error reduction worth claiming") as err:
            diagnose(data, MorisonModel(), min_gain=gain)
        assert err.value.key == "min_gain"


def test_a_campaign_without_workers_or_time_is_refused_before_its_folder_is_made(tmp_path):
    cases = grid_cases(IdentificationGrid(), frequencies=[1.0], heave_amplitudes=[0.3],
                       phases_deg=[90])
    with pytest.raises(ConfigError, match="the campaign has no cases") as err:
        run_campaign([], tmp_path / "c", progress=False)
    with pytest.raises(ConfigError, match="lists a case twice: ") as err:
        run_campaign([*cases, *cases], tmp_path / "c", progress=False)
    assert err.value.key == "cases"
    with pytest.raises(ConfigError, match="at least one worker") as err:
        run_campaign(cases, tmp_path / "c", n_workers=0, progress=False)
    assert err.value.key == "n_workers"
    for timeout in (0.0, -5.0, math.nan, math.inf):
        with pytest.raises(ConfigError, match="time limit per case") as err:
            run_campaign(cases, tmp_path / "c", CampaignSetup(timeout_s=timeout),
                         progress=False)
        assert err.value.key == "timeout_s"
    assert not (tmp_path / "c").exists()


@pytest.mark.parametrize("timeout", [0.0, -1.0, math.nan])
def test_an_application_without_time_to_run_is_refused_before_it_starts(tmp_path, timeout):
    with pytest.raises(ConfigError, match="time limit of blockMesh") as err:
        run_application(tmp_path, "blockMesh", timeout_s=timeout)
    assert err.value.key == "timeout_s"
    assert not (tmp_path / "log.blockMesh").exists()


def test_run_refuses_a_coefficient_set_it_does_not_identify_before_its_folder_is_made(
        tmp_path):
    out = tmp_path / "run"
    res = CliRunner().invoke(cli, ["run", str(CASE), "--out", str(out), "--set",
                                   "optimisation.coefficients=medium"])
    assert res.exit_code == 2, res.output
    assert "optimisation.coefficients: value 'medium' is not allowed" in res.output
    assert "one of 'uniform', 'low', 'high', 'case'" in res.output
    assert not out.exists()


def test_evaluate_and_gradcheck_put_their_figures_in_the_working_folder(tmp_path,
                                                                       monkeypatch):
    """Not beside the case file, whose folder may be the package's or read-only."""
    cases = tmp_path / "cases"
    cases.mkdir()
    case = cases / "study.toml"
    case.write_text(CASE.read_text())
    work = tmp_path / "work"
    work.mkdir()
    monkeypatch.chdir(work)
    runner = CliRunner()
    for args, name in ((["evaluate", str(case)], "study.cycle.png"),
                       (["gradcheck", str(case), "--n-steps", "12"],
                        "study_gradcheck/gradcheck.png")):
        res = runner.invoke(cli, args)
        assert res.exit_code == 0, res.output
        assert f"figure: {name}" in res.output
        assert (work / name).stat().st_size > 0
    assert sorted(p.name for p in cases.iterdir()) == ["study.toml"]


def test_a_results_file_of_another_kind_is_refused_by_its_kind(tmp_path):
    """Each reader says which kind of file it was given; before, `report identification` of
    an optimisation file ended in h5py's KeyError and a CFD record's inputs were read as a
    study's ('unknown table [parameters]')."""
    from mfflap.cfd.model_comparison import read_model_comparison
    from mfflap.records.record import fixture_dir, read_record
    from mfflap.results import ResultsFile

    optimisation = tmp_path / "o.h5"
    with ResultsFile(optimisation, "w", kind="optimisation", config_toml=CASE.read_text()):
        pass
    record = sorted(fixture_dir("table1_coarse").glob("*.h5"))[0]
    runner = CliRunner()
    for args, held, wanted in (
            (["report", "identification", str(optimisation)], "optimisation",
             "'identification' or 'run'"),
            (["report", "identification", str(record)], "cfd_record", "'identification' or 'run'"),
            (["backtest", str(record)], "cfd_record", "'optimisation' or 'run'"),
            (["cfd", "motion-table", str(record), str(tmp_path / "m.csv"), "--beta", "0"],
             "cfd_record", "'optimisation' or 'run'")):
        res = runner.invoke(cli, args)
        assert res.exit_code == 2, res.output
        assert f"holds '{held}' results, not {wanted}" in res.output
        assert "Traceback" not in res.output
    assert not (tmp_path / "m.csv").exists()
    for read in (read_record, read_model_comparison):
        with pytest.raises(MfflapError, match=f"{optimisation}: holds 'optimisation' results"):
            read(optimisation)
    with h5py.File(optimisation, "r+") as f:  # the reader closed the file it refused
        assert f.attrs["kind"] == "optimisation"


@pytest.mark.slow
def test_a_scheduler_that_cannot_be_parsed_or_reached_is_a_clear_error(tmp_path):
    """Before: dask's ValueError or OSError as a traceback."""
    import socket

    import dask

    cases = grid_cases(IdentificationGrid(), frequencies=[1.0], heave_amplitudes=[0.3],
                       phases_deg=[90])
    for address in ("notanaddress", "tcp://host-without-port", "xyz://h:1"):
        with pytest.raises(ConfigError, match="is not a dask scheduler address") as err:
            run_campaign(cases, tmp_path / "c", scheduler_address=address, progress=False)
        assert err.value.key == "scheduler_address"
    assert not (tmp_path / "c").exists()
    with socket.socket() as free:  # a port nothing listens on
        free.bind(("127.0.0.1", 0))
        port = free.getsockname()[1]
    with dask.config.set({"distributed.comm.timeouts.connect": "2s"}):
        with pytest.raises(MfflapError, match=f"cannot reach the dask scheduler at "
                                              f"tcp://127.0.0.1:{port}"):
            run_campaign(cases, tmp_path / "c", scheduler_address=f"tcp://127.0.0.1:{port}",
                         progress=False)
    assert not list((tmp_path / "c").glob("*.h5"))


def test_still_water_gives_an_infinite_strouhal_number_printed_as_null(tmp_path):
    """U = 0 is allowed (a plate flapping on the spot): St = 2 f A / U is infinite there,
    without a RuntimeWarning, and --json prints it as null."""
    import re
    import warnings

    from mfflap.performance import strouhal_number

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert strouhal_number(1.0, 0.3, 0.0) == math.inf
        assert math.isnan(strouhal_number(1.0, 0.0, 0.0))
        assert strouhal_number(1.0, 0.3, 0.3) == pytest.approx(2.0)
    case = tmp_path / "still.toml"
    case.write_text(re.sub(r"^velocity = .*$", "velocity = 0.0", CASE.read_text(),
                           flags=re.M))
    res = CliRunner().invoke(cli, ["evaluate", str(case), "--json", "--figure",
                                   str(tmp_path / "f.png")])
    assert res.exit_code == 0, res.output
    out = _strict_loads(res.stdout)
    assert out["strouhal_number"] is None and out["mean_thrust"] > 0
    assert "RuntimeWarning" not in res.stderr


@pytest.mark.slow
def test_outputs_asked_for_in_new_folders_are_written_there(tmp_path):
    """Before: optimise did its minutes of work and then failed to create its file, and
    evaluate / gradcheck / motion-table failed with a traceback, when the folder named in
    --output / --figure / the table's path did not exist yet."""
    from mfflap.results import ResultsFile

    runner = CliRunner()
    new = tmp_path / "new"
    commands = [
        (["identify", str(CASE), "--bootstrap", "0", "--strategy", "uniform", "--output",
          str(new / "a" / "i.h5")], new / "a" / "i.h5"),
        (["evaluate", str(CASE), "--output", str(new / "b" / "e.h5"), "--figure",
          str(new / "c" / "f.png")], new / "c" / "f.png"),
        (["gradcheck", str(CASE), "--n-steps", "8", "--out", str(new / "d" / "g")],
         new / "d" / "g" / "gradcheck.png"),
    ]
    for args, made in commands:
        res = runner.invoke(cli, args)
        assert res.exit_code == 0, res.output
        assert made.stat().st_size > 0
    assert (new / "b" / "e.h5").is_file()
    with ResultsFile(new / "e" / "f" / "r.h5", "w", kind="evaluation", config_toml="") as rf:
        rf.write_group("g", {"x": np.arange(3.0)}, {"x": "m"})
    with ResultsFile(new / "e" / "f" / "r.h5", kinds=("evaluation",)) as rf:
        assert rf.read_group("g")[0]["x"].tolist() == [0.0, 1.0, 2.0]
    from mfflap.kinematics.table_file import read_motion_table, write_motion_table

    table = write_motion_table(new / "g" / "m.csv", HarmonicMotion(1.0, 0.3, 0.3, 1.0), 1.0,
                               40)
    assert read_motion_table(table).table_time[-1] == pytest.approx(1.0)


def test_a_term_that_acts_on_no_fitted_component_is_refused_by_name():
    """The tangential force has no arm about the leading edge: fitted to the moment alone,
    the tangential terms used to come out as 0.000, a number the data never gave."""
    cases, _ = prepare_cases(_model_records(np.random.default_rng(4)))
    with pytest.raises(MfflapError, match=r"do not determine the coefficients "
                                          r"\['tangential_added_mass', 'tangential_drag'\]"):
        identify(cases, MorisonModel(), components=("moment",), n_bootstrap=0)
    held = identify(cases, MorisonModel(), components=("moment",), n_bootstrap=0,
                    fixed={"tangential_added_mass": 0.87, "tangential_drag": 3.12})
    assert held.fitted_terms == ("normal_added_mass", "normal_drag")
    assert all(v > 0 for v in held.coefficients.values())


def test_one_case_per_frequency_gives_no_spread_rather_than_zero():
    """Each replicate of a stratified case bootstrap with one case per frequency is the data
    itself: a standard error of 0 would claim certainty."""
    records = _model_records(np.random.default_rng(5))
    single = {}
    for record in records:  # the first case of each frequency
        single.setdefault(record.parameters["frequency"], record)
    cases, _ = prepare_cases(list(single.values()))
    assert len(cases) == 3
    res = identify(cases, MorisonModel(), n_bootstrap=20)
    assert all(math.isnan(res.standard_error[n]) for n in res.fitted_terms)
    both, _ = prepare_cases(records)
    spread = identify(both, MorisonModel(), n_bootstrap=20)
    assert all(spread.standard_error[n] > 0 for n in spread.fitted_terms)


def test_linear_check_refuses_an_empty_case_list_and_runs_a_repeated_case_once(tmp_path):
    """`--cases ''` used to run all eleven motions, and a case id given twice was refused
    only as a campaign listing a case twice."""
    runner = CliRunner()
    for empty in ("", ","):
        res = runner.invoke(cli, ["cfd", "linear-check", str(tmp_path / "lc"), "--cases",
                                  empty, "--list"])
        assert res.exit_code == 2 and "--cases: no case ids" in res.output
    case = "harmonic_f1p000_h0p0050_th0p00_phi000p0"
    res = runner.invoke(cli, ["cfd", "linear-check", str(tmp_path / "lc"), "--cases",
                              f"{case},{case}", "--list"])
    assert res.exit_code == 0 and res.output.count(case) == 1
    assert not (tmp_path / "lc").exists()


IGNORED = [  # an option the rest of the command line would make it ignore
    (["cfd", "write", str(CASE), "OUT", "--motion-table", "TABLE", "--cycles", "5"],
     "--cycles applies only to the case file's [motion]; a --motion-table runs to --end-time"),
    (["cfd", "fluent", str(CASE), "OUT", "--motion-table", "TABLE", "--cycles", "5"],
     "--cycles applies only to the case file's [motion]"),
    (["cfd", "convergence", str(CASE), "OUT", "--motion-table", "TABLE", "--cycles", "2"],
     "--cycles applies only to the case file's [motion]"),
    (["backtest", "OPT", "--setup", "affordable", "--save-to", "OUT"],
     "--save-to, --setup apply only to live runs (--live); without it the back-test reads "
     "CFD records (--fixtures), run on the mesh and set-up they were made with"),
    (["backtest", "OPT", "--work", "OUT"], "--work applies only to live runs (--live)"),
    (["backtest", "OPT", "--mesh", "medium", "--json"], "--mesh applies only to live runs"),
    (["cfd", "convergence", str(CASE), "OUT", "--courant", "4@coarse"],
     "Invalid value for '--courant': '4@coarse': a mesh after @ is repeated at the limits "
     "after the first; give two or more"),
    (["cfd", "convergence", str(CASE), "OUT", "--meshes", "coarse,medium", "--courant",
      "4,2@fine"],
     "Invalid value for --courant: 'fine' is not one of the study's --meshes (coarse, "
     "medium)"),
    (["campaign", "run", str(CASE), "--out", "OUT", "--workers", "2", "--scheduler",
      "tcp://127.0.0.1:1"], "--workers applies only to the LocalCluster mfflap starts; with "
                            "--scheduler the cluster's own workers run the cases"),
]


@pytest.mark.parametrize(("args", "words"), IGNORED,
                         ids=[" ".join(a[:2] + a[-2:]) for a, _ in IGNORED])
def test_an_option_the_command_would_ignore_is_refused_by_name_before_anything_is_written(
        tmp_path, optimisation_file, args, words):
    """Before, each of these ran without the option: `backtest --setup affordable` read the
    coarse mesh's fixtures, and `cfd write --motion-table --cycles 5` ran the table's
    length."""
    table = tmp_path / "motion.csv"
    time_s = np.linspace(0.0, 2.0, 201)
    np.savetxt(table, np.column_stack([time_s, 0.1 * np.sin(2 * np.pi * time_s),
                                       0.1 * np.sin(2 * np.pi * time_s + 1.0)]),
               delimiter=",", header="time,heave_position,pitch_angle", comments="")
    out = tmp_path / "out"
    args = [str(a).replace("OUT", str(out)).replace("TABLE", str(table))
            .replace("OPT", str(optimisation_file)) for a in args]
    res = CliRunner().invoke(cli, args)
    assert res.exit_code == 2, res.output
    assert words in " ".join(res.output.split())
    assert not out.exists()


@pytest.mark.parametrize("args", [["--set", 'cfd.frame="plate"'],
                                  ["--setup", "affordable_plate"]])
def test_a_far_field_the_plate_frame_cannot_take_is_refused_by_its_key(tmp_path, args):
    """The plate's frame with the freestream far field, from [cfd] frame or a set-up's
    frame: the refusal names the [cfd] key that set the far field."""
    out = tmp_path / "out"
    res = CliRunner().invoke(cli, ["cfd", "write", str(CASE), str(out), *args,
                                   "--set", 'cfd.far_field="freestream"'])
    assert res.exit_code == 2, res.output
    assert ("cfd.far_field: the plate frame needs the inletOutlet far field, not freestream"
            in " ".join(res.output.split()))
    assert not out.exists()


@pytest.mark.slow
def test_identify_weights_not_one_per_frequency_of_the_records_name_the_option(tmp_path):
    """The count is known once the records are read: the refusal names --weights and the
    records' frequencies (it used to name only the case file's identification key)."""
    out = tmp_path / "out"
    for weights, said in (("1,2,3", "3 weights [1.0, 2.0, 3.0]"),
                          ("0,0,0,0,0,0,0", "7 weights [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]")):
        res = CliRunner().invoke(cli, ["identify", str(CASE), "--weights", weights,
                                       "--bootstrap", "0", "--output", str(out / "i.h5")])
        assert res.exit_code == 2, res.output
        assert "Invalid value for --weights" in res.output
        assert (f"{said} for the 7 frequencies of the records, 0.1, 0.2, 0.5, 1, 1.5, 2, "
                "2.5 Hz"
                in " ".join(res.output.split()))
    assert not out.exists()


@pytest.mark.parametrize(("duration", "ramp", "said"), [
    (1.0, 1.0, "ramp_time: the start-up ramp (1 s) lasts the whole run (1 s)"),
    (0.5, 2.0, "ramp_time: the start-up ramp (2 s) lasts the whole run (0.5 s)"),
    (0.0, 0.0, "duration: the duration must be a finite time > 0 s, got 0"),
    (math.inf, 0.25, "duration: the duration must be a finite time > 0 s, got inf"),
    (2.0, -0.1, "ramp_time: the start-up ramp must be a finite time >= 0 s"),
])
def test_a_campaign_case_that_could_not_run_is_refused_when_it_is_made(duration, ramp, said):
    """Built in code, such a case used to be refused only when its run was written, after
    its campaign had started the cases before it."""
    from mfflap.campaign.cases import CfdCase, HarmonicCase

    with pytest.raises(ConfigError) as err:
        CfdCase(1.0, 0.3, 90.0, 10.0, duration, ramp)
    assert str(err.value).startswith(f"case f1p000_h0p300_phi090p0: {said}")
    with pytest.raises(ConfigError, match=f"case harmonic_f1p000_h0p0100_th2p00_phi090p0: "
                                          f"{re.escape(said)}"):
        HarmonicCase(1.0, 0.01, 2.0, 90.0, duration, ramp)
    assert CfdCase(1.0, 0.3, 90.0, 10.0, 3.0, 0.25).duration == 3.0


@pytest.mark.parametrize(("args", "words"), [
    (["cfd", "write", str(CASE), "OUT", "--cycles", "1e-300"],
     "end_time: the run's 1e-300 s hold fewer than 10 of its first time steps"),
    (["cfd", "fluent", str(CASE), "OUT", "--time-step", "1e-300"],
     "at most 10,000,000 are written"),
])
def test_a_run_too_short_for_its_first_step_or_too_long_to_write_is_refused(
        tmp_path, args, words):
    """--cycles 1e-300 wrote an endTime below the first deltaT; --time-step 1e-300 a
    journal of a 301-digit step count."""
    out = tmp_path / "out"
    res = CliRunner().invoke(cli, [a.replace("OUT", str(out)) for a in args])
    assert res.exit_code == 2 and words in res.output, res.output
    assert len(res.output) < 400 and not out.exists()
