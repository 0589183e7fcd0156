"""A user's motion table (CSV): reading it, its refusals (file and line), fuzzing, and the
cases written from it: OpenFOAM (run for real and parsed), Fluent (UDF compiled and run)."""

import json
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from motion_tables import HEAVE, PITCH_DEG, T, write_table

from mfflap.cfd.imposed_motion import imposed_state
from mfflap.cfd.openfoam.runner import openfoam_available
from mfflap.cfd.openfoam.writer import MOTION_TABLE_FILE
from mfflap.cli.main import cli
from mfflap.errors import MotionError, ParseError
from mfflap.kinematics import TabulatedMotion
from mfflap.kinematics.table_file import largest_pitch, read_motion_table, table_end_time
from mfflap.toml_io import read_toml

CASE = Path(__file__).parents[2] / "cases" / "paper2026.toml"
def test_a_table_in_degrees_or_radians_is_the_same_smooth_motion(tmp_path):
    motion = read_motion_table(write_table(tmp_path / "deg.csv"))
    radians = read_motion_table(write_table(tmp_path / "rad.csv", "pitch_angle", False))
    s = motion.sample(T)
    np.testing.assert_allclose(s.heave_position, HEAVE, atol=1e-15)
    np.testing.assert_allclose(s.pitch_angle, np.radians(PITCH_DEG), atol=1e-15)
    np.testing.assert_allclose(radians.sample(T).pitch_angle, s.pitch_angle, atol=1e-15)
    # the cubic spline's rates: close to the exact ones away from the ends
    mid = np.linspace(0.2, 1.8, 33)
    exact_rate = 0.2 * np.pi * np.sin(4 * np.pi * mid)
    assert np.max(np.abs(motion.sample(mid).heave_velocity - exact_rate)) < 1e-3
    exact_pitch_rate = np.radians(8.0 * np.pi * np.sin(np.pi * mid))
    assert np.max(np.abs(motion.sample(mid).pitch_rate - exact_pitch_rate)) < 1e-4
    # past the last row the table is held at rest: what a solver's padding rows see
    past = motion.sample(np.array([2.0, 2.1, 3.0]))
    assert np.all(past.heave_position == past.heave_position[0])
    assert np.all(past.heave_velocity[1:] == 0) and np.all(past.pitch_acceleration[1:] == 0)
    with pytest.raises(MotionError, match="leave the table's range"):
        TabulatedMotion(T, HEAVE, HEAVE).sample(np.array([2.5]))
    assert table_end_time(motion) == 2.0 and table_end_time(motion, 1.5) == 1.5
    with pytest.raises(MotionError, match=r"\(0, 2\] s"):
        table_end_time(motion, 2.5)


@pytest.mark.parametrize(("edit", "message", "line"), [
    (lambda ls: [ls[0], "time,heave_position,note,x", *ls[2:]],
     r"missing column\(s\) for pitch_angle \(as theta or pitch or pitch_angle\)", 2),
    (lambda ls: [ls[0], "time,pitch_angle_deg,note,x", *ls[2:]], r"missing column.*"
                                                                  "heave_position", 2),
    (lambda ls: [*ls[:2], "time,pitch_angle,pitch_angle_deg,heave_position", *ls[3:]],
     "4 values for 4 columns|unreadable", None),
    (lambda ls: [*ls[:10], "0.1,0.2,oops,0", *ls[10:]], "unreadable number", 11),
    (lambda ls: [*ls[:10], "0.1,0.2,nan,0", *ls[10:]], "pitch_angle_deg is not finite", 11),
    # numbers float() takes but no solver writes
    (lambda ls: [*ls[:10], "1_000," + ls[10].split(",", 1)[1], *ls[11:]],
     "'1_000' is not a plain decimal", 11),
    (lambda ls: [*ls[:10], "\u0661\u0662," + ls[10].split(",", 1)[1], *ls[11:]],
     "is not a plain decimal", 11),
    # values beyond any flapping motion
    (lambda ls: [*ls[:10], "1e6," + ls[10].split(",", 1)[1], *ls[11:]],
     "heave_position 1e\\+06 is beyond 100 m", 11),
    (lambda ls: [*ls[:10], ",".join([*ls[10].split(",")[:2], "-1e308", "0"]), *ls[11:]],
     "pitch_angle_deg -1e\\+308 is beyond 180 deg", 11),
    (lambda ls: [*ls[:12], ls[11], *ls[12:]], "does not increase", 13),
    (lambda ls: [*ls[:2], *ls[3:]], "must start at t = 0 s", 3),
    (lambda ls: ls[:5], "a motion table needs at least 4", 5),
    (lambda ls: ls[:2], "no data rows", 2),
    (lambda ls: ["# only a comment"], "no header line", None),
    (lambda ls: [*ls[:6], "0.1,0.2", *ls[6:]], "2 values for 4 columns", 7),
])
def test_bad_tables_are_refused_naming_file_and_line(tmp_path, edit, message, line):
    good = write_table(tmp_path / "good.csv").read_text().splitlines()
    bad = tmp_path / "bad.csv"
    bad.write_text("\n".join(edit(good)) + "\n")
    with pytest.raises(ParseError, match=message) as info:
        read_motion_table(bad)
    assert "bad.csv" in str(info.value)
    if line is not None:
        assert info.value.line == line, str(info.value)


