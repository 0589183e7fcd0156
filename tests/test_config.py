import dataclasses
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner
from scipy.optimize import brentq

from mfflap.cli.main import cli
from mfflap.config import CaseConfig, load_case, loads_case
from mfflap.errors import ConfigError, MfflapError
from mfflap.hydro import MorisonModel
from mfflap.kinematics import RampHarmonicMotion, harmonic_to_discrete
from mfflap.performance import evaluate_discrete
from mfflap.results import SCHEMA_VERSION, ResultsFile

ROOT = Path(__file__).resolve().parents[1]


def test_paper_case_loads_with_paper_values():
    case = load_case(ROOT / "cases" / "paper2026.toml")
    assert case.plate.chord == 0.16 and case.plate.span == 0.18 and case.plate.thickness == 0.003
    assert case.flow.velocity == 0.3
    assert case.coefficients.normal_drag == 2.49 and case.coefficients.tangential_added_mass == 0.87
    assert case.optimisation.max_power == 50.0
    assert case.identification.frequencies == (0.1, 0.2, 0.5, 1.0, 2.0)
    assert len(case.identification.phases_deg) == 5


def test_case_toml_round_trip():
    case = load_case(ROOT / "cases" / "paper2026.toml")
    again = loads_case(case.to_toml())
    assert again == case


