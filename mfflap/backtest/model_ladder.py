"""The model ladder on a CFD run: Morison, the discrete-vortex model and CFD side by side.

Both models are run through the motion the CFD run imposed (its kinematics, resampled on a
uniform time base from the start of the run, ramp included), and the three are compared over
the run's last periods: mean thrust, mean input power, peak input power, and the NRMSE of F_n
against CFD.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

from mfflap.hydro.base import ForceModel
from mfflap.hydro.discrete_vortex import VortexModelSettings, simulate_vortex_model
from mfflap.hydro.loads import Loads
from mfflap.hydro.morison import MorisonModel
from mfflap.kinematics.state import KinematicState
from mfflap.metrics import nrmse, time_mean
from mfflap.parameters import Fluid, FreeStream, Plate
from mfflap.performance import thrust_and_power
from mfflap.records.record import CfdRecord

#: the models' time steps per period of the motion
STEPS_PER_PERIOD = 200


@dataclass(frozen=True)
class LevelFigures:
    """What one level of the ladder gives over the compared periods.

    Attributes
    ----------
    mean_thrust : N
    mean_power : W
    peak_power : W
    normal_force_nrmse : float
        NRMSE of F_n against CFD on CFD's samples; for CFD itself its own repeat: the last
        period against the one before (NaN when fewer than two periods are compared), the
        closest a model can be asked to follow it.
    """

    mean_thrust: float
    mean_power: float
    peak_power: float
    normal_force_nrmse: float


@dataclass(frozen=True)
class LadderComparison:
    """CFD, Morison and the discrete-vortex model on one CFD run.

    Attributes
    ----------
    name, label : str
        The record's name and its motion's label.
    periods : float
        The periods compared, at the end of the run.
    cfd, morison, vortex : LevelFigures
    """

    name: str
    label: str
    periods: float
    cfd: LevelFigures
    morison: LevelFigures
    vortex: LevelFigures

    def as_dict(self) -> dict:
        """Plain values for JSON and reports."""
        return asdict(self)


def _figures(loads: Loads, state: KinematicState, window: np.ndarray,
             cfd_normal: np.ndarray | None, cfd_time: np.ndarray) -> LevelFigures:
    thrust, power = thrust_and_power(loads, state)
    if cfd_normal is None:
        error = 0.0
    else:
        on_cfd = np.interp(cfd_time, loads.time, loads.normal_force)
        error = float(nrmse(on_cfd, cfd_normal))
    # time averages: OpenFOAM's adaptive step samples the fast parts of a cycle densely, so
    # a plain mean over its samples weighs them more than their share of the time
    t = np.asarray(loads.time, dtype=float)[window]
    return LevelFigures(time_mean(t, thrust[window]), time_mean(t, power[window]),
                        float(power[window].max()), error)


def compare_model_ladder(record: CfdRecord, morison: ForceModel | None = None,
                         settings: VortexModelSettings | None = None,
                         plate: Plate | None = None, fluid: Fluid | None = None,
                         stream: FreeStream | None = None, periods: float = 2.0,
                         steps_per_period: int = STEPS_PER_PERIOD) -> LadderComparison:
    """Run Morison and the discrete-vortex model through a CFD run's motion and compare.

    Parameters
    ----------
    record : CfdRecord
        A CFD run from its start (t = 0 s at rest); ``parameters["period"]`` gives the
        period, s.
    morison
        The Morison model (the paper's coefficients if omitted).
    settings
        The discrete-vortex model's settings (its defaults if omitted).
    plate, fluid, stream
        The package's defaults if omitted.
    periods
        How many periods at the end of the run are compared.
    steps_per_period
        The models' uniform time steps per period.

    Returns
    -------
    LadderComparison

    Raises
    ------
    MfflapError
        If the record names neither its period nor its frequency, or is shorter than the
        compared periods (:meth:`~mfflap.records.record.CfdRecord.last_periods`).

    Examples
    --------
    >>> from mfflap.records.record import fixture_dir, read_records
    >>> run = read_records(fixture_dir("backtest_main_job"))[0]
    >>> ladder = compare_model_ladder(run)
    >>> ladder.vortex.peak_power > 0
    True
    """
    period, start = record.last_periods(periods)
    t_cfd = np.asarray(record.state.time, dtype=float)
    state = record.state.on_uniform_time(period / steps_per_period, start=0.0)
    window = state.time >= start
    cfd_window = t_cfd >= start
    morison = morison or MorisonModel()
    vortex = simulate_vortex_model(state, plate, fluid, stream, settings).loads
    cfd = _figures(record.loads, record.state, cfd_window, None, t_cfd)
    cfd_normal = record.loads.normal_force[cfd_window]
    repeat = record.repeat_nrmse() if periods >= 2 else float("nan")
    cfd = LevelFigures(cfd.mean_thrust, cfd.mean_power, cfd.peak_power, repeat)
    levels = {name: _figures(loads, state, window, cfd_normal, t_cfd[cfd_window])
              for name, loads in (("morison", morison.loads(state)), ("vortex", vortex))}
    return LadderComparison(record.name, str(record.parameters.get("label", record.name)),
                            periods, cfd, levels["morison"], levels["vortex"])
