"""Fluent adapter: generated UDFs compiled with gcc (ND_ND 2 and 3) and run in a C test
program against the Python motion; journal; report-file parser on real output, fuzzed."""

import json
import re
import shutil
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner
from fluent_files import compile_syntax, report_text, run_udf, write_plate_report
from hypothesis import given, settings
from hypothesis import strategies as st

from mfflap.cfd.fluent.report import parse_report, read_report, report_forces
from mfflap.cfd.fluent.udf import (
    analytic_udf,
    journal,
    table_udf,
    velocity_table,
    write_fluent_case,
)
from mfflap.cfd.force_history import to_loads
from mfflap.cfd.imposed_motion import imposed_state
from mfflap.cfd.openfoam.forces import read_forces
from mfflap.errors import ConfigError, ParseError
from mfflap.kinematics import HarmonicMotion, RampHarmonicMotion
from mfflap.kinematics.convert import harmonic_to_discrete, to_spline

DATA = Path(__file__).parents[2] / "data"
RAMP = RampHarmonicMotion(0.5, 0.3, np.deg2rad(10.0), np.deg2rad(67.5))
SINE = HarmonicMotion(1.0, 0.2, np.deg2rad(25.0), np.deg2rad(90.0))

@pytest.mark.parametrize("nd", [2, 3])
def test_every_generated_udf_compiles_against_the_standin_header(tmp_path, nd):
    for source in (analytic_udf(RAMP, ramp_time=0.5), analytic_udf(SINE),
                   table_udf(RAMP, 2.0, ramp_time=0.5),
                   table_udf(to_spline(harmonic_to_discrete(1.0, 0.2, 0.4, 1.2, 20)), 1.0,
                             periodic_period=1.0)):
        compile_syntax(source, tmp_path, nd)


