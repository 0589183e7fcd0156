"""The model's predicted mean thrust and power against CFD's on each back-tested motion of
a round (:class:`MotionCheck`), and which errors count."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mfflap.config import CaseConfig
from mfflap.performance import discrete_means

#: a motion's relative mean thrust error counts where its CFD mean thrust is at least this
#: fraction of the largest CFD mean thrust among the round's back-tested motions
THRUST_FLOOR = 0.05


@dataclass
class MotionCheck:
    """The model against CFD on one back-tested motion of a round.

    Attributes
    ----------
    cfd_mean_thrust, model_mean_thrust : N (the model's own on the kinematics CFD imposed,
        as the back-test compares them)
    cfd_mean_power, model_mean_power : W (likewise)
    thrust_error, power_error : (prediction - CFD) / |CFD| of the means
    thrust_counted : whether the thrust error counts (:data:`THRUST_FLOOR`)
    in_fit : whether the fit of this round had already seen this motion's CFD
    thrust_scale, power_scale : the output correction the motion was optimised with (1: none);
        the prediction is the optimiser's mean times it
    optimised_mean_thrust, optimised_mean_power : N, W, the model's means as the optimiser
        saw them (:func:`~mfflap.performance.discrete_means`: at the motion's N samples, the
        ones the correction's scales are measured with); NaN where not known, the
        back-test's model means then stand in
    cfd_record : the name of the CFD record compared ("": not known); another motion's
        (:attr:`cfd_of_neighbour`) where the back-test look-up found one within its tolerance
    """

    label: str
    key: str
    cfd_mean_thrust: float
    model_mean_thrust: float
    cfd_mean_power: float
    model_mean_power: float
    thrust_error: float
    power_error: float
    thrust_counted: bool
    in_fit: bool
    thrust_scale: float = 1.0
    power_scale: float = 1.0
    optimised_mean_thrust: float = float("nan")
    optimised_mean_power: float = float("nan")
    cfd_record: str = ""

    @property
    def cfd_of_neighbour(self) -> bool:
        """Whether the CFD compared is that of a motion within the look-up's tolerance, not of
        this motion itself (its record is named for another key)."""
        return bool(self.cfd_record) and self.cfd_record != f"backtest_{self.key}"

    @property
    def predicted_thrust(self) -> float:
        """N: the mean thrust the optimisation relied on (corrected model)."""
        own = self.optimised_mean_thrust
        return self.thrust_scale * (own if np.isfinite(own) else self.model_mean_thrust)

    @property
    def predicted_power(self) -> float:
        """W: the mean input power the optimisation relied on (corrected model)."""
        own = self.optimised_mean_power
        return self.power_scale * (own if np.isfinite(own) else self.model_mean_power)

    @property
    def error(self) -> float:
        """The largest counted relative error of the means."""
        return max(abs(self.power_error), abs(self.thrust_error) if self.thrust_counted else 0)

    def as_dict(self) -> dict:
        """JSON-friendly."""
        return {"label": self.label, "key": self.key, "cfd_mean_thrust": self.cfd_mean_thrust,
                "model_mean_thrust": self.model_mean_thrust,
                "cfd_mean_power": self.cfd_mean_power,
                "model_mean_power": self.model_mean_power, "thrust_error": self.thrust_error,
                "power_error": self.power_error, "thrust_counted": self.thrust_counted,
                "in_fit": self.in_fit, "error": self.error,
                "thrust_scale": self.thrust_scale, "power_scale": self.power_scale,
                "predicted_thrust": self.predicted_thrust,
                "predicted_power": self.predicted_power,
                "optimised_mean_thrust": _finite_or_none(self.optimised_mean_thrust),
                "optimised_mean_power": _finite_or_none(self.optimised_mean_power),
                "cfd_record": self.cfd_record, "cfd_of_neighbour": self.cfd_of_neighbour}


def motion_checks(backtests: dict, in_fit: set[str],
                  scales: dict[str, tuple[float, float]] | None = None,
                  optimised: dict[str, tuple[float, float]] | None = None
                  ) -> dict[str, MotionCheck]:
    """Per back-tested motion: the mean thrust and power predicted for it against CFD's.

    ``in_fit``: the names of the cases the round's fit used (a record's name is its case's);
    ``scales``: label -> (thrust, power) scale of the output correction the motion was
    optimised with (a motion not in it: the model's own means); ``optimised``: label ->
    (thrust N, power W) the optimiser's own means of the motion, which the prediction is
    made of (a motion not in it: the back-test's model means).
    """
    done = {k: o for k, o in backtests.items() if o.comparison is not None}
    largest = max((abs(o.comparison.cfd_mean_thrust) for o in done.values()), default=0.0)
    out = {}
    for label, o in done.items():
        c = o.comparison
        k_t, k_p = (scales or {}).get(label, (1.0, 1.0))
        own = (optimised or {}).get(label)
        own_t, own_p = own if own is not None else (c.model_mean_thrust, c.model_mean_power)
        out[label] = MotionCheck(
            label, o.key, c.cfd_mean_thrust, c.model_mean_thrust, c.cfd_mean_power,
            c.model_mean_power, _relative(k_t * own_t, c.cfd_mean_thrust),
            _relative(k_p * own_p, c.cfd_mean_power),
            thrust_counted=bool(abs(c.cfd_mean_thrust) >= THRUST_FLOOR * largest > 0),
            in_fit=o.record is not None and o.record.name in in_fit,
            thrust_scale=k_t, power_scale=k_p,
            optimised_mean_thrust=np.nan if own is None else float(own_t),
            optimised_mean_power=np.nan if own is None else float(own_p),
            cfd_record="" if o.record is None else str(o.record.name))
    return out


def _finite_or_none(value: float) -> float | None:
    """A number for JSON: None where it is NaN (not known)."""
    return float(value) if np.isfinite(value) else None


def optimised_means(outcome, config: CaseConfig) -> dict[str, tuple[float, float]]:
    """label -> (mean thrust N, mean power W) of each back-tested motion of a round as its
    optimiser saw them (:func:`~mfflap.performance.discrete_means`, the round's model and
    scheme); empty without a model."""
    if outcome.model is None:
        return {}
    scheme = (outcome.config or config).optimisation.scheme
    return {label: discrete_means(outcome.model, motion, scheme)
            for label, motion in outcome.backtest_motions.items()}


def _relative(predicted: float, cfd: float) -> float:
    """(predicted - CFD) / |CFD|, as the back-test's comparison gives it."""
    return (predicted - cfd) / max(abs(cfd), 1e-12)


__all__ = ["THRUST_FLOOR", "MotionCheck", "motion_checks", "optimised_means"]
