"""The vortex level of the gap diagnosis on real OpenFOAM back-test records."""

import dataclasses
import json

import numpy as np
import pytest
from click.testing import CliRunner

from mfflap.cli.main import cli
from mfflap.gap.levels import STEPS_PER_PERIOD, level_residuals
from mfflap.hydro.discrete_vortex import VortexModelSettings, simulate_vortex_model
from mfflap.hydro.morison import MorisonModel
from mfflap.records.record import fixture_dir, read_records

CASE = "cases/paper2026.toml"


def test_the_share_is_what_the_two_residuals_say():
    rows = level_residuals(read_records(fixture_dir("backtest_main_job")), MorisonModel())
    for row in rows:
        # both NRMSEs share CFD's range, so the share of the sum of squares is their ratio
        assert row.explained_share == pytest.approx(
            1 - (row.vortex_nrmse / row.morison_nrmse) ** 2, rel=1e-9)
    # measured: on the main job's optimised motions the vortex model removes 34-76 % of it
    assert sum(row.explained_share > 0 for row in rows) >= 3


def test_cfd_that_is_the_vortex_model_is_wholly_explained():
    """A record whose loads are the vortex model's own, run the way the level runs it."""
    record = read_records(fixture_dir("backtest_main_job"))[0]
    uniform = record.state.on_uniform_time(record.period / STEPS_PER_PERIOD, start=0.0)
    run = simulate_vortex_model(uniform, None, None, None, VortexModelSettings()).loads
    t = record.state.time
    loads = dataclasses.replace(record.loads, normal_force=np.interp(t, run.time,
                                                                     run.normal_force))
    (row,) = level_residuals([dataclasses.replace(record, loads=loads)], MorisonModel())
    assert row.vortex_nrmse < 1e-12
    assert row.explained_share == pytest.approx(1.0, abs=1e-12)
    assert row.morison_nrmse > 0.05


def test_the_command_reports_each_record_and_refuses_another_plate(tmp_path):
    folder = str(fixture_dir("backtest_main_job"))
    res = CliRunner().invoke(cli, ["gap", "levels", CASE, "--fixtures", folder, "--json"])
    assert res.exit_code == 0, res.output
    out = json.loads(res.stdout)
    assert out["n_records"] == len(out["records"]) == len(list(
        fixture_dir("backtest_main_job").glob("*.h5")))
    assert out["median_vortex_nrmse"] < out["median_morison_nrmse"]
    case = tmp_path / "mid.toml"
    with open(CASE) as f:
        case.write_text(f.read().replace("[plate]", "[plate]\npivot_chord_fraction = 0.5"))
    res = CliRunner().invoke(cli, ["gap", "levels", str(case), "--fixtures", folder])
    assert res.exit_code != 0 and "plate.pivot_chord_fraction" in res.output


def test_the_diagnosis_carries_the_level_of_its_records_and_held_out_runs_into_file_and_report(
        tmp_path):
    """Records given to the diagnosis get a vortex-level row each, grouped as diagnosed or
    held out; the rows survive the results file and the report shows both groups."""
    from pathlib import Path

    from mfflap.config import CaseConfig
    from mfflap.gap.blindtest import synthesize
    from mfflap.gap.store import read_diagnosis, write_diagnosis
    from mfflap.gap.workflow import diagnose_cases
    from mfflap.reports.gap import gap_report
    from mfflap.results import ResultsFile

    records = read_records(fixture_dir("backtest_main_job"))
    cases = synthesize(np.random.default_rng(1), "circulatory_lift", 4.0, n_cases=12)
    diag, where, _ = diagnose_cases(CaseConfig(), cases, records=records[:2],
                                    held_out_records=records[2:3])
    assert [r.group for r in diag.levels.rows] == ["diagnosed", "diagnosed", "held out"]
    assert all(0 < r.vortex_nrmse < 1 and 0 < r.cfd_repeat_nrmse < 1 for r in diag.levels.rows)
    with ResultsFile(tmp_path / "gap.h5", "w") as rf:
        write_diagnosis(rf, diag, where)
    with ResultsFile(tmp_path / "gap.h5") as rf:
        back, _ = read_diagnosis(rf)
    assert [(r.record, r.group) for r in back.levels.rows] == [
        (r.record, r.group) for r in diag.levels.rows]
    np.testing.assert_allclose([r.explained_share for r in back.levels.rows],
                               [r.explained_share for r in diag.levels.rows])
    html = Path(gap_report(tmp_path / "gap.html", back, where)).read_text()
    assert "The discrete-vortex level" in html and "held out" in html
