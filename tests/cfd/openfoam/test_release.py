"""Which OpenFOAM is on PATH: openfoam.com's line runs mfflap's cases, openfoam.org's is
refused before anything is written into the case."""

from __future__ import annotations

import os
import stat
from pathlib import Path

import pytest

from mfflap.cfd.openfoam.release import installed_release, release_from_help
from mfflap.cfd.openfoam.runner import run_case
from mfflap.cfd.openfoam.writer import write_case
from mfflap.errors import CfdRunError
from mfflap.kinematics import HarmonicMotion

DATA = Path(__file__).parents[2] / "data" / "openfoam_v1912"

#: the last lines of `foamRun -help` / `blockMesh -help` of the openfoam.org line's release
#: 11 (that line cannot be installed here: Debian packages openfoam.com's)
FOUNDATION_11_HELP = ("  -help             print the usage\n\n"
                      "Using: OpenFOAM-11 (see https://openfoam.org)\n"
                      "Build: 11-e1fc8c682ae6\n")


def test_debian_v1912_help_names_openfoam_com_and_its_release():
    """Real output of this machine's pimpleFoam -help: v1912 leaves its name empty and
    gives the release only as its API number."""
    release = release_from_help((DATA / "pimpleFoam-help.txt").read_text())
    assert (release.line, release.version) == ("openfoam.com", "v1912")
    assert release.describe() == "OpenFOAM v1912 of openfoam.com"


@pytest.mark.parametrize(("text", "line", "version"), [
    (FOUNDATION_11_HELP, "openfoam.org", "11"),
    ("Using: OpenFOAM-v2312 (2312) - visit www.openfoam.com\nBuild: f8fc98ec70-20231220 "
     "OPENFOAM=2312 version=v2312\n", "openfoam.com", "v2312"),
    ("Usage: blockMesh [OPTIONS]\n  -help  print the usage\n", "unknown", ""),
    ("Using: OpenFOAM-dev (see somewhere else)\n", "unknown", "dev"),
])
def test_other_releases_help_lines(text, line, version):
    release = release_from_help(text)
    assert (release.line, release.version) == (line, version)


def test_the_installed_solvers_are_openfoam_com_s():
    """.ci/run installs Debian's openfoam: the release the runner checks must pass."""
    release = installed_release("blockMesh", os.environ["PATH"])
    assert release is not None and release.line == "openfoam.com", release
    assert release.version.startswith("v")


def _stand_in(folder: Path, name: str, help_text: str) -> None:
    """An executable `name` that prints help_text and would leave a mark if run on a case."""
    folder.mkdir(exist_ok=True)
    script = folder / name
    script.write_text("#!/bin/sh\n"
                      f"if [ \"$1\" = -help ]; then printf '%s' '{help_text}'; exit 0; fi\n"
                      "touch \"$3/ran_$0\"\n")
    script.chmod(script.stat().st_mode | stat.S_IXUSR)


def test_openfoam_org_solvers_are_refused_before_the_case_is_touched(tmp_path, monkeypatch):
    case = write_case(tmp_path / "case", HarmonicMotion(1.0, 0.1, 0.1, 1.57), end_time=0.01)
    before = sorted(p.relative_to(case) for p in case.rglob("*"))
    bin_dir = tmp_path / "bin"
    for name in ("blockMesh", "checkMesh", "pimpleFoam"):
        _stand_in(bin_dir, name, FOUNDATION_11_HELP)
    monkeypatch.setenv("PATH", f"{bin_dir}{os.pathsep}{os.environ['PATH']}")
    with pytest.raises(CfdRunError, match=r"blockMesh on PATH is OpenFOAM 11 of openfoam\.org "
                                          r"\('Using: OpenFOAM-11 \(see https://openfoam\.org\)'"
                                          r"\), but mfflap writes cases for the openfoam\.com "
                                          r"line") as err:
        run_case(case)
    assert str(case) in str(err.value)
    assert sorted(p.relative_to(case) for p in case.rglob("*")) == before  # nothing ran


def test_foam_run_without_block_mesh_is_named(tmp_path, monkeypatch):
    case = write_case(tmp_path / "case", HarmonicMotion(1.0, 0.1, 0.1, 1.57), end_time=0.01)
    bin_dir = tmp_path / "bin"
    _stand_in(bin_dir, "foamRun", FOUNDATION_11_HELP)
    monkeypatch.setenv("PATH", str(bin_dir))  # no other OpenFOAM on PATH
    with pytest.raises(CfdRunError, match=r"OpenFOAM's blockMesh is not on PATH \(foamRun is "
                                          r"there instead: that is the openfoam\.org line"):
        run_case(case)
