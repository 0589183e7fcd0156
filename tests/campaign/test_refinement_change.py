"""The mesh and time-step change of a record from a refined run of its motion: the NRMSE,
Pearson r and two-level index checked against figures worked out here from the signals'
closed forms, the refusals of pairs that are not a refinement, and the whole path on real
OpenFOAM records (stored in the coarse record, naming the refined file by its hash)."""

from __future__ import annotations

import hashlib
import shutil
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from mfflap.campaign.refinement import add_refinement, refinement_change, refinement_kind
from mfflap.cli.main import cli
from mfflap.errors import ConfigError, MfflapError
from mfflap.hydro.loads import Loads
from mfflap.kinematics.continuous import HarmonicMotion
from mfflap.records.record import CfdRecord, read_record

ROOT = Path(__file__).parents[2]
CAMPAIGNS = ROOT / "campaigns"
FREQUENCY_HZ = 1.5
T = np.linspace(0.0, 4.0, 4001)


def _record(fn_amplitude: float, phase_rad: float, *, n_cells: int = 10_000,
            max_courant: float = 2.0, mesh: str = "coarse", frequency: float = FREQUENCY_HZ
            ) -> CfdRecord:
    state = HarmonicMotion(frequency, 0.1, 0.0).sample(T)  # no pitch: thrust is -F_t
    w = 2 * np.pi * frequency
    fn = fn_amplitude * np.sin(w * T + phase_rad)
    ft = -0.5 + 0 * T  # a constant tangential force: thrust 0.5 N
    return CfdRecord("case", state, Loads(T, fn, ft, 0 * T),
                     {"kind": "harmonic", "frequency": frequency, "ramp_time": 0.5},
                     {"n_cells": n_cells, "solver_max_courant": max_courant, "mesh": mesh})


def test_the_change_of_a_sinusoid_scaled_and_shifted_is_its_closed_form():
    """F_n = A sin(wt) against 1.2 A sin(wt + 0.3): the RMS difference is
    A sqrt((1 + 1.44 - 2.4 cos 0.3) / 2), the range 2A, Pearson cos 0.3; the RMS F_n's change
    +20 % and its index Fs |d| r^p / (r^p - 1) with r = sqrt(4)."""
    coarse = _record(10.0, 0.0)
    refined = _record(12.0, 0.3, n_cells=40_000, mesh="medium")
    change = refinement_change(coarse, refined, "mesh")
    assert change.refinement_ratio == pytest.approx(2.0)
    rms = 10.0 * np.sqrt((1 + 1.44 - 2.4 * np.cos(0.3)) / 2)
    assert change.normal_force_nrmse == pytest.approx(rms / 20.0, rel=1e-3)
    assert change.normal_force_pearson == pytest.approx(np.cos(0.3), rel=1e-4)
    assert change.relative_change("rms_normal_force") == pytest.approx(0.2, rel=1e-4)
    rms_coarse = 10.0 / np.sqrt(2)
    band = 3.0 * (0.2 * rms_coarse) * 4.0 / 3.0
    assert change.gci_rms_normal_force == pytest.approx(band / rms_coarse, rel=1e-3)
    assert change.mean_thrust_n == pytest.approx((0.5, 0.5))
    assert change.gci_mean_thrust == pytest.approx(0.0, abs=1e-9)
    # the whole periods after the ramp in common, less the first: (4 - 0.5) * 1.5 = 5.25
    assert change.n_cycles == 4


def test_halving_the_courant_limit_is_a_time_step_refinement_of_ratio_two():
    coarse, refined = _record(10.0, 0.0), _record(10.5, 0.0, max_courant=1.0)
    assert refinement_kind(coarse, refined) == "time_step"
    assert refinement_change(coarse, refined, "time_step").refinement_ratio == 2.0


@pytest.mark.parametrize(("refined", "kind", "match"), [
    (_record(10.0, 0.0, n_cells=40_000, mesh="medium", frequency=2.0), "mesh",
     "different motions.*frequency"),
    (_record(10.0, 0.0, n_cells=5_000, mesh="medium"), "mesh", "not a mesh refinement"),
    (_record(10.0, 0.0, max_courant=4.0), "time_step", "not a time_step refinement"),
])
def test_a_pair_that_is_not_a_refinement_is_refused_naming_why(refined, kind, match):
    with pytest.raises(MfflapError, match=match):
        refinement_change(_record(10.0, 0.0), refined, kind)


def test_the_kind_is_read_from_what_differs_and_one_at_a_time():
    coarse = _record(10.0, 0.0)
    assert refinement_kind(coarse, _record(1.0, 0.0, mesh="medium")) == "mesh"
    with pytest.raises(MfflapError, match="both the mesh and the Courant limit"):
        refinement_kind(coarse, _record(1.0, 0.0, mesh="medium", max_courant=1.0))
    with pytest.raises(MfflapError, match="nothing was refined"):
        refinement_kind(coarse, _record(1.0, 0.0))
    with pytest.raises(ConfigError, match="no refinement"):
        refinement_change(coarse, coarse, "space")


def test_too_few_periods_in_common_are_refused():
    coarse = _record(10.0, 0.0)
    refined = _record(10.0, 0.0, mesh="medium", n_cells=40_000)
    with pytest.raises(MfflapError, match="whole period"):
        refinement_change(coarse, refined, "mesh", periods=9)


def test_real_records_get_their_change_stored_naming_the_refined_file(tmp_path):
    """A shipped coarse harmonic record and its medium-mesh rerun (real OpenFOAM), through
    the command: the change lands in the coarse record, with the refined file's SHA-256,
    and what the command prints is what the record holds."""
    name = "harmonic_f1p500_h0p0500_th30p00_phi090p0.h5"
    coarse_dir, refined_dir = tmp_path / "coarse", tmp_path / "medium"
    coarse_dir.mkdir(), refined_dir.mkdir()
    shutil.copy(CAMPAIGNS / "harmonic_set" / name, coarse_dir / name)
    shutil.copy(CAMPAIGNS / "uncertainty_harmonic_medium" / name, refined_dir / name)
    res = CliRunner().invoke(cli, ["campaign", "refinement", str(coarse_dir),
                                   str(refined_dir), "--json"])
    assert res.exit_code == 0, res.output
    stored = read_record(coarse_dir / name).refinement["mesh"]
    assert stored.refined_sha256 == hashlib.sha256((refined_dir / name).read_bytes()
                                                   ).hexdigest()
    assert f'"normal_force_nrmse": {stored.normal_force_nrmse}' in res.output
    assert 0 < stored.normal_force_nrmse < 0.5 and stored.normal_force_pearson > 0.5
    assert stored.refinement_ratio == pytest.approx(
        (read_record(refined_dir / name).provenance["n_cells"]
         / read_record(coarse_dir / name).provenance["n_cells"]) ** 0.5)
    (refined_dir / "harmonic_f9p000_h0p0500_th30p00_phi090p0.h5").write_bytes(
        (refined_dir / name).read_bytes())
    with pytest.raises(MfflapError, match="no record harmonic_f9p000"):
        add_refinement(coarse_dir, refined_dir)