@pytest.mark.parametrize(
    ("text", "key", "fragment"),
    [
        ("[plate]\nchord = -0.1\n", "plate.chord", "(0, 100] m"),
        ("[plate]\nspan = 1e308\n", "plate.span", "(0, 1000] m"),
        # names that become file names stay inside the working folder
        ('[study]\nname = "../x"\n', "study.name", "cannot name a file"),
        ('[study]\nname = "/tmp/x"\n', "study.name", "cannot name a file"),
        ("[fluid]\ndensity = 1e308\n", "fluid.density", "(0, 100000] kg/m^3"),
        ("[motion]\nfrequency = 5e-324\n", "motion.frequency", "[0.001, 100] Hz"),
        ("[plate]\nspan = 0\n", "plate.span", "(0, 1000] m"),
        ("[plate]\nthickness = 0.5\n", "plate.thickness", "smaller than the chord"),
        ("[fluid]\ndensity = 0\n", "fluid.density", "(0, 100000]"),
        ("[flow]\nvelocity = -1\n", "flow.velocity", "[0, 1000] m/s"),
        ("[flow]\nvelocity = 1e308\n", "flow.velocity", "[0, 1000] m/s"),
        ("[model]\nn_strips = 0\n", "model.n_strips", "[1, 100000]"),
        ("[model]\nn_strips = 2.5\n", "model.n_strips", "whole number"),
        ("[model]\nscheme = 'rk4'\n", "model.scheme", "'paper', 'midpoint'"),
        ("[model.coefficients]\nnormal_drag = -2\n", "model.coefficients.normal_drag",
         "[0, 1000]"),
        ("[model.coefficients]\nnormal_drag = 1e308\n", "model.coefficients.normal_drag",
         "[0, 1000]"),
        ("[model.coefficients]\nlift = 1\n", "model.coefficients.lift", "unknown key"),
        ("[motion]\nfrequency = 0\n", "motion.frequency", "[0.001, 100] Hz"),
        ("[motion]\npitch_amplitude_deg = 95\n", "motion.pitch_amplitude_deg", "[0, 90) deg"),
        ("[motion]\nkind = 'square'\n", "motion.kind", "'harmonic'"),
        ("[discretisation]\nn_steps = 1\n", "discretisation.n_steps", "[2, "),
        ("[optimisation]\nbetas = [0.0, 1.5]\n", "optimisation.betas[1]", "[0, 1]"),
        ("[optimisation]\nmax_heave = 0\n", "optimisation.max_heave", "(0, inf) m"),
        ("[optimisation]\npenalty_power = -1\n", "optimisation.penalty_power", "[0, inf)"),
        ("[optimisation]\nmin_period = 5\nmax_period = 1\n", "optimisation.min_period",
         "exclude every period"),
        ("[identification]\nfrequencies = []\n", "identification.frequencies", "empty list"),
        ("[identification]\nfrequency_weights = [1, 2]\n", "identification.frequency_weights",
         "one weight"),
        ("[nonsense]\na = 1\n", "nonsense", "unknown table"),
        ("[plate]\nchord = 'big'\n", "plate.chord", "not a number"),
        # a value given twice in a grid axis or a list of betas
        ("[identification]\nfrequencies = [0.5, 1.0, 1]\n", "identification.frequencies[2]",
         "given twice (identification.frequencies[1] and [2])"),
        ("[identification]\nheave_amplitudes = [0.1, 0.1]\n",
         "identification.heave_amplitudes[1]", "given twice"),
        ("[identification]\nphases_deg = [90, 45, 90]\n", "identification.phases_deg[2]",
         "given twice"),
        ("[optimisation]\nbetas = [0.5, 0.5]\n", "optimisation.betas[1]", "given twice"),
        # two values one case id apart: their cases would share a record
        ("[identification]\nfrequencies = [0.5, 1.0, 1.0004]\n",
         "identification.frequencies[2]", "values 1.0 and 1.0004 (frequencies[1] and [2]) are "
         "one value to 3 decimals, as a campaign case's id keeps them (1.000)"),
        ("[identification]\nphases_deg = [90.0, 90.04]\n", "identification.phases_deg[1]",
         "one value to 1 decimal, as"),
        # a phase a whole turn from another is the same motion
        ("[identification]\nphases_deg = [45, 90, -270]\n", "identification.phases_deg[2]",
         "value -270 is the same as 90 (identification.phases_deg[1]): they lie 360 deg apart"),
        ("[identification]\nphases_deg = [-45, 315.0]\n", "identification.phases_deg[1]",
         "the same as -45"),
        # one value where a list goes, a list where one value goes
        ("[identification]\nfrequencies = 1.0\n", "identification.frequencies",
         "must be a list, e.g. [1.0]"),
        ("[identification]\nfrequency_weights = 1.0\n", "identification.frequency_weights",
         "must be a list"),
        ("[motion]\nfrequency = [1.0]\n", "motion.frequency", "is a list; give one value"),
        ("[study]\nname = ['a']\n", "study.name", "is a list"),
        ("[study]\ndescription = 3\n", "study.description", "any text in quotes"),
        # the optional settings are checked with the others, naming the file
        ("[identification]\nfrequency_weights = ['a', 1, 1, 1, 1]\n",
         "identification.frequency_weights[0]", "not a number"),
        ("[identification]\nfrequency_weights = [nan, 1, 1, 1, 1]\n",
         "identification.frequency_weights[0]", "[0, inf)"),
        ("[model]\ndrag_area_normal = 'x'\n", "model.drag_area_normal", "not a number"),
        ("[model]\nadded_mass_volume_tangential = -1.0\n",
         "model.added_mass_volume_tangential", "[0, inf) m^3"),
        # a ramp whose end would stand the plate across the stream
        ("[identification]\nmax_ramp_pitch_deg = 90\n", "identification.max_ramp_pitch_deg",
         "89"),
        # cases that would end inside their start-up ramp
        ("[identification]\nmax_duration = 0.4\n", "identification.max_duration",
         "leaves the f = 0.1 Hz cases no time after their 0.5 s start-up ramp"),
    ],
)
def test_every_validation_error_names_file_key_value_range(tmp_path, text, key, fragment):
    path = tmp_path / "bad.toml"
    path.write_text(text)
    with pytest.raises(ConfigError) as info:
        load_case(path)
    message = str(info.value)
    assert str(path) in message
    assert key in message
    assert fragment in message


