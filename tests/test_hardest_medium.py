"""The grid's hardest motions on the medium mesh (campaigns/hardest_medium, committed as its
runs finish): whether a finer mesh holds what the coarse one lost, and how far the coarse
mesh is from it where both hold."""

from pathlib import Path

import pytest

from mfflap.campaign.compare import compare_records
from mfflap.campaign.execute import campaign_status
from mfflap.campaign.records import fixture_dir, read_record, record_paths
from mfflap.identification.data import prepare_case
from mfflap.toml_io import read_toml

CAMPAIGNS = Path(__file__).parents[1] / "campaigns"
MEDIUM = CAMPAIGNS / "hardest_medium"


def test_the_medium_campaign_is_the_shipped_set_up_on_the_medium_mesh():
    medium, shipped = (read_toml(d / "campaign.toml")
                       for d in (MEDIUM, fixture_dir("table1_coarse")))
    assert medium["setup"]["mesh"] == "medium"
    assert medium["setup"]["solver"] == shipped["setup"]["solver"]
    for case_id, motion in medium["cases"].items():
        assert motion == shipped["cases"][case_id]
        assert motion["heave_amplitude"] == 0.5 and motion["phase_deg"] == 135.0


@pytest.mark.parametrize("path", record_paths(MEDIUM), ids=lambda p: p.stem)
def test_a_finished_medium_run_is_done_without_bursts_and_fit_for_identification(path):
    """What campaign status and identification judge: no numerical burst after the ramp,
    not lost (inside the force bound), so identification takes it as it is."""
    rec = read_record(path)
    assert rec.provenance["mesh"] == "medium"
    status = {s.case_id: s for s in campaign_status(MEDIUM)}[path.stem]
    assert (status.state, status.message) == ("done", "")
    case = prepare_case(rec)
    assert case.notes == []  # nothing bridged, nothing despiked
    assert case.state.time[-1] == pytest.approx(rec.time[-1], rel=1e-6)


def test_the_coarse_mesh_is_far_from_the_medium_one_on_the_hardest_motion():
    """f = 1 Hz, h = 0.5 m, phi = 135 deg held on both meshes (coarse at max Co 2): the
    first period after the ramp agrees well, the later ones, dominated by shed vortices,
    do not; the coarse mesh's mean thrust is about half the medium's."""
    name = "f1p000_h0p500_phi135p0.h5"
    medium = read_record(MEDIUM / name)
    coarse = read_record(CAMPAIGNS / "table1_coarse_co2" / name)
    whole = compare_records(medium, coarse)
    assert whole.pearson_normal_force > 0.6
    assert 0.1 < whole.nrmse_normal_force < 0.3
    assert 1.5 < whole.mean_thrust_a_n / whole.mean_thrust_b_n < 2.5
    assert abs(whole.power_difference) < 0.2
    first_period = compare_records(medium, coarse, end_s=1.0)  # the ramp's end to t = 1 s
    later = compare_records(medium, coarse, start_s=1.0)
    assert first_period.nrmse_normal_force < 0.1 < later.nrmse_normal_force
    assert later.nrmse_normal_force > 1.5 * first_period.nrmse_normal_force
