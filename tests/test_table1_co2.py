"""The Table 1 grid rerun at max Co 2 (campaigns/table1_coarse_co2, committed as its runs
finish): the shipped fixtures' set-up but for the Courant limit, and free of their numerical
bursts."""

from pathlib import Path

import numpy as np
import pytest

from mfflap.campaign.records import fixture_dir, read_record
from mfflap.cfd.bursts import find_numerical_bursts
from mfflap.cfd.openfoam.setups import setup
from mfflap.toml_io import read_toml

CO2 = Path(__file__).parents[1] / "campaigns" / "table1_coarse_co2"
SHIPPED = fixture_dir("table1_coarse")
COMPONENTS = ("normal_force", "tangential_force", "moment")


def _finished() -> list[Path]:
    return sorted(CO2.glob("*.h5"))


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
def test_a_finished_co2_run_has_no_numerical_burst(path):
    """Checked like identification checks a record: after its start-up ramp."""
    rec = read_record(path)
    assert rec.provenance["solver_max_courant"] == 2.0
    keep = rec.time >= float(rec.parameters["ramp_time"])
    signals = [np.asarray(getattr(rec.loads, k))[keep] for k in COMPONENTS]
    assert find_numerical_bursts(rec.time[keep], signals) == []
