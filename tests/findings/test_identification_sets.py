"""The identification sets mfflap ships are compact copies of the repository's campaigns:
every one of the 125 Table 1 cases and the 36 harmonic motions, with the full record's
parameters, provenance and uncertainty, and coefficients identified from them that the
full records give too, within the identification's own bootstrap spread."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from mfflap.config import load_case
from mfflap.identification.workflow import identify_strategies, load_cases
from mfflap.records.cycle_scatter import read_cycle_scatter
from mfflap.records.record import (
    IDENTIFICATION_FIXTURES,
    identification_fixture_dirs,
    read_record,
    record_paths,
)
from mfflap.records.reduce import SAMPLES_PER_PERIOD

ROOT = Path(__file__).resolve().parents[2]
CASE = ROOT / "cases" / "paper2026.toml"
#: shipped set -> the campaign folder it was reduced from
CAMPAIGNS = {"table1_grid": ROOT / "campaigns" / "table1_full",
             "harmonic_set": ROOT / "campaigns" / "harmonic_set"}


@pytest.mark.parametrize("name", IDENTIFICATION_FIXTURES)
def test_every_campaign_record_ships_as_its_compact_copy(name):
    shipped = dict(zip(IDENTIFICATION_FIXTURES, identification_fixture_dirs(), strict=True))
    copies = record_paths(shipped[name])
    fulls = record_paths(CAMPAIGNS[name])
    assert [p.name for p in copies] == [p.name for p in fulls]
    assert len(copies) == {"table1_grid": 125, "harmonic_set": 36}[name]
    for copy, full_path in zip(copies, fulls, strict=True):
        small, full = read_record(copy), read_record(full_path)
        assert small.parameters == full.parameters, copy.name
        assert small.provenance["solver"] == "OpenFOAM pimpleFoam"
        assert small.provenance["cpu_time_s"] == full.provenance["cpu_time_s"]
        assert small.provenance["reduced_from_samples"] == len(full.time)
        half_window = 0.5 * (small.time[1] - small.time[0])  # each mean at its window's centre
        assert small.time[-1] + half_window == pytest.approx(full.time[-1], abs=1e-6)
        periods = (full.time[-1] - full.time[0]) / full.period
        assert len(small.time) == round(periods * SAMPLES_PER_PERIOD), copy.name
        assert read_cycle_scatter(copy) == read_cycle_scatter(full_path), copy.name
        assert small.refinement == full.refinement, copy.name


def test_the_compact_sets_identify_the_coefficients_the_full_records_do():
    """Pooled grid and harmonic set, uniform weighting: each coefficient from the compact
    copies lies within one bootstrap standard error of the full records' (the reduction
    moves the fit less than resampling the cases does)."""
    config = load_case(CASE)
    fits = {}
    for label, folders in (("full", list(CAMPAIGNS.values())),
                           ("compact", list(identification_fixture_dirs()))):
        cases, excluded = load_cases(config, folders)
        assert len(cases) == 161 and not excluded
        fits[label] = identify_strategies(config, cases, excluded, ["uniform"],
                                          n_bootstrap=60 if label == "compact" else 0
                                          )["uniform"]
    full, compact = fits["full"], fits["compact"]
    for term, value in full.coefficients.items():
        spread = compact.standard_error[term]
        assert np.isfinite(spread) and spread > 0
        assert abs(compact.coefficients[term] - value) < spread, term
    # the normal coefficients, which set the thrust and power, agree far closer
    for term in ("normal_added_mass", "normal_drag"):
        assert compact.coefficients[term] == pytest.approx(full.coefficients[term], rel=0.03)
