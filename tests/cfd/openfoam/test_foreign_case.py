"""An OpenFOAM case mfflap did not write: a case written by hand (blockMesh, its own
dynamicMeshDict with a multiMotion, a forces function object of another name whose moments
are about another point) run in real OpenFOAM and parsed; and the motion, depth and CofR
readers on their own."""

import json
import os
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from mfflap.cfd.openfoam.foreign_case import (
    forces_centre,
    read_case_motion,
    read_foreign_case,
    read_six_dof_table,
)
from mfflap.cli.main import cli
from mfflap.errors import ConfigError, ParseError

HAND_WRITTEN = Path(__file__).parents[2] / "data" / "hand_written_openfoam_case"
PAPER = Path(__file__).parents[3] / "cases" / "paper2026.toml"


def _case_file(tmp_path: Path) -> Path:
    """The paper's case file for the hand-written case's plate (0.1 m chord) and stream."""
    text = PAPER.read_text().replace("chord = 0.16", "chord = 0.1").replace(
        "velocity = 0.3 ", "velocity = 0.5 ")
    path = tmp_path / "hand_written.toml"
    path.write_text(text)
    return path


def _points(path: Path) -> np.ndarray:
    from foamlib import FoamFile

    return np.asarray(FoamFile(path)[None], dtype=float)


@pytest.fixture(scope="module")
def ran_case(tmp_path_factory):
    """The hand-written case meshed and run to 0.25 s by blockMesh and pimpleFoam."""
    case = tmp_path_factory.mktemp("hand") / "case"
    shutil.copytree(HAND_WRITTEN, case)
    env = {**os.environ, "WM_PROJECT_DIR": os.environ.get("WM_PROJECT_DIR",
                                                          "/usr/share/openfoam")}
    for tool in ("blockMesh", "pimpleFoam"):
        done = subprocess.run([tool, "-case", str(case)], capture_output=True, text=True,
                              env=env, timeout=600)
        assert done.returncode == 0, done.stdout[-2000:] + done.stderr[-2000:]
    return case


@pytest.mark.openfoam
def test_the_motion_read_is_the_one_the_solver_imposed_on_the_mesh(ran_case):
    """Every mesh point pimpleFoam wrote at 0.125 s and 0.25 s lies where the motion read
    from the dynamicMeshDict puts it: x' = pivot + (0, h) + R(theta)(x - pivot)."""
    read = read_case_motion(ran_case, 0.25)
    assert read.pivot_m == (0.02, 0.0) and "multiMotion (heave, pitch)" in read.source
    rest = _points(ran_case / "constant" / "polyMesh" / "points")
    pivot = np.array([*read.pivot_m, 0.0])
    for t in (0.125, 0.25):
        state = read.motion.sample(np.array([t]))
        th, h = float(state.pitch_angle[0]), float(state.heave_position[0])
        rot = np.array([[np.cos(th), -np.sin(th), 0], [np.sin(th), np.cos(th), 0], [0, 0, 1]])
        expected = pivot + np.array([0.0, h, 0.0]) + (rest - pivot) @ rot.T
        moved = _points(ran_case / f"{t:g}" / "polyMesh" / "points")
        assert np.abs(moved - expected).max() < 1e-8
    peak = read.motion.sample(np.array([0.125]))
    assert np.degrees(peak.pitch_angle[0]) == pytest.approx(12.0)
    assert peak.heave_position[0] == pytest.approx(0.03)


