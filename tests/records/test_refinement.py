"""A record's refinement changes go into its HDF5 file and come back whole, through every
way a record is written (a rewrite in single precision keeps them), and a record without
them reads with none."""

from __future__ import annotations

from pathlib import Path

import h5py
import numpy as np
import pytest

from mfflap.records.record import compact_folder, read_record, write_record
from mfflap.records.refinement import RefinementChange, read_refinement, write_refinement

ROOT = Path(__file__).parents[2]
SHIPPED = ROOT / "campaigns" / "harmonic_set" / "harmonic_f1p000_h0p0500_th45p00_phi090p0.h5"


def _change(kind: str = "mesh") -> RefinementChange:
    return RefinementChange(kind, "f.h5", "campaigns/fine", "ab" * 32, 1.49, 3, 0.052, 0.987,
                            (1.5, 1.6), (-12.0, -12.5), (8.0, 8.3), 0.31, 0.19, 0.17)


def test_a_change_written_into_a_record_reads_back_equal(tmp_path):
    record = read_record(SHIPPED)
    assert record.refinement == {}
    record.refinement = {"mesh": _change("mesh"), "time_step": _change("time_step")}
    path = write_record(tmp_path / "r.h5", record)
    again = read_record(path)
    assert again.refinement == record.refinement
    assert isinstance(again.refinement["mesh"].mean_power_w, tuple)


def test_a_rewrite_in_single_precision_keeps_the_changes(tmp_path):
    record = read_record(SHIPPED)
    record.provenance.pop("storage", None)  # as a campaign writes it, in full precision
    record.refinement = {"mesh": _change()}
    write_record(tmp_path / "r.h5", record)
    assert compact_folder(tmp_path) == [tmp_path / "r.h5"]
    assert read_record(tmp_path / "r.h5").refinement == {"mesh": _change()}
    assert read_record(tmp_path / "r.h5").window(1.0).refinement == {"mesh": _change()}


def test_writing_a_kind_again_replaces_it_and_keeps_the_other(tmp_path):
    path = tmp_path / "x.h5"
    with h5py.File(path, "w") as h5:
        write_refinement(h5, _change("mesh"))
        write_refinement(h5, _change("time_step"))
        newer = RefinementChange(**{**_change("mesh").__dict__, "normal_force_nrmse": 0.2})
        write_refinement(h5, newer)
    with h5py.File(path, "r") as h5:
        got = read_refinement(h5)
    assert got["mesh"].normal_force_nrmse == 0.2
    assert got["time_step"] == _change("time_step")


def test_the_relative_change_names_the_means_it_knows():
    change = _change()
    assert change.relative_change("mean_thrust") == pytest.approx(0.1 / 1.5)
    assert np.isfinite(change.relative_change("rms_normal_force"))
    with pytest.raises(KeyError, match="mean_thrust"):
        change.relative_change("thrust")
