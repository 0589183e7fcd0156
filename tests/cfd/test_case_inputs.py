"""A case keeps what it was written for; parsing it against another case file is an error."""

from __future__ import annotations

import json
import shutil
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from mfflap.cfd.case_inputs import check_case_inputs, motion_sample_times
from mfflap.cfd.imposed_motion import imposed_state
from mfflap.cfd.openfoam.writer import SolverSettings, write_case
from mfflap.cli.main import cli
from mfflap.config import load_case
from mfflap.errors import ConfigError
from mfflap.kinematics import HarmonicMotion
from mfflap.toml_io import read_toml

CASE = Path(__file__).resolve().parents[2] / "cases" / "paper2026.toml"
DATA = Path(__file__).parents[1] / "data" / "openfoam_v1912"


@pytest.fixture(scope="module")
def config():
    return load_case(CASE)


def _write(folder: Path, config, motion, frame="inertial") -> dict:
    solver = SolverSettings(frame=frame, far_field="inletOutlet")
    write_case(folder, motion, 0.4, plate=config.plate, fluid=config.fluid,
               stream=config.flow, ramp_time=0.1, solver=solver)
    return read_toml(folder / "mfflap_case.toml")


@pytest.mark.parametrize("frame", ["inertial", "plate"])
def test_a_case_keeps_its_physics_and_samples_of_the_motion_it_imposes(tmp_path, config,
                                                                        frame):
    motion = config.motion.build()
    meta = _write(tmp_path / "case", config, motion, frame)
    kept = tmp_path / "case" / "mfflap_case.toml"
    assert meta["plate_chord_m"] == config.plate.chord
    assert meta["flow_velocity_m_per_s"] == config.flow.velocity
    assert meta["fluid_density_kg_per_m3"] == config.fluid.density
    t = np.asarray(meta["motion_sample_time_s"])
    np.testing.assert_array_equal(t, motion_sample_times(0.4))
    state = imposed_state(motion, t, 0.1)  # the ramp is in the samples
    np.testing.assert_array_equal(meta["motion_sample_heave_m"], state.heave_position)
    np.testing.assert_array_equal(meta["motion_sample_pitch_rad"], state.pitch_angle)
    unramped = imposed_state(motion, t[:1], 0.0).pitch_angle[0]
    assert abs(meta["motion_sample_pitch_rad"][0]) < 0.1 * abs(unramped)
    check_case_inputs(kept, meta, CASE, motion, config.plate, config.fluid,
                      config.flow)  # the case file it was written from passes


def test_another_motion_plate_fluid_or_stream_is_named(tmp_path, config):
    motion = config.motion.build()
    meta = _write(tmp_path / "case", config, motion)
    kept = tmp_path / "case" / "mfflap_case.toml"
    args = (config.plate, config.fluid, config.flow)
    other = HarmonicMotion(motion.frequency, motion.heave_amplitude,
                           motion.pitch_amplitude * 1.001, motion.phase)
    with pytest.raises(ConfigError, match=r"paper2026.toml: motion: not the motion .*case "
                                          r"imposes: at t = \S+ s its pitch is") as err:
        check_case_inputs(kept, meta, CASE, other, *args)
    assert "mfflap_case.toml, motion_sample_pitch_rad" in str(err.value)
    later = HarmonicMotion(motion.frequency * 1.01, motion.heave_amplitude,
                           motion.pitch_amplitude, motion.phase)
    with pytest.raises(ConfigError, match="its heave is"):
        check_case_inputs(kept, meta, CASE, later, *args)
    with pytest.raises(ConfigError, match=r"plate.span: 0.2 in the case file, but .* was "
                                          r"written for 0.18"):
        check_case_inputs(kept, meta, CASE, motion,
                          replace(config.plate, span=0.2), config.fluid, config.flow)
    with pytest.raises(ConfigError, match=r"flow\.velocity: 0\.35 in the case file"):
        check_case_inputs(kept, meta, CASE, motion, config.plate,
                          config.fluid, replace(config.flow, velocity=0.35))
    with pytest.raises(ConfigError, match=r"fluid\.density"):
        check_case_inputs(kept, meta, CASE, motion, config.plate,
                          replace(config.fluid, density=998.0), config.flow)


def test_a_case_of_an_earlier_mfflap_is_checked_only_for_what_it_kept(tmp_path, config):
    motion = config.motion.build()
    meta = _write(tmp_path / "case", config, motion)
    kept = tmp_path / "case" / "mfflap_case.toml"
    old = {k: meta[k] for k in ("mesh", "end_time", "depth", "span", "ramp_time", "n_cells")}
    other = HarmonicMotion(motion.frequency, motion.heave_amplitude, 0.5, motion.phase)
    check_case_inputs(kept, old, CASE, other, config.plate, config.fluid,
                      config.flow)
    with pytest.raises(ConfigError, match=r"plate\.span"):  # span was always kept
        check_case_inputs(kept, old, CASE, motion,
                          replace(config.plate, span=0.3), config.fluid, config.flow)


def test_cli_parse_refuses_a_case_file_the_case_was_not_written_from(tmp_path):
    runner = CliRunner()
    case_dir = tmp_path / "of"
    res = runner.invoke(cli, ["cfd", "write", str(CASE), str(case_dir), "--cycles", "0.05"])
    assert res.exit_code == 0, res.output
    forces = case_dir / "postProcessing" / "forces" / "0"
    forces.mkdir(parents=True)
    for name in ("force.dat", "moment.dat"):  # real v1912 output
        shutil.copy(DATA / name, forces / name)
    res = runner.invoke(cli, ["cfd", "parse", str(case_dir), "--case-file", str(CASE),
                              "--json"])
    assert res.exit_code == 0, res.output
    assert json.loads(res.stdout)["dialect"] == "v1912"
    text = CASE.read_text()
    assert "\npitch_amplitude_deg = 20.0\n" in text
    other = tmp_path / "other.toml"
    other.write_text(text.replace("\npitch_amplitude_deg = 20.0\n",
                                  "\npitch_amplitude_deg = 25.0\n"))
    res = runner.invoke(cli, ["cfd", "parse", str(case_dir), "--case-file", str(other)])
    assert res.exit_code == 2
    assert "other.toml: motion: not the motion" in res.output