@pytest.mark.parametrize(("name", "encode"), [
    ("excel_utf8", lambda text: b"\xef\xbb\xbf" + text.encode()),  # Excel's "CSV UTF-8"
    ("semicolons", lambda text: text.replace(",", ";").encode()),  # spreadsheets in many
    ("tabs", lambda text: text.replace(",", "\t").encode()),       # locales
    ("windows", lambda text: text.replace("\n", "\r\n").encode()),
    ("spaced", lambda text: text.replace(",", ", ").encode())])
def test_a_table_saved_by_a_spreadsheet_reads_as_the_same_motion(tmp_path, name, encode):
    """Before: the byte-order mark became part of the first column's name, and semicolons
    or tabs made the header one column, each refused as 'missing column'."""
    plain = read_motion_table(write_table(tmp_path / "plain.csv"))
    saved = tmp_path / f"{name}.csv"
    saved.write_bytes(encode(write_table(tmp_path / "src.csv").read_text()))
    motion = read_motion_table(saved)
    np.testing.assert_array_equal(motion.table_time, plain.table_time)
    kept, exact = motion.sample(T), plain.sample(T)
    np.testing.assert_array_equal(kept.heave_position, exact.heave_position)
    np.testing.assert_array_equal(kept.pitch_angle, exact.pitch_angle)


def test_a_decimal_comma_is_refused_with_the_reason(tmp_path):
    text = write_table(tmp_path / "src.csv").read_text().replace(",", ";")
    lines = text.splitlines()
    lines[3] = lines[3].replace(".", ",")  # the second data row, in a comma-decimal locale
    path = tmp_path / "comma.csv"
    path.write_text("\n".join(lines) + "\n")
    with pytest.raises(ParseError, match=r"the decimal mark is '\.', not ','") as info:
        read_motion_table(path)
    assert info.value.line == 4 and "comma.csv" in str(info.value)


def test_a_binary_file_is_refused(tmp_path):
    path = tmp_path / "motion.csv"
    path.write_bytes(b"\x89HDF\r\n\x1a\n\xff\xfe")
    with pytest.raises(ParseError, match=r"motion\.csv"):
        read_motion_table(path)


@settings(max_examples=80, deadline=None, suppress_health_check=[HealthCheck.too_slow,
                                                                  HealthCheck.function_scoped_fixture])
@given(cut=st.integers(0, 4000), junk=st.text(max_size=12), pos=st.integers(0, 4000))
def test_table_reader_fuzz_never_hangs_or_lies(tmp_path, cut, junk, pos):
    """Truncated or garbled: a clear error naming the file, or a motion that agrees with
    the intact table on every row it kept."""
    text = write_table(tmp_path / "t.csv").read_text()
    text = text[:cut]
    text = text[:pos] + junk + text[pos:]
    path = tmp_path / "fuzz.csv"
    path.write_text(text)
    try:
        motion = read_motion_table(path)
    except ParseError as exc:
        assert "fuzz.csv" in str(exc)
        return
    kept = motion.table_time
    rows = np.searchsorted(T, kept)
    exact = (rows < len(T)) & np.isclose(T[np.minimum(rows, len(T) - 1)], kept, rtol=0,
                                         atol=0)
    # every row that kept its time kept its values unless the junk edited that row
    s = motion.sample(kept[exact])
    changed = np.abs(s.heave_position - HEAVE[rows[exact]]) > 1e-12
    assert changed.sum() <= 1


