"""Trust region of the rounds: each optimum kept near the last motion CFD confirmed.

The output correction is measured at one motion (a zeroth-order modifier,
:mod:`mfflap.optimisation.output_correction`): the corrected model is exact there and its
error grows with the distance from it. Unbounded, each round's optimum moves to where the
ratio of CFD to model differs and the rounds do not converge (docs/findings/optimised_motions.md,
"Filtered output correction"). A trust region bounds the step instead (trust-region modifier
adaptation; Conn, Gould and Toint 2000 for the radius update, del Rio Chanona et al. 2021
for its use with modifiers).

The region is a box about the centre motion c in the optimiser's own scaled variables:

    |theta_ddot_j - theta_ddot_c,j| <= r max_i |theta_ddot_c,i|,
    |h_ddot_j - h_ddot_c,j|         <= r max_i |h_ddot_c,i|,
    |dt - dt_c|                     <= r dt_c,

for every step j, with r the radius (a fraction). After CFD has run the new optimum u, the
step is judged by the ratio of the decrease of the objective J that CFD found to the decrease
the optimisation predicted:

    rho = (J_CFD(c) - J_CFD(u)) / (J_pred(c) - J_pred(u)),

J being the penalised objective of the optimisation (beta-weighted means, power, heave and
pitch penalties, smoothing). J_pred is the one the round optimised, its outputs corrected as
they were; J_CFD at a motion is the same objective with the model's thrust and power scaled
to that motion's own CFD means
(:meth:`~mfflap.optimisation.output_correction.OutputCorrection.measured`): CFD's means
with the model's shape of the power over the cycle, so that a step which brings the power
back under P_max counts for what it gains, as in the optimiser's own merit.

rho >= :data:`ACCEPT_RATIO`: the step is accepted (u becomes the centre); otherwise the centre
stays. rho < :data:`SHRINK_RATIO`: the radius becomes half the step's length (half the radius
when u is on the boundary; Conn, Gould and Toint allow any radius between a fraction of the
step and a fraction of the radius, and the step's keeps a rejected optimum from being found
again); rho > :data:`GROW_RATIO` with u on the boundary: it doubles (at most
:data:`MAX_RADIUS`). An optimum that did not leave
the centre (within :data:`NO_STEP_SHARE` of the radius) made no step: nothing to judge, the
centre and the radius stay.

CFD's noise. Two runs of one motion differ (docs/findings/optimised_motions.md, "First-order
corrections":
2.8 % of the last cycle's mean thrust). Where that repeatability is known, as a share e of the
means, the noise of J at the centre is

    eps_J = e ((1 - beta) |F_bar_CFD(c)| + beta |P_bar_CFD(c)|),

the ratio is relaxed by it (Sun and Nocedal 2023: a term proportional to the noise level in
numerator and denominator),

    rho = (J_CFD(c) - J_CFD(u) + eps_J) / (J_pred(c) - J_pred(u) + eps_J),

and a step predicted to gain no more than eps_J is within CFD's noise: one run can neither
confirm nor refuse it, and the rounds count it as settled.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from mfflap.errors import ConfigError
from mfflap.study_tables import MAX_TRUST_RADIUS

#: a step is accepted when CFD confirms at least this share of the predicted decrease
ACCEPT_RATIO = 0.1
#: below this share the radius becomes half the step (half the radius on the boundary)
SHRINK_RATIO = 0.25
#: above this share, with the optimum on the boundary, the radius doubles
GROW_RATIO = 0.75
#: the largest radius the update reaches
MAX_RADIUS = MAX_TRUST_RADIUS
#: a radius below this is a collapsed region: the rounds stop
MIN_RADIUS = 1e-3
#: an optimum within this share of the radius from a face of the box is on the boundary
BOUNDARY_SHARE = 1e-3
#: an optimum within this share of the radius of the centre made no step: the centre is the
#: corrected model's optimum, and the difference of J between them is round-off
NO_STEP_SHARE = 1e-3


def check_radius(radius: float, key: str = "trust_region") -> None:
    """Refuse a radius that is not a finite fraction in (0, :data:`MAX_RADIUS`]
    (:class:`~mfflap.errors.ConfigError` naming ``key``)."""
    if not (isinstance(radius, int | float) and not isinstance(radius, bool)
            and math.isfinite(radius)
            and 0 < radius <= MAX_RADIUS):
        raise ConfigError(f"a trust region's radius must be a fraction in (0, {MAX_RADIUS:g}] "
                          f"of the centre motion's accelerations and time step, got {radius!r}",
                          key=key)


def check_repeatability(share: float, key: str = "cfd_repeatability") -> None:
    """Refuse a CFD repeatability that is not a share in (0, 1)
    (:class:`~mfflap.errors.ConfigError` naming ``key``)."""
    if not (isinstance(share, int | float) and not isinstance(share, bool)
            and math.isfinite(share) and 0 < share < 1):
        raise ConfigError("CFD's repeatability is the share by which two runs of one motion "
                          f"differ in their means, in (0, 1) (e.g. 0.03), got {share!r}",
                          key=key)


def noise_of_objective(share: float, beta: float, cfd_mean_thrust: float,
                       cfd_mean_power: float) -> float:
    """eps_J = share ((1 - beta) |F_bar| + beta |P_bar|) of CFD's means (module docstring)."""
    return float(share) * ((1 - beta) * abs(cfd_mean_thrust) + beta * abs(cfd_mean_power))