def test_a_dropped_table_header_is_refused_in_a_short_line(tmp_path):
    """Without its [identification] header, that table's keys land in [optimisation]: the
    error names the first of them and stays short however many keys either table has."""
    text = (ROOT / "cases" / "paper2026.toml").read_text()
    path = tmp_path / "case.toml"
    path.write_text(text.replace("[identification]", "", 1))
    with pytest.raises(ConfigError) as caught:
        load_case(path)
    assert caught.value.key == "optimisation.frequencies"
    message = str(caught.value)
    assert "more)" in message and "`mfflap case show`" in message
    assert len(message) < 250 + len(str(path))


def test_toml_syntax_error_names_file_and_line(tmp_path):
    path = tmp_path / "broken.toml"
    path.write_text("[plate]\nchord = 0.16\nspan = = 3\n")
    with pytest.raises(ConfigError, match=r"broken.toml.*line 3"):
        load_case(path)


def test_missing_case_file(tmp_path):
    with pytest.raises(ConfigError, match="no such file"):
        load_case(tmp_path / "nope.toml")


def test_results_are_not_written_over_a_file_that_holds_something_else(tmp_path):
    """The same kind is a rerun and is written over; another kind of results, an HDF5 file
    mfflap did not write, or a file that is not HDF5 is kept, refused by name (by the
    library after the work, by the command line's --output before it)."""
    import h5py

    results = tmp_path / "opt.h5"
    with ResultsFile(results, "w", kind="optimisation") as rf:
        rf.h5.attrs["marker"] = 1
    with ResultsFile(results, "w", kind="optimisation") as rf:  # a rerun
        rf.h5.attrs["marker"] = 2
    with ResultsFile(results) as rf:
        assert rf.h5.attrs["marker"] == 2
    foreign = tmp_path / "theirs.h5"
    with h5py.File(foreign, "w") as h5:
        h5["x"] = np.arange(3)
    page = tmp_path / "report.html"
    page.write_text("<html></html>")
    refused = {results: "holds 'optimisation' results; writing 'identification' results over "
                        "them would lose them",
               foreign: "is an HDF5 file mfflap did not write",
               page: "exists and is not an HDF5 file",
               tmp_path: "is a folder"}
    for path, why in refused.items():
        with pytest.raises(MfflapError, match=why):
            ResultsFile(path, "w", kind="identification")
    with ResultsFile(results) as rf:
        assert rf.h5.attrs["kind"] == "optimisation" and rf.h5.attrs["marker"] == 2
    assert page.read_text() == "<html></html>"
    # the commands refuse it by the option's name before the work
    res = CliRunner().invoke(cli, ["evaluate", str(ROOT / "cases" / "paper2026.toml"),
                                   "--output", str(results), "--figure",
                                   str(tmp_path / "f.png")])
    assert res.exit_code == 2 and "Invalid value for '--output'" in res.output
    assert "holds 'optimisation' results" in res.output and not (tmp_path / "f.png").exists()


def test_hdf5_round_trip(tmp_path):
    model = MorisonModel()
    d = harmonic_to_discrete(np.array([0.5, 1.0]), 0.3, 0.3, np.pi / 2, 30)
    ev = evaluate_discrete(model, d)
    case = CaseConfig()
    path = tmp_path / "r.h5"
    with ResultsFile(path, "w", kind="test", config_toml=case.to_toml()) as rf:
        rf.write_discrete_motion("motion", d)
        rf.write_state("state", ev.state)
        rf.write_loads("loads", ev.loads)
        rf.write_summary("summary", ev.summary)
    with ResultsFile(path) as rf:
        assert rf.h5.attrs["mfflap_schema_version"] == SCHEMA_VERSION
        assert loads_case(rf.config_toml) == case
        d2 = rf.read_discrete_motion("motion")
        np.testing.assert_array_equal(d2.pitch_acceleration, d.pitch_acceleration)
        np.testing.assert_array_equal(d2.time_step, d.time_step)
        st = rf.read_state("state")
        np.testing.assert_array_equal(st.heave_velocity, ev.state.heave_velocity)
        lo = rf.read_loads("loads")
        assert lo.source == "morison"
        np.testing.assert_array_equal(lo.moment, ev.loads.moment)
        s2 = rf.read_summary("summary")
        np.testing.assert_array_equal(s2.mean_thrust, ev.summary.mean_thrust)
        units = rf.units("loads")
        assert units["moment"] == "N*m" and units["time"] == "s"
        for grp in ("motion", "state", "loads", "summary"):
            for name, ds in rf.h5[grp].items():
                assert ds.attrs["units"], f"{grp}/{name} has no unit"