def test_cfd_write_and_fluent_from_a_table(tmp_path):
    """The OpenFOAM case imposes the table (heave from zero, pitch in degrees about z) and
    keeps it; the Fluent UDF is table-driven and follows it."""
    from fluent_files import compile_syntax, run_udf

    table = write_table(tmp_path / "motion.csv")
    case_dir = tmp_path / "of"
    res = CliRunner().invoke(cli, ["cfd", "write", str(CASE), str(case_dir), "--motion-table",
                                   str(table), "--end-time", "1.5"])
    assert res.exit_code == 0, res.output
    meta = read_toml(case_dir / "mfflap_case.toml")
    assert meta["end_time"] == 1.5 and meta["motion_table"] == MOTION_TABLE_FILE
    assert (case_dir / MOTION_TABLE_FILE).read_text() == table.read_text()
    text = (case_dir / "constant" / "motion.dat").read_text().splitlines()
    rows = np.array([[float(v) for v in line.replace("(", " ").replace(")", " ").split()]
                     for line in text[2:-1]])
    imposed = read_motion_table(table).sample(rows[:, 0])  # held past the last row
    moving = np.abs(rows[:, 1:4]).max(axis=0).argmax()  # the heave axis of the case
    np.testing.assert_allclose(np.abs(rows[:, 1 + moving]), imposed.heave_position,
                               rtol=1e-7, atol=1e-9)  # 9 digits written (t too)
    np.testing.assert_allclose(np.abs(rows[:, 6]), np.degrees(imposed.pitch_angle),
                               rtol=1e-7, atol=1e-9)
    assert rows[-1, 0] > 1.5 * 1.1  # padding rows past the end
    res = CliRunner().invoke(cli, ["cfd", "write", str(CASE), str(tmp_path / "x"),
                                   "--motion-table", str(table), "--end-time", "3"])
    assert res.exit_code == 2 and "(0, 2] s" in res.output
    res = CliRunner().invoke(cli, ["cfd", "write", str(CASE), str(tmp_path / "y"),
                                   "--end-time", "3"])
    assert res.exit_code == 2 and "--end-time goes with --motion-table" in res.output
    fluent_dir = tmp_path / "fl"
    res = CliRunner().invoke(cli, ["cfd", "fluent", str(CASE), str(fluent_dir),
                                   "--motion-table", str(table)])
    assert res.exit_code == 0, res.output
    source = (fluent_dir / "mfflap_motion.c").read_text()
    for nd in (2, 3):
        compile_syntax(source, tmp_path, nd)
    times = np.linspace(0.0, 1.9, 39)
    out = run_udf(source, tmp_path, times)
    exact = imposed_state(read_motion_table(table), times)
    scale = np.abs(exact.heave_velocity).max()
    assert np.max(np.abs(np.abs(out[:, 0] + out[:, 1]) - np.abs(exact.heave_velocity))) < (
        1e-2 * scale)
    assert np.max(np.abs(np.abs(out[:, 2]) - np.abs(exact.pitch_rate))) < (
        1e-2 * np.abs(exact.pitch_rate).max())


def test_degrees_in_the_radian_column_are_refused_naming_the_line(tmp_path):
    """Degrees written under ``pitch_angle`` (which is in rad, so up to 16 rad here) are
    refused at the first row beyond the upright (pi / 2 rad: no unit named), with the line
    and the column to use; the same
    numbers under ``pitch_angle_deg`` are a motion, written without a warning."""
    degrees = write_table(tmp_path / "deg.csv")
    wrong = tmp_path / "wrong.csv"
    wrong.write_text(degrees.read_text().replace("pitch_angle_deg", "pitch_angle"))
    with pytest.raises(ParseError) as info:
        read_motion_table(wrong)
    first = next(i for i, line in enumerate(wrong.read_text().splitlines(), start=1)
                 if line[:1].isdigit() and abs(float(line.split(",")[2])) > np.pi / 2)
    assert info.value.path == str(wrong) and info.value.line == first
    assert "'pitch_angle [deg]'" in str(info.value)
    assert largest_pitch(read_motion_table(degrees), 2.0)[0] == pytest.approx(np.radians(16))
    runner = CliRunner()
    res = runner.invoke(cli, ["cfd", "write", str(CASE), str(tmp_path / "w"),
                              "--motion-table", str(wrong)])
    assert res.exit_code == 2 and f"{wrong}, line {first}" in res.output
    res = runner.invoke(cli, ["cfd", "write", str(CASE), str(tmp_path / "d"),
                              "--motion-table", str(degrees)])
    assert res.exit_code == 0 and "warning" not in res.stderr


