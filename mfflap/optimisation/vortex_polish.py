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
from mfflap.hydro.discrete_vortex import vortex_loads
from mfflap.kinematics.convert import resample
from mfflap.kinematics.discrete import DiscreteMotion
from mfflap.optimisation.optimise import optimise_sqp, replace_problem
from mfflap.optimisation.problem import FlappingProblem, SampleOffsets
from mfflap.optimisation.trust_region import (
    TrustRegion,
    accepted,
    step_ratio,
    updated_radius,
)
from mfflap.optimisation.vortex_problem import VortexFlappingProblem
from mfflap.performance import thrust_and_power

#: the vortex model's time steps per period (the model ladder's)
STEPS_PER_PERIOD = 200
#: the trust region's first radius (a fraction of the centre's peak accelerations and dt)
START_RADIUS = 0.25
#: a polish stops once the radius has shrunk below this
MIN_RADIUS = 0.01


@dataclass(frozen=True)
class VortexSamples:
    """The vortex model's last settled period of a motion.

    Attributes
    ----------
    thrust, power : N, W, shape (N,)
        At the N samples of the half period, each the mean of the two half periods.
    sample_peaks : W, shape (N,)
        The largest power over each sample's share of the cycle (the model's steps nearest
        to it, in either half period): what the P_max penalty sees, so that the limit holds
        between the samples too.
    peak_power : W
        The largest input power over the whole period on the model's own steps.
    mean_thrust, mean_power : N, W
        Over the whole period on the model's own steps.
    """

    thrust: np.ndarray
    power: np.ndarray
    sample_peaks: np.ndarray
    peak_power: float
    mean_thrust: float
    mean_power: float


