"""Compact copies of CFD records: window means checked against exact integrals, a real
OpenFOAM record's means and force history kept through the reduction, the record's other
groups carried over, and refusals that name the record."""

from __future__ import annotations

from pathlib import Path

import h5py
import numpy as np
import pytest
from click.testing import CliRunner
from scipy.integrate import quad

from mfflap.cli.main import cli
from mfflap.errors import MfflapError
from mfflap.hydro.loads import Loads
from mfflap.kinematics.state import KinematicState
from mfflap.metrics import nrmse, time_mean
from mfflap.performance import thrust_and_power
from mfflap.records.cycle_scatter import read_cycle_scatter
from mfflap.records.record import CfdRecord, read_record, write_record
from mfflap.records.reduce import (
    SAMPLES_PER_PERIOD,
    reduce_folder,
    reduced_record,
    window_means,
)

ROOT = Path(__file__).resolve().parents[2]
#: a Table 1 record of the full campaign (17,000 adaptive steps over 3 periods at 0.1 Hz)
#: and a harmonic-set record with its mesh and time-step refinement
GRID_RECORD = ROOT / "campaigns" / "table1_full" / "f0p100_h0p100_phi045p0.h5"
HARMONIC_RECORD = ROOT / "campaigns" / "harmonic_set" / \
    "harmonic_f1p000_h0p0500_th30p00_phi060p0.h5"


def test_window_means_are_the_exact_means_of_the_piecewise_linear_signal():
    rng = np.random.default_rng(3)
    t = np.cumsum(rng.uniform(0.01, 0.2, 60))
    v = rng.normal(size=60)
    edges = np.sort(rng.uniform(t[0], t[-1], 9))
    def signal(x):
        return np.interp(x, t, v)

    for a, b, mean in zip(edges[:-1], edges[1:], window_means(t, v, edges), strict=True):
        inside = t[(t > a) & (t < b)]
        expected = quad(signal, a, b, points=inside, limit=200)[0] / (b - a)
        assert mean == pytest.approx(expected, rel=1e-9, abs=1e-12)


def test_window_means_keep_a_rate_the_change_of_its_position():
    """A window mean is a linear filter: the mean of the rate is the position's change over
    the window, so the reduced kinematics stay consistent."""
    t = np.sort(np.random.default_rng(1).uniform(0.0, 2.0, 3000))
    t[0], t[-1] = 0.0, 2.0
    edges = np.linspace(0.0, 2.0, 41)
    rate = window_means(t, 2 * np.pi * np.cos(2 * np.pi * t), edges)
    change = np.diff(np.sin(2 * np.pi * edges)) / np.diff(edges)
    assert np.max(np.abs(rate - change)) < 2e-3 * 2 * np.pi


def test_a_real_record_keeps_its_means_and_force_history_at_100_samples_a_period():
    full = read_record(GRID_RECORD)
    small = reduced_record(full)
    periods = (full.time[-1] - full.time[0]) / full.period
    assert len(small.time) == round(periods * SAMPLES_PER_PERIOD)
    assert len(small.time) < len(full.time) / 20
    assert np.allclose(np.diff(small.time), full.period / SAMPLES_PER_PERIOD, rtol=1e-4)
    assert small.raw_force is None and small.raw_moment is None
    assert small.provenance["reduced_from_samples"] == len(full.time)
    # the means of the last two periods (thrust, power, mean square F_n as time averages)
    # move by less than 0.5 % of each signal's RMS (this motion's mean power is 5 % of its
    # RMS, so a relative bound on it would measure nothing but that)
    means, rms = [], []
    for record in (full, small):
        last = record.window(record.time[-1] - 2 * record.period)
        thrust, power = thrust_and_power(last.loads, last.state)
        signals = (thrust, power, last.loads.normal_force ** 2)
        means.append([time_mean(last.time, x) for x in signals])
        rms.append([np.sqrt(np.mean(x ** 2)) for x in signals])
    assert np.all(np.abs(np.subtract(*means)) < 5e-3 * np.asarray(rms[0]))
    # the history: within a percent of the full record at the reduced record's times
    f_n = np.interp(small.time, full.time, full.loads.normal_force)
    assert nrmse(small.loads.normal_force, f_n) < 0.01


def test_a_folder_copy_keeps_the_records_groups_and_the_campaign_file(tmp_path):
    source = tmp_path / "campaign"
    source.mkdir()
    for path in (GRID_RECORD, HARMONIC_RECORD):
        (source / path.name).write_bytes(path.read_bytes())
    (source / "campaign.toml").write_text("[campaign]\nsetup = \"table1\"\n")
    result = CliRunner().invoke(cli, ["campaign", "reduce", str(source), str(tmp_path / "copy")])
    assert result.exit_code == 0, result.output
    assert "2 records reduced to 100 samples a period" in result.output
    assert (tmp_path / "copy" / "campaign.toml").read_text() == \
        (source / "campaign.toml").read_text()
    for path in (GRID_RECORD, HARMONIC_RECORD):
        copy = tmp_path / "copy" / path.name
        assert copy.stat().st_size < path.stat().st_size / 4
        full, small = read_record(path), read_record(copy)
        assert small.parameters == full.parameters
        assert {k: v for k, v in small.provenance.items() if not k.startswith("reduced_")} \
            == {**full.provenance, "storage": "float32"}
        assert read_cycle_scatter(copy) == read_cycle_scatter(path)
        assert small.refinement == full.refinement
        with h5py.File(copy) as h5:
            assert "raw" not in h5
            assert h5["loads/normal_force"].dtype == np.float32
    assert read_record(tmp_path / "copy" / HARMONIC_RECORD.name).refinement  # it had some


def _record(n: int, parameters: dict) -> CfdRecord:
    t = np.linspace(0.0, 2.0, n)
    zero = np.zeros_like(t)
    return CfdRecord("plain", KinematicState(t, *(zero for _ in range(6))),
                     Loads(t, zero, zero, zero), parameters)


def test_records_that_cannot_be_reduced_are_refused_by_name(tmp_path):
    with pytest.raises(MfflapError, match="record plain: no period nor frequency"):
        reduced_record(_record(1000, {"kind": "table"}))
    with pytest.raises(MfflapError, match="record plain: 150 samples, no more than the 200"):
        reduced_record(_record(150, {"frequency": 1.0}))
    with pytest.raises(MfflapError, match="no CFD record to reduce"):
        reduce_folder(tmp_path, tmp_path / "copy")
    write_record(tmp_path / "plain.h5", _record(150, {"period": 1.0}))
    with pytest.raises(MfflapError, match="record plain"):
        reduce_folder(tmp_path, tmp_path / "copy")