def test_results_refuse_unitless_data_and_foreign_files(tmp_path):
    with ResultsFile(tmp_path / "a.h5", "w") as rf, pytest.raises(MfflapError, match="no unit"):
        rf.write_group("g", {"x": [1.0]}, {})
    import h5py

    with h5py.File(tmp_path / "foreign.h5", "w") as f:
        f["x"] = 1
    with pytest.raises(MfflapError, match="not an mfflap results file"):
        ResultsFile(tmp_path / "foreign.h5")
    (tmp_path / "text.h5").write_text("time,force\n0,1\n")
    with pytest.raises(MfflapError, match=r"text\.h5: cannot be opened as an HDF5 file"):
        ResultsFile(tmp_path / "text.h5")


def test_a_results_file_stopped_while_written_keeps_the_file_before(tmp_path):
    """Written over, a results file used to be emptied at once: an error or Ctrl-C before
    the new one was complete lost both. Now the new file takes the old one's place only
    when it is closed cleanly."""
    path = tmp_path / "r.h5"
    with ResultsFile(path, "w", kind="evaluation", config_toml="old") as rf:
        rf.write_group("g", {"x": np.arange(3.0)}, {"x": "m"})
    for stop in (KeyboardInterrupt, MfflapError):
        with pytest.raises(stop):
            with ResultsFile(path, "w", kind="evaluation", config_toml="new") as rf:
                rf.write_group("g", {"x": np.arange(5.0)}, {"x": "m"})
                assert path.exists() and len(list(tmp_path.iterdir())) == 2  # beside it
                raise stop("stopped while writing")
        with ResultsFile(path, kinds=("evaluation",)) as rf:
            assert rf.config_toml == "old" and len(rf.read_group("g")[0]["x"]) == 3
        assert [p.name for p in tmp_path.iterdir()] == ["r.h5"]  # nothing left beside it
    with ResultsFile(path, "w", kind="evaluation", config_toml="new") as rf:
        rf.write_group("g", {"x": np.arange(5.0)}, {"x": "m"})
    with ResultsFile(path) as rf:
        assert rf.config_toml == "new" and len(rf.read_group("g")[0]["x"]) == 5
    assert [p.name for p in tmp_path.iterdir()] == ["r.h5"]


def test_a_report_stopped_while_written_keeps_the_report_before(tmp_path, monkeypatch):
    from mfflap.reports import html

    path = html.Report("old report").write(tmp_path / "r.html")
    assert "old report" in path.read_text()

    class Stopped:
        def render(self, **_):
            raise KeyboardInterrupt

    monkeypatch.setattr(html, "_TEMPLATE", Stopped())
    with pytest.raises(KeyboardInterrupt):
        html.Report("new report").write(path)
    assert "old report" in path.read_text()
    assert [p.name for p in tmp_path.iterdir()] == ["r.html"]


