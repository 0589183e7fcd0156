"""Output correction of the model from CFD (multiplicative output space mapping).

The back-tests of the optimised motions find the model's mean thrust and power off by a
factor that stays nearly the same from one optimum to the next
(docs/findings/optimised_motions.md: 15-20 % low at beta = 0 in every round), even after
a refit on those very back-tests. A correction scales the model's outputs by what CFD
measured at the last motion of the same beta:

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
the other way (docs/findings/optimised_motions.md, "Output correction"). The usual cure in modifier
adaptation is a first-order filter of the modifiers (Marchetti, Chachuat and Bonvin 2009),

    kappa_k = (1 - K) kappa_(k-1) + K kappa_measured,     0 < K <= 1,

where kappa_(k-1) is the scale the measured motion was optimised with
(:attr:`CorrectionPoint.scales`) and K the gain (:meth:`OutputCorrection.filtered`);
K = 1 takes the measured scale as it is.

First-order correction (a slope of J). The scales make the corrected model exact at the
motion they were measured on, with the model's own slope there; in the trust-region rounds
CFD then refuses steps whose direction that slope gets wrong (docs/findings/optimised_motions.md,
"Trust
region"). CFD gradients of 2N + 1 controls are out of reach (one CFD run per control), but every
earlier back-tested motion u_i of the same beta is a secant from the centre c. As in modifier
adaptation, the first-order modifier goes on the objective: with J_CFD(u) the objective with
the model's outputs scaled to u's own CFD means (what a trust region judges steps by,
:func:`cfd_objective`) and J_0(u) the objective corrected by the centre's scales,

    J_corr(u) = J_0(u) + lambda . (u - c),     lambda . (u_i - c) = J_CFD(u_i) - J_0(u_i),

so the corrected objective is CFD's at the centre and at every u_i: its values, and so its
slope along the secants, power penalty included. lambda is the minimum-norm solution in the
controls scaled as a trust region scales them
(:meth:`~mfflap.kinematics.discrete.DiscreteMotion.control_scales`): the slope is
corrected only along the secants, the model's own kept across them (minimum-norm
interpolation of derivative-free trust-region methods, Conn, Scheinberg and Vicente 2009,
applied to the residual of a physics model as in first-order-consistent model management,
Alexandrov and Lewis 2001). The rounds take the earlier motions within
:data:`SECANT_REACH` radii of the centre (:func:`secants_within`). The term enters J as a
:class:`~mfflap.optimisation.problem.LinearModifier`; the predicted means stay the scaled
ones. Unbounded it would lead the optimiser off along a secant: it belongs in a trust region.

In the shipped series (docs/findings/optimised_motions.md, "First-order corrections") CFD refused
every step taken with a slope: each optimum went to a face of the box, the slope's term made
the whole predicted decrease, and the scales' part alone foretold what CFD found. A first
version put the slopes on the mean thrust and power instead. It was inconsistent: the power
penalty still saw the centre's scale, while CFD's objective sees each motion's own, so a
round of its series chose a step whose CFD power peaks, scaled so, raised J by 35 where 0.6
of decrease was predicted.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from mfflap.errors import ConfigError
from mfflap.kinematics.discrete import DiscreteMotion
from mfflap.optimisation.optimise import replace_problem
from mfflap.optimisation.problem import FlappingProblem, LinearModifier
from mfflap.performance import evaluate_discrete


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


#: a secant shorter than this (largest scaled control change) is left out: the motion is the
#: centre's, or so near it that CFD's difference is noise
SECANT_MIN_STEP = 1e-4
#: the rounds take secants to earlier motions within this many trust radii of the centre
#: (:func:`secants_within`): a linear model is good only near where it is used
SECANT_REACH = 2.0


def secants_within(centre, points, reach: float) -> list:
    """The ``points`` (:class:`CorrectionPoint`) within ``reach`` of the ``centre`` motion,
    the largest change of a control scaled as a trust region scales it
    (:meth:`~mfflap.kinematics.discrete.DiscreteMotion.control_scales`); points of another N are
    left out too.

    Derivative-free trust-region methods build their linear models from points within a
    multiple of the radius (Conn, Scheinberg and Vicente 2009, ch. 6 and 10), so that the
    model is accurate where it is used. With :data:`SECANT_REACH` = 2 the rounds keep the
    step just refused (a refused step halves the radius) and drop the older, farther ones
    as the region shrinks.
    """
    c, w = np.real(centre.controls()), centre.control_scales()
    return [p for p in points if p.motion.n_steps == centre.n_steps
            and np.max(np.abs((np.real(p.motion.controls()) - c) / w)) <= reach * (1 + 1e-9)]


def cfd_objective(point: CorrectionPoint, problem: FlappingProblem) -> float:
    """J of ``problem`` at ``point``'s motion with the model's thrust and power scaled to
    that motion's own CFD means (:meth:`OutputCorrection.measured`): CFD's means with the
    model's shape of the power over the cycle, so the power penalty counts too."""
    corr = OutputCorrection.measured(point, problem.model, problem.scheme)
    return corr.objective_factor(problem.beta) * float(
        corr.problem(problem).objective(point.motion))


