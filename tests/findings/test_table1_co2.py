"""The Table 1 grid rerun at max Co 2 (campaigns/table1_coarse_co2, committed as its runs
finish): the shipped fixtures' set-up but for the Courant limit, free of their numerical
bursts and inside the force bound, one run that lost its numerics there rerun."""

from pathlib import Path

import numpy as np
import pytest

from mfflap.cfd.openfoam.setups import setup
from mfflap.errors import MfflapError
from mfflap.identification.data import prepare_case
from mfflap.parameters import Fluid, FreeStream, Plate
from mfflap.records.bursts import find_numerical_bursts
from mfflap.records.force_envelope import find_envelope_breaches
from mfflap.records.record import LOST_SUFFIX, fixture_dir, read_record, record_paths
from mfflap.toml_io import read_toml

pytestmark = pytest.mark.findings  # shipped research data, not code

CO2 = Path(__file__).parents[2] / "campaigns" / "table1_coarse_co2"
SHIPPED = fixture_dir("table1_coarse")
COMPONENTS = ("normal_force", "tangential_force", "moment")


def _finished() -> list[Path]:
    return record_paths(CO2)


def test_the_co2_campaign_is_the_shipped_grid_at_max_co_2():
    co2, shipped = (read_toml(d / "campaign.toml") for d in (CO2, SHIPPED))
    assert co2["cases"] == shipped["cases"]
    assert co2["setup"]["mesh"] == shipped["setup"]["mesh"] == setup("coarse_co2").mesh.name
    solver = co2["setup"]["solver"]
    assert solver["max_courant"] == setup("coarse_co2").solver.max_courant == 2.0
    changed = {k for k, v in shipped["setup"]["solver"].items() if solver[k] != v}
    assert changed == {"max_courant"}
    assert {p.stem for p in _finished()} <= set(co2["cases"])


@pytest.mark.parametrize("path", _finished(), ids=lambda p: p.stem)
def test_a_finished_co2_run_has_no_numerical_burst_and_stays_inside_the_force_bound(path):
    """Checked like identification checks a record: after its start-up ramp."""
    rec = read_record(path)
    assert rec.provenance["solver_max_courant"] == 2.0
    after_ramp = rec.time >= float(rec.parameters["ramp_time"])
    signals = [np.asarray(getattr(rec.loads, k))[after_ramp] for k in COMPONENTS]
    assert find_numerical_bursts(rec.time[after_ramp], signals) == []
    assert find_envelope_breaches(rec.state, rec.loads, Plate(), Fluid(), FreeStream(),
                                  window=after_ramp) == []


def test_the_run_that_lost_its_numerics_at_max_co_2_was_rerun_and_is_kept_aside():
    """f = 2 Hz, h = 0.3 m, phi = 90 deg ran through at max Co 4 but, at max Co 2, F_n grew
    to 50 kN in its last 0.07 s. The campaign kept that record aside (--retry-failed) and
    ran the case again: the run left the bound at the same time, was rewound to its write
    at 1.125 s and went on with the inletOutlet far field, within the bound."""
    name = "f2p000_h0p300_phi090p0"
    lost = read_record(CO2 / f"{name}{LOST_SUFFIX}")
    breaches = find_envelope_breaches(lost.state, lost.loads, Plate(), Fluid(), FreeStream(),
                                      window=lost.time >= 0.125)
    assert breaches and breaches[0].start_s == pytest.approx(1.435, abs=0.01)
    with pytest.raises(MfflapError, match="the run lost its numerics"):
        prepare_case(lost)
    rerun = read_record(CO2 / f"{name}.h5")
    assert rerun.provenance["retries"] == (
        "forces beyond what the motion can drive from t = 1.43513 s; resumed from t = 1.125 s"
        " with the inletOutlet far field")
    assert np.abs(rerun.loads.normal_force).max() < 2e3
    prepare_case(rerun)


def test_the_hardest_motions_that_failed_at_max_co_2_are_kept_with_where_they_left_the_bound():
    """f = 0.5 and 2 Hz at h = 0.5 m, phi = 135 deg failed under every remedy; the campaign
    reports them as failed, each with its retries and the flow times of its losses, which
    stay within 2 % of c/U of one another once the Courant limit was halved (the
    same-flow-time rule that stopped them). f = 0.5 Hz failed before failures listed their
    retries (campaigns/README tells them)."""
    import re

    from mfflap.campaign.execute import campaign_status

    failed = {s.case_id: s.message for s in campaign_status(CO2) if s.state == "failed"}
    if set(failed) - {"f0p500_h0p500_phi135p0", "f2p000_h0p500_phi135p0"}:
        pytest.fail(f"unexpected failures: {sorted(failed)}")
    chord_over_stream_s = Plate().chord / FreeStream().velocity
    for case_id, message in failed.items():
        assert "forces leave what the motion can drive" in message
        losses = [float(t) for t in re.findall(r"beyond what the motion can drive from "
                                                r"t = ([0-9.]+) s", message)]
        if case_id == "f0p500_h0p500_phi135p0":
            assert "t = 1.638-" in message
            continue
        assert "after 4 retries" in message and len(losses) == 4, message
        halved = losses[1:]  # after the first remedy (inletOutlet), the limit was halved
        assert max(halved) - min(halved) < 0.02 * chord_over_stream_s, message
        assert not (CO2 / f"{case_id}.h5").exists()
