"""The plate's wall treatment: the k-epsilon wall functions made for the log layer
("log_law", which the older shipped records ran) or Spalding's law for nut with epsilon's
low-Re correction ("all_y_plus", valid at any y+ of the first cell, as Fluent's enhanced
wall treatment that the paper used is).

The shipped meshes put the plate's first cells at y+ of about 5-15, below the 30-300 that
the log-law wall functions assume (docs/findings/known_limits.md); all_y_plus, the default
of a case without a named set-up (`[cfd] wall_treatment`), gives wall conditions that hold
there.
"""

from __future__ import annotations

import json
import re
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from mfflap.cfd.openfoam.writer import (
    WALL_TREATMENTS,
    SolverSettings,
    write_case,
    written_wall_treatment,
)
from mfflap.cli.main import cli
from mfflap.errors import ConfigError
from mfflap.kinematics import HarmonicMotion

CASE = Path(__file__).resolve().parents[3] / "cases" / "paper2026.toml"
MOTION = HarmonicMotion(1.0, 0.3, np.deg2rad(20), np.pi / 2)


def _plate_entry(case: Path, field: str) -> str:
    return re.search(r"^\s*plate\s*\{([^}]*)\}", (case / "0" / field).read_text(),
                     re.M).group(1)


@pytest.mark.parametrize("treatment, nut, epsilon_low_re", [
    ("log_law", "nutkWallFunction", False),
    ("all_y_plus", "nutUSpaldingWallFunction", True),
])
def test_each_wall_treatment_reaches_the_plates_wall_conditions(tmp_path, treatment, nut,
                                                                epsilon_low_re):
    case = write_case(tmp_path / treatment, MOTION, end_time=0.1,
                      solver=SolverSettings(wall_treatment=treatment))
    assert f"type {nut};" in _plate_entry(case, "nut")
    epsilon = _plate_entry(case, "epsilon")
    assert "type epsilonWallFunction;" in epsilon
    assert ("lowReCorrection true;" in epsilon) is epsilon_low_re
    assert "type kqRWallFunction;" in _plate_entry(case, "k")
    assert f"solver_wall_treatment = '{treatment}'" in (case / "mfflap_case.toml").read_text()
    assert written_wall_treatment(case) == treatment


def test_the_default_case_keeps_the_wall_functions_it_was_run_with(tmp_path):
    """The shipped fixtures and the cost study ran with nutkWallFunction: the default."""
    assert SolverSettings().wall_treatment == "log_law"
    case = write_case(tmp_path / "c", MOTION, end_time=0.1)
    assert "type nutkWallFunction;" in _plate_entry(case, "nut")
    assert "lowReCorrection" not in (case / "0" / "epsilon").read_text()


def test_the_wall_treatment_read_back_is_the_one_the_case_holds(tmp_path):
    """Changed by hand since it was written, or unknown, or no 0/nut at all."""
    case = write_case(tmp_path / "c", MOTION, end_time=0.1)
    nut = case / "0" / "nut"
    nut.write_text(nut.read_text().replace("nutkWallFunction", "nutUSpaldingWallFunction"))
    assert written_wall_treatment(case) == "all_y_plus"
    nut.write_text(nut.read_text().replace("nutUSpaldingWallFunction", "nutLowReWallFunction"))
    assert written_wall_treatment(case) == "other"
    nut.unlink()
    assert written_wall_treatment(case) == "other"


def test_an_unknown_wall_treatment_is_refused_by_name():
    with pytest.raises(ConfigError, match="wall_treatment must be one of log_law, "
                                          "all_y_plus, got 'spalding'") as err:
        SolverSettings(wall_treatment="spalding")
    assert err.value.key == "wall_treatment"


def test_the_case_file_offers_the_writers_wall_treatments():
    from mfflap.study_tables import WALL_TREATMENT_NAMES

    assert WALL_TREATMENT_NAMES == tuple(WALL_TREATMENTS)


