"""A record's cycle scatter: on real OpenFOAM records (a back-tested periodic motion and a
Table 1 pitch ramp), against cycles built to differ by a known amount, stored in the record
and listed by `mfflap campaign scatter`."""

from __future__ import annotations

import json
import shutil

import h5py
import numpy as np
import pytest
from click.testing import CliRunner

from mfflap.cli.main import cli
from mfflap.hydro.loads import Loads
from mfflap.kinematics.continuous import HarmonicMotion
from mfflap.records.cycle_scatter import (
    GROUP,
    add_cycle_scatter,
    cycle_scatter,
    folder_cycle_scatter,
    read_cycle_scatter,
)
from mfflap.records.record import (
    CfdRecord,
    backtest_fixture_dirs,
    fixture_dir,
    read_record,
    record_paths,
)


def _periodic_record_path():
    return record_paths(backtest_fixture_dirs()[0])[0]


def _synthetic(scale_per_cycle, kind="harmonic"):
    t = np.linspace(0.0, 4.0, 1601)
    state = HarmonicMotion(1.0, 0.1, 0.3).sample(t)
    growth = 1 + scale_per_cycle * np.floor(t)
    fn = np.sin(2 * np.pi * t) * growth
    return CfdRecord("c", state, Loads(t, fn, 0.1 * fn, 0 * t),
                     {"kind": kind, "frequency": 1.0, "ramp_time": 0.25})


def test_identical_cycles_have_no_scatter():
    s = cycle_scatter(_synthetic(0.0))
    assert s.n_cycles == 2 and s.repeats  # 3 whole periods after the ramp, the first left out
    assert s.rms_normal_force_scatter_n < 1e-9 * s.rms_normal_force_n


def test_cycles_that_grow_give_their_spread():
    """The last two periods of sin(2 pi t) scaled by 1.2 and 1.3: RMS 1.25 / sqrt 2, sample
    standard deviation 0.05 sqrt 2 / sqrt 2 = 0.05."""
    s = cycle_scatter(_synthetic(0.1))
    assert s.rms_normal_force_n == pytest.approx(1.25 / np.sqrt(2), rel=1e-3)
    assert s.rms_normal_force_scatter_n == pytest.approx(0.05, rel=1e-2)


def test_a_record_without_a_period_or_a_whole_cycle_has_none():
    record = _synthetic(0.0)
    record.parameters = {"kind": "harmonic"}
    assert cycle_scatter(record) is None
    record.parameters = {"kind": "harmonic", "frequency": 0.2}  # 4 s of a 5 s period
    assert cycle_scatter(record) is None


def test_a_real_periodic_record_repeats_and_a_pitch_ramp_does_not():
    periodic = cycle_scatter(read_record(_periodic_record_path()))
    assert periodic.repeats and periodic.n_cycles >= 2
    assert np.isfinite(periodic.thrust_scatter_n) and periodic.rms_normal_force_n > 0
    assert periodic.relative("rms_normal_force") < 0.2
    ramp = cycle_scatter(read_record(record_paths(fixture_dir("table1_coarse"))[-1]))
    assert ramp is not None and not ramp.repeats


def test_the_scatter_is_stored_in_the_record_and_read_back(tmp_path):
    path = shutil.copy(_periodic_record_path(), tmp_path / "case.h5")
    added = add_cycle_scatter(path)
    assert read_cycle_scatter(path) == added
    with h5py.File(path) as h5:
        assert GROUP in h5 and "units" in h5[GROUP].attrs
    np.testing.assert_array_equal(read_record(path).loads.normal_force,
                                  read_record(_periodic_record_path()).loads.normal_force)


def test_campaign_scatter_adds_and_lists_every_record(tmp_path):
    for path in record_paths(backtest_fixture_dirs()[0])[:2]:
        shutil.copy(path, tmp_path / path.name)
    result = CliRunner().invoke(cli, ["campaign", "scatter", str(tmp_path), "--json"])
    assert result.exit_code == 0, result.output
    rows = json.loads(result.output)
    assert len(rows) == 2 and all(r["n_cycles"] >= 2 for r in rows)
    assert all(read_cycle_scatter(p) is not None for p in record_paths(tmp_path))
    assert [n for n, _ in folder_cycle_scatter(tmp_path)] == [r["name"] for r in rows]
    text = CliRunner().invoke(cli, ["campaign", "scatter", str(tmp_path)])
    assert text.exit_code == 0 and "+-" in text.output
