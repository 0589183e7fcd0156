"""The Table 1 grid rerun at max Co 2 (campaigns/table1_coarse_co2, committed as its runs
finish): the shipped fixtures' set-up but for the Courant limit, free of their numerical
bursts, and a run that lost its numerics there refused by identification."""

from pathlib import Path

import numpy as np
import pytest

from mfflap.campaign.records import fixture_dir, read_record, record_paths
from mfflap.cfd.bursts import find_numerical_bursts
from mfflap.cfd.force_envelope import find_envelope_breaches
from mfflap.cfd.openfoam.setups import setup
from mfflap.errors import MfflapError
from mfflap.identification.data import prepare_case
from mfflap.parameters import Fluid, FreeStream, Plate
from mfflap.toml_io import read_toml

CO2 = Path(__file__).parents[1] / "campaigns" / "table1_coarse_co2"
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


#: finished runs that lost their numerics at max Co 2 (where the shipped max Co 4 run did
#: not), and from when: F_n grows to 50 kN in the last 0.07 s of f = 2 Hz, h = 0.3 m
LOST = {"f2p000_h0p300_phi090p0": 1.43}


@pytest.mark.parametrize("path", _finished(), ids=lambda p: p.stem)
def test_a_finished_co2_run_has_no_numerical_burst_or_is_refused(path):
    """Checked like identification checks a record: after its start-up ramp."""
    rec = read_record(path)
    assert rec.provenance["solver_max_courant"] == 2.0
    after_ramp = rec.time >= float(rec.parameters["ramp_time"])
    breaches = find_envelope_breaches(rec.state, rec.loads, Plate(), Fluid(), FreeStream(),
                                      window=after_ramp)
    if rec.name in LOST:
        assert breaches and abs(breaches[0].start_s - LOST[rec.name]) < 0.02
        with pytest.raises(MfflapError, match="the run lost its numerics"):
            prepare_case(rec)
        return
    signals = [np.asarray(getattr(rec.loads, k))[after_ramp] for k in COMPONENTS]
    assert find_numerical_bursts(rec.time[after_ramp], signals) == []
    assert breaches == []