@pytest.mark.openfoam
def test_cfd_parse_reads_the_hand_written_case_and_its_loads(ran_case, tmp_path):
    """`mfflap cfd parse` of the case: its forces function object (plateLoads), the depth of
    its mesh, the moment moved from its CofR (0.045, 0) to the heaving pivot; F_n and M
    checked against the force and moment files worked out here."""
    case_file = _case_file(tmp_path)
    res = CliRunner().invoke(cli, ["cfd", "parse", str(ran_case), "--case-file",
                                   str(case_file), "--json"])
    assert res.exit_code == 0, res.output
    out = json.loads(res.stdout)
    assert out["depth_m"] == pytest.approx(0.05) and out["pivot_m"] == [0.02, 0.0]
    assert "multiMotion" in out["motion_from"] and out["inputs_checked_against"] is None
    assert out["dialect"] == "v1912" and out["end_time"] == pytest.approx(0.25)

    foreign = read_foreign_case(ran_case)
    assert foreign.forces_function == "plateLoads"
    assert np.allclose(foreign.history.centre_of_rotation, [0.045, 0.0, 0.0])
    from mfflap.cfd.force_history import to_loads
    from mfflap.cfd.imposed_motion import imposed_state

    state = imposed_state(foreign.motion, foreign.history.time)
    loads = to_loads(foreign.history, state, 0.18, foreign.depth_m, "test",
                     pivot_m=foreign.pivot_m)
    rows = np.loadtxt(ran_case / "postProcessing" / "plateLoads" / "0" / "force.dat",
                      converters=lambda s: s.strip("()"), comments="#",
                      usecols=(0, 1, 2))
    moments = np.loadtxt(ran_case / "postProcessing" / "plateLoads" / "0" / "moment.dat",
                         converters=lambda s: s.strip("()"), comments="#", usecols=(3,))
    scale = 0.18 / 0.05
    th, h = state.pitch_angle, state.heave_position
    fx, fy = rows[:, 1] * scale, rows[:, 2] * scale
    normal = -fx * np.sin(th) + fy * np.cos(th)  # along e_n = (-sin, cos) in (x, y)
    about_pivot = moments * scale + (0.045 - 0.02) * fy + h * fx  # M_C + (r_C - r_P) x F
    assert np.allclose(loads.normal_force, normal, rtol=1e-9, atol=1e-9)
    assert np.allclose(loads.moment, about_pivot, rtol=1e-9, atol=1e-9)


@pytest.mark.openfoam
def test_a_csv_motion_and_a_given_depth_replace_what_the_case_says(ran_case, tmp_path):
    t = np.linspace(0.0, 0.3, 61)
    table = tmp_path / "motion.csv"
    np.savetxt(table, np.column_stack([t, 0.03 * np.sin(4 * np.pi * t),
                                       12 * np.sin(4 * np.pi * t)]),
               delimiter=",", header="time,heave_position,pitch_angle_deg", comments="")
    res = CliRunner().invoke(cli, ["cfd", "parse", str(ran_case), "--case-file",
                                   str(_case_file(tmp_path)), "--motion-table", str(table),
                                   "--depth", "0.1", "--json"])
    assert res.exit_code == 0, res.output
    out = json.loads(res.stdout)
    assert out["depth_m"] == 0.1 and out["motion_from"] == str(table)


def _with_motion(tmp_path: Path, text: str) -> Path:
    case = tmp_path / "case"
    (case / "constant").mkdir(parents=True)
    (case / "constant" / "dynamicMeshDict").write_text(
        "FoamFile { version 2.0; format ascii; class dictionary; object dynamicMeshDict; }\n"
        "dynamicFvMesh dynamicMotionSolverFvMesh;\nmotionSolver solidBody;\n" + text)
    return case


def test_a_multimotion_that_would_surge_the_pivot_is_refused_naming_the_file(tmp_path):
    """Pitch listed before heave: OpenFOAM heaves the mesh first and then turns it about the
    fixed origin, which carries the pivot along the stream."""
    text = (HAND_WRITTEN / "constant" / "dynamicMeshDict").read_text()
    heave = text[text.index("    heave\n"):text.index("    pitch\n")]
    pitch = text[text.index("    pitch\n"):text.rindex("}")]
    case = _with_motion(tmp_path, text[text.index("solidBodyMotionFunction"):text.index(
        "    heave\n")] + pitch + heave + "}\n")
    with pytest.raises(ConfigError, match="moves along the stream") as caught:
        read_case_motion(case, 0.25)
    assert caught.value.source == str(case / "constant" / "dynamicMeshDict")


