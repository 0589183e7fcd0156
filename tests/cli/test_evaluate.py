"""``mfflap evaluate`` with each model: the case's Morison model and the discrete-vortex
model."""

from __future__ import annotations

import json
from pathlib import Path

import h5py
import numpy as np
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
