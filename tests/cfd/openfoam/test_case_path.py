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
from mfflap.cfd.openfoam.case_path import (
    check_case_path,
    prepare_case_folder,
    stripped_characters,
)
from mfflap.cfd.openfoam.runner import openfoam_available, run_application, run_case
from mfflap.cfd.openfoam.writer import write_case
from mfflap.cli.main import cli
from mfflap.errors import ConfigError, MotionError
from mfflap.kinematics import HarmonicMotion
from mfflap.toml_io import read_toml

MOTION = HarmonicMotion(1.0, 0.3, np.deg2rad(20), np.pi / 2)
CASE_FILE = os.path.join(os.path.dirname(__file__), "..", "..", "..", "cases", "paper2026.toml")


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
    said = []
    for run in (lambda: run_case(moved, progress=said.append),
                lambda: run_application(moved, "blockMesh")):
        with pytest.raises(ConfigError, match="strips whitespace and quotes"):
            run()
    assert said == []  # refused before "meshing" was said
    res = CliRunner().invoke(cli, ["cfd", "run", str(moved)])
    assert res.exit_code == 2 and "strips whitespace" in res.output
    assert "meshing" not in res.output
    assert not (spaced / "case" / "constant" / "polyMesh").exists()
    assert not list((spaced / "case").glob("log.*"))
    quoted = tmp_path / "it's"
    with pytest.raises(ConfigError, match=r"\"'\" here"):
        run_campaign([CfdCase(1.0, 0.3, 90.0, 10.0, duration=0.02, ramp_time=0.01)], quoted,
                     progress=False)
    assert not quoted.exists()
    # a time limit the solver cannot have is refused before the case is meshed
    ok = write_case(tmp_path / "ok", MOTION, end_time=0.01)
    for timeout in (0.0, float("nan")):
        with pytest.raises(ConfigError, match="time limit of pimpleFoam") as err:
            run_case(ok, timeout_s=timeout, progress=said.append)
        assert err.value.key == "timeout_s" and said == []
    assert not (ok / "constant" / "polyMesh").exists()
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


def test_a_case_is_written_only_into_a_new_or_empty_folder_or_over_a_case_on_request(
        tmp_path):
    """A case written over another used to mix with it: the run resumed from the old times,
    kept the old mesh, and a plate-frame case's MRFProperties stayed in an inertial case."""
    from mfflap.cfd.openfoam.case_lock import LOCK_FILE
    from mfflap.cfd.openfoam.writer import SolverSettings

    assert prepare_case_folder(tmp_path / "new", "mfflap_case.toml") == tmp_path / "new"
    (tmp_path / "empty").mkdir()
    (tmp_path / "empty" / LOCK_FILE).write_text("")  # a lock file alone is no content
    write_case(tmp_path / "empty", MOTION, end_time=0.01)
    # a folder of something else is never deleted, overwrite or not
    other = tmp_path / "notes"
    other.mkdir()
    (other / "todo.txt").write_text("keep me")
    for overwrite in (False, True):
        with pytest.raises(ConfigError, match=r"notes is not empty \(todo.txt\) and holds no "
                                              r"case mfflap wrote"):
            write_case(other, MOTION, end_time=0.01, overwrite=overwrite)
    assert (other / "todo.txt").read_text() == "keep me" and len(list(other.iterdir())) == 1
    # a plate-frame case that ran: refused, then overwritten by an inertial one
    case = write_case(tmp_path / "case", MOTION, end_time=0.01,
                      solver=SolverSettings(frame="plate", far_field="inletOutlet"))
    assert (case / "constant" / "MRFProperties").exists()
    for ran in ("0.005/U", "postProcessing/forces/0/force.dat", "constant/polyMesh/points"):
        (case / ran).parent.mkdir(parents=True, exist_ok=True)
        (case / ran).write_text("")
    with pytest.raises(ConfigError, match=r"holds a case written before \(0, 0.005, constant, "
                                          r"mfflap_case.toml, postProcessing, system\).*"
                                          r"--overwrite"):
        write_case(case, MOTION, end_time=0.01)
    with pytest.raises(MotionError, match="end_time"):  # a bad setting deletes nothing
        write_case(case, MOTION, end_time=-1.0, overwrite=True)
    assert (case / "0.005" / "U").exists()
    write_case(case, MOTION, end_time=0.01, overwrite=True)
    assert not (case / "0.005").exists() and not (case / "postProcessing").exists()
    assert not (case / "constant" / "polyMesh").exists()
    assert not (case / "constant" / "MRFProperties").exists()
    assert (case / "constant" / "dynamicMeshDict").exists()
    assert read_toml(case / "mfflap_case.toml")["frame"] == "inertial"
    with pytest.raises(ConfigError, match="is a file"):
        write_case(case / "mfflap_case.toml", MOTION, end_time=0.01)


def test_a_case_with_a_run_going_is_not_overwritten(tmp_path):
    import threading

    from mfflap.cfd.openfoam.case_lock import CaseBusyError, case_lock

    case = write_case(tmp_path / "case", MOTION, end_time=0.01)
    holding, release = threading.Event(), threading.Event()

    def run() -> None:
        with case_lock(case):
            holding.set()
            release.wait(30)

    thread = threading.Thread(target=run)
    thread.start()
    try:
        assert holding.wait(30)
        with pytest.raises(CaseBusyError):
            write_case(case, MOTION, end_time=0.02, overwrite=True)
        assert read_toml(case / "mfflap_case.toml")["end_time"] == 0.01
    finally:
        release.set()
        thread.join()


@pytest.mark.openfoam
def test_cfd_write_over_a_case_that_ran_needs_overwrite_and_then_starts_afresh(tmp_path):
    """The real run: written again with another end time, the case used to resume from the
    first run's last time; refused now, and overwritten it runs from t = 0 on a new mesh."""
    assert openfoam_available(), "OpenFOAM must be installed (.ci/run installs it)"
    case = tmp_path / "case"
    write = ["cfd", "write", CASE_FILE, str(case), "--set", "cfd.writes=1"]
    runner = CliRunner()
    assert runner.invoke(cli, [*write, "--cycles", "0.002"]).exit_code == 0
    run_case(case, timeout_s=120)
    assert (case / "0.002").is_dir()
    res = runner.invoke(cli, [*write, "--cycles", "0.004"])
    assert res.exit_code == 2 and "holds a case written before (0, 0.002," in res.output
    assert read_toml(case / "mfflap_case.toml")["end_time"] == 0.002
    res = runner.invoke(cli, [*write, "--cycles", "0.004", "--overwrite"])
    assert res.exit_code == 0, res.output
    run_case(case, timeout_s=120)
    log = (case / "log.pimpleFoam").read_text()
    assert log.count("Create time") == 1 and "Starting time loop" in log
    assert sorted(p.name for p in case.iterdir() if p.name[0].isdigit()) == ["0", "0.004"]
