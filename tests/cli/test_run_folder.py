"""`mfflap run --out` into a folder that holds another run: refused unless --overwrite, and
then the old run's outputs go first while its CFD stays."""

from __future__ import annotations

from pathlib import Path

import pytest
from click.testing import CliRunner

from mfflap.cli.main import cli
from mfflap.errors import OutputExistsError
from mfflap.reports.run_folder import prepare_run_folder, run_outputs_in

CASE = Path(__file__).parents[2] / "cases" / "paper2026.toml"


def _an_earlier_run(folder):
    (folder / "vtk").mkdir(parents=True)
    (folder / "vtk" / "beta__0.5.pvd").write_text("<VTKFile/>")
    (folder / "report.html").write_text("<html>earlier</html>")
    (folder / "results.h5").write_bytes(b"earlier")
    (folder / "round_2").mkdir()
    (folder / "backtest_records").mkdir()
    (folder / "backtest_records" / "backtest_1.h5").write_bytes(b"cfd")
    (folder / "cfd_cases" / "beta_0").mkdir(parents=True)
    (folder / "notes.txt").write_text("mine")


def test_a_second_run_into_the_same_folder_is_refused_and_touches_nothing(tmp_path):
    out = tmp_path / "paper_run"
    _an_earlier_run(out)
    before = sorted(p.relative_to(out) for p in out.rglob("*"))
    res = CliRunner().invoke(cli, ["run", str(CASE), "--out", str(out)])
    assert res.exit_code == 2, res.output
    assert str(out) in res.output and "--overwrite" in res.output
    assert "report.html" in res.output and "results.h5" in res.output
    assert sorted(p.relative_to(out) for p in out.rglob("*")) == before
    assert (out / "report.html").read_text() == "<html>earlier</html>"


def test_overwrite_removes_the_old_outputs_and_keeps_its_cfd_and_other_files(tmp_path):
    out = tmp_path / "paper_run"
    _an_earlier_run(out)
    assert run_outputs_in(out) == ("report.html", "results.h5", "round_2", "vtk")
    prepare_run_folder(out, overwrite=True)
    assert run_outputs_in(out) == ()
    assert not (out / "vtk").exists()
    assert (out / "backtest_records" / "backtest_1.h5").read_bytes() == b"cfd"
    assert (out / "cfd_cases" / "beta_0").is_dir()
    assert (out / "notes.txt").read_text() == "mine"


def test_a_folder_without_a_run_is_used_as_it_is(tmp_path):
    out = tmp_path / "fresh"
    assert prepare_run_folder(out, overwrite=False) == out and out.is_dir()
    (out / "notes.txt").write_text("mine")
    prepare_run_folder(out, overwrite=False)
    assert (out / "notes.txt").read_text() == "mine"


def test_the_refusal_is_typed_and_names_what_the_folder_holds(tmp_path):
    _an_earlier_run(tmp_path)
    with pytest.raises(OutputExistsError) as refused:
        prepare_run_folder(tmp_path, overwrite=False)
    assert refused.value.path == str(tmp_path)
    assert refused.value.held == ("report.html", "results.h5", "round_2", "vtk")


def test_outputs_are_never_written_through_a_symbolic_link(tmp_path):
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    out = tmp_path / "run"
    out.mkdir()
    (out / "vtk").symlink_to(elsewhere)
    with pytest.raises(OutputExistsError, match=r"symbolic links .*\(vtk\)"):
        prepare_run_folder(out, overwrite=True)
    linked = tmp_path / "linked_run"
    linked.symlink_to(elsewhere)
    res = CliRunner().invoke(cli, ["run", str(CASE), "--out", str(linked)])
    assert res.exit_code == 2 and "is a symbolic link" in res.output
    assert not any(elsewhere.iterdir())
