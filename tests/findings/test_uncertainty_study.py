"""The mesh and time-step study (campaigns/uncertainty_*) as far as it has run: every
finished record is a real OpenFOAM run of a motion of the identification sets, on the
medium mesh or at half the Courant limit of the set-up of the coarse records it is set
against, and the statements of the findings page about it hold."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from mfflap.records.cycle_scatter import cycle_scatter
from mfflap.records.record import read_record, record_paths

ROOT = Path(__file__).parents[2]
CAMPAIGNS = ROOT / "campaigns"
#: each study folder, the coarse folder its records are set against, and what it varies
STUDIES = {"uncertainty_harmonic_medium": ("harmonic_set", "medium", 2.0),
           "uncertainty_harmonic_co1": ("harmonic_set", "coarse", 1.0),
           "uncertainty_grid_medium": ("table1_full", "medium", 2.0),
           "uncertainty_grid_co1": ("table1_full", "coarse", 1.0)}
PAIRS = [(study, path) for study in STUDIES for path in record_paths(CAMPAIGNS / study)]

pytestmark = pytest.mark.findings


@pytest.mark.parametrize(("study", "path"), PAIRS, ids=[p.stem for _, p in PAIRS])
def test_each_finished_record_is_its_coarse_motion_on_the_varied_set_up(study, path):
    coarse_folder, mesh, max_courant = STUDIES[study]
    record = read_record(path)
    coarse = read_record(CAMPAIGNS / coarse_folder / path.name)
    assert record.parameters == coarse.parameters
    assert record.provenance["openfoam_build"].startswith("OPENFOAM=")
    assert record.provenance["mesh"] == mesh
    assert record.provenance["solver_max_courant"] == max_courant
    for key in ("as_run_wall_treatment", "as_run_far_field", "solver_velocity_convection"):
        assert record.provenance[key] == coarse.provenance[key], key
    assert record.time[-1] == pytest.approx(coarse.time[-1], rel=1e-3)
    if mesh == "medium":
        assert record.provenance["n_cells"] > 2 * coarse.provenance["n_cells"]


def test_halving_the_courant_limit_moves_the_harmonic_means_less_than_one_percent():
    """The findings page: at max Co 1 the harmonic motions' mean thrust, power and RMS F_n
    stay within 1 % of the max-Co-2 records, within each record's cycle scatter of thrust."""
    paths = record_paths(CAMPAIGNS / "uncertainty_harmonic_co1")
    if not paths:
        pytest.fail("no finished record in campaigns/uncertainty_harmonic_co1")
    for path in paths:
        fine = cycle_scatter(read_record(path))
        coarse = cycle_scatter(read_record(CAMPAIGNS / "harmonic_set" / path.name))
        for name in ("mean_thrust_n", "mean_power_w", "rms_normal_force_n"):
            change = getattr(fine, name) / getattr(coarse, name) - 1
            assert abs(change) < 0.01, (path.stem, name, change)
        assert abs(fine.mean_thrust_n - coarse.mean_thrust_n) < \
            np.hypot(fine.thrust_scatter_n, coarse.thrust_scatter_n)


def test_the_medium_mesh_moves_the_fastest_harmonic_means_beyond_their_cycle_scatter():
    """The findings page: at f = 2.5 Hz the medium mesh raises the mean thrust, power and
    RMS F_n by more than the record's cycle scatter of thrust (about 9 % against 5 %),
    while at f = 2 Hz they stay within 1.5 %: the mesh error grows with frequency."""
    name = "harmonic_f2p500_h0p0500_th30p00_phi060p0.h5"
    path = CAMPAIGNS / "uncertainty_harmonic_medium" / name
    if not path.exists():
        pytest.fail(f"{path} has not run")
    fine = cycle_scatter(read_record(path))
    coarse = cycle_scatter(read_record(CAMPAIGNS / "harmonic_set" / name))
    scatter = coarse.thrust_scatter_n / coarse.mean_thrust_n
    for key in ("mean_thrust_n", "mean_power_w", "rms_normal_force_n"):
        assert getattr(fine, key) / getattr(coarse, key) - 1 > scatter, key
    slower = "harmonic_f2p000_h0p0500_th30p00_phi120p0.h5"
    fine = cycle_scatter(read_record(CAMPAIGNS / "uncertainty_harmonic_medium" / slower))
    coarse = cycle_scatter(read_record(CAMPAIGNS / "harmonic_set" / slower))
    for key in ("mean_thrust_n", "mean_power_w", "rms_normal_force_n"):
        assert abs(getattr(fine, key) / getattr(coarse, key) - 1) < 0.015, key


