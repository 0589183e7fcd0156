"""A case written before is resumed only for the run it was written for.

Before, `run_motion` resumed (or, finished, read) any case folder of the asked name: a
`backtest --live` into the work folder of an earlier one, with another plate, mesh or set-up,
took the earlier case's forces as this run's.
"""

from __future__ import annotations

from dataclasses import replace

import pytest

from mfflap.cfd.openfoam.run_motion import check_written_for, run_motion
from mfflap.cfd.openfoam.writer import SolverSettings, write_case
from mfflap.errors import ConfigError
from mfflap.kinematics import HarmonicMotion
from mfflap.parameters import FreeStream, Plate

MOTION = HarmonicMotion(1.0, 0.1, 0.1, 1.5)
END_S, RAMP_S = 0.2, 0.1
SOLVER = SolverSettings(write_interval=END_S / 4)  # what run_motion uses when given none


@pytest.fixture
def written(tmp_path):
    case = tmp_path / "backtest_x"
    write_case(case, MOTION, END_S, ramp_time=RAMP_S, solver=SOLVER)
    return case


@pytest.mark.parametrize(("change", "key", "said"), [
    ({"plate": Plate(chord=0.1)}, "plate.chord", "0.1 asked, but"),
    ({"stream": FreeStream(velocity=0.5)}, "flow.velocity", "0.5 asked, but"),
    ({"motion": HarmonicMotion(1.0, 0.2, 0.1, 1.5)}, "motion", "its heave is"),
    ({"mesh": "medium"}, "mesh", "was written for mesh = 'coarse', this run asks 'medium'"),
    ({"end_time": 0.4}, "end_time", "was written for end_time = 0.2, this run asks 0.4"),
    ({"ramp_time": 0.05}, "ramp_time", "ramp_time = 0.1, this run asks 0.05"),
    ({"solver": replace(SOLVER, max_courant=2.0)}, "solver_max_courant",
     "solver_max_courant = 4.0, this run asks 2.0"),
    ({"solver": replace(SOLVER, frame="plate", far_field="inletOutlet")}, "solver_far_field",
     "solver_far_field = 'freestream', this run asks 'inletOutlet'"),
])
def test_a_case_written_for_another_run_is_refused_before_anything_runs(written, change, key,
                                                                        said):
    before = sorted(p.name for p in written.iterdir())
    args = {"motion": MOTION, "end_time": END_S, "ramp_time": RAMP_S, "solver": SOLVER,
            **change}
    with pytest.raises(ConfigError) as err:
        run_motion(written, args.pop("motion"), "backtest_x", {}, args.pop("end_time"),
                   **args)
    assert err.value.key == key
    assert said in str(err.value) and str(written) in str(err.value)
    assert "delete that folder, or give another work folder" in str(err.value)
    after = sorted(p.name for p in written.iterdir() if p.name != ".mfflap-run.lock")
    assert after == before  # nothing meshed, run or written


def test_the_same_run_is_not_refused(written):
    """The run the case was written for passes, with the solver given or run_motion's own
    default (a resumed run in OpenFOAM: test_campaign)."""
    from mfflap.parameters import Fluid

    check_written_for(written, MOTION, END_S, RAMP_S, "coarse", SOLVER, None, None, None)
    check_written_for(written, MOTION, END_S, RAMP_S, "coarse", SOLVER, Plate(), Fluid(),
                      FreeStream())