def test_the_y_plus_note_follows_the_wall_treatment():
    """Below y+ 30 the log-law wall functions do not hold and all_y_plus does; past 300
    neither does."""
    from mfflap.cfd.openfoam.yplus import wall_function_note

    below = {"y_plus_share_below_log_law": 1.0, "y_plus_share_above_log_law": 0.0}
    assert "below 30 for 100% of the output times" in wall_function_note(below)
    assert "below 30" in wall_function_note(below, "other")
    assert wall_function_note(below, "all_y_plus") is None
    past = {"y_plus_share_below_log_law": 0.0, "y_plus_share_above_log_law": 0.25}
    note = wall_function_note(past, "all_y_plus")
    assert note.startswith("the plate's average y+ lies above the log layer's end (300), "
                           "where its all_y_plus wall treatment does not hold")
    assert "above 300 for 25% of the output times" in note
    both = {"y_plus_share_below_log_law": 0.5, "y_plus_share_above_log_law": 0.25}
    assert "above 300 for 25% of them" in wall_function_note(both)
    assert "below" not in wall_function_note(both, "all_y_plus")


def test_a_case_that_does_not_say_its_wall_treatment_ran_the_log_law_one():
    """Cases, records and campaigns written before the setting kept their other solver
    settings: they ran with nutkWallFunction, and are compared as such; what keeps no solver
    settings at all is not compared."""
    from mfflap.cfd.case_inputs import ADDED_SOLVER_SETTINGS, kept_differences, solver_keys

    assert ADDED_SOLVER_SETTINGS["wall_treatment"] == "log_law"
    asked = solver_keys(SolverSettings(wall_treatment="all_y_plus"))
    old = {key: value for key, value in solver_keys(SolverSettings()).items()
           if key != "solver_wall_treatment"}
    assert kept_differences(old, asked) == [("solver_wall_treatment", "log_law", "all_y_plus")]
    assert kept_differences(old, solver_keys(SolverSettings())) == []
    assert kept_differences({"mesh": "coarse"}, asked) == []


def test_a_case_of_the_other_wall_treatment_is_not_resumed(tmp_path):
    """Nor one written before the setting (no solver_wall_treatment) for an all_y_plus run."""
    from mfflap.cfd.openfoam.run_motion import check_written_for

    solver = SolverSettings(write_interval=0.05)
    case = write_case(tmp_path / "c", MOTION, 0.2, solver=solver)
    spalding = replace(solver, wall_treatment="all_y_plus")
    with pytest.raises(ConfigError, match="solver_wall_treatment = 'log_law', this run asks "
                                          "'all_y_plus'") as err:
        check_written_for(case, MOTION, 0.2, 0.0, "coarse", spalding, None, None, None)
    assert err.value.key == "solver_wall_treatment"
    kept = case / "mfflap_case.toml"
    kept.write_text(kept.read_text().replace("solver_wall_treatment = 'log_law'\n", ""))
    with pytest.raises(ConfigError, match="solver_wall_treatment"):
        check_written_for(case, MOTION, 0.2, 0.0, "coarse", spalding, None, None, None)
    check_written_for(case, MOTION, 0.2, 0.0, "coarse", solver, None, None, None)


def test_cfd_write_takes_the_wall_treatment_with_a_set_up_and_says_it(tmp_path):
    res = CliRunner().invoke(cli, ["cfd", "write", str(CASE), str(tmp_path / "c"), "--setup",
                                   "affordable", "--set", 'cfd.wall_treatment="all_y_plus"',
                                   "--cycles", "0.1"])
    assert res.exit_code == 0, res.output
    assert "all_y_plus wall treatment" in res.output
    assert written_wall_treatment(tmp_path / "c") == "all_y_plus"
    kept = (tmp_path / "c" / "mfflap_case.toml").read_text()
    assert "solver_velocity_convection = 'LUST'" in kept  # the set-up's other settings stay
    bad = CliRunner().invoke(cli, ["cfd", "write", str(CASE), str(tmp_path / "d"),
                                   "--set", 'cfd.wall_treatment="spalding"'])
    assert bad.exit_code == 2 and "cfd.wall_treatment" in bad.output
    assert not (tmp_path / "d").exists()


