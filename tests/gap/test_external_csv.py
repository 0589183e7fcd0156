"""External (motion, force) CSV files for the gap diagnosis (mfflap.gap.external): the
parameters a file states, the set-up checked against the case file, folders of files, and
the leave-one-group-out checks said to be skipped when the cases cannot be grouped."""

from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from mfflap.cli.main import cli
from mfflap.config import load_case
from mfflap.errors import ConfigError, ParseError
from mfflap.gap.blindtest import NULL, synthesize
from mfflap.gap.diagnose import diagnose
from mfflap.gap.external import csv_parameters, csv_paths, read_csv_case
from mfflap.hydro import MorisonModel

CASE = Path(__file__).parents[2] / "cases" / "paper2026.toml"
HEADER = "time,pitch_angle,heave_position,normal_force,tangential_force,moment"


def _write_csv(path: Path, case, comments: list[str]) -> Path:
    """A synthetic case as a CSV file, its loads the model's plus a little noise."""
    rows = [*comments, HEADER]
    s, cfd = case.state, case.cfd
    rows += [",".join(repr(float(v)) for v in values) for values in zip(
        s.time, s.pitch_angle, s.heave_position, cfd.normal_force, cfd.tangential_force,
        cfd.moment, strict=True)]
    path.write_text("\n".join(rows) + "\n")
    return path


def test_a_csv_file_states_its_motion_and_set_up_before_its_header(tmp_path):
    path = tmp_path / "run.csv"
    path.write_text("# from a Fluent run\n# frequency = 1.5\n# velocity: 0.5\n"
                    "# phase_deg = 90  \n" + HEADER + "\n0,0,0,0,0,0\n# frequency = 9\n")
    assert csv_parameters(path) == {"frequency": 1.5, "velocity": 0.5, "phase_deg": 90.0}
    path.write_text("# frequency = fast\n" + HEADER + "\n")
    with pytest.raises(ParseError, match=r"run\.csv, line 1: parameter frequency: 'fast'"):
        csv_parameters(path)
    path.write_text("# frequency = 1\n# frequency = 2\n" + HEADER + "\n")
    with pytest.raises(ParseError, match="line 2: parameter frequency given twice"):
        csv_parameters(path)


def test_a_run_of_another_stream_or_plate_is_refused_naming_the_file_and_key(tmp_path):
    config = load_case(CASE)
    data = synthesize(np.random.default_rng(0), NULL, 0.0, n_cases=1)
    other = config.flow.velocity * 1.2
    path = _write_csv(tmp_path / "other.csv", data[0], [f"# velocity = {other}"])
    with pytest.raises(ConfigError) as err:
        read_csv_case(path, config=config)
    assert err.value.key == "velocity" and str(path) in str(err.value)
    assert "[flow] velocity" in str(err.value)
    same = _write_csv(tmp_path / "same.csv", data[0],
                      [f"# velocity = {config.flow.velocity}", f"# chord = {config.plate.chord}",
                       "# frequency = 0.5"])
    case = read_csv_case(same, config=config)
    assert case.parameters["frequency"] == 0.5
    assert read_csv_case(same, {"frequency": 2.0}).parameters["frequency"] == 2.0


def test_a_folder_gives_its_csv_files_and_an_empty_one_is_refused(tmp_path):
    for name in ("b.csv", "a.csv", "notes.txt"):
        (tmp_path / name).write_text("")
    assert [p.name for p in csv_paths([tmp_path])] == ["a.csv", "b.csv"]
    empty = tmp_path / "empty"
    empty.mkdir()
    with pytest.raises(ParseError, match="holds no"):
        csv_paths([empty])


def test_leave_one_group_out_says_why_it_did_not_run():
    data = synthesize(np.random.default_rng(1), NULL, 0.0, n_cases=8)
    model = MorisonModel()
    for c in data[:3]:
        c.parameters.pop("frequency")
    diag = diagnose(data, model)
    why = diag.validation_skipped["leave-one-frequency-out"]
    assert why.startswith("3 of 8 cases give no frequency")
    assert "leave-one-frequency-out" not in diag.validation
    for c in data:
        c.parameters["frequency"] = 1.0
    diag = diagnose(data, model)
    assert "the same frequency" in diag.validation_skipped["leave-one-frequency-out"]


@pytest.mark.slow
def test_gap_diagnose_reads_a_folder_of_csv_files_with_their_frequencies(tmp_path):
    data = synthesize(np.random.default_rng(2), NULL, 0.0, n_cases=6)
    folder = tmp_path / "runs"
    folder.mkdir()
    for c in data:
        _write_csv(folder / f"{c.name}.csv", c,
                   [f"# frequency = {float(c.parameters['frequency'])!r}",
                    f"# heave_amplitude = {float(c.parameters['heave_amplitude'])!r}"])
    out = tmp_path / "gap.h5"
    res = CliRunner().invoke(cli, ["gap", "diagnose", str(CASE), "--csv", str(folder),
                                   "--output", str(out)])
    assert res.exit_code == 0, res.output
    # the loads are the model's plus noise: rates from the splines of the positions (their
    # ends left out) leave noise only
    assert res.output.startswith("Within noise: "), res.output
    assert "not checked by leave-one-frequency-out" not in res.output
    # without the frequencies, the check is said to be skipped, and why
    for c in data:
        _write_csv(folder / f"{c.name}.csv", c, [])
    res = CliRunner().invoke(cli, ["gap", "diagnose", str(CASE), "--csv", str(folder),
                                   "--output", str(out)])
    assert res.exit_code == 0, res.output
    assert "not checked by leave-one-frequency-out: 6 of 6 cases give no frequency" in (
        res.output)


def test_rates_given_in_the_file_are_used_as_they_are(tmp_path):
    """All four rate columns: the case's rates are the file's (no spline, no end bias);
    some of them only: refused naming the missing ones."""
    data = synthesize(np.random.default_rng(4), NULL, 0.0, n_cases=1)
    s = data[0].state
    path = _write_csv(tmp_path / "rates.csv", data[0], [])
    text = path.read_text().splitlines()
    header = HEADER + ",pitch_rate,pitch_acceleration,heave_velocity,heave_acceleration"
    rows = [",".join([line, *(repr(float(v)) for v in values)]) for line, values in zip(
        text[1:], zip(s.pitch_rate, s.pitch_acceleration, s.heave_velocity,
                      s.heave_acceleration, strict=True), strict=True)]
    path.write_text("\n".join([header, *rows]) + "\n")
    case = read_csv_case(path)
    assert np.array_equal(case.state.heave_acceleration, s.heave_acceleration)
    assert np.array_equal(case.state.pitch_rate, s.pitch_rate)
    splined = read_csv_case(_write_csv(tmp_path / "positions.csv", data[0], []))
    end_error = abs(splined.state.heave_acceleration[-1] - s.heave_acceleration[-1])
    assert end_error > 10 * abs(case.state.heave_acceleration[-1] - s.heave_acceleration[-1])
    path.write_text("\n".join([HEADER + ",pitch_rate", *(f"{r},0" for r in text[1:])]) + "\n")
    with pytest.raises(ParseError, match=r"rate columns \['pitch_rate'\] without"):
        read_csv_case(path)