@dataclass(frozen=True)
class TrustRegion:
    """The box of motions within ``radius`` of ``centre`` (module docstring).

    Attributes
    ----------
    centre : :class:`~mfflap.kinematics.discrete.DiscreteMotion`
    radius : fraction of the centre's peak accelerations and of its time step
    source : where the centre comes from, e.g. ``round 2's beta = 0``
    """

    centre: object
    radius: float
    source: str = ""

    def __post_init__(self) -> None:
        check_radius(self.radius)

    def half_widths(self) -> np.ndarray:
        """Per packed variable (N pitch, N heave accelerations, dt): how far it may move."""
        return self.radius * self.centre.control_scales()

    def bounds(self, n_steps: int, time_step_bounds: tuple[float, float]
               ) -> tuple[np.ndarray, np.ndarray]:
        """Lower and upper bounds of the packed variables (unscaled), dt within both the
        region and ``time_step_bounds`` (s).

        Raises
        ------
        ConfigError
            The centre has not ``n_steps`` steps, or its dt range misses the period bounds.
        """
        if self.centre.n_steps != n_steps:
            raise ConfigError(f"the trust region's centre ({self.source or 'a motion'}) has "
                              f"{self.centre.n_steps} steps, the optimisation {n_steps}",
                              key="trust_region")
        x_c, width = np.real(self.centre.controls()), self.half_widths()
        lower, upper = x_c - width, x_c + width
        lower[-1] = max(lower[-1], time_step_bounds[0])
        upper[-1] = min(upper[-1], time_step_bounds[1])
        if lower[-1] > upper[-1]:
            raise ConfigError(f"the trust region about {self.source or 'its centre'} (dt "
                              f"{x_c[-1]:.4g} s +/- {width[-1]:.3g} s) misses the time steps "
                              f"the period bounds allow ({time_step_bounds[0]:.4g}-"
                              f"{time_step_bounds[1]:.4g} s)", key="trust_region")
        return lower, upper

    def step_fraction(self, motion) -> float:
        """The step from the centre to ``motion`` as a share of the radius (the largest over
        the variables; 1: on the boundary)."""
        step = np.real(motion.controls()) - np.real(self.centre.controls())
        return float(np.max(np.abs(step) / self.half_widths()))

    def on_boundary(self, motion) -> bool:
        """Whether ``motion`` lies on a face of the box (within :data:`BOUNDARY_SHARE`)."""
        return self.step_fraction(motion) >= 1 - BOUNDARY_SHARE


def step_ratio(actual_decrease: float, predicted_decrease: float) -> float:
    """rho = CFD's decrease of f over the predicted one (module docstring).

    A step the model predicted no decrease for (<= 0) has rho = +inf when CFD decreased f
    (a bonus), else -inf (nothing to confirm).
    """
    if not (math.isfinite(actual_decrease) and math.isfinite(predicted_decrease)):
        raise ConfigError(f"a trust-region step needs finite decreases, got CFD "
                          f"{actual_decrease!r} and predicted {predicted_decrease!r}",
                          key="trust_region")
    if predicted_decrease <= 0:
        return math.inf if actual_decrease > 0 else -math.inf
    return actual_decrease / predicted_decrease


def updated_radius(radius: float, ratio: float, on_boundary: bool,
                   step_fraction: float = 1.0) -> float:
    """The next radius after a step of ``ratio`` that went ``step_fraction`` of ``radius``
    (module docstring): a poor step halves the radius or the step, whichever is shorter, so
    that the next optimum differs from a rejected one inside the region."""
    if ratio < SHRINK_RATIO:
        return 0.5 * radius * min(step_fraction, 1.0)
    if ratio > GROW_RATIO and on_boundary:
        return min(2.0 * radius, MAX_RADIUS)
    return radius


def accepted(ratio: float) -> bool:
    """Whether a step of ``ratio`` is taken (its optimum becomes the centre)."""
    return ratio >= ACCEPT_RATIO


