"""Polishing a Morison optimum on the discrete-vortex model: Morison corrected sample by
sample by the vortex model, in a trust region judged by the vortex model.

The vortex model's exact gradient of a cycle objective is dominated by its chaotic free wake
(docs' findings, *The discrete-vortex model*), so steepest descent on it fails at its first
line search. What the vortex model gets right, and Morison does not, is the shape of the
thrust and power over the cycle: the leading-edge vortex's power peaks. The polish carries
that shape into Morison as fixed per-sample offsets and lets Morison's exact adjoint steer:

1. At the centre motion c, run the vortex model (``cycles`` periods from rest,
   ``steps_per_period`` steps a period) and take its last period's thrust and input power at
   the N samples of the half period, each the mean of the two half periods, and the largest
   power over each sample's share of the cycle. The offsets are these minus Morison's at the
   same samples (:class:`~mfflap.optimisation.problem.SampleOffsets`; the P_max penalty sees
   the largest power): the corrected Morison model gives the vortex model's outputs at c
   exactly (a zeroth-order output correction), and its power limit holds on the vortex
   model's own steps, not only at the N samples.
2. Optimise the corrected Morison problem (SQP with the exact adjoint gradient) within a box
   trust region about c (:class:`~mfflap.optimisation.trust_region.TrustRegion`).
3. Judge the step by the vortex model: J_v(u) is the same objective with the vortex model's
   outputs at u itself. With rho = (J_v(c) - J_v(u)) / (J_corr(c) - J_corr(u)) the step is
   taken and the radius updated as the CFD rounds do
   (:func:`~mfflap.optimisation.trust_region.updated_radius`).

This is trust-region model management (Alexandrov et al. 1998) with a physics model as the
surrogate: each round costs one Morison optimisation and one vortex-model run, and the
vortex objective is only ever evaluated, never differentiated.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from mfflap.errors import ConfigError
from mfflap.kinematics.discrete import DiscreteMotion
from mfflap.optimisation.bandwidth import band_limited
from mfflap.optimisation.optimise import optimise_sqp
from mfflap.optimisation.problem import FlappingProblem
from mfflap.optimisation.trust_region import (
    TrustRegion,
    accepted,
    step_ratio,
    updated_radius,
)
from mfflap.optimisation.vortex_correction import (
    STEPS_PER_PERIOD,
    VortexSamples,
    corrected_problem,
)
from mfflap.optimisation.vortex_problem import VortexFlappingProblem

#: the trust region's first radius (a fraction of the centre's peak accelerations and dt)
START_RADIUS = 0.25
#: a polish stops once the radius has shrunk below this
MIN_RADIUS = 0.01
#: each candidate's controls are rounded to this share of the centre's control scales
#: before the vortex model runs it
QUANTUM = 1e-4


def quantised(motion: DiscreteMotion, scales: np.ndarray) -> DiscreteMotion:
    """``motion`` with each control rounded to :data:`QUANTUM` of its scale in ``scales``
    (the scale taken down to a power of two).

    The vortex model's wake is chaotic: a change in a motion far below any that matters can
    change its period means by more than a polish step gains, and with them which steps the
    trust region takes. Rounded to a grid of its own (the scale taken down to a power of
    two, so that the grid does not move with the motion's round-off), a candidate that SQP
    finds to within less than the grid's step is the same motion to the vortex model. SQP's
    end points move with round-off in its inputs (another BLAS, the compiled kernel against
    the array code) by more than round-off, so a control near a grid point can still round
    the other way and the polish go on elsewhere: the rounding makes the polish repeat
    itself on one machine and set-up, not everywhere (docs' findings, *Known limits*).

    Examples
    --------
    >>> m = DiscreteMotion(np.array([1.0 + 1e-9, -2.0]), np.array([0.5, 0.25]), 0.01)
    >>> q = quantised(m, m.control_scales())
    >>> float(q.pitch_acceleration[0])
    1.0
    """
    # a grid of its own, not the scales themselves: they move with the motion's round-off
    step = QUANTUM * 2.0 ** np.floor(np.log2(np.asarray(scales, dtype=float)))
    return DiscreteMotion.from_controls(np.round(np.real(motion.controls()) / step) * step)


@dataclass(frozen=True)
class PolishRound:
    """One round of the polish.

    Attributes
    ----------
    radius : the trust region's radius it was optimised in
    predicted_decrease, vortex_decrease : float
        Of J, by the corrected Morison model and by the vortex model.
    ratio : rho, their quotient
    accepted : bool
        Whether its optimum became the centre.
    vortex_objective : float
        J_v at the round's optimum.
    peak_power : W
        The vortex model's peak input power at the round's optimum.
    """

    radius: float
    predicted_decrease: float
    vortex_decrease: float
    ratio: float
    accepted: bool
    vortex_objective: float
    peak_power: float


@dataclass(frozen=True)
class PolishResult:
    """A Morison optimum polished on the discrete-vortex model.

    Attributes
    ----------
    motion : DiscreteMotion
        The last accepted centre (the start if no step was taken).
    start_objective, objective : float
        J_v at the start and at ``motion``.
    start_samples, samples : VortexSamples
        The vortex model's outputs at the start and at ``motion``.
    rounds : list of PolishRound
    message : str
        Why it stopped.
    wall_time_s : float
    start : str
        Where the polish started (the Morison optimum, or a sinusoid the vortex model
        ranked best).
    """

    motion: DiscreteMotion
    start_objective: float
    objective: float
    start_samples: VortexSamples
    samples: VortexSamples
    rounds: list[PolishRound]
    message: str
    wall_time_s: float
    start: str = "the Morison optimum"

    @property
    def n_accepted(self) -> int:
        """How many rounds moved the centre."""
        return sum(r.accepted for r in self.rounds)

    def moved_from(self, start: DiscreteMotion) -> bool:
        """Whether the polished motion differs from ``start`` by more than
        :data:`MIN_RADIUS` of its control scales in some control (a motion worth its own
        back-test)."""
        step = np.real(self.motion.controls()) - np.real(start.controls())
        return bool(np.max(np.abs(step) / start.control_scales()) > MIN_RADIUS)


def polish_on_vortex_model(problem: FlappingProblem, vortex: VortexFlappingProblem,
                           start: DiscreteMotion, *, min_period: float, max_period: float,
                           max_rounds: int = 10, radius: float = START_RADIUS,
                           steps_per_period: int = STEPS_PER_PERIOD,
                           callback: Callable[[int, PolishRound], None] | None = None,
                           start_label: str = "the Morison optimum",
                           bandwidth_harmonics: int | None = None) -> PolishResult:
    """Refine ``start`` on the vortex model (module docstring).

    Parameters
    ----------
    problem : FlappingProblem
        The Morison problem (beta, P_max and the penalties are the polish's too).
    vortex : VortexFlappingProblem
        The vortex model's settings, plate, flow and start-up ``cycles``; its beta and
        penalties are not used (``problem``'s are).
    start : DiscreteMotion
        Typically the Morison optimum.
    min_period, max_period : float, s
        The period's bounds.
    max_rounds : int
        Vortex-model runs after the start's.
    radius : float
        The first trust-region radius.
    steps_per_period : int
        The vortex model's resolution.
    callback : callable(round, PolishRound), optional
        Called after each round (progress).
    start_label : str
        What ``start`` is (:attr:`PolishResult.start`).
    bandwidth_harmonics : int, optional
        The highest harmonic a polished motion may contain (an actuator's bandwidth,
        :mod:`mfflap.optimisation.bandwidth`): the start is projected onto the band and every
        round's SQP holds it. Without it, the vortex model's per-sample offsets let SQP
        trade smoothness for thrust, and the controls chatter from sample to sample.

    Returns
    -------
    PolishResult

    Examples
    --------
    >>> from mfflap.hydro.discrete_vortex import VortexModelSettings
    >>> from mfflap.hydro.morison import MorisonModel
    >>> n = 10
    >>> phase = (np.arange(n) + 0.5) * np.pi / n
    >>> start = DiscreteMotion(-20 * np.sin(phase), -4 * np.sin(phase + 1.2), 0.05)
    >>> vortex = VortexFlappingProblem(VortexModelSettings(wake_chords=0.5,
    ...                                                    chord_points=16), cycles=2)
    >>> result = polish_on_vortex_model(FlappingProblem(MorisonModel(), max_power=5.0),
    ...                                 vortex, start, min_period=0.5, max_period=2.0,
    ...                                 max_rounds=2, steps_per_period=40)
    >>> bool(result.objective <= result.start_objective), len(result.rounds)
    (True, 2)
    """
    if not isinstance(max_rounds, int) or max_rounds < 1:
        raise ConfigError(f"value {max_rounds!r} is not allowed; allowed: an integer >= 1",
                          key="vortex_polish.max_rounds")
    t0 = time.perf_counter()
    if bandwidth_harmonics is not None:
        start = band_limited(start, bandwidth_harmonics)
    centre = quantised(start, start.control_scales())
    corrected, samples = corrected_problem(problem, vortex, centre, steps_per_period)
    start_samples = samples
    j_centre = start_objective = float(corrected.objective(centre))
    rounds: list[PolishRound] = []
    message = f"{max_rounds} rounds run"
    for k in range(max_rounds):
        region = TrustRegion(centre, radius, "the polish's centre")
        result = optimise_sqp(corrected, centre, min_period=min_period, max_period=max_period,
                              trust_region=region, start_label="polish centre",
                              bandwidth_harmonics=bandwidth_harmonics)
        candidate = quantised(result.motion, centre.control_scales())
        predicted = j_centre - float(corrected.objective(candidate))
        try:
            trial, trial_samples = corrected_problem(problem, vortex, candidate,
                                                     steps_per_period)
            j_trial = float(trial.objective(candidate))
        except ConfigError:  # the vortex model failed there: a step to refuse
            trial, trial_samples, j_trial = None, None, np.inf
        actual = j_centre - j_trial if np.isfinite(j_trial) else -np.inf
        ratio = (step_ratio(actual, predicted) if np.isfinite(actual) else -np.inf)
        fraction = region.step_fraction(candidate)
        taken = bool(np.isfinite(ratio) and accepted(ratio) and actual > 0)
        round_ = PolishRound(radius, predicted, float(actual), float(ratio), taken,
                             float(j_trial),
                             trial_samples.peak_power if trial_samples else float("nan"))
        rounds.append(round_)
        if callback is not None:
            callback(k + 1, round_)
        radius = updated_radius(radius, ratio if np.isfinite(ratio) else -1.0,
                                region.on_boundary(candidate), fraction)
        if taken:
            centre, corrected, samples, j_centre = candidate, trial, trial_samples, j_trial
        if radius < MIN_RADIUS:
            message = f"the trust region shrank below {MIN_RADIUS:g} after {k + 1} rounds"
            break
    return PolishResult(centre, start_objective, j_centre, start_samples, samples, rounds,
                        message, time.perf_counter() - t0, start_label)


__all__ = ["MIN_RADIUS", "QUANTUM", "START_RADIUS", "PolishResult", "PolishRound",
           "polish_on_vortex_model", "quantised"]