def test_a_pitch_past_upright_is_written_with_a_warning(tmp_path):
    """A pitch of -90 deg or less is written, with a warning naming the file, the pitch and
    its time; the Fluent UDF's writer warns the same way."""
    degrees = write_table(tmp_path / "deg.csv")
    runner = CliRunner()
    # a pitch of -90 deg or less counts as well; the Fluent UDF's writer warns the same way
    upright = tmp_path / "upright.csv"
    rows = [line.split(",") for line in degrees.read_text().splitlines()]
    rows = [[*row[:2], "-90.0", *row[3:]] if row[1:2] == ["0.5"] else row for row in rows]
    upright.write_text("\n".join(",".join(row) for row in rows) + "\n")
    assert largest_pitch(read_motion_table(upright), 2.0) == (pytest.approx(-np.pi / 2),
                                                              pytest.approx(0.5))
    res = runner.invoke(cli, ["cfd", "fluent", str(CASE), str(tmp_path / "f"),
                              "--motion-table", str(upright)])
    assert res.exit_code == 0, res.output
    assert "the pitch reaches -90 deg at t = 0.5 s" in res.stderr


def test_a_spline_that_turns_past_upright_between_rows_is_flagged(tmp_path):
    """Rows at most 89.5 deg, but the spline through them peaks at 93.2 deg between the two
    rows at 89.5 deg: the solver follows the spline, so that is the pitch warned of."""
    table = tmp_path / "peak.csv"
    table.write_text("time,heave_position,pitch_angle_deg\n" + "".join(
        f"{t},0.0,{p}\n" for t, p in zip([0, 0.1, 0.2, 0.3, 0.4, 0.5],
                                         [0, 60, 89.5, 89.5, 60, 0], strict=True)))
    motion = read_motion_table(table)
    assert np.degrees(np.abs(motion.sample(motion.table_time).pitch_angle).max()) == 89.5
    pitch, time = largest_pitch(motion, 0.5)
    fine = np.linspace(0.0, 0.5, 20001)
    assert np.degrees(pitch) == pytest.approx(
        np.degrees(np.abs(motion.sample(fine).pitch_angle).max()), abs=0.01)
    assert np.degrees(pitch) > 93.0 and time == pytest.approx(0.25, abs=0.01)
    res = CliRunner().invoke(cli, ["cfd", "write", str(CASE), str(tmp_path / "w"),
                                   "--motion-table", str(table)])
    assert res.exit_code == 0, res.output
    assert f"warning: {table}: the pitch reaches 93.16 deg at t = 0.25 s" in res.stderr


@pytest.mark.openfoam
def test_a_table_motion_runs_in_openfoam_and_parses_from_its_own_case(tmp_path):
    """Write from a table, run pimpleFoam on the coarse mesh, parse the case with nothing
    but the case file (the case keeps its table): the forces follow the model's."""
    assert openfoam_available()
    table = write_table(tmp_path / "motion.csv")
    case_dir = tmp_path / "of"
    runner = CliRunner()
    res = runner.invoke(cli, ["cfd", "write", str(CASE), str(case_dir), "--motion-table",
                              str(table), "--end-time", "0.25"])
    assert res.exit_code == 0, res.output
    res = runner.invoke(cli, ["cfd", "run", str(case_dir), "--json"])
    assert res.exit_code == 0, res.output
    res = runner.invoke(cli, ["cfd", "parse", str(case_dir), "--case-file", str(CASE),
                              "--discard", "0.05", "--json"])
    assert res.exit_code == 0, res.output
    out = json.loads(res.stdout)
    assert out["end_time"] == pytest.approx(0.25, abs=1e-3)
    assert out["pearson_normal_force"] > 0.9, out
    res = runner.invoke(cli, ["cfd", "parse", str(case_dir), "--case-file", str(CASE),
                              "--motion-table", str(table)])
    assert res.exit_code == 2 and "keeps its own motion table" in res.output