def test_a_tabulated_motion_is_read_with_its_pivot(tmp_path):
    t = np.linspace(0.0, 1.0, 21)
    rows = "\n".join(f"({ti:g} ((0 {0.1 * np.sin(2 * np.pi * ti):.12g} 0) (0 0 "
                     f"{20 * np.cos(2 * np.pi * ti):.12g})))" for ti in t)
    case = _with_motion(tmp_path, "solidBodyMotionFunction tabulated6DoFMotion;\n"
                        "CofG (0.05 0.01 0);\ntimeDataFileName \"<constant>/table.dat\";\n")
    (case / "constant" / "table.dat").write_text(f"{len(t)}\n(\n{rows}\n)\n")
    read = read_case_motion(case, 0.9)
    assert read.pivot_m == (0.05, 0.01)
    state = read.motion.sample(np.array([0.0, 0.5]))
    assert np.degrees(state.pitch_angle) == pytest.approx([20.0, -20.0])
    assert state.heave_position == pytest.approx([0.0, 0.0], abs=1e-9)
    with pytest.raises(ParseError, match="ends at t = 1 s"):
        read_case_motion(case, 2.0)


@pytest.mark.parametrize("table, message, line", [
    ("3\n(\n(0 ((0 0 0) (0 0 0)))\n)\n", "says 3 rows but holds 1", None),
    ("2\n(\n(0 ((0 0 0) (0 0 0)))\n(x ((0 0 0) (0 0 0)))\n)\n", "not a number", 4),
    ("", "empty motion table", None),
])
def test_a_damaged_motion_table_is_named_with_its_line(tmp_path, table, message, line):
    path = tmp_path / "table.dat"
    path.write_text(table)
    with pytest.raises(ParseError, match=message) as caught:
        read_six_dof_table(path)
    assert (caught.value.path, caught.value.line) == (str(path), line)


@pytest.mark.parametrize("text, message", [
    ("solidBodyMotionFunction rotatingMotion;\n", "'rotatingMotion' .* is not one mfflap"),
    ("solidBodyMotionFunction oscillatingRotatingMotion;\norigin (0 0 0);\n"
     "amplitude (5 0 10);\nomega 2;\n", "about x or y"),
    ("solidBodyMotionFunction oscillatingLinearMotion;\namplitude (0.1 0.1 0);\nomega 2;\n",
     "moves along the stream"),
])
def test_motions_the_model_has_not_are_refused(tmp_path, text, message):
    with pytest.raises(ConfigError, match=message):
        read_case_motion(_with_motion(tmp_path, text), 1.0)


def test_a_mesh_that_does_not_move_as_a_solid_body_is_refused(tmp_path):
    case = tmp_path / "case"
    (case / "constant").mkdir(parents=True)
    with pytest.raises(ConfigError, match="no constant/dynamicMeshDict"):
        read_case_motion(case, 1.0)
    (case / "constant" / "dynamicMeshDict").write_text(
        "FoamFile { version 2.0; format ascii; class dictionary; }\n"
        "motionSolver displacementLaplacian;\n")
    with pytest.raises(ConfigError, match="displacementLaplacian"):
        read_case_motion(case, 1.0)


def test_the_centre_of_the_moments_comes_from_the_function_objects_entry(tmp_path):
    (tmp_path / "system").mkdir()
    (tmp_path / "system" / "controlDict").write_text(
        "FoamFile { version 2.0; format ascii; class dictionary; }\n"
        "functions { loads { type forces; CofR (0.1 0.2 0); } other { type forces; "
        "origin (1 2 3); } }\n")
    assert forces_centre(tmp_path, "loads") == pytest.approx([0.1, 0.2, 0.0])
    assert forces_centre(tmp_path, "other") == pytest.approx([1.0, 2.0, 3.0])
    assert forces_centre(tmp_path, "missing") is None
