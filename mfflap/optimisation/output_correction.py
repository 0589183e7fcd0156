"""Output correction of the model from CFD (multiplicative output space mapping).

The back-tests of the optimised motions find the model's mean thrust and power off by a
factor that stays nearly the same from one optimum to the next (README, "The model on the
optimised motions": 15-20 % low at beta = 0 in every round), even after a refit on those
very back-tests. A correction scales the model's outputs by what CFD measured at the last
motion of the same beta:

    F_thrust,j -> kappa_T F_thrust,j,   P_in,j -> kappa_P P_in,j,
    kappa_T = F_bar_CFD / F_bar_model,  kappa_P = P_bar_CFD / P_bar_model   (at that motion),

so the corrected model predicts that motion's CFD mean thrust and power exactly (a
zeroth-order modifier, as in modifier adaptation for real-time optimisation: if the rounds
reach a fixed point, the corrected model's predictions there are CFD's). The optimiser's
P_max then holds for the corrected power, and for 0 < beta < 1 the trade-off weighs the
corrected thrust against the corrected power.

The corrected stage cost

    L'_j = -(1 - beta) kappa_T F_j + beta kappa_P P_j + 1/2 sigma_P max(0, kappa_P P_j - P_max)^2
           + (heave, pitch-envelope penalties and smoothing as before)

is c times the stage cost of an ordinary problem, c = (1 - beta) kappa_T + beta kappa_P, with

    beta' = beta kappa_P / c,   P_max' = P_max / kappa_P,   sigma_P' = sigma_P kappa_P^2 / c,
    sigma_h' = sigma_h / c,     sigma_theta' = sigma_theta / c,   eps' = eps / c,

so the corrected optimisation is :class:`~mfflap.optimisation.problem.FlappingProblem` with
those settings, its exact adjoint, SQP and IPOPT unchanged. The optimisers work on that
problem (their progress lines give J_corrected / c); :func:`~mfflap.optimisation.study.beta_study`
labels their results with the case's beta and the corrected J.

A scale is taken only where both means are finite, nonzero and of one sign, so that it is
positive (a thrust that the rounds do not count, :data:`mfflap.rounds.THRUST_FLOOR`, is not
taken either); otherwise it is 1 and :attr:`OutputCorrection.notes` says why.

Filter. Applied round after round, the measured scales alone can make the optima oscillate:
each optimum moves to where the ratio of CFD to model differs, the next scale overshoots
the other way (README, "Output correction"). The usual cure in modifier adaptation is a
first-order filter of the modifiers (Marchetti, Chachuat and Bonvin 2009),

    kappa_k = (1 - K) kappa_(k-1) + K kappa_measured,     0 < K <= 1,

where kappa_(k-1) is the scale the measured motion was optimised with
(:attr:`CorrectionPoint.scales`) and K the gain (:meth:`OutputCorrection.filtered`);
K = 1 takes the measured scale as it is.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from mfflap.errors import ConfigError
from mfflap.optimisation.problem import FlappingProblem


@dataclass(frozen=True)
class CorrectionPoint:
    """A motion with its CFD means, where a correction is measured.

    Attributes
    ----------
    motion : the discrete motion CFD ran (:class:`~mfflap.kinematics.discrete.DiscreteMotion`)
    cfd_mean_thrust : N
    cfd_mean_power : W
    source : where the motion and its CFD come from, e.g. ``round 1, beta = 0 (key ...)``
    thrust_usable : False where the CFD thrust is too small for a ratio to mean anything
    scales : (kappa_T, kappa_P) the motion was optimised with ((1, 1): the model's own), from
        which a filter (:meth:`OutputCorrection.filtered`) moves
    """

    motion: object
    cfd_mean_thrust: float
    cfd_mean_power: float
    source: str
    thrust_usable: bool = True
    scales: tuple[float, float] = (1.0, 1.0)


@dataclass(frozen=True)
class OutputCorrection:
    """Scales of the model's thrust and input power (module docstring).

    Attributes
    ----------
    thrust_scale : kappa_T the model is corrected by, 1 where not measured
    power_scale : kappa_P the model is corrected by, 1 where not measured
    source : the motion it was measured on
    model_mean_thrust, cfd_mean_thrust : N, at that motion
    model_mean_power, cfd_mean_power : W, at that motion
    notes : why a scale was left at 1
    gain : K of the filter that made the scales (1: the measured scales themselves)
    measured_scales : (kappa_T, kappa_P) measured at the motion, before the filter
    previous_scales : (kappa_T, kappa_P) the filter moved from
    """

    thrust_scale: float
    power_scale: float
    source: str
    model_mean_thrust: float = float("nan")
    cfd_mean_thrust: float = float("nan")
    model_mean_power: float = float("nan")
    cfd_mean_power: float = float("nan")
    notes: tuple[str, ...] = field(default=())
    gain: float = 1.0
    measured_scales: tuple[float, float] | None = None
    previous_scales: tuple[float, float] = (1.0, 1.0)

    def __post_init__(self) -> None:
        for name in ("thrust_scale", "power_scale"):
            value = getattr(self, name)
            if not (np.isfinite(value) and value > 0):
                raise ConfigError(f"an output correction's {name} must be finite and > 0, "
                                  f"got {value!r}", key=name)
        check_gain(self.gain)
        if self.measured_scales is None:
            object.__setattr__(self, "measured_scales", (self.thrust_scale, self.power_scale))

    @classmethod
    def measured(cls, point: CorrectionPoint, model, scheme: str) -> OutputCorrection:
        """The correction that makes ``model`` predict ``point``'s CFD means."""
        from mfflap.performance import evaluate_discrete

        s = evaluate_discrete(model, point.motion, scheme).summary
        model_thrust, model_power = float(s.mean_thrust), float(s.mean_power)
        notes = []

        def ratio(name: str, cfd: float, predicted: float, usable: bool = True) -> float:
            if not usable:
                notes.append(f"{name}: the CFD mean {cfd:.3g} is too small to scale by")
                return 1.0
            if not (np.isfinite(cfd) and np.isfinite(predicted) and cfd * predicted > 0):
                notes.append(f"{name}: CFD mean {cfd:.3g} and model mean {predicted:.3g} are "
                             "not of one sign")
                return 1.0
            return cfd / predicted

        return cls(ratio("thrust", point.cfd_mean_thrust, model_thrust, point.thrust_usable),
                   ratio("power", point.cfd_mean_power, model_power), point.source,
                   model_thrust, float(point.cfd_mean_thrust), model_power,
                   float(point.cfd_mean_power), tuple(notes))

    def filtered(self, previous: tuple[float, float], gain: float) -> OutputCorrection:
        """This measured correction through the first-order filter (module docstring).

        Parameters
        ----------
        previous : (kappa_T, kappa_P) the measured motion was optimised with
        gain : K in (0, 1]; 1 returns the measured scales (a scale left at 1, see
            :attr:`notes`, counts as measured 1)

        Raises
        ------
        ConfigError
            ``gain`` outside (0, 1], or a previous scale not finite and > 0.
        """
        check_gain(gain)
        for name, value in zip(("thrust", "power"), previous, strict=True):
            if not (np.isfinite(value) and value > 0):
                raise ConfigError(f"the previous {name} scale of an output correction must be "
                                  f"finite and > 0, got {value!r}", key="scales")
        measured = self.measured_scales
        k_t, k_p = ((1 - gain) * p + gain * m for p, m in zip(previous, measured, strict=True))
        return replace(self, thrust_scale=k_t, power_scale=k_p, gain=float(gain),
                       measured_scales=measured,
                       previous_scales=(float(previous[0]), float(previous[1])))

    def objective_factor(self, beta: float) -> float:
        """c = (1 - beta) kappa_T + beta kappa_P: corrected objective = c x that of
        :meth:`problem`'s."""
        return (1 - beta) * self.thrust_scale + beta * self.power_scale

    def problem(self, problem: FlappingProblem) -> FlappingProblem:
        """The ordinary problem whose objective is the corrected one of ``problem`` over c."""
        from mfflap.optimisation.optimise import replace_problem

        c = self.objective_factor(problem.beta)
        k_p = self.power_scale
        return replace_problem(
            problem, beta=min(max(problem.beta * k_p / c, 0.0), 1.0),
            max_power=problem.max_power / k_p,
            penalty_power=problem.penalty_power * k_p ** 2 / c,
            penalty_heave=problem.penalty_heave / c,
            smoothing_pitch=problem.smoothing_pitch / c,
            smoothing_heave=problem.smoothing_heave / c,
            penalty_pitch=problem.penalty_pitch / c)

    def describe(self) -> str:
        """One line: the scales and where they were measured."""
        return describe_correction(self.as_dict())

    def as_dict(self) -> dict:
        """JSON-friendly."""
        return {"thrust_scale": self.thrust_scale, "power_scale": self.power_scale,
                "source": self.source, "model_mean_thrust": self.model_mean_thrust,
                "cfd_mean_thrust": self.cfd_mean_thrust,
                "model_mean_power": self.model_mean_power,
                "cfd_mean_power": self.cfd_mean_power, "notes": list(self.notes),
                "gain": self.gain, "measured_scales": list(self.measured_scales),
                "previous_scales": list(self.previous_scales)}


def describe_correction(correction: dict) -> str:
    """One line of an :meth:`OutputCorrection.as_dict`: the scales, where they were measured
    and, filtered, from what towards what (a dict written before the filter: unfiltered)."""
    text = (f"thrust x {correction['thrust_scale']:.3f}, power x "
            f"{correction['power_scale']:.3f} ")
    if correction.get("gain", 1.0) == 1.0:
        text += f"(measured on {correction['source']})"
    else:
        (m_t, m_p), (p_t, p_p) = correction["measured_scales"], correction["previous_scales"]
        text += (f"(filter gain {correction['gain']:g} from {p_t:.3f}, {p_p:.3f} towards "
                 f"{m_t:.3f}, {m_p:.3f} measured on {correction['source']})")
    return text + "".join(f"; {n}" for n in correction.get("notes", ()))


def check_gain(gain: float) -> None:
    """Refuse a filter gain outside (0, 1] (:class:`~mfflap.errors.ConfigError`, key
    ``correction_gain``)."""
    if not (np.isfinite(gain) and 0 < gain <= 1):
        raise ConfigError(f"the output correction's filter gain must be in (0, 1] (1: no "
                          f"filter), got {gain!r}", key="correction_gain")


__all__ = ["CorrectionPoint", "OutputCorrection", "check_gain", "describe_correction"]
