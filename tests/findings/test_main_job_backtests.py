"""The main job's back-tests as it ships (identified from the pooled Table 1 grid and
harmonic set, every run on the table1 set-up; docs/findings/optimised_motions.md, "The main
job as shipped"): real OpenFOAM runs of its six motions, where the Morison optimum breaks
P_max in CFD and its polish on the vortex model holds it."""

from __future__ import annotations

import pytest

from mfflap.backtest.model_ladder import compare_model_ladder
from mfflap.records.record import fixture_dir, read_records

P_MAX_W = 50.0
LABELS = ("best sinusoid", "β = 0", "β = 0.5", "β = 1", "β = 0 polished", "β = 1 polished")


@pytest.fixture(scope="module")
def ladders():
    """Label -> the three levels on the record of that motion run on the table1 set-up."""
    records = [r for r in read_records(fixture_dir("backtest_main_job"))
               if r.provenance.get("solver_max_courant") == 2.0
               and r.provenance.get("solver_far_field") == "inletOutlet"
               and r.provenance.get("solver_wall_treatment") == "all_y_plus"]
    return {r.parameters["label"]: compare_model_ladder(r) for r in records}


def test_every_motion_ran_in_openfoam_on_the_table1_set_up(ladders):
    assert sorted(ladders) == sorted(LABELS)
    for record in read_records(fixture_dir("backtest_main_job")):
        if record.parameters["label"] in ladders and record.provenance.get(
                "solver_max_courant") == 2.0:
            assert record.provenance["solver"] == "OpenFOAM pimpleFoam"
            assert record.provenance["cpu_time_s"] > 100
            assert record.time[-1] >= 5.4 * record.period


def test_the_morison_optimum_breaks_p_max_in_cfd_and_its_polish_holds_it(ladders):
    assert ladders["β = 0"].cfd.peak_power > 3 * P_MAX_W
    polished = ladders["β = 0 polished"]
    assert polished.cfd.peak_power < P_MAX_W
    assert polished.cfd.mean_thrust > 10.0
    # the vortex model predicts the polish's CFD within 10 %
    for quantity in ("mean_thrust", "mean_power", "peak_power"):
        ratio = getattr(polished.vortex, quantity) / getattr(polished.cfd, quantity)
        assert abs(ratio - 1) < 0.10, quantity


def test_the_best_sinusoid_gives_more_thrust_only_beyond_p_max(ladders):
    sinusoid, polished = ladders["best sinusoid"], ladders["β = 0 polished"]
    assert sinusoid.cfd.peak_power > 1.4 * P_MAX_W
    assert sinusoid.cfd.mean_thrust > 1.5 * polished.cfd.mean_thrust
