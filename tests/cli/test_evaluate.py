"""``mfflap evaluate`` with each model: the case's Morison model and the discrete-vortex
model."""

from __future__ import annotations

import json
from pathlib import Path

import h5py
import numpy as np
import pytest
from click.testing import CliRunner

from mfflap.cli.main import cli

CASE = Path(__file__).parents[2] / "cases" / "paper2026.toml"


def test_the_vortex_model_evaluates_the_case_s_motion_once_its_start_up_wake_has_left(
        tmp_path):
    """The paper's sinusoid: the last of the periods from rest, its loads and means saved;
    it draws power and makes thrust, and its peak power is above its mean."""
    out = tmp_path / "vortex.h5"
    res = CliRunner().invoke(cli, ["evaluate", str(CASE), "--model", "vortex", "--json",
                                   "--output", str(out), "--figure", str(tmp_path / "v.png")])
    assert res.exit_code == 0, res.output
    summary = json.loads(res.output[res.output.index("{"):])
    assert summary["scheme"] == "discrete-vortex"
    assert summary["mean_thrust"] > 0 and summary["max_power"] > summary["mean_power"] > 0
    with h5py.File(out) as h5:
        time = h5["state/time"][()]
        assert h5["loads/normal_force"].shape == time.shape
    # one period of the 1 Hz motion, sampled 200 times, after at least three from rest
    assert time.size == 200 and time[0] >= 3.0 and np.ptp(time) < 1.0
    assert (tmp_path / "v.png").stat().st_size > 0


def test_a_discrete_scheme_is_refused_for_the_vortex_model():
    res = CliRunner().invoke(cli, ["evaluate", str(CASE), "--model", "vortex", "--scheme",
                                   "midpoint"])
    assert res.exit_code == 2
    assert "scheme" in res.output and "discrete-vortex model" in res.output


def test_the_case_files_vortex_table_sets_the_model(tmp_path):
    """[vortex]: never shedding from the leading edge, against the default critical LESP."""
    said = {}
    for name, extra in (("default", ""), ("attached", "\n[vortex]\ncritical_lesp = inf\n")):
        case = tmp_path / f"{name}.toml"
        case.write_text(CASE.read_text() + extra)
        res = CliRunner().invoke(cli, ["evaluate", str(case), "--model", "vortex", "--json",
                                       "--output", str(tmp_path / f"{name}.h5"),
                                       "--figure", str(tmp_path / f"{name}.png")])
        assert res.exit_code == 0, res.output
        said[name] = json.loads(res.output[res.output.index("{"):])
    assert said["attached"]["max_power"] != said["default"]["max_power"]
    bad = tmp_path / "bad.toml"
    bad.write_text(CASE.read_text() + "\n[vortex]\ncore_radius_chords = 2.0\n")
    res = CliRunner().invoke(cli, ["evaluate", str(bad), "--model", "vortex"])
    assert res.exit_code != 0 and "vortex.core_radius_chords" in res.output


def _the_case_s_sinusoid_as_a_table(path: Path, rows_per_period: int = 400) -> Path:
    """The case's [motion] (1 Hz, 0.3 m, 20 deg, heave leading by 90 deg) over one period,
    heave in mm and pitch in degrees."""
    t = np.arange(rows_per_period + 1) / rows_per_period
    path.write_text("time [s],h [mm],theta [deg]\n" + "".join(
        f"{a:.6f},{300 * np.sin(2 * np.pi * a + np.pi / 2):.9g},"
        f"{20 * np.sin(2 * np.pi * a):.9g}\n" for a in t))
    return path


def test_one_s_own_motion_table_is_evaluated_like_the_case_s_own_motion(tmp_path):
    """A table of the case's own sinusoid (in mm and degrees) gives the case's cycle means
    within the difference of the continuous and the discrete scheme (a few per cent)."""
    table = _the_case_s_sinusoid_as_a_table(tmp_path / "mine.csv")
    runner = CliRunner()
    own = runner.invoke(cli, ["evaluate", str(CASE), "--json", "--figure",
                              str(tmp_path / "a.png")])
    mine = runner.invoke(cli, ["evaluate", str(CASE), "--motion", str(table), "--json",
                               "--figure", str(tmp_path / "b.png")])
    assert own.exit_code == 0 and mine.exit_code == 0, (own.output, mine.output)
    own_s = json.loads(own.output[own.output.index("{"):])
    mine_s = json.loads(mine.output[mine.output.index("{"):])
    assert mine_s["scheme"] == "continuous" and (tmp_path / "b.png").exists()
    for key in ("mean_thrust", "mean_power"):
        assert mine_s[key] == pytest.approx(own_s[key], rel=0.05), key
    vortex = runner.invoke(cli, ["evaluate", str(CASE), "--motion", str(table), "--model",
                                 "vortex", "--json", "--figure", str(tmp_path / "c.png")])
    assert vortex.exit_code == 0, vortex.output
    assert json.loads(vortex.output[vortex.output.index("{"):])["scheme"] == "discrete-vortex"


def test_a_motion_table_with_a_discrete_scheme_or_a_bad_row_is_refused(tmp_path):
    table = _the_case_s_sinusoid_as_a_table(tmp_path / "mine.csv")
    res = CliRunner().invoke(cli, ["evaluate", str(CASE), "--motion", str(table),
                                   "--scheme", "paper"])
    assert res.exit_code == 2 and "evaluated continuously" in res.output
    bad = tmp_path / "bad.csv"
    bad.write_text(table.read_text().replace("\n0.005000,", "\n0.005000,abc", 1))
    res = CliRunner().invoke(cli, ["evaluate", str(CASE), "--motion", str(bad)])
    assert res.exit_code == 2 and f"{bad}, line 4" in " ".join(res.output.split())


def test_study_evaluate_takes_a_table_s_path_or_its_motion(tmp_path):
    from mfflap.api import Study
    from mfflap.kinematics.table_file import read_motion_table

    table = _the_case_s_sinusoid_as_a_table(tmp_path / "mine.csv")
    study = Study.from_toml(CASE)
    by_path, by_motion = study.evaluate(table), study.evaluate(read_motion_table(table))
    assert by_path.summary.mean_thrust == pytest.approx(by_motion.summary.mean_thrust)
    own = study.evaluate()
    assert by_path.summary.mean_thrust == pytest.approx(own.summary.mean_thrust, rel=0.05)
    assert by_path.plot() is not None


def test_a_plate_the_stream_drives_has_no_efficiency_and_its_regime_is_named(tmp_path):
    """At 1,000 m/s the paper's sinusoid makes no thrust and takes no power: energy
    extraction, whose thrust-to-power ratio is no efficiency."""
    fast = tmp_path / "fast.toml"
    fast.write_text(CASE.read_text().replace("velocity = 0.3 ", "velocity = 1000.0 ", 1))
    res = CliRunner().invoke(cli, ["evaluate", str(fast), "--json", "--figure",
                                   str(tmp_path / "f.png")])
    assert res.exit_code == 0, res.output
    said = json.loads(res.output[res.output.index("{"):])
    assert said["mean_thrust"] < 0 and said["mean_power"] < 0
    assert said["regime"] == "energy extraction" and said["efficiency"] is None  # NaN: null
    res = CliRunner().invoke(cli, ["evaluate", str(fast), "--figure", str(tmp_path / "f.png")])
    assert "regime: energy extraction" in res.output
