"""The harmonic identification set (campaigns/harmonic_set) as far as it has run: every
finished record is a real OpenFOAM run of its harmonic case for the set's n_cycles periods,
on the one set-up of the Table 1 campaign, and the cases it holds are the set's."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from mfflap.campaign.cases import harmonic_set_cases
from mfflap.config import load_case
from mfflap.records.as_run import as_run_since_s
from mfflap.records.record import read_record, record_paths
from mfflap.toml_io import read_toml

ROOT = Path(__file__).parents[2]
FOLDER = ROOT / "campaigns" / "harmonic_set"
RECORDS = record_paths(FOLDER)
CASE = load_case(ROOT / "cases" / "paper2026.toml")
SET = {c.case_id: c for c in harmonic_set_cases(CASE.harmonic_set)}

pytestmark = pytest.mark.findings


def test_the_campaign_lists_the_whole_set_on_the_grid_campaigns_set_up():
    manifest = read_toml(FOLDER / "campaign.toml")
    grid = read_toml(ROOT / "campaigns" / "table1_full" / "campaign.toml")
    assert set(manifest["cases"]) == set(SET) and len(SET) >= 30
    assert manifest["setup"] == grid["setup"]
    for case_id, listed in manifest["cases"].items():
        case = SET[case_id]
        assert listed["duration"] == pytest.approx(CASE.harmonic_set.n_cycles / case.frequency)
        assert 1.0 <= case.frequency <= 2.5 and 30.0 <= case.pitch_amplitude_deg <= 60.0


@pytest.mark.parametrize("path", RECORDS, ids=[p.stem for p in RECORDS])
def test_each_finished_record_is_a_real_run_of_its_case_for_its_periods(path):
    record = read_record(path)
    case = SET[path.stem]
    assert record.parameters["kind"] == "harmonic"
    assert record.parameters["pitch_amplitude_deg"] == case.pitch_amplitude_deg
    assert record.provenance["openfoam_build"].startswith("OPENFOAM=")
    assert record.provenance["cpu_time_s"] > 0
    assert record.time[-1] == pytest.approx(case.duration, rel=1e-3)
    assert np.all(np.diff(record.time) > 0)
    assert record.provenance["as_run_wall_treatment"] == "all_y_plus"
    assert record.provenance["retries_from_start"] is True
    assert as_run_since_s(record) == 0.0