@dataclass(frozen=True)
class Slopes:
    """The first-order part of an output correction (module docstring).

    Attributes
    ----------
    centre : packed controls c where the affine term vanishes, shape (2N + 1,)
    objective : lambda, units of J per packed control
    sources : the earlier motions the corrected objective meets CFD's at
    residuals : J_CFD(u_i) - J_0(u_i) at each (units of J)
    """

    centre: np.ndarray = field(compare=False)
    objective: np.ndarray = field(compare=False)
    sources: tuple[str, ...] = ()
    residuals: tuple[float, ...] = ()

    def shift(self, motion) -> float:
        """lambda . (u - c) at ``motion`` (units of J)."""
        z = np.real(motion.controls())
        if z.size != self.centre.size:
            raise ConfigError(f"the output correction's slopes are for N = "
                              f"{(self.centre.size - 1) // 2} steps, the motion has "
                              f"{motion.n_steps}", key="slopes")
        return float(self.objective @ (z - self.centre))

    def as_dict(self) -> dict:
        """JSON-friendly: the sources, residuals and the slope's scaled length."""
        w = DiscreteMotion.from_controls(self.centre).control_scales()
        return {"sources": list(self.sources), "residuals": list(self.residuals),
                "scaled_norm": float(np.linalg.norm(self.objective * w))}


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
    slopes : the first-order part (:meth:`with_slopes`; None: scales only)
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
    slopes: Slopes | None = None

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

    def with_slopes(self, centre, points, problem: FlappingProblem) -> OutputCorrection:
        """This correction with a slope of J that makes the corrected objective CFD's at
        ``points`` too (module docstring).

        Parameters
        ----------
        centre : the :class:`~mfflap.kinematics.discrete.DiscreteMotion` this correction's
            scales were measured on
        points : earlier :class:`CorrectionPoint` of the same beta; those within
            :data:`SECANT_MIN_STEP` of the centre or of another N are left out
        problem : the case's problem of that beta (uncorrected; its model and scheme)

        Returns
        -------
        OutputCorrection
            With :attr:`slopes` (a zero slope, and no sources, when no point is left).

        Raises
        ------
        ConfigError
            The scales come through a filter (gain < 1): the centre would not be met.
        """
        if self.gain != 1.0:
            raise ConfigError("slopes need the measured scales (filter gain 1), so that the "
                              f"corrected model meets CFD at the centre; gain {self.gain:g}",
                              key="correction_gain")
        c, w = np.real(centre.controls()), centre.control_scales()
        zeroth = self.problem(problem)
        factor = self.objective_factor(problem.beta)
        rows, residuals, sources = [], [], []
        for p in points:
            if p.motion.n_steps != centre.n_steps:
                continue
            step = (np.real(p.motion.controls()) - c) / w
            if np.max(np.abs(step)) < SECANT_MIN_STEP:
                continue
            rows.append(step)
            residuals.append(cfd_objective(p, problem)
                             - factor * float(zeroth.objective(p.motion)))
            sources.append(p.source)
        slope = np.zeros_like(c)
        if rows:
            slope = (np.linalg.pinv(np.array(rows), rcond=1e-10) @ np.array(residuals)) / w
            if not np.isfinite(slope).all():
                raise ConfigError(f"the slope of J through {sources} is not finite",
                                  key="slopes")
        return replace(self, slopes=Slopes(c, slope, tuple(sources), tuple(residuals)))

    def shift(self, motion) -> float:
        """What the slope adds to the corrected J at ``motion`` (0 without slopes)."""
        return 0.0 if self.slopes is None else self.slopes.shift(motion)

    def objective_factor(self, beta: float) -> float:
        """c = (1 - beta) kappa_T + beta kappa_P: corrected objective = c x that of
        :meth:`problem`'s."""
        return (1 - beta) * self.thrust_scale + beta * self.power_scale

    def problem(self, problem: FlappingProblem) -> FlappingProblem:
        """The ordinary problem whose objective is the corrected one of ``problem`` over c."""
        c = self.objective_factor(problem.beta)
        k_p = self.power_scale
        modifier = None
        if self.slopes is not None:
            modifier = LinearModifier(self.slopes.objective / c, self.slopes.centre)
        return replace_problem(
            problem, beta=min(max(problem.beta * k_p / c, 0.0), 1.0),
            max_power=problem.max_power / k_p,
            penalty_power=problem.penalty_power * k_p ** 2 / c,
            penalty_heave=problem.penalty_heave / c,
            smoothing_pitch=problem.smoothing_pitch / c,
            smoothing_heave=problem.smoothing_heave / c,
            penalty_pitch=problem.penalty_pitch / c, linear_modifier=modifier)

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
                "previous_scales": list(self.previous_scales),
                **({} if self.slopes is None else {"slopes": self.slopes.as_dict()})}


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
    slopes = correction.get("slopes")
    if slopes is not None:
        n = len(slopes["sources"])
        text += (f"; a slope of J through {n} earlier motion(s) (J of CFD minus J of the "
                 "scales there: " + ", ".join(f"{r:+.3g}" for r in slopes["residuals"]) + ")"
                 if n else "; a slope of J: no earlier motion near (zero)")
    return text + "".join(f"; {n}" for n in correction.get("notes", ()))


def check_gain(gain: float) -> None:
    """Refuse a filter gain outside (0, 1] (:class:`~mfflap.errors.ConfigError`, key
    ``correction_gain``)."""
    if not (np.isfinite(gain) and 0 < gain <= 1):
        raise ConfigError(f"the output correction's filter gain must be in (0, 1] (1: no "
                          f"filter), got {gain!r}", key="correction_gain")


__all__ = [
    "SECANT_MIN_STEP",
    "SECANT_REACH",
    "CorrectionPoint",
    "OutputCorrection",
    "Slopes",
    "cfd_objective",
    "check_gain",
    "describe_correction",
    "secants_within",
]