@pytest.mark.parametrize("motion", [RAMP, SINE], ids=["ramp", "sine"])
def test_analytic_udf_output_matches_the_python_motion(tmp_path, motion):
    times = np.linspace(0.0, 3.0, 61)
    out = run_udf(analytic_udf(motion, ramp_time=0.4), tmp_path, times)
    exact = imposed_state(motion, times, 0.4)
    assert np.all(out[:, 0] == 0) and np.all(out[:, 3] == 0)
    np.testing.assert_allclose(out[:, 1], exact.heave_velocity, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(out[:, 2], exact.pitch_rate, rtol=1e-12, atol=1e-12)


def test_table_udf_interpolates_like_numpy_and_wraps_periodically(tmp_path):
    times = np.concatenate([np.linspace(0.0, 2.5, 137), [-0.1, 10.0]])
    src = table_udf(RAMP, 2.0, ramp_time=0.5)
    out = run_udf(src, tmp_path, times, nd=3)
    rows = velocity_table(RAMP, 2.0, ramp_time=0.5)
    np.testing.assert_allclose(out[:, 1], np.interp(times, rows[:, 0], rows[:, 1]),
                               rtol=1e-12, atol=1e-12)  # clamped outside
    exact = imposed_state(RAMP, times[:137], 0.5)
    inside = times[:137] <= rows[-1, 0]
    np.testing.assert_allclose(out[:137][inside, 2], exact.pitch_rate[inside],
                               atol=2e-3 * np.abs(exact.pitch_rate).max())
    spline = to_spline(harmonic_to_discrete(1.0, 0.2, 0.4, 1.2, 20))
    periodic = run_udf(table_udf(spline, 1.0, periodic_period=1.0), tmp_path, [0.3, 1.3, 5.3])
    np.testing.assert_allclose(periodic[1:, 1:3], periodic[[0, 0], 1:3], atol=1e-9)
    np.testing.assert_allclose(periodic[0, 1], spline.sample(np.array([0.3])).heave_velocity[0],
                               rtol=2e-3)


def test_udf_settings_are_checked():
    for bad in ("my motion", "bewegung_\u00fc", "double", "2fast", ""):
        with pytest.raises(ConfigError, match="not a C identifier"):
            analytic_udf(SINE, udf_name=bad)
    for ramp_time in (-0.2, float("nan")):
        with pytest.raises(ConfigError, match="start-up ramp must be a finite time"):
            analytic_udf(SINE, ramp_time=ramp_time)
        with pytest.raises(ConfigError, match="start-up ramp must be a finite time"):
            table_udf(SINE, 1.0, ramp_time=ramp_time)
    for period in (0.0, -1.0, float("inf")):
        with pytest.raises(ConfigError, match="periodic_period must be a finite time > 0 s"):
            table_udf(SINE, 1.0, periodic_period=period)


def test_a_sinusoid_s_table_holds_its_ramp_and_one_period_and_wraps_after_it(tmp_path):
    """`cfd fluent --table` of a sinusoid: the table's size no longer grows with the run (200
    periods made a 30 MB C file); compiled and run, the UDF follows the motion, ramp
    included, to the run's end."""
    times = np.concatenate([np.linspace(0.0, 3.0, 121), np.linspace(196.0, 200.0, 41)])
    out = run_udf(table_udf(SINE, 200.0, ramp_time=0.4, periodic_period=1.0), tmp_path, times)
    exact = imposed_state(SINE, times, 0.4)
    for column, name in ((1, "heave_velocity"), (2, "pitch_rate")):
        expected = getattr(exact, name)
        np.testing.assert_allclose(out[:, column], expected,
                                   atol=1e-4 * np.abs(expected).max())  # linear interpolation
    folder = write_fluent_case(tmp_path / "fl", SINE, 200.0, ramp_time=0.5, time_step=2e-3,
                               table=True)
    source = (folder / "mfflap_motion.c").read_text()
    assert "#define MFFLAP_PERIODIC 1" in source and "#define MFFLAP_WRAP_FROM 0.5" in source
    assert len(source) < 500_000  # 1.5 s of rows; the whole run: about 30 MB
    short = write_fluent_case(tmp_path / "short", SINE, 1.2, ramp_time=0.5, time_step=2e-3,
                              table=True)  # less than the ramp and a period: the whole run
    assert "#define MFFLAP_PERIODIC 0" in (short / "mfflap_motion.c").read_text()


def test_a_start_up_ramp_as_long_as_the_run_writes_no_udf(tmp_path):
    with pytest.raises(ConfigError, match=r"ramp \(6 s\) lasts the whole run \(6 s\)"):
        write_fluent_case(tmp_path / "fl", RAMP, 6.0, ramp_time=6.0, time_step=2e-3)
    assert not (tmp_path / "fl").exists()


def test_journal_references_the_udf_and_the_report_file(tmp_path):
    folder = write_fluent_case(tmp_path / "fl", RAMP, 6.0, ramp_time=0.5, time_step=2e-3)
    text = (folder / "mfflap_run.jou").read_text()
    assert '"mfflap_motion.c"' in text and "mfflap_motion::libudf" in text
    assert "flow-time" in text and '"plate-forces.out"' in text
    assert "/solve/dual-time-iterate 3000 " in text
    commands = [ln for ln in text.splitlines() if ln and not ln.startswith(";")]
    for line in commands:
        assert line.startswith("/"), line
        assert line.count('"') % 2 == 0 and line.count("(") == line.count(")"), line
    # the paper's turbulence model is set after the case is read, before the flow starts
    order = [next(i for i, line in enumerate(commands) if line.startswith(prefix))
             for prefix in ("/file/read-case", "/define/models/viscous/ke-realizable yes",
                            "/define/models/viscous/near-wall-treatment/enhanced-wall-"
                            "treatment yes", "/solve/initialize/initialize-flow")]
    assert order == sorted(order)
    # the report columns the journal creates are the parser's defaults
    names = re.findall(r"/solve/report-definitions/add (\S+)", text)
    assert names == ["fx-plate", "fy-plate", "mz-plate"]
    assert "vel[1]" in (folder / "mfflap_motion.c").read_text()
    with pytest.raises(ConfigError):
        journal("x.c", n_steps=0)


def test_real_fluent_report_file_uses_flow_time_not_step_times_dt():
    rep = read_report(DATA / "fluent" / "report-def-0-rfile.out")
    assert rep.title == "vazao-mass-porta" and rep.kind == "transient"
    assert list(rep.columns) == ["Time Step", "vazao-mass-porta", "flow-time"]
    step, t = rep.columns["Time Step"], rep.time
    assert t[step == 505][0] == pytest.approx(50.05)  # 0.1 s steps to 500, 0.01 s after
    assert not np.allclose(t, step * 0.1)
    assert rep.columns["vazao-mass-porta"][-1] == pytest.approx(-7.418637935812349)


def test_columns_by_name_restart_overlap_and_cut_last_line():
    names = ["flow-time", "mz-plate", "Time Step", "fy-plate", "fx-plate"]
    rows = [[0.1 * i, i, i, 2 * i, 3 * i] for i in range(1, 8)]
    rows += [[0.1 * i, -i, i, -2 * i, -3 * i] for i in range(5, 10)]  # restart from t = 0.5
    text = report_text(names, rows)
    rep = parse_report(text, "f.out")
    np.testing.assert_allclose(rep.time, 0.1 * np.arange(1, 10))
    assert rep.columns["fx-plate"][5] == -18  # the restarted rows win
    cut = text + "1.0 3.0 10"  # killed while writing
    assert len(parse_report(cut, "f.out").time) == 9
    # cut inside the last number: a value for every column, one of them wrong, is dropped
    cut = text + "1.0 -10.0 10.0 -20.0 -30.0"[:-1]
    np.testing.assert_array_equal(parse_report(cut, "f.out").columns["fx-plate"],
                                  rep.columns["fx-plate"])


@pytest.mark.parametrize(("text", "message", "line"), [
    ('"t"\n"Iteration" "x"\n("Iteration" "cd")\n1 0.1\n2 nan\n', "NaN", 5),
    ('"t"\n"Time Step" "x"\n("Time Step" "fx" "flow-time")\n1 0.1 0.1\n2 0.2\n3 0.3 0.3\n',
     "2 values for 3 columns", 5),
    ('"t"\n"Time Step" "x"\n("Time Step" "fx" "flow-time")\n1 0.1 abc\n2 0.2 0.2\n',
     "unreadable number", 4),
    ("# Forces\n# Time forces\n0 (1 2 3) (0 0 0) (0 0 0)\n", "quoted report title", 1),
    ('"t"\n"Time Step" "x"\n"Time Step" "fx"\n', "parentheses", 3),
])
def test_bad_report_files_name_file_and_line(text, message, line):
    with pytest.raises(ParseError, match=rf"bad\.out, line {line}: .*{message}"):
        parse_report(text, "bad.out")


def test_missing_force_columns_are_named(tmp_path):
    path = tmp_path / "r.out"
    path.write_text(report_text(["Time Step", "flow-time", "drag"], [[1, 0.1, 2.0],
                                                                    [2, 0.2, 2.0]]))
    with pytest.raises(ParseError, match=r"missing column\(s\) \['fx-plate', 'fy-plate', "
                                         r"'mz-plate'\]"):
        report_forces(path)


def test_fluent_and_openfoam_forces_map_to_the_same_loads(tmp_path):
    """The real OpenFOAM v1912 forces written as a Fluent report give identical loads."""
    case = tmp_path / "case" / "postProcessing" / "forces" / "0"
    case.mkdir(parents=True)
    for name in ("force.dat", "moment.dat"):
        shutil.copy(DATA / "openfoam_v1912" / name, case / name)
    of = read_forces(tmp_path / "case")
    rows = np.column_stack([np.arange(len(of.time)), of.moment[:, 2], of.force[:, 1],
                            of.time, of.force[:, 0]])
    path = tmp_path / "plate-forces.out"
    path.write_text(report_text(["Time Step", "mz-plate", "fy-plate", "flow-time", "fx-plate"],
                                rows))
    fl = report_forces(path)
    motion = HarmonicMotion(1.0, 0.3, np.deg2rad(20), np.pi / 2)
    state = imposed_state(motion, of.time)
    a = to_loads(of, state, 0.18, 0.18, "openfoam")
    b = to_loads(fl, state, 0.18, 0.18, "fluent")
    for k in ("normal_force", "tangential_force", "moment"):
        np.testing.assert_allclose(getattr(b, k), getattr(a, k), rtol=1e-12, atol=1e-12)


@settings(max_examples=150, deadline=None)
@given(cut=st.integers(min_value=0, max_value=400), junk=st.text(max_size=12),
       pos=st.integers(min_value=0, max_value=400))
def test_report_parser_fuzz_never_hangs_or_lies(cut, junk, pos):
    names = ["Time Step", "fx-plate", "flow-time"]
    rows = [[i, np.sin(i), 0.01 * i] for i in range(1, 30)]
    text = report_text(names, rows)
    broken = text[:cut] if cut < len(text) else text
    broken = broken[:pos] + junk + broken[pos:]
    try:
        rep = parse_report(broken, "fuzz.out")
        t = rep.time
        fx_values = rep.columns["fx-plate"]
    except ParseError as exc:
        assert "fuzz.out" in str(exc)
        return
    except KeyError:  # junk renamed the column: the caller asks by name and is refused
        with pytest.raises(ParseError, match="missing column"):
            report_forces_from_text(broken)
        return
    # a successful parse returns only true rows, in order
    assert np.all(np.diff(t) > 0)
    truth = {round(0.01 * i, 9): np.sin(i) for i in range(1, 30)}
    for ti, fx in zip(t, fx_values, strict=True):
        if round(ti, 9) in truth and truth[round(ti, 9)] == fx:
            continue
        # junk may have altered a number into another valid one; it must still be finite
        assert np.isfinite(fx) and np.isfinite(ti)


def report_forces_from_text(text):
    import tempfile

    with tempfile.TemporaryDirectory() as d:
        p = Path(d) / "fuzz.out"
        p.write_text(text)
        return report_forces(p, "fx-plate", "fx-plate", None)


def test_cli_writes_fluent_files_and_parses_a_report(tmp_path):
    from mfflap.cli.main import cli

    case = Path(__file__).parents[3] / "cases" / "paper2026.toml"
    res = CliRunner().invoke(cli, ["cfd", "fluent", str(case), str(tmp_path / "fl"),
                                   "--cycles", "1"])
    assert res.exit_code == 0, res.output
    assert (tmp_path / "fl" / "mfflap_motion.c").exists()
    t = np.linspace(0.01, 1.0, 100)
    path = write_plate_report(tmp_path / "plate-forces.out", t, np.sin(6 * t), np.cos(6 * t),
                              0.1 * t)
    res = CliRunner().invoke(cli, ["cfd", "parse", str(path), "--case-file", str(case),
                                   "--json"])
    assert res.exit_code == 0, res.output
    out = json.loads(res.stdout)  # the report is not beside the UDF: a warning on stderr
    assert out["dialect"] == "fluent-report" and out["n_samples"] == 100
    assert out["inputs_checked_against"] is None and "not checked" in res.stderr


def test_cli_parse_averages_over_time_and_bridges_a_burst(tmp_path):
    """`cfd parse` means are time averages (samples crowd where a solver's steps shrink) and
    a numerical burst is bridged and listed, not averaged in."""
    from mfflap.cli.main import cli

    case = Path(__file__).parents[3] / "cases" / "paper2026.toml"

    def forces(t):
        return np.column_stack([40 * np.sin(2 * np.pi * t) + 15, 30 * np.cos(2 * np.pi * t),
                                2 * np.sin(2 * np.pi * t)])

    def parse(t, f, name):
        path = write_plate_report(tmp_path / f"{name}.out", t, *f.T)
        res = CliRunner().invoke(cli, ["cfd", "parse", str(path), "--case-file", str(case),
                                       "--json"])
        assert res.exit_code == 0, res.output
        return json.loads(res.stdout)

    even = np.linspace(0.0, 2.0, 2001)
    # the same history with ten times as many samples in the first half of each cycle
    crowded = np.unique(np.concatenate([even, np.linspace(0.0, 0.5, 5001),
                                        np.linspace(1.0, 1.5, 5001)]))
    ref, dense = parse(even, forces(even), "even"), parse(crowded, forces(crowded), "dense")
    assert ref["numerical_bursts"] == []
    for key in ("cfd_mean_thrust", "cfd_mean_power", "model_mean_thrust"):
        scale = max(abs(ref[key]), 1.0)
        assert dense[key] == pytest.approx(ref[key], abs=2e-3 * scale), key
    # a burst: 30 steps of a microsecond, forces off by 50,000 N
    i = 1300
    burst_t = even[i] + 1e-6 * np.arange(1, 31)
    burst_f = forces(burst_t) + 5e4 * np.sin(np.pi * np.arange(1, 31) / 31)[:, None]
    t2 = np.concatenate([even[:i + 1], burst_t, even[i + 1:]])
    f2 = np.concatenate([forces(even[:i + 1]), burst_f, forces(even[i + 1:])])
    hit = parse(t2, f2, "burst")
    assert len(hit["numerical_bursts"]) == 1
    assert re.match(r"t = 1\.29\d*-1\.30", hit["numerical_bursts"][0])
    assert hit["cfd_mean_thrust"] == pytest.approx(ref["cfd_mean_thrust"],
                                                   abs=2e-3 * max(abs(ref["cfd_mean_thrust"]), 1))
    assert hit["nrmse_normal_force"] == pytest.approx(ref["nrmse_normal_force"], rel=0.02)


def test_a_new_udf_is_not_written_beside_the_report_of_an_earlier_run(tmp_path):
    """Beside a new UDF an earlier run's report would parse as the new motion's forces: it
    is refused (other files, such as the Fluent case the journal reads, stay welcome); a
    failed write deletes nothing; --overwrite deletes the report only."""
    from mfflap.cfd.fluent.udf import REPORT_FILE
    from mfflap.cli.main import cli
    from mfflap.errors import MotionError
    from mfflap.toml_io import read_toml

    case = Path(__file__).parents[3] / "cases" / "paper2026.toml"
    motion = HarmonicMotion(1.0, 0.3, np.radians(20.0), np.pi / 2)
    folder = tmp_path / "fl"
    write_fluent_case(folder, motion, 1.0)
    (folder / "plate.cas.h5").write_text("the user's Fluent case")
    write_fluent_case(folder, motion, 2.0)  # no report yet: written again, the case kept
    t = np.linspace(0.01, 2.0, 50)
    write_plate_report(folder / REPORT_FILE, t, np.sin(t), np.cos(t), 0 * t)
    with pytest.raises(ConfigError, match=f"holds {REPORT_FILE}, the report of a run"):
        write_fluent_case(folder, motion, 1.0)
    with pytest.raises(MotionError):
        write_fluent_case(folder, motion, -1.0, table=True, overwrite=True)
    assert (folder / REPORT_FILE).exists()
    assert read_toml(folder / "mfflap_fluent.toml")["end_time"] == 2.0
    res = CliRunner().invoke(cli, ["cfd", "fluent", str(case), str(folder), "--cycles", "1"])
    assert res.exit_code == 2 and "--overwrite deletes the report" in res.output
    res = CliRunner().invoke(cli, ["cfd", "fluent", str(case), str(folder), "--cycles", "1",
                                   "--overwrite"])
    assert res.exit_code == 0, res.output
    assert not (folder / REPORT_FILE).exists()
    assert (folder / "plate.cas.h5").read_text() == "the user's Fluent case"
    assert read_toml(folder / "mfflap_fluent.toml")["end_time"] == 1.0


def _pitched_table(path: Path) -> Path:
    """A user's CSV motion that starts pitched (25 deg) and moving, heave offset 0.3 m."""
    t = np.linspace(0.0, 2.0, 201)
    pitch = 25.0 + 20.0 * np.sin(2 * np.pi * t)
    heave = 0.1 + 0.2 * np.cos(2 * np.pi * t)
    path.write_text("time,heave_position,pitch_angle_deg\n" + "".join(
        f"{a!r},{b!r},{c!r}\n" for a, b, c in zip(t.tolist(), heave.tolist(), pitch.tolist(),
                                                   strict=True)))
    return path


def test_the_fluent_udf_and_the_openfoam_table_of_one_csv_impose_one_absolute_motion(
        tmp_path):
    """The table UDF's rates, compiled and integrated from the mesh (as Fluent does), give
    the positions of OpenFOAM's tabulated6DoFMotion table at every row of it: one absolute
    motion, ramped from the mesh at rest, though the CSV starts pitched at 25 deg."""
    from mfflap.cfd.openfoam.writer import motion_table
    from mfflap.kinematics.table_file import read_motion_table

    motion = read_motion_table(_pitched_table(tmp_path / "pitched.csv"))
    ramp, end = 0.3, 2.0
    rows = motion_table(motion, end, ramp_time=ramp)
    rows = rows[rows[:, 0] <= end]
    times = np.linspace(0.0, end, 8001)
    out = run_udf(table_udf(motion, end, ramp_time=ramp), tmp_path, times)
    dt = np.diff(times)
    pitch_deg = np.degrees(np.concatenate([[0.0], np.cumsum(0.5 * dt * (out[1:, 2]
                                                                         + out[:-1, 2]))]))
    heave = np.concatenate([[0.0], np.cumsum(0.5 * dt * (out[1:, 1] + out[:-1, 1]))])
    integrated_pitch = np.interp(rows[:, 0], times, pitch_deg)
    integrated_heave = np.interp(rows[:, 0], times, heave)
    # OpenFOAM's rotation about z and displacement along y, in the case's axes
    np.testing.assert_allclose(integrated_pitch, rows[:, 6], atol=0.05)
    np.testing.assert_allclose(integrated_heave, rows[:, 2], atol=2e-4)
    # past the ramp both follow the CSV's absolute pitch, not the pitch less its first value
    from mfflap.cfd.frames import case_rotation_deg

    after = rows[:, 0] > ramp
    expected = case_rotation_deg(motion.sample(rows[after, 0]).pitch_angle)[:, 2]
    np.testing.assert_allclose(rows[after, 6], expected, atol=1e-6)
    assert np.abs(rows[after, 6]).max() > 40.0  # 25 + 20 deg: the first pitch is kept


def test_a_motion_that_starts_pitched_without_a_ramp_is_refused_by_both_writers(tmp_path):
    """Without a start-up ramp OpenFOAM would jump to the first pitch and Fluent would pitch
    that much less throughout: both writers refuse it, naming the pitch, before writing."""
    from mfflap.cfd.openfoam.writer import write_case
    from mfflap.errors import MotionError
    from mfflap.kinematics.table_file import read_motion_table

    motion = read_motion_table(_pitched_table(tmp_path / "pitched.csv"))
    with pytest.raises(MotionError, match="starts pitched at 25 deg"):
        write_fluent_case(tmp_path / "fluent", motion, 2.0)
    with pytest.raises(MotionError, match="starts pitched at 25 deg"):
        write_case(tmp_path / "openfoam", motion, 2.0)
    assert not (tmp_path / "fluent").exists() and not (tmp_path / "openfoam").exists()
    from mfflap.cli.main import cli

    case = Path(__file__).parents[3] / "cases" / "paper2026.toml"
    res = CliRunner().invoke(cli, ["cfd", "fluent", str(case), str(tmp_path / "f"),
                                   "--motion-table", str(tmp_path / "pitched.csv")])
    assert res.exit_code == 2 and "--ramp-time" in res.output


def test_a_plate_pitching_about_mid_chord_turns_about_it_and_reports_moments_about_it(tmp_path):
    """The journal puts the rigid body's centre of gravity at the pivot (the case's leading
    edge at the origin); the report's moments about the origin, read back beside the UDF, are
    moved to the moving pivot: a force acting there has no moment about it."""
    from mfflap.cfd.fluent.solver import Fluent
    from mfflap.parameters import Plate

    plate = Plate(pivot_chord_fraction=0.5)
    motion = HarmonicMotion(1.0, 0.2, np.deg2rad(20), np.pi / 2)
    folder = write_fluent_case(tmp_path / "fl", motion, 2.0, time_step=2e-3, plate=plate)
    create = next(ln for ln in (folder / "mfflap_run.jou").read_text().splitlines()
                  if ln.startswith("/define/dynamic-mesh/zones/create"))
    assert create.endswith(" yes 0.08 0 no no"), create
    t = np.linspace(0.0, 2.0, 401)
    heave = imposed_state(motion, t).heave_position
    fx, fy = 3.0 + np.sin(5 * t), -2.0 + np.cos(3 * t)
    report = write_plate_report(folder / "plate-forces.out", t, fx, fy,
                                0.08 * fy - heave * fx)  # r_P x F, r_P = (x_p, h)
    run = Fluent().read_forces(report)
    assert run.pivot_m == pytest.approx((0.08, 0.0))
    loads = to_loads(run.history, imposed_state(motion, run.history.time), plate.span,
                     run.depth_m, "fluent", pivot_m=run.pivot_m)
    np.testing.assert_allclose(loads.moment, 0.0, atol=1e-12)
    assert np.max(np.abs(loads.normal_force)) > 0.1  # 0.18 m of span from the 1 m report


def test_one_wrong_flow_time_is_an_error_naming_its_line_not_a_restart():
    """1,500 rows of 2 ms; row 1,000's flow time written 0.2 for 2.0 s. Read as a restart it
    would drop the 900 rows after 0.2 s; the Time Step column does not go back, so it is
    an error naming the line."""
    names = ["Time Step", "fx-plate", "fy-plate", "flow-time"]
    rows = [[i, 0.1, -0.072, 0.002 * i] for i in range(1, 1501)]
    rows[999][3] = 0.2  # 2.0 s, mistyped
    with pytest.raises(ParseError, match=r"w\.out, line 1003: flow-time goes back from "
                                         r"1\.998 s to 0\.2 s, but this is no restart"):
        parse_report(report_text(names, rows), "w.out")
    no_steps = report_text(["flow-time", "fx-plate"], [[r[3], r[1]] for r in rows])
    with pytest.raises(ParseError, match="no Time Step column"):
        parse_report(no_steps, "w.out")


def test_a_restart_from_a_step_the_report_did_not_write_is_a_restart():
    """Rows every 5 steps of 0.01 s; the run restarts from its data at step 42 (not a
    written row) and writes steps 43, 48, ...: the rows after 0.42 s written before are
    replaced by the restarted ones."""
    names = ["Time Step", "fx-plate", "flow-time"]
    rows = [[s, 1.0, 0.01 * s] for s in range(5, 80, 5)]
    rows += [[s, 2.0, 0.01 * s] for s in range(43, 100, 5)]
    rep = parse_report(report_text(names, rows), "r.out")
    assert np.all(np.diff(rep.time) > 0)
    assert rep.time[rep.columns["fx-plate"] == 1.0].max() == pytest.approx(0.40)
    assert rep.time[rep.columns["fx-plate"] == 2.0].min() == pytest.approx(0.43)