@dataclass(frozen=True)
class TrustStep:
    """One beta's step in its trust region, judged by CFD (module docstring).

    Attributes
    ----------
    beta : the beta optimised
    radius : the radius it was optimised within
    centre : where the centre came from
    step_fraction : the step as a share of the radius (1: on the boundary)
    on_boundary : whether the optimum lies on the region's boundary
    cfd_decrease : J_CFD(centre) - J_CFD(optimum)
    predicted_decrease : J_pred(centre) - J_pred(optimum), the objective the round optimised
    ratio : rho, their ratio
    accepted : whether the optimum becomes the next centre
    next_radius : the radius of the next round
    noise : eps_J, CFD's noise of J at the centre (0: not known; module docstring)
    ran_otherwise : how the optimum's CFD ran otherwise than the centre's (a retry's far
        field or Courant limit, :func:`~mfflap.records.as_run.as_run_differences`), and
        either run's compared cycles mixing two set-ups (a retry resumed it within them);
        empty: alike, so that ``cfd_decrease`` holds the motion's change alone
    """

    beta: float
    radius: float
    centre: str
    step_fraction: float
    on_boundary: bool
    cfd_decrease: float
    predicted_decrease: float
    ratio: float
    accepted: bool
    next_radius: float
    noise: float = 0.0
    ran_otherwise: tuple[str, ...] = ()

    @classmethod
    def judged(cls, region: TrustRegion, beta: float, optimum, cfd_centre: float,
               cfd_optimum: float, predicted_centre: float, predicted_optimum: float,
               noise: float = 0.0) -> TrustStep:
        """The step from ``region``'s centre to ``optimum`` (a motion), from the objective J
        of CFD and the predicted one (module docstring) at both; ``noise``: eps_J, which
        relaxes the ratio (0: CFD taken as exact).

        Raises
        ------
        ConfigError
            ``noise`` negative or not finite.
        """
        if not (math.isfinite(noise) and noise >= 0):
            raise ConfigError(f"CFD's noise of J must be finite and >= 0, got {noise!r}",
                              key="cfd_repeatability")
        cfd = float(cfd_centre) - float(cfd_optimum)
        predicted = float(predicted_centre) - float(predicted_optimum)
        fraction = region.step_fraction(optimum)
        if fraction < NO_STEP_SHARE:  # no step: the ratio of two round-offs means nothing
            return cls(float(beta), region.radius, region.source, fraction, False, cfd,
                       predicted, math.nan, True, region.radius, float(noise))
        rho = step_ratio(cfd + noise, predicted + noise)
        edge = region.on_boundary(optimum)
        return cls(float(beta), region.radius, region.source, fraction, edge, cfd, predicted,
                   rho, accepted(rho), updated_radius(region.radius, rho, edge, fraction),
                   float(noise))

    @property
    def within_noise(self) -> bool:
        """Whether the step was predicted to gain no more than CFD's noise (known noise
        only): one run can neither confirm nor refuse it."""
        return self.noise > 0 and self.predicted_decrease <= self.noise

    @property
    def moved(self) -> bool:
        """Whether the optimum left the centre (see :data:`NO_STEP_SHARE`)."""
        return self.step_fraction >= NO_STEP_SHARE

    def describe(self) -> str:
        """One line: the step, its ratio and what follows."""
        return describe_step(self.as_dict())

    def as_dict(self) -> dict:
        """JSON-friendly (an infinite ratio as a string)."""
        return {"beta": self.beta, "radius": self.radius, "centre": self.centre,
                "step_fraction": self.step_fraction, "on_boundary": self.on_boundary,
                "cfd_decrease": self.cfd_decrease,
                "predicted_decrease": self.predicted_decrease,
                "ratio": self.ratio if math.isfinite(self.ratio) else str(self.ratio),
                "accepted": self.accepted, "next_radius": self.next_radius,
                "noise": self.noise, "within_noise": self.within_noise,
                "ran_otherwise": list(self.ran_otherwise)}


def describe_step(step: dict) -> str:
    """One line of a :meth:`TrustStep.as_dict`."""
    if step["step_fraction"] < NO_STEP_SHARE:
        return (f"trust region {step['radius']:.3g} about {step['centre']}: no step (the "
                "centre is the optimum); centre and radius kept")
    ratio = float(step["ratio"])
    where = "on the boundary" if step["on_boundary"] else "inside"
    noise = step.get("noise", 0.0)
    return (f"trust region {step['radius']:.3g} about {step['centre']}: step "
            f"{step['step_fraction']:.2f} of it ({where}); CFD decreased J by "
            f"{step['cfd_decrease']:.4g}, predicted {step['predicted_decrease']:.4g} "
            + (f"(ratio {ratio:.3g}" if not noise else
               f"(CFD's noise {noise:.3g}; ratio relaxed by it {ratio:.3g}")
            + ("; within CFD's noise" if step.get("within_noise") else "")
            + f"): {'accepted' if step['accepted'] else 'rejected'}, "
            f"next radius {step['next_radius']:.3g}"
            + ("; the CFD runs compared did not run alike (centre against optimum: "
               + ", ".join(step["ran_otherwise"]) + ")" if step.get("ran_otherwise") else ""))


__all__ = [
    "ACCEPT_RATIO",
    "BOUNDARY_SHARE",
    "GROW_RATIO",
    "MAX_RADIUS",
    "MIN_RADIUS",
    "NO_STEP_SHARE",
    "SHRINK_RATIO",
    "TrustRegion",
    "TrustStep",
    "accepted",
    "check_radius",
    "check_repeatability",
    "describe_step",
    "noise_of_objective",
    "step_ratio",
    "updated_radius",
]