@pytest.mark.slow
def test_an_optimised_motion_becomes_a_table_and_the_same_case_as_the_back_test(
        tmp_path, optimisation_file):
    """cfd motion-table then cfd write --motion-table imposes what the back-test imposes
    (the periodic spline through the optimised cycle), to within the written digits."""
    from mfflap.backtest.run import cfd_motion
    from mfflap.cfd.openfoam.writer import motion_table
    from mfflap.optimisation.store import read_result
    from mfflap.results import ResultsFile

    table = tmp_path / "opt.csv"
    res = CliRunner().invoke(cli, ["cfd", "motion-table", str(optimisation_file), str(table),
                                   "--beta", "0.5", "--cycles", "2"])
    assert res.exit_code == 0, res.output
    assert "does not start at rest" in res.output and "--ramp-time" in res.output
    sine = CliRunner().invoke(cli, ["cfd", "motion-table", str(optimisation_file),
                                    str(tmp_path / "sine.csv"), "--best-sinusoid"])
    assert sine.exit_code == 0, sine.output
    # a sinusoid starts at pitch 0: its round-off (1e-15 deg) is not shown as a pitch
    assert "it does not start at rest (pitch rate " in sine.output, sine.output
    with ResultsFile(optimisation_file) as rf:
        spline = cfd_motion(read_result(rf, "optimisation/sqp/beta_0.50").motion)
    motion = read_motion_table(table)
    assert motion.table_time[-1] == pytest.approx(2 * spline.period)
    t = np.linspace(0.0, 2 * spline.period, 977)
    exact, got = spline.sample(t), motion.sample(t)
    for name in ("heave_position", "pitch_angle", "heave_velocity", "pitch_rate"):
        scale = np.abs(getattr(exact, name)).max()
        assert np.max(np.abs(getattr(got, name) - getattr(exact, name))) < 1e-4 * scale, name
    ramp = 0.5 * spline.period
    res = CliRunner().invoke(cli, ["cfd", "write", str(CASE), str(tmp_path / "of"),
                                   "--motion-table", str(table), "--ramp-time", str(ramp)])
    assert res.exit_code == 0, res.output
    end = 2 * spline.period
    written = (tmp_path / "of" / "constant" / "motion.dat").read_text().splitlines()[2:-1]
    rows = np.array([[float(v) for v in line.replace("(", " ").replace(")", " ").split()]
                     for line in written])
    back_test = motion_table(spline, end, ramp_time=ramp)
    inside = rows[:, 0] <= end
    np.testing.assert_allclose(rows[inside], back_test[inside],
                               atol=1e-6 * np.abs(back_test[:, 1:]).max())
    res = CliRunner().invoke(cli, ["cfd", "motion-table", str(optimisation_file), str(table),
                                   "--beta", "0.3"])
    assert res.exit_code == 2 and "has β = 0.5" in res.output
    res = CliRunner().invoke(cli, ["cfd", "motion-table", str(optimisation_file), str(table)])
    assert res.exit_code == 2 and "--beta B or --best-sinusoid" in res.output
    res = CliRunner().invoke(cli, ["cfd", "motion-table", str(optimisation_file), str(table),
                                   "--beta", "0.5", "--best-sinusoid"])
    assert res.exit_code == 2 and "not both" in res.output
    res = CliRunner().invoke(cli, ["cfd", "motion-table", str(optimisation_file), str(table),
                                   "--best-sinusoid"])
    assert res.exit_code == 0 and read_motion_table(table).table_time[-1] > 0


@pytest.mark.openfoam
def test_a_mesh_study_of_a_table_motion(tmp_path):
    """cfd convergence on a table: two meshes, real pimpleFoam, to the table's given end."""
    assert openfoam_available()
    table = write_table(tmp_path / "motion.csv")
    res = CliRunner().invoke(cli, ["cfd", "convergence", str(CASE), str(tmp_path / "c"),
                                   "--motion-table", str(table), "--end-time", "0.03",
                                   "--meshes", "coarse,lean", "--courant", "4", "--json"])
    assert res.exit_code == 0, res.output
    data = json.loads(res.output[res.output.index("{"):])
    assert set(data["runs"]) == {"coarse_co4", "lean_co4"}
    assert 0 <= data["nrmse"]["coarse_co4 vs lean_co4"]["normal_force"] < 0.5
    assert "motion table motion.csv, 0.03 s" in (tmp_path / "c" / "convergence.html").read_text()
    assert data["phase_nrmse"] == {}  # a table is not periodic: no mean cycles