def _report(path: Path) -> Path:
    """A Fluent report file of 1 s of smooth forces."""
    from fluent_files import write_plate_report

    t = np.linspace(0.01, 1.0, 100)
    return write_plate_report(path, t, 40 * np.sin(6 * t), 30 * np.cos(6 * t),
                              2 * np.sin(6 * t))


def _parse(*args: str) -> tuple[int, str]:
    """`cfd parse`'s exit code, and its standard output or, when it fails, its error."""
    res = CliRunner().invoke(cli, ["cfd", "parse", *args])
    return res.exit_code, res.stdout if res.exit_code == 0 else res.output


def test_a_fluent_report_beside_its_udf_parses_with_the_udf_s_ramp_and_case(tmp_path):
    fl = tmp_path / "fl"
    res = CliRunner().invoke(cli, ["cfd", "fluent", str(CASE), str(fl), "--cycles", "1",
                                   "--ramp-time", "0.25"])
    assert res.exit_code == 0, res.output
    meta = read_toml(fl / "mfflap_fluent.toml")
    assert meta["ramp_time"] == 0.25 and meta["report_file"] == "plate-forces.out"
    assert meta["udf"] == "mfflap_motion.c" and len(meta["motion_sample_heave_m"]) == 64
    assert "plate-forces.out" in (fl / "mfflap_run.jou").read_text()
    beside = _report(fl / "plate-forces.out")
    alone = _report(tmp_path / "alone.out")  # the same forces, no UDF beside them
    code, kept = _parse(str(beside), "--case-file", str(CASE), "--json")
    assert code == 0, kept
    res = CliRunner().invoke(cli, ["cfd", "parse", str(alone), "--case-file", str(CASE)])
    assert res.exit_code == 0 and "warning: nothing beside" in res.stderr
    assert "were not checked" in res.stderr and "were not checked" not in res.stdout
    code, same = _parse(str(alone), "--case-file", str(CASE), "--json", "--ramp-time", "0.25")
    assert code == 0, same
    code, unramped = _parse(str(alone), "--case-file", str(CASE), "--json")
    assert code == 0, unramped
    kept, same, unramped = (json.loads(o) for o in (kept, same, unramped))
    assert kept.pop("inputs_checked_against") == str(fl / "mfflap_fluent.toml")
    assert same.pop("inputs_checked_against") is None
    # 1 s of forces for the 1 s (one cycle) the UDF was written for: they get there
    assert kept.pop("written_end_time") == 1.0 and kept.pop("forces_reach_end_time") is True
    assert same.pop("written_end_time") is None and same.pop("forces_reach_end_time") is None
    kept.pop("source"), same.pop("source"), unramped.pop("source")
    assert kept == same  # the kept ramp is the one used
    assert kept["model_mean_power"] != unramped["model_mean_power"]
    code, out = _parse(str(beside), "--case-file", str(CASE), "--ramp-time", "0.5")
    assert code == 2 and "--ramp-time 0.5 s, but the case was written with a ramp of " \
                         "0.25 s" in out and "mfflap_fluent.toml" in out
    other = tmp_path / "other.toml"
    other.write_text(CASE.read_text().replace("\nheave_amplitude = 0.3 ",
                                              "\nheave_amplitude = 0.35 "))
    assert load_case(other).motion.heave_amplitude == 0.35
    code, out = _parse(str(beside), "--case-file", str(other))
    assert code == 2 and "other.toml: motion: not the motion" in out and "heave" in out


def test_a_fluent_udf_from_a_table_keeps_it_for_the_parse(tmp_path):
    from motion_tables import write_table

    table = write_table(tmp_path / "motion.csv")
    fl = tmp_path / "fl"
    res = CliRunner().invoke(cli, ["cfd", "fluent", str(CASE), str(fl), "--motion-table",
                                   str(table)])
    assert res.exit_code == 0, res.output
    meta = read_toml(fl / "mfflap_fluent.toml")
    assert (fl / meta["motion_table"]).read_text() == table.read_text()
    report = _report(fl / "plate-forces.out")
    code, out = _parse(str(report), "--case-file", str(CASE), "--json")
    assert code == 0, out  # the case file's [motion] is not the table's: the table is used
    code, out = _parse(str(report), "--case-file", str(CASE), "--motion-table", str(table))
    assert code == 2 and "keeps its own motion table" in out


def test_an_openfoam_case_refuses_another_ramp_time(tmp_path):
    case_dir = tmp_path / "of"
    res = CliRunner().invoke(cli, ["cfd", "write", str(CASE), str(case_dir), "--cycles", "0.05",
                                   "--ramp-time", "0.02"])
    assert res.exit_code == 0, res.output
    forces = case_dir / "postProcessing" / "forces" / "0"
    forces.mkdir(parents=True)
    for name in ("force.dat", "moment.dat"):
        shutil.copy(DATA / name, forces / name)
    assert _parse(str(case_dir), "--case-file", str(CASE), "--ramp-time", "0.02")[0] == 0
    code, out = _parse(str(case_dir), "--case-file", str(CASE), "--ramp-time", "0")
    assert code == 2 and "but the case was written with a ramp of 0.02 s" in out