def test_a_campaign_keeps_its_wall_treatment_in_its_set_up(tmp_path):
    """`campaign run` with [cfd] wall_treatment: the manifest says it, and a folder of the
    other one is refused (as any other setting, `--dry-run` too)."""
    from mfflap.campaign.cases import grid_cases
    from mfflap.campaign.execute import CampaignSetup, _write_manifest
    from mfflap.cfd.openfoam.setups import case_mesh_and_solver
    from mfflap.config import load_case
    from mfflap.toml_io import read_toml

    out = tmp_path / "camp"
    args = ["campaign", "run", str(CASE), "--out", str(out), "--dry-run",
            "--set", "identification.frequencies=[1]",
            "--set", "identification.heave_amplitudes=[0.1]",
            "--set", "identification.phases_deg=[90]"]
    res = CliRunner().invoke(cli, [*args, "--set", 'cfd.wall_treatment="all_y_plus"'])
    assert res.exit_code == 0, res.output
    assert not out.exists()  # a dry run writes nothing
    case = load_case(CASE)
    grid = replace(case.identification, frequencies=(1.0,), heave_amplitudes=(0.1,),
                   phases_deg=(90.0,))
    setup = CampaignSetup(solver=case_mesh_and_solver(case.cfd)[1])  # table1: all_y_plus
    out.mkdir()
    _write_manifest(out, grid_cases(grid), setup)
    assert read_toml(out / "campaign.toml")["setup"]["solver"]["wall_treatment"] == "all_y_plus"
    again = CliRunner().invoke(cli, args)  # all_y_plus: the default set-up's
    assert again.exit_code == 0, again.output
    other = CliRunner().invoke(cli, [*args, "--set", 'cfd.wall_treatment="log_law"'])
    assert other.exit_code == 2
    assert "another setup" in other.output and "wall_treatment" in other.output


def test_backtest_refuses_a_wall_treatment_without_live_runs(optimisation_file):
    res = CliRunner().invoke(cli, ["backtest", str(optimisation_file), "--set",
                                   'cfd.wall_treatment="all_y_plus"'])
    assert res.exit_code == 2
    assert "--set cfd.wall_treatment applies only to live runs (--live)" in res.output


@pytest.mark.openfoam
def test_both_wall_treatments_run_and_move_the_shear_not_the_pressure_forces(tmp_path):
    """Real runs of 0.1 s on the coarse mesh, one per treatment.

    That the all_y_plus conditions take effect is checked on what they change: the plate's
    y+ (the yPlus function object takes u_tau from nut's wall condition, and Spalding's law
    gives another). The heave-wise force, a pressure force, depends on the wall treatment
    only through the separation it shapes and barely moves in 0.1 s. `cfd run` gives the
    y+ note only where the treatment does not hold.
    """
    from mfflap.cfd.openfoam.forces import read_forces

    runs = {}
    for treatment in WALL_TREATMENTS:
        case = tmp_path / treatment
        res = CliRunner().invoke(cli, ["cfd", "write", str(CASE), str(case), "--cycles",
                                       "0.1", "--ramp-time", "0.04", "--set", "cfd.y_plus=true",
                                       "--set", "cfd.writes=1",
                                       "--set", f'cfd.wall_treatment="{treatment}"'])
        assert res.exit_code == 0, res.output
        run = CliRunner().invoke(cli, ["cfd", "run", str(case), "--json"])
        assert run.exit_code == 0, run.output
        runs[treatment] = json.loads(run.stdout)
        assert runs[treatment]["wall_treatment"] == treatment
    log_law, spalding = runs["log_law"], runs["all_y_plus"]
    assert log_law["y_plus_mean"] < 30 and spalding["y_plus_mean"] < 30
    assert log_law["wall_function_note"].startswith("the plate's average y+ lies outside")
    assert spalding["wall_function_note"] is None
    assert abs(spalding["y_plus_mean"] / log_law["y_plus_mean"] - 1) > 0.05
    forces = {t: read_forces(tmp_path / t) for t in WALL_TREATMENTS}
    time = forces["log_law"].time
    heave_wise = {t: np.interp(time, f.time, f.force[:, 1]) for t, f in forces.items()}
    scale = np.ptp(heave_wise["log_law"])
    assert np.sqrt(np.mean((heave_wise["all_y_plus"] - heave_wise["log_law"]) ** 2)) < (
        0.02 * scale)
