"""Compare the CFD of a periodic motion with the model over its last simulated cycle."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from mfflap.backtest.cycles import cycle_means
from mfflap.errors import MfflapError
from mfflap.metrics import nrmse, pearson, time_mean
from mfflap.parameters import Fluid, FreeStream, Plate
from mfflap.performance import thrust_and_power
from mfflap.records.as_run import as_run_since_s
from mfflap.records.bursts import bridge_load_bursts
from mfflap.records.force_envelope import find_envelope_breaches
from mfflap.records.record import CfdRecord


@dataclass
class BacktestComparison:
    """Model against CFD over the last cycle (the CFD's own time base).

    Attributes
    ----------
    time : s; cfd_thrust, model_thrust : N; cfd_power, model_power : W
    nrmse, pearson : dict per signal (thrust, input_power, normal_force, moment)
    cfd_mean_thrust, model_mean_thrust : N; cfd_mean_power, model_mean_power : W
    cfd_max_power : W; max_power_ok : bool (CFD's instantaneous power <= P_max)
    cycle_to_cycle_thrust_change : fraction between the last two cycles (periodicity check)
    numerical_bursts : the CFD's numerical bursts in the last two cycles
        (:mod:`mfflap.records.bursts`), bridged before any of the numbers above
    cycles_averaged : the whole cycles the CFD means are taken over (1: the last cycle);
        the curves, NRMSE, Pearson and maximum power are the last cycle's
    cfd_thrust_standard_error : N; cfd_power_standard_error : W; of the CFD means over
        ``cycles_averaged`` cycles (:class:`~mfflap.backtest.cycles.CycleMeans`; NaN with one)
    cfd_repeat_nrmse : dict per signal: the CFD's last cycle against its own cycle before
        (NRMSE over the same range as ``nrmse``; NaN without a whole cycle before): how
        closely the run repeats itself, the yardstick beside which ``nrmse`` is read
    compared_from_s : s, where the cycles the CFD means are taken over start
    cfd_settings_since_s : s, since when the CFD ran the settings it ended with
        (:func:`~mfflap.records.as_run.as_run_since_s`: 0 unless a retry resumed it
        part-way with another far field or Courant limit)
    """

    time: np.ndarray
    cfd_thrust: np.ndarray
    model_thrust: np.ndarray
    cfd_power: np.ndarray
    model_power: np.ndarray
    nrmse: dict[str, float]
    pearson: dict[str, float]
    cfd_mean_thrust: float
    model_mean_thrust: float
    cfd_mean_power: float
    model_mean_power: float
    cfd_max_power: float
    max_power_ok: bool
    cycle_to_cycle_thrust_change: float
    numerical_bursts: list[str] = field(default_factory=list)
    cycles_averaged: int = 1
    cfd_thrust_standard_error: float = float("nan")
    cfd_power_standard_error: float = float("nan")
    compared_from_s: float = float("nan")
    cfd_settings_since_s: float = 0.0
    cfd_repeat_nrmse: dict[str, float] = field(default_factory=dict)

    @property
    def compared_cycles_mixed_set_up(self) -> bool:
        """Whether the CFD's settings changed within the cycles its means are taken over
        (a retry resumed the run part-way through them): those means mix two set-ups."""
        return bool(self.cfd_settings_since_s > self.compared_from_s + 1e-9)

    def describe_mixed_set_up(self) -> str:
        """Why the compared cycles mix two set-ups ('' when they do not)."""
        if not self.compared_cycles_mixed_set_up:
            return ""
        return (f"the CFD's settings changed at t = {self.cfd_settings_since_s:.4g} s (a retry "
                f"resumed it with another far field or Courant limit), within the cycles "
                f"compared from t = {self.compared_from_s:.4g} s: its means mix two set-ups "
                "(rerun with --retries-from-start, or more --cycles)")

    @property
    def mean_thrust_error(self) -> float:
        """(model - CFD) / |CFD| mean thrust."""
        return (self.model_mean_thrust - self.cfd_mean_thrust) / max(abs(self.cfd_mean_thrust),
                                                                     1e-12)

    @property
    def mean_power_error(self) -> float:
        """(model - CFD) / |CFD| mean input power."""
        return (self.model_mean_power - self.cfd_mean_power) / max(abs(self.cfd_mean_power),
                                                                   1e-12)

    @property
    def cycle_scatter(self) -> float:
        """The larger of one cycle's CFD mean thrust and power scatter (standard deviation
        of the cycle means over |their mean|) over ``cycles_averaged`` cycles: the noise of
        a back-test that reads one cycle (NaN with one cycle averaged)."""
        if self.cycles_averaged < 2:
            return float("nan")
        root = np.sqrt(self.cycles_averaged)
        return max(self.cfd_thrust_standard_error * root / max(abs(self.cfd_mean_thrust), 1e-12),
                   self.cfd_power_standard_error * root / max(abs(self.cfd_mean_power), 1e-12))

    def as_dict(self) -> dict[str, float | bool | dict]:
        """Scalars only (for JSON and HDF5 attributes)."""
        return {"nrmse": self.nrmse, "pearson": self.pearson,
                "cfd_repeat_nrmse": {k: _or_none(v) for k, v in self.cfd_repeat_nrmse.items()},
                "cfd_mean_thrust": self.cfd_mean_thrust,
                "model_mean_thrust": self.model_mean_thrust,
                "cfd_mean_power": self.cfd_mean_power, "model_mean_power": self.model_mean_power,
                "mean_thrust_error": self.mean_thrust_error,
                "mean_power_error": self.mean_power_error, "cfd_max_power": self.cfd_max_power,
                "max_power_ok": self.max_power_ok,
                "cycle_to_cycle_thrust_change": self.cycle_to_cycle_thrust_change,
                "numerical_bursts": list(self.numerical_bursts),
                "cycles_averaged": self.cycles_averaged,
                "cfd_thrust_standard_error": _or_none(self.cfd_thrust_standard_error),
                "cfd_power_standard_error": _or_none(self.cfd_power_standard_error),
                "cycle_scatter": _or_none(self.cycle_scatter),
                "compared_from_s": _or_none(self.compared_from_s),
                "cfd_settings_since_s": self.cfd_settings_since_s,
                "compared_cycles_mixed_set_up": self.compared_cycles_mixed_set_up}


def _or_none(value: float) -> float | None:
    """JSON has no NaN."""
    return None if np.isnan(value) else float(value)


def compare_last_cycle(record: CfdRecord, model, period: float,
                       max_power: float, *, average_cycles: int = 1) -> BacktestComparison:
    """Model (on the imposed kinematics) against CFD over the last full period of the record.

    Numerical bursts of the CFD in the last two periods are bridged first (and listed).
    With ``average_cycles`` above 1, the CFD and model means are those over the record's
    last ``average_cycles`` whole cycles, with the CFD's standard errors
    (:mod:`mfflap.backtest.cycles`: one cycle's mean can lie far from the run's).

    Raises
    ------
    MfflapError
        If the CFD forces of the last two periods leave what the motion can drive
        (:mod:`mfflap.records.force_envelope`): the run lost its numerics and says nothing about
        the model.
    ConfigError
        ``average_cycles`` more than the whole cycles the record holds after its start-up
        (key ``average_cycles``).
    """
    averaged = (None if average_cycles == 1
                else cycle_means(record, period).last(average_cycles))
    t = record.time
    end = t[-1]
    last = t >= end - period
    prev = (t >= end - 2 * period) & (t < end - period)
    state = record.state
    pred = model.loads(state)
    cfd, bursts = bridge_load_bursts(record.loads, last | prev)
    breaches = find_envelope_breaches(state, cfd, getattr(model, "plate", Plate()),
                                      getattr(model, "fluid", Fluid()),
                                      getattr(model, "stream", FreeStream()),
                                      window=last | prev)
    if breaches:
        raise MfflapError(f"{record.name}: the CFD forces of the last two periods leave what "
                          f"the motion can drive, {breaches[0].describe()}: the run lost its "
                          "numerics; rerun it (a lower Courant limit)")
    m_thrust, m_power = thrust_and_power(pred, state)
    c_thrust, c_power = thrust_and_power(cfd, state)
    signals = {"thrust": (m_thrust, c_thrust), "input_power": (m_power, c_power),
               "normal_force": (pred.normal_force, cfd.normal_force),
               "moment": (pred.moment, cfd.moment)}
    nr = {k: float(nrmse(m[last], c[last])) for k, (m, c) in signals.items()}
    tl = t[last]
    whole_cycle_before = bool(tl[0] - period >= t[0] - 1e-9 * max(1.0, period))
    repeat = {k: (float(nrmse(np.interp(tl - period, t, c), c[last])) if whole_cycle_before
                  else float("nan")) for k, (_, c) in signals.items()}
    pe = {k: float(pearson(m[last], c[last])) for k, (m, c) in signals.items()}
    cfd_mean_thrust = time_mean(tl, c_thrust[last])
    change = np.nan
    if prev.sum() > 4:
        before = time_mean(t[prev], c_thrust[prev])
        change = abs(cfd_mean_thrust - before) / max(abs(cfd_mean_thrust), 1e-12)
    cfd_max = float(np.max(c_power[last]))
    means = {"cfd_mean_thrust": cfd_mean_thrust,
             "model_mean_thrust": time_mean(tl, m_thrust[last]),
             "cfd_mean_power": time_mean(tl, c_power[last]),
             "model_mean_power": time_mean(tl, m_power[last])}
    errors = {"compared_from_s": float(tl[0]), "cfd_settings_since_s": as_run_since_s(record)}
    if averaged is not None:
        window = t >= averaged.start_s[0]
        means = {"cfd_mean_thrust": averaged.mean_thrust,
                 "model_mean_thrust": time_mean(t[window], m_thrust[window]),
                 "cfd_mean_power": averaged.mean_power,
                 "model_mean_power": time_mean(t[window], m_power[window])}
        errors |= {"compared_from_s": float(averaged.start_s[0]),
                   "cycles_averaged": averaged.n_cycles,
                  "cfd_thrust_standard_error": averaged.thrust_standard_error,
                  "cfd_power_standard_error": averaged.power_standard_error}
    return BacktestComparison(
        time=tl, cfd_thrust=c_thrust[last], model_thrust=m_thrust[last],
        cfd_power=c_power[last], model_power=m_power[last], nrmse=nr, pearson=pe,
        **means, cfd_max_power=cfd_max,
        max_power_ok=bool(cfd_max <= max_power), cycle_to_cycle_thrust_change=float(change),
        numerical_bursts=[b.describe() for b in bursts], cfd_repeat_nrmse=repeat, **errors)
