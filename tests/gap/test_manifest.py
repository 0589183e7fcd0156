"""A whole external dataset in one input (mfflap.gap.manifest): a folder of CSV runs with a
manifest.toml giving each run's motion and the shared set-up, read by the API and by
`mfflap gap diagnose --csv FOLDER`, and refused, naming the manifest and key, when it does
not describe the folder."""

import json
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from mfflap.cli.main import cli
from mfflap.config import load_case
from mfflap.errors import ConfigError, ParseError
from mfflap.gap.blindtest import NULL, synthesize
from mfflap.gap.manifest import read_dataset, read_manifest

CASE = Path(__file__).parents[2] / "cases" / "paper2026.toml"
HEADER = ("time,pitch_angle,heave_position,normal_force,tangential_force,moment,pitch_rate,"
          "pitch_acceleration,heave_velocity,heave_acceleration")


def _dataset(folder: Path, n_cases: int = 12, comments: dict | None = None) -> list:
    """n_cases synthetic null runs as CSV files (with their rates) and their manifest."""
    config = load_case(CASE)
    cases = synthesize(np.random.default_rng(3), NULL, 0.0, n_cases=n_cases)
    lines = ["[setup]", f"velocity = {config.flow.velocity}", f"chord = {config.plate.chord}",
             f"span = {config.plate.span}", ""]
    for i, c in enumerate(cases):
        s, cfd = c.state, c.cfd
        rows = [*(comments or {}).get(i, []), HEADER]
        rows += [",".join(repr(float(v)) for v in values) for values in zip(
            s.time, s.pitch_angle, s.heave_position, cfd.normal_force, cfd.tangential_force,
            cfd.moment, s.pitch_rate, s.pitch_acceleration, s.heave_velocity,
            s.heave_acceleration, strict=True)]
        (folder / f"run{i:02d}.csv").write_text("\n".join(rows) + "\n")
        lines += ["[[run]]", f'file = "run{i:02d}.csv"',
                  f"frequency = {c.parameters['frequency']}",
                  f"heave_amplitude = {c.parameters['heave_amplitude']}", ""]
    (folder / "manifest.toml").write_text("\n".join(lines))
    return cases


def test_a_dataset_folder_gives_every_run_its_manifest_parameters(tmp_path):
    cases = _dataset(tmp_path, n_cases=3)
    read = read_dataset(tmp_path, config=load_case(CASE))
    assert [c.name for c in read] == ["run00", "run01", "run02"]
    for mine, given in zip(read, cases, strict=True):
        assert mine.parameters["frequency"] == given.parameters["frequency"]
        assert mine.parameters["heave_amplitude"] == given.parameters["heave_amplitude"]
        # the rates the files give are used as they are: no sample is lost to splines
        assert np.array_equal(mine.state.heave_acceleration, given.state.heave_acceleration)


def test_gap_diagnose_reads_a_dataset_folder_as_one_input(tmp_path):
    _dataset(tmp_path)
    res = CliRunner().invoke(cli, ["gap", "diagnose", str(CASE), "--csv", str(tmp_path),
                                   "--output", str(tmp_path / "gap.h5"), "--json"])
    assert res.exit_code == 0, res.output
    out = json.loads(res.output[res.output.index("{"):])
    assert out["finding"] == "within noise"
    assert "leave-one-frequency-out" not in out["validation_skipped"]


@pytest.mark.parametrize("edit, key, said", [
    (lambda d: (d / "extra.csv").write_text("x\n"), "run", "not in the manifest"),
    (lambda d: (d / "run01.csv").unlink(), "run[2].file", "does not exist"),
    (lambda d: _append(d, "[[run]]\nfile = \"run00.csv\"\n"), "run[4].file", "listed twice"),
    (lambda d: _append(d, "[[run]]\nfile = \"run00.csv\"\nspeed = 2\n"), "run[4].speed",
     "unknown run[4] key"),
    (lambda d: _replace(d, "velocity = 0.3", "velocity = 0.5"), "velocity", "[flow] velocity"),
    (lambda d: _replace(d, "[setup]", "[setup]\nreynolds = 1e5"), "setup.reynolds",
     "unknown [setup] key"),
])
def test_a_manifest_that_does_not_describe_its_folder_is_refused(tmp_path, edit, key, said):
    _dataset(tmp_path, n_cases=3)
    edit(tmp_path)
    with pytest.raises(ConfigError) as err:
        read_dataset(tmp_path, config=load_case(CASE))
    assert err.value.key == key and said in str(err.value)
    assert "manifest.toml" in str(err.value)


def test_a_run_that_contradicts_its_manifest_is_refused_naming_both(tmp_path):
    _dataset(tmp_path, n_cases=3, comments={1: ["# frequency = 99"]})
    with pytest.raises(ConfigError) as err:
        read_dataset(tmp_path)
    assert err.value.key == "frequency" and "run01.csv" in str(err.value)
    assert "the manifest gives" in str(err.value)


def test_a_manifest_that_is_not_toml_names_its_line(tmp_path):
    _dataset(tmp_path, n_cases=3)
    _append(tmp_path, "[[run]\n")
    with pytest.raises(ParseError, match=r"manifest\.toml"):
        read_manifest(tmp_path)


def _append(folder: Path, text: str) -> None:
    path = folder / "manifest.toml"
    path.write_text(path.read_text() + text)


def _replace(folder: Path, old: str, new: str) -> None:
    path = folder / "manifest.toml"
    assert old in path.read_text()
    path.write_text(path.read_text().replace(old, new))