def test_a_cut_or_incomplete_cfd_record_is_refused_naming_its_file(tmp_path):
    """A record cut short (a copy killed midway) or missing a group says which file it is."""
    import shutil

    import h5py

    from mfflap.records.record import read_record

    shipped = sorted((Path(__file__).parents[1] / "data" / "mfflap_data" / "fixtures"
                      / "small_motion_coarse").glob("*.h5"))[0]
    whole = read_record(shipped)
    cut = tmp_path / "cut.h5"
    cut.write_bytes(shipped.read_bytes()[: shipped.stat().st_size // 2])
    with pytest.raises(MfflapError, match=r"cut\.h5: cannot be opened as an HDF5 file"):
        read_record(cut)
    for group in ("parameters", "provenance", "loads/moment", "kinematics/pitch_angle"):
        broken = tmp_path / f"no_{group.replace('/', '_')}.h5"
        shutil.copyfile(shipped, broken)
        with h5py.File(broken, "a") as f:
            del f[group]
        with pytest.raises(MfflapError, match=rf"{broken.name}: (not a complete CFD record|"
                                              rf"no group)"):
            read_record(broken)
    assert read_record(shipped).name == whole.name  # the shipped file is untouched


@pytest.mark.slow
def test_cli_evaluate_text_json_and_figure(tmp_path):
    import json

    runner = CliRunner()
    fig = tmp_path / "c.png"
    out = tmp_path / "c.h5"
    res = runner.invoke(cli, ["evaluate", str(ROOT / "cases" / "paper2026.toml"), "--json",
                              "--figure", str(fig), "--output", str(out)])
    assert res.exit_code == 0, res.output
    data = json.loads(res.stdout)
    assert data["mean_thrust"] > 0 and data["mean_power"] > 0
    assert fig.stat().st_size > 10_000
    with ResultsFile(out) as rf:
        assert "paper2026" in rf.config_toml
    res = runner.invoke(cli, ["evaluate", str(ROOT / "cases" / "paper2026.toml"),
                              "--figure", str(fig)])
    assert res.exit_code == 0 and "mean_thrust" in res.output


def test_cli_ramp_motion(tmp_path):
    path = tmp_path / "ramp.toml"
    path.write_text("[study]\nname='r'\n[motion]\nkind='ramp_harmonic'\nfrequency=0.5\n"
                    "heave_amplitude=0.2\npitch_ramp_rate_deg=10\nphase_deg=90\n")
    res = CliRunner().invoke(cli, ["evaluate", str(path), "--figure", str(tmp_path / "r.png")])
    assert res.exit_code == 0, res.output
    assert "scheme continuous" in res.output
    # a discrete scheme is for the harmonic motion: asked for a ramp, it is refused
    res = CliRunner().invoke(cli, ["evaluate", str(path), "--scheme", "midpoint",
                                   "--figure", str(tmp_path / "r.png")])
    assert res.exit_code == 2 and "scheme: scheme 'midpoint' is a discrete scheme" in res.output


def test_largest_pitch_of_a_ramp_is_its_last_peak():
    # |k t sin(2 pi f t)| peaks where tan x = -x (x = 2 pi f t); up to t = 1.5 s at f = 1 Hz
    # the last such peak is the root just past x = 5 pi / 2
    x = brentq(lambda x: np.tan(x) + x, 2.5 * np.pi + 1e-9, 3.0 * np.pi)
    k = np.radians(10.0)
    pitch, time = RampHarmonicMotion(1.0, 0.2, k).largest_pitch(1.5)
    assert time == pytest.approx(x / (2 * np.pi), abs=2e-3)
    assert abs(pitch) == pytest.approx(k * x / (2 * np.pi) * abs(np.sin(x)), rel=1e-5)
    # ending on a rising flank, the end is the largest pitch
    pitch, time = RampHarmonicMotion(1.0, 0.2, k).largest_pitch(1.2)
    assert time == pytest.approx(1.2) and pitch == pytest.approx(k * 1.2 * np.sin(2.4 * np.pi))


def test_every_grid_case_runs_its_cycles_and_ramps_no_further_than_the_cap(tmp_path):
    """Each case runs n_cycles periods (up to max_duration) and its pitch ramp never exceeds
    max_ramp_pitch_deg: the cases that would go further ramp slower, the others keep
    theta_kamp, whatever rate the case file asks for."""
    path = tmp_path / "ramp.toml"
    for rate in (1.0, 10.0, 100.0):
        path.write_text(f"[identification]\npitch_ramp_rate_deg = {rate}\n"
                        "max_ramp_pitch_deg = 45\n")
        grid = load_case(path).identification
        for f in grid.frequencies:
            duration = grid.case_duration(f)
            assert duration == pytest.approx(min(3.0 / f, grid.max_duration))
            k = grid.case_pitch_ramp_rate_deg(f)
            assert k <= rate
            assert k * duration <= 45.0 + 1e-9
            assert k == rate or k * duration == pytest.approx(45.0)
            peak = abs(RampHarmonicMotion(f, 0.0, np.radians(k)).largest_pitch(duration)[0])
            assert peak <= np.radians(45.0) + 1e-12


def test_a_ramp_motion_past_90_deg_is_refused_for_its_run(tmp_path):
    """evaluate runs the ramp as long as its campaign case; cfd write and fluent for
    --cycles periods; each refuses a ramp that turns the plate across the stream."""
    path = tmp_path / "ramp.toml"
    path.write_text("[motion]\nkind='ramp_harmonic'\nfrequency=1.0\nheave_amplitude=0.2\n"
                    "pitch_ramp_rate_deg=35\nphase_deg=90\n")
    runner = CliRunner()
    res = runner.invoke(cli, ["evaluate", str(path), "--figure", str(tmp_path / "r.png")])
    assert res.exit_code == 2 and "Traceback" not in res.output
    assert str(path) in res.output and "motion.pitch_ramp_rate_deg" in res.output
    assert "of the 3 s run (identification.n_cycles" in res.output
    for command in ("write", "fluent"):
        res = runner.invoke(cli, ["cfd", command, str(path), str(tmp_path / command),
                                  "--cycles", "4"])
        assert res.exit_code == 2 and "(--cycles 4)" in res.output, res.output
        assert not (tmp_path / command).exists()
        res = runner.invoke(cli, ["cfd", command, str(path), str(tmp_path / command),
                                  "--cycles", "2"])
        assert res.exit_code == 0, res.output


def test_cli_bad_case_gives_clear_error(tmp_path):
    path = tmp_path / "bad.toml"
    path.write_text("[plate]\nchord = -1\n")
    res = CliRunner().invoke(cli, ["evaluate", str(path)])
    assert res.exit_code == 2
    assert "plate.chord" in res.output and "Traceback" not in res.output


def test_cli_help_everywhere():
    runner = CliRunner()
    for args in (["--help"], ["evaluate", "--help"]):
        res = runner.invoke(cli, args)
        assert res.exit_code == 0 and "Usage" in res.output


@pytest.mark.parametrize("text", [
    '[model]\nscheme = "{long}"\n',
    '[study]\nname = "{long}"\n',
    '[identification]\nfrequencies = ["{long}"]\n',
])
def test_a_huge_value_is_named_cut_short_in_one_line(tmp_path, text):
    """A 100,000-character value is refused with its key and the first characters of the
    value, in a message of a few hundred characters, not echoed whole."""
    path = tmp_path / "huge.toml"
    path.write_text(text.replace("{long}", "x" * 100_000))
    with pytest.raises(ConfigError) as info:
        load_case(path)
    message = str(info.value)
    assert "xxxxxxxxxx" in message and "..." in message
    assert len(message) < 500 and "\n" not in message


def test_a_motion_table_without_a_key_its_kind_needs_is_refused_naming_it(tmp_path):
    """A [motion] without heave_amplitude used to run with the default 0.3 m."""
    path = tmp_path / "m.toml"
    path.write_text("[motion]\nkind = 'harmonic'\nfrequency = 1.0\npitch_amplitude_deg = 20\n"
                    "phase_deg = 90\n")
    with pytest.raises(ConfigError) as info:
        load_case(path)
    assert info.value.key == "motion.heave_amplitude" and info.value.source == str(path)
    res = CliRunner().invoke(cli, ["evaluate", str(path), "--figure", str(tmp_path / "f.png")])
    assert res.exit_code == 2 and "heave_amplitude missing" in res.output


def test_a_motion_key_the_kind_does_not_read_is_warned_by_name(tmp_path):
    from mfflap.config import ConfigWarning

    path = tmp_path / "m.toml"
    path.write_text("[motion]\nkind = 'harmonic'\nfrequency = 1.0\nheave_amplitude = 0.2\n"
                    "pitch_amplitude_deg = 20\nphase_deg = 90\npitch_ramp_rate_deg = 10\n")
    with pytest.warns(ConfigWarning, match="motion.pitch_ramp_rate_deg is not read"):
        assert load_case(path).motion.heave_amplitude == 0.2
    res = CliRunner().invoke(cli, ["evaluate", str(path), "--figure", str(tmp_path / "f.png")])
    assert res.exit_code == 0
    assert (f"warning: {path}: motion.pitch_ramp_rate_deg is not read by a harmonic motion"
            in res.stderr)


@pytest.mark.parametrize("text", ["a\x00b", "tab\tand\nnewline are fine\x1b[31m"])
def test_a_control_character_in_the_case_file_s_text_is_refused_naming_the_key(tmp_path, text):
    """HDF5 attributes cannot hold a NUL whole: refused when the case is read, not at the
    results' write after the run's work."""
    import tomllib

    from mfflap.config import load_case

    shipped = Path(__file__).parents[1] / "cases" / "paper2026.toml"
    data = tomllib.loads(shipped.read_text())
    case = tmp_path / "bad.toml"
    case.write_text(shipped.read_text().replace(
        f'description = "{data["study"]["description"]}"',
        'description = "' + text.replace("\x00", "\\u0000").replace("\t", "\\t")
        .replace("\n", "\\n").replace("\x1b", "\\u001b") + '"'))
    with pytest.raises(ConfigError) as refused:
        load_case(case)
    assert refused.value.key == "study.description" and "control character" in str(refused.value)


def test_the_case_file_names_each_coefficient_as_the_model_and_the_fit_do():
    """One name per coefficient: the case file's [model.coefficients] keys are the Morison
    model's term names, which identify and the results files use; another spelling is an
    unknown key with the right one suggested."""
    from mfflap.hydro.morison import MorisonModel

    case = load_case(Path(__file__).parents[1] / "cases" / "paper2026.toml")
    keys = set(case.coefficients.as_term_values())
    assert keys == set(MorisonModel().coefficients)
    assert {f.name for f in dataclasses.fields(case.coefficients)} == keys
    with pytest.raises(ConfigError, match=r"did you mean normal_drag|allowed: .*normal_drag"):
        loads_case('[study]\nname = "x"\n[model.coefficients]\ndrag_normal = 2.0\n')


def test_a_results_file_storing_the_other_coefficient_spellings_reads_back(tmp_path):
    """A case stored in a results file with drag_normal and the like reads as the term
    names; a case file with them is refused (one name per coefficient)."""
    from mfflap.results import ResultsFile
    from mfflap.study_results import open_results

    stored = (Path(__file__).parents[1] / "cases" / "paper2026.toml").read_text()
    for spelled, name in (("normal_drag", "drag_normal"),
                          ("normal_added_mass", "added_mass_normal")):
        stored = stored.replace(f"{spelled} =", f"{name} =")
    path = tmp_path / "older.h5"
    with ResultsFile(path, "w", kind="evaluation", config_toml=stored):
        pass
    back = open_results(path)
    assert back.config.coefficients.normal_drag == 2.49
    assert back.config.coefficients.normal_added_mass == 1.02
    with pytest.raises(ConfigError, match="drag_normal"):
        loads_case(stored)
