"""The full Table 1 campaign (campaigns/table1_full) as far as it has run: every finished
record is a real OpenFOAM run of its grid case for the case's n_cycles periods, on the one
set-up the campaign names, and the cases it holds are the grid's."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from mfflap.campaign.cases import grid_cases
from mfflap.config import load_case
from mfflap.records.as_run import as_run_since_s
from mfflap.records.record import read_record, record_paths
from mfflap.toml_io import read_toml

ROOT = Path(__file__).parents[2]
FOLDER = ROOT / "campaigns" / "table1_full"
RECORDS = record_paths(FOLDER)
GRID = {c.case_id: c for c in grid_cases(load_case(ROOT / "cases" / "paper2026.toml")
                                         .identification)}

pytestmark = pytest.mark.findings


def test_the_campaign_lists_the_whole_grid_on_one_set_up():
    manifest = read_toml(FOLDER / "campaign.toml")
    assert set(manifest["cases"]) == set(GRID) and len(GRID) == 125
    solver = manifest["setup"]["solver"]
    assert (solver["wall_treatment"], solver["far_field"], solver["max_courant"]) == (
        "all_y_plus", "inletOutlet", 2.0)
    for case_id, listed in manifest["cases"].items():
        case = GRID[case_id]
        assert listed["duration"] == pytest.approx(3.0 / case.frequency)
        assert listed["pitch_ramp_rate_deg"] * listed["duration"] <= 60.0 + 1e-9


@pytest.mark.parametrize("path", RECORDS, ids=[p.stem for p in RECORDS])
def test_each_finished_record_is_a_real_run_of_its_case_for_three_periods(path):
    record = read_record(path)
    case = GRID[path.stem]
    assert record.parameters["frequency"] == case.frequency
    assert record.parameters["pitch_ramp_rate_deg"] == case.pitch_ramp_rate_deg
    assert record.provenance["openfoam_build"].startswith("OPENFOAM=")
    assert record.provenance["cpu_time_s"] > 0
    assert record.time[-1] == pytest.approx(3.0 / case.frequency, rel=1e-3)
    assert np.all(np.diff(record.time) > 0)
    # one set-up throughout: the settings asked, and a retry (if any) rerun from t = 0 s
    assert record.provenance["as_run_wall_treatment"] == "all_y_plus"
    assert record.provenance["as_run_far_field"] == "inletOutlet"
    assert record.provenance["retries_from_start"] is True
    assert as_run_since_s(record) == 0.0