def vortex_samples(vortex: VortexFlappingProblem, motion: DiscreteMotion,
                   steps_per_period: int = STEPS_PER_PERIOD) -> VortexSamples:
    """Run ``motion`` through the vortex model and take its last period (module docstring).

    The motion is resampled to M steps a half period, M the multiple of N nearest above
    ``steps_per_period`` / 2, so that every M / N-th step is one of the motion's samples.

    Examples
    --------
    >>> from mfflap.hydro.discrete_vortex import VortexModelSettings
    >>> n = 10
    >>> phase = (np.arange(n) + 0.5) * np.pi / n
    >>> motion = DiscreteMotion(-20 * np.sin(phase), -4 * np.sin(phase + 1.2), 0.05)
    >>> problem = VortexFlappingProblem(VortexModelSettings(wake_chords=0.5,
    ...                                                     chord_points=16), cycles=2)
    >>> out = vortex_samples(problem, motion, steps_per_period=40)
    >>> out.power.shape, bool(out.peak_power == out.sample_peaks.max() >= out.power.max())
    ((10,), True)
    """
    n = motion.n_steps
    per_sample = max(1, int(np.ceil(steps_per_period / (2 * n))))
    fine = resample(motion, per_sample * n) if per_sample > 1 else motion
    state = vortex.repeated_states(fine)
    loads = vortex_loads(state, vortex.plate, vortex.fluid, vortex.stream, vortex.settings)
    thrust, power = thrust_and_power(loads, state)
    period = 2 * per_sample * n
    thrust, power = np.asarray(thrust)[-period:], np.asarray(power)[-period:]
    if not (np.isfinite(thrust).all() and np.isfinite(power).all()):
        raise ConfigError("the discrete-vortex model's loads are not finite on this motion "
                          "(a vortex too close to the plate: try a larger core radius)",
                          key="vortex.core_radius")
    halves_t = thrust.reshape(2, n, per_sample)[:, :, 0]
    halves_p = power.reshape(2, n, per_sample)[:, :, 0]
    # the steps nearest each sample: a window of per_sample steps centred on it
    windows = np.roll(power, per_sample // 2).reshape(2, n, per_sample)
    peaks = windows.max(axis=2).max(axis=0)
    return VortexSamples(halves_t.mean(axis=0), halves_p.mean(axis=0), peaks,
                         float(power.max()), float(thrust.mean()), float(power.mean()))


def morison_samples(problem: FlappingProblem, motion: DiscreteMotion
                    ) -> tuple[np.ndarray, np.ndarray]:
    """Morison's thrust (N) and input power (W) at the motion's N samples."""
    state = motion.states(problem.scheme)  # type: ignore[arg-type]
    thrust, power = thrust_and_power(problem.model.loads(state), state)
    return np.asarray(thrust, dtype=float), np.asarray(power, dtype=float)


def corrected_problem(problem: FlappingProblem, vortex: VortexFlappingProblem,
                      motion: DiscreteMotion, steps_per_period: int = STEPS_PER_PERIOD
                      ) -> tuple[FlappingProblem, VortexSamples]:
    """``problem`` with the offsets that make Morison give the vortex model's outputs at
    ``motion``, and those outputs."""
    samples = vortex_samples(vortex, motion, steps_per_period)
    thrust, power = morison_samples(problem, motion)
    offsets = SampleOffsets(samples.thrust - thrust, samples.power - power,
                            samples.sample_peaks - power)
    return replace_problem(problem, sample_offsets=offsets), samples


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
    """

    motion: DiscreteMotion
    start_objective: float
    objective: float
    start_samples: VortexSamples
    samples: VortexSamples
    rounds: list[PolishRound]
    message: str
    wall_time_s: float

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
                           callback: Callable[[int, PolishRound], None] | None = None
                           ) -> PolishResult:
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
    centre = start
    corrected, samples = corrected_problem(problem, vortex, centre, steps_per_period)
    start_samples = samples
    j_centre = start_objective = float(corrected.objective(centre))
    rounds: list[PolishRound] = []
    message = f"{max_rounds} rounds run"
    for k in range(max_rounds):
        region = TrustRegion(centre, radius, "the polish's centre")
        result = optimise_sqp(corrected, centre, min_period=min_period, max_period=max_period,
                              trust_region=region, start_label="polish centre")
        candidate = result.motion
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
                        message, time.perf_counter() - t0)


def polished_problem(problem: FlappingProblem, result: PolishResult) -> FlappingProblem:
    """``problem`` corrected at the polished motion: Morison with the vortex model's
    outputs there (what a report compares the polish against)."""
    thrust, power = morison_samples(problem, result.motion)
    return replace_problem(problem, sample_offsets=SampleOffsets(
        result.samples.thrust - thrust, result.samples.power - power,
        result.samples.sample_peaks - power))


def vortex_problem_for(config, beta: float) -> VortexFlappingProblem:
    """The case's optimisation problem of ``beta`` on its discrete-vortex model ([vortex],
    the plate, fluid and stream; three periods from rest)."""
    o = config.optimisation
    return VortexFlappingProblem(config.vortex, plate=config.plate, fluid=config.fluid,
                                 stream=config.flow, beta=beta, max_power=o.max_power,
                                 max_heave=o.max_heave, penalty_power=o.penalty_power,
                                 penalty_heave=o.penalty_heave,
                                 smoothing_pitch=o.smoothing_pitch,
                                 smoothing_heave=o.smoothing_heave)


def polish_optima(config, optima: dict, model,
                  progress: Callable[[str], None] | None = None) -> dict[float, PolishResult]:
    """Polish each beta's optimum (beta -> OptimisationResult) of the case on its
    discrete-vortex model, Morison being ``model`` (beta -> :class:`PolishResult`)."""
    from mfflap.optimisation.study import problem_for

    o = config.optimisation
    out = {}
    for beta, optimum in optima.items():
        def said(k: int, r: PolishRound, beta=beta) -> None:
            if progress is not None:
                progress(f"polish beta {beta:g}, round {k}: radius {r.radius:.3g}, J "
                         f"predicted -{r.predicted_decrease:.3g}, vortex model "
                         f"{-r.vortex_decrease:+.3g} ({'taken' if r.accepted else 'refused'}); "
                         f"peak power {r.peak_power:.3g} W")

        out[beta] = polish_on_vortex_model(
            problem_for(config, beta, model), vortex_problem_for(config, beta),
            optimum.motion, min_period=o.min_period, max_period=o.max_period, callback=said)
        if progress is not None:
            s0, s1 = out[beta].start_samples, out[beta].samples
            progress(f"polish beta {beta:g}: on the vortex model thrust {s0.mean_thrust:.3g} "
                     f"-> {s1.mean_thrust:.3g} N, mean power {s0.mean_power:.3g} -> "
                     f"{s1.mean_power:.3g} W, peak power {s0.peak_power:.3g} -> "
                     f"{s1.peak_power:.3g} W ({out[beta].message})")
    return out


__all__ = ["MIN_RADIUS", "START_RADIUS", "STEPS_PER_PERIOD", "PolishResult", "PolishRound",
           "VortexSamples", "corrected_problem", "morison_samples", "polish_on_vortex_model",
           "polish_optima", "polished_problem", "vortex_problem_for", "vortex_samples"]