def _rows(path, header, heave, pitch):
    t = np.linspace(0.0, 1.0, 11)
    path.write_text(header + "\n" + "".join(
        f"{a:.3f},{b:.6g},{c:.6g}\n" for a, b, c in zip(
            t, heave * np.sin(2 * np.pi * t), pitch * np.cos(2 * np.pi * t), strict=True)))
    return path


def test_a_heave_in_millimetres_without_its_unit_is_refused_and_read_with_it(tmp_path):
    """±50 under ``h`` (no unit: metres) is 300 chords of the plate: refused, naming the
    line and the unit to name; under ``h [mm]`` it is a 5 cm heave. A heave beyond ten
    chords with its unit named is taken as given."""
    bare = _rows(tmp_path / "bare.csv", "t,h,theta [deg]", 50.0, 20.0)
    with pytest.raises(ParseError) as refused:
        read_motion_table(bare)
    assert refused.value.line == 3 and "'h [mm]'" in str(refused.value)
    assert "10 chords" in str(refused.value)
    named = _rows(tmp_path / "mm.csv", "t,h [mm],theta [deg]", 50.0, 20.0)
    row = np.sin(2 * np.pi * 0.3)  # a row's heave, a fraction of the amplitude
    heave = read_motion_table(named).sample(np.array([0.3])).heave_position
    assert heave == pytest.approx([0.05 * row], rel=1e-5)
    large = _rows(tmp_path / "m.csv", "t,h [m],theta [deg]", 5.0, 20.0)
    assert read_motion_table(large).sample(np.array([0.3])).heave_position == \
        pytest.approx([5.0 * row], rel=1e-5)
    # against the plate the caller names: 1 m is 10 chords of a 10 cm plate, 2 m is not
    metre = _rows(tmp_path / "metre.csv", "t,h,theta [deg]", 1.5, 20.0)
    read_motion_table(metre, chord=0.2)
    with pytest.raises(ParseError, match=r"10 chords of 0\.1 m"):
        read_motion_table(metre, chord=0.1)


def test_a_small_pitch_in_degrees_without_its_unit_is_refused(tmp_path):
    """A pitch of ±3 under ``theta`` (no unit: radians) passes the upright: refused as
    degrees taken for radians; under ``theta [rad]`` it is taken as given."""
    bare = _rows(tmp_path / "bare.csv", "t,h,theta", 0.1, 3.0)
    with pytest.raises(ParseError) as refused:
        read_motion_table(bare)
    assert refused.value.line == 2 and "'theta [deg]'" in str(refused.value)
    named = _rows(tmp_path / "rad.csv", "t,h,theta [rad]", 0.1, 3.0)
    assert largest_pitch(read_motion_table(named), 1.0)[0] == pytest.approx(3.0, rel=1e-3)


def test_numpy_savetxt_s_commented_header_is_the_header(tmp_path):
    """``numpy.savetxt(..., header="t,h,theta")`` writes ``# t,h,theta`` over the rows:
    the comment is the header, and the motion reads as written."""
    t = np.linspace(0.0, 1.0, 21)
    data = np.column_stack([t, 0.1 * np.sin(2 * np.pi * t), 0.3 * np.cos(2 * np.pi * t)])
    path = tmp_path / "saved.csv"
    np.savetxt(path, data, delimiter=",", header="t,h,theta")
    motion = read_motion_table(path)
    state = motion.sample(t)
    assert state.heave_position == pytest.approx(data[:, 1])
    assert state.pitch_angle == pytest.approx(data[:, 2])


@pytest.mark.parametrize("text, says", [
    ("t h theta\n0 0 0\n0.1 0.01 0.02\n0.2 0.02 0.01\n0.3 0 0\n",
     "separated by ',', ';' or a tab"),
    ("t,h,theta\n0,0,0\n0.1 0.01 0.02\n0.2,0.02,0.01\n0.3,0,0\n",
     "a file may use ',', ';' or a tab"),
])
def test_a_file_separated_by_spaces_is_told_which_separators_work(tmp_path, text, says):
    path = tmp_path / "spaces.csv"
    path.write_text(text)
    with pytest.raises(ParseError) as refused:
        read_motion_table(path)
    assert says in str(refused.value) and str(path) in str(refused.value)
