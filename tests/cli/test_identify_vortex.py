"""``mfflap identify-vortex`` on a real OpenFOAM back-test record."""

import json
import shutil

from click.testing import CliRunner

from mfflap.cli.main import cli
from mfflap.records.record import fixture_dir, record_paths

CASE = "cases/paper2026.toml"


def _one_record(tmp_path):
    folder = tmp_path / "records"
    folder.mkdir()
    shutil.copy(record_paths(fixture_dir("backtest_main_job"))[0], folder)
    return folder


def test_the_identified_pair_is_the_grids_best_and_says_each_records_error(tmp_path):
    folder = _one_record(tmp_path)
    res = CliRunner().invoke(cli, ["identify-vortex", CASE, "--fixtures", str(folder),
                                   "--json"])
    assert res.exit_code == 0, res.output
    out = json.loads(res.stdout)
    assert len(out["grid"]) == 15 and out["n_records"] == 1
    best = min(out["grid"], key=lambda row: row["rms_nrmse_normal_force"])
    assert (out["critical_lesp"], out["core_radius_chords"]) == (
        best["critical_lesp"], best["core_radius_chords"])
    # the grid is not flat: the pairs differ, and the best follows CFD's F_n within 20 %
    scores = [row["rms_nrmse_normal_force"] for row in out["grid"]]
    assert max(scores) > 1.05 * min(scores)
    assert 0 < out["rms_nrmse_normal_force"] < 0.2
    assert list(out["record_nrmse_normal_force"].values()) == [out["rms_nrmse_normal_force"]]


def test_records_of_another_pivot_are_refused_by_key(tmp_path):
    folder = _one_record(tmp_path)
    case = tmp_path / "quarter.toml"
    with open(CASE) as f:  # the case file has a [plate] table: the pivot goes into it
        case.write_text(f.read().replace("[plate]", "[plate]\npivot_chord_fraction = 0.25"))
    res = CliRunner().invoke(cli, ["identify-vortex", str(case), "--fixtures", str(folder)])
    assert res.exit_code != 0
    assert "plate.pivot_chord_fraction" in res.output and "0.25" in res.output


def test_the_records_are_asked_for():
    res = CliRunner().invoke(cli, ["identify-vortex", CASE])
    assert res.exit_code == 2 and "--fixtures" in res.output
