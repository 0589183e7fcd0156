"""Case folders OpenFOAM cannot read (whitespace, quotes) are refused before anything is
written or run; the premise is checked against the real blockMesh, and a path with the
characters OpenFOAM keeps runs for real."""

import os
import shutil
import subprocess

import numpy as np
import pytest
from click.testing import CliRunner

from mfflap.campaign.cases import CfdCase
from mfflap.campaign.execute import run_campaign
from mfflap.cfd.openfoam.case_path import check_case_path, stripped_characters
from mfflap.cfd.openfoam.runner import openfoam_available, run_application, run_case
from mfflap.cfd.openfoam.writer import write_case
from mfflap.cli.main import cli
from mfflap.errors import ConfigError
from mfflap.kinematics import HarmonicMotion

MOTION = HarmonicMotion(1.0, 0.3, np.deg2rad(20), np.pi / 2)
CASE_FILE = os.path.join(os.path.dirname(__file__), "..", "cases", "paper2026.toml")


@pytest.mark.parametrize(("name", "stripped"), [("a b", [" "]), ("a\tb c", ["\t", " "]),
                                                ('a"b', ['"']), ("a'b'", ["'"]),
                                                ("a$b#c(d){e}~f;g,h@i=j:k", []),
                                                ("ébène", [])])
def test_the_characters_openfoam_strips_are_found_once_each(tmp_path, name, stripped):
    assert stripped_characters(tmp_path / name / "case") == stripped


def test_a_relative_path_is_judged_with_the_working_folder(tmp_path, monkeypatch):
    spaced = tmp_path / "work folder"
    spaced.mkdir()
    monkeypatch.chdir(spaced)
    assert stripped_characters("case") == [" "]
    with pytest.raises(ConfigError, match="work folder/case"):
        check_case_path("case")


def test_write_run_and_campaign_refuse_such_a_folder_before_touching_it(tmp_path):
    spaced = tmp_path / "my runs"
    with pytest.raises(ConfigError) as info:
        write_case(spaced / "case", MOTION, end_time=0.01)
    message = str(info.value)
    assert f"{spaced / 'case'}" in message and "' '" in message
    assert f"{tmp_path / 'myruns' / 'case'}" in message  # where OpenFOAM would look
    assert not spaced.exists()
    # a case written elsewhere and moved there is refused before a solver starts
    case = write_case(tmp_path / "good" / "case", MOTION, end_time=0.01)
    spaced.mkdir()
    moved = shutil.move(case, spaced / "case")
    for run in (lambda: run_case(moved), lambda: run_application(moved, "blockMesh")):
        with pytest.raises(ConfigError, match="strips whitespace and quotes"):
            run()
    assert not (spaced / "case" / "constant" / "polyMesh").exists()
    assert not list((spaced / "case").glob("log.*"))
    quoted = tmp_path / "it's"
    with pytest.raises(ConfigError, match=r"\"'\" here"):
        run_campaign([CfdCase(1.0, 0.3, 90.0, 10.0, duration=0.02, ramp_time=0.01)], quoted,
                     progress=False)
    assert not quoted.exists()
    res = CliRunner().invoke(cli, ["cfd", "write", CASE_FILE, str(tmp_path / "a b"),
                                   "--cycles", "0.01"])
    assert res.exit_code == 2 and "OpenFOAM cannot run a case in" in res.output
    assert not (tmp_path / "a b").exists()


@pytest.mark.openfoam
def test_openfoam_strips_them_and_keeps_the_others(tmp_path):
    """The premise, on the real OpenFOAM: blockMesh in a folder with a space looks for the
    folder without it; in a folder with the characters it keeps, mfflap runs a case whole."""
    assert openfoam_available(), "OpenFOAM must be installed (.ci/run installs it)"
    case = write_case(tmp_path / "good", MOTION, end_time=0.002)
    spaced = tmp_path / "x y"
    shutil.copytree(case, spaced)
    env = {**os.environ, "WM_PROJECT_DIR": os.environ.get("WM_PROJECT_DIR",
                                                          "/usr/share/openfoam")}
    done = subprocess.run(["blockMesh", "-case", str(spaced)], capture_output=True,
                          text=True, env=env, timeout=120)
    assert done.returncode != 0
    assert f"Case   : {tmp_path / 'xy'}" in done.stdout
    kept = tmp_path / "x$y#(z)"
    write_case(kept, MOTION, end_time=0.002)
    run_case(kept, timeout_s=120)
    assert (kept / "constant" / "polyMesh" / "points").exists()
    assert (kept / "postProcessing").exists()