def _changes(study: str, name: str) -> dict[str, float]:
    path = CAMPAIGNS / study / name
    if not path.exists():
        pytest.fail(f"{path} has not run")
    fine = cycle_scatter(read_record(path))
    coarse = cycle_scatter(read_record(CAMPAIGNS / STUDIES[study][0] / name))
    return {key: getattr(fine, key) / getattr(coarse, key) - 1
            for key in ("mean_thrust_n", "mean_power_w", "rms_normal_force_n")}


def test_on_the_grid_the_medium_mesh_moves_large_heaves_not_small_ones():
    """The findings page: at h = 0.1 m, phi = 45 deg the medium mesh moves the power and RMS
    F_n by at most 3 %; at h = 0.3 m by 8-30 % (and its coarse index exceeds 40 %)."""
    from mfflap.cfd.gci import two_level_index

    for name in ("f1p000_h0p100_phi045p0.h5", "f2p000_h0p100_phi045p0.h5"):
        changes = _changes("uncertainty_grid_medium", name)
        for key in ("mean_power_w", "rms_normal_force_n"):
            assert abs(changes[key]) < 0.035, (name, key, changes[key])
    for name in ("f1p000_h0p300_phi045p0.h5", "f1p000_h0p300_phi135p0.h5",
                 "f2p000_h0p300_phi045p0.h5", "f2p000_h0p300_phi135p0.h5"):
        changes = _changes("uncertainty_grid_medium", name)
        for key in ("mean_power_w", "rms_normal_force_n"):
            assert 0.08 < abs(changes[key]) < 0.31, (name, key, changes[key])
            fine = read_record(CAMPAIGNS / "uncertainty_grid_medium" / name)
            coarse = read_record(CAMPAIGNS / "table1_full" / name)
            ratio = (fine.provenance["n_cells"] / coarse.provenance["n_cells"]) ** 0.5
            index = two_level_index(1.0, 1.0 + changes[key], ratio)
            assert index.gci_coarse > 0.4, (name, key, index.gci_coarse)


def test_halving_the_courant_limit_moves_the_grids_small_heaves_little():
    """The findings page: at max Co 1 the h = 0.1 m, phi = 45 deg grid motions move by less
    than 3 % in all three means; f = 2 Hz, h = 0.3 m, phi = 45 deg by 15-25 %."""
    for name in ("f1p000_h0p100_phi045p0.h5", "f2p000_h0p100_phi045p0.h5"):
        for key, change in _changes("uncertainty_grid_co1", name).items():
            assert abs(change) < 0.03, (name, key, change)
    for key, change in _changes("uncertainty_grid_co1", "f2p000_h0p300_phi045p0.h5").items():
        assert 0.14 < change < 0.26, (key, change)


@pytest.mark.parametrize(("study", "path"), PAIRS, ids=[p.stem for _, p in PAIRS])
def test_each_coarse_record_states_its_change_under_each_finished_refinement(study, path):
    """The coarse record holds the change of the refined run as it is now (`mfflap
    campaign refinement` rerun after a refined record is added or rerun: the hash
    matches), and the stored figures are those the pair gives."""
    import hashlib

    from mfflap.campaign.refinement import refinement_change

    coarse_folder, mesh, _ = STUDIES[study]
    coarse = read_record(CAMPAIGNS / coarse_folder / path.name)
    kind = "mesh" if mesh == "medium" else "time_step"
    assert kind in coarse.refinement, f"rerun mfflap campaign refinement for {study}"
    stored = coarse.refinement[kind]
    assert stored.refined_sha256 == hashlib.sha256(path.read_bytes()).hexdigest()
    again = refinement_change(coarse, read_record(path), kind)
    assert stored.normal_force_nrmse == pytest.approx(again.normal_force_nrmse, rel=1e-9)
    assert stored.gci_mean_power == pytest.approx(again.gci_mean_power, rel=1e-9)
