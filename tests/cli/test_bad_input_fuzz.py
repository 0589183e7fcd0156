"""Bad input never ends in a traceback: case files, motion CSVs and options mutated at
random (hypothesis) give exit status 0 or 2 and, on 2, an error of one line of at most a few
hundred characters."""

from pathlib import Path
from tempfile import mkdtemp

import pytest
from click.testing import CliRunner
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from mfflap.cli.main import cli

CASE = Path(__file__).parents[2] / "cases" / "paper2026.toml"
CASE_LINES = CASE.read_text().splitlines()
#: values a mutated setting may take: wrong types, extremes, junk
VALUES = st.sampled_from(["0", "-1", "1e308", "-1e308", "nan", "inf", '"x"', "[]", "{}",
                          "true", "1e-320", '"' + "z" * 5000 + '"', "", "[1, 2", "0.3.4"])
CSV_CELLS = st.sampled_from(["0", "-1", "1e308", "nan", "x", "", "1,5", "١٢", "1_000",
                             "0.1", "1e-3", "-1e308", "inf"])
FUZZ = settings(max_examples=20, deadline=None,
                suppress_health_check=[HealthCheck.function_scoped_fixture])


def _check(res) -> None:
    assert res.exit_code in (0, 2), (res.exit_code, res.output[-2000:], res.exception)
    assert "Traceback" not in res.output
    if res.exit_code == 2:
        error = [line for line in res.output.splitlines()
                 if line.startswith(("Error", "mfflap: error"))]
        assert error, res.output[-2000:]
        assert len(error[0]) <= 400, error[0][:500]


@FUZZ
@given(line=st.integers(0, len(CASE_LINES) - 1), value=VALUES,
       mode=st.sampled_from(["value", "drop", "duplicate", "garble"]))
def test_a_mutated_case_file_is_read_or_refused_in_one_line(tmp_path, line, value, mode):
    lines = list(CASE_LINES)
    target = lines[line]
    if mode == "value" and "=" in target:
        key = target.split("=", 1)[0]
        lines[line] = f"{key}= {value}"
    elif mode == "drop":
        del lines[line]
    elif mode == "duplicate":
        lines.insert(line, target)
    else:
        lines[line] = target[: len(target) // 2] + value
    case = tmp_path / "case.toml"
    case.write_text("\n".join(lines) + "\n")
    _check(CliRunner().invoke(cli, ["case", "show", str(case)]))


@pytest.mark.slow
@FUZZ
@given(header=st.sampled_from(["t,theta [deg],h", "time,heave_position,pitch_angle",
                               "t;theta;h", "t,theta [furlongs],h", "h,h,h", "t,x,y", ""]),
       rows=st.lists(st.lists(CSV_CELLS, min_size=2, max_size=4), min_size=0, max_size=8))
def test_a_mutated_motion_csv_is_written_or_refused_in_one_line(tmp_path, header, rows):
    table = tmp_path / "m.csv"
    good = [f"{0.05 * k:g},{5.0 * (k % 3)},{0.01 * k}" for k in range(6)]
    table.write_text("\n".join([header, *good[:3], *(",".join(r) for r in rows), *good[3:]])
                     + "\n")
    _check(CliRunner().invoke(cli, ["cfd", "write", str(CASE), mkdtemp(dir=tmp_path),
                                    "--motion-table", str(table), "--ramp-time", "0.05"]))


@pytest.mark.slow
@FUZZ
@given(option=st.sampled_from(["--cycles", "--ramp-time", "--mesh", "--setup",
                               "cfd.max_courant", "cfd.writes", "cfd.frame", "cfd.procs"]),
       value=st.sampled_from(["0", "-3", "1e9", "nan", "inf", "x", "", "1e-320",
                              "z" * 5000, '"plate"', "[1, 2]"]))
def test_mutated_options_are_refused_in_one_line(tmp_path, option, value):
    given = ([option, value] if option.startswith("--")
             else ["--set", f"{option}={value}"])
    _check(CliRunner().invoke(cli, ["cfd", "write", str(CASE), mkdtemp(dir=tmp_path),
                                    *given]))
