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
from dataclasses import dataclass, replace

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
#: each candidate's controls are rounded to this share of the centre's control scales
#: before the vortex model runs it
QUANTUM = 1e-4


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


def quantised(motion: DiscreteMotion, scales: np.ndarray) -> DiscreteMotion:
    """``motion`` with each control rounded to :data:`QUANTUM` of its scale in ``scales``.

    The vortex model's wake is chaotic: a change of 1e-12 in a motion, such as SQP's
    round-off on another machine or with another BLAS, can change its period means by more
    than a polish step gains, and with them which steps the trust region takes. SQP's end
    points from one start differ by about 1e-6-1e-5 of the scales between the compiled
    kernel and the array code; rounded to 1e-4, below any change that matters (the
    back-test look-up tolerates 2e-3 of a signal's range), the motions the vortex model
    runs are the same wherever the polish runs, but for a control that lies on a rounding
    boundary.

    Examples
    --------
    >>> m = DiscreteMotion(np.array([1.0 + 1e-9, -2.0]), np.array([0.5, 0.25]), 0.01)
    >>> q = quantised(m, m.control_scales())
    >>> float(q.pitch_acceleration[0])
    1.0
    """
    step = QUANTUM * np.asarray(scales, dtype=float)
    return DiscreteMotion.from_controls(np.round(np.real(motion.controls()) / step) * step)


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
                           start_label: str = "the Morison optimum") -> PolishResult:
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
    centre = quantised(start, start.control_scales())
    corrected, samples = corrected_problem(problem, vortex, centre, steps_per_period)
    start_samples = samples
    j_centre = start_objective = float(corrected.objective(centre))
    rounds: list[PolishRound] = []
    message = f"{max_rounds} rounds run"
    for k in range(max_rounds):
        region = TrustRegion(centre, radius, "the polish's centre")
        result = optimise_sqp(corrected, centre, min_period=min_period, max_period=max_period,
                              trust_region=region, start_label="polish centre")
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


#: the sinusoids the vortex model ranks best that a polish also starts from
SINUSOID_STARTS = 3
#: the vortex model's time steps per period and periods from rest when it ranks sinusoids
RANKING_STEPS_PER_PERIOD, RANKING_CYCLES = 100, 2


@dataclass(frozen=True)
class SinusoidStart:
    """A sinusoid the vortex model ran, a candidate start of the polish.

    Attributes
    ----------
    label : str
    motion : DiscreteMotion
    samples : VortexSamples
        At :data:`RANKING_STEPS_PER_PERIOD` steps a period, :data:`RANKING_CYCLES` periods
        from rest.
    """

    label: str
    motion: DiscreteMotion
    samples: VortexSamples


def sinusoid_starts(config, n_steps: int) -> list[SinusoidStart]:
    """The vortex model on a coarse grid of sinusoids (heave leading pitch by 90 deg): eight
    frequencies from max(1 / max_period, 0.3 Hz) to min(1 / min_period, 2 Hz), six heave
    amplitudes from 0.1 m to h_max, pitch amplitudes 30, 45 and 60 deg (within the case's
    pitch limit). Motions the vortex model cannot run are left out.

    The Morison sweep's best sinusoid is a poor start on the vortex model: Morison
    under-predicts the peak power of large motions 2-4x, so its best sinusoid within P_max
    draws far more on the vortex model (and in CFD).
    """
    from mfflap.kinematics.convert import harmonic_to_discrete

    o = config.optimisation
    f_lo, f_hi = max(1.0 / o.max_period, 0.3), min(1.0 / o.min_period, 2.0)
    max_pitch_deg = o.max_pitch_deg if o.max_pitch_deg is not None else 60.0
    ranking = replace(vortex_problem_for(config, 0.0), cycles=RANKING_CYCLES)
    out = []
    for f in np.geomspace(f_lo, f_hi, 8):
        for h in np.linspace(min(0.1, o.max_heave), o.max_heave, 6):
            for pitch_deg in (30.0, 45.0, 60.0):
                if pitch_deg > max_pitch_deg:
                    continue
                motion = harmonic_to_discrete(f, h, np.deg2rad(pitch_deg), np.pi / 2, n_steps)
                try:
                    samples = vortex_samples(ranking, motion, RANKING_STEPS_PER_PERIOD)
                except ConfigError:
                    continue
                out.append(SinusoidStart(f"sinusoid f={f:.3g} Hz h={h:.3g} m "
                                         f"th={pitch_deg:g} deg phi=90 deg", motion, samples))
    return out


def vortex_objective(problem: FlappingProblem, motion: DiscreteMotion,
                     samples: VortexSamples) -> float:
    """J of ``problem`` with the vortex model's ``samples`` of ``motion`` for Morison's."""
    thrust, power = morison_samples(problem, motion)
    return float(replace_problem(problem, sample_offsets=SampleOffsets(
        samples.thrust - thrust, samples.power - power, samples.sample_peaks - power)
    ).objective(motion))


def polish_optima(config, optima: dict, model,
                  progress: Callable[[str], None] | None = None,
                  starts: list[SinusoidStart] | None = None) -> dict[float, PolishResult]:
    """Polish each beta's optimum (beta -> OptimisationResult) of the case on its
    discrete-vortex model, Morison being ``model`` (beta -> :class:`PolishResult`).

    Each beta is polished from its Morison optimum. Given ``starts`` (e.g.
    :func:`sinusoid_starts`), it is also polished from the :data:`SINUSOID_STARTS` of them
    with the lowest J on the vortex model, and the polish with the lowest J on the vortex
    model is kept: a polish ends in the optimum nearest its start. The main job does not
    give them: in CFD the polishes from sinusoids drew 1.5-1.8 times the peak power the
    vortex model predicted, where the polish from the Morison optimum held P_max (docs'
    findings, *The discrete-vortex model*).
    """
    from mfflap.optimisation.study import problem_for

    o = config.optimisation
    out = {}
    for beta, optimum in optima.items():
        problem, vortex = problem_for(config, beta, model), vortex_problem_for(config, beta)
        candidates = [("the Morison optimum", optimum.motion)]
        ranked = sorted(starts or [],
                        key=lambda s: vortex_objective(problem, s.motion, s.samples))
        candidates += [(s.label, s.motion) for s in ranked[:SINUSOID_STARTS]]
        results = []
        for label, start in candidates:
            def said(k: int, r: PolishRound, beta=beta, label=label) -> None:
                if progress is not None:
                    progress(f"polish beta {beta:g} from {label}, round {k}: radius "
                             f"{r.radius:.3g}, J predicted {-r.predicted_decrease:+.3g}, "
                             f"vortex model {-r.vortex_decrease:+.3g} "
                             f"({'taken' if r.accepted else 'refused'}); peak power "
                             f"{r.peak_power:.3g} W")

            results.append(polish_on_vortex_model(
                problem, vortex, start, min_period=o.min_period, max_period=o.max_period,
                callback=said, start_label=label))
        out[beta] = min(results, key=lambda r: r.objective)
        if progress is not None:
            s0, s1 = out[beta].start_samples, out[beta].samples
            progress(f"polish beta {beta:g}, kept the one from {out[beta].start}: on the "
                     f"vortex model thrust {s0.mean_thrust:.3g} -> {s1.mean_thrust:.3g} N, "
                     f"mean power {s0.mean_power:.3g} -> {s1.mean_power:.3g} W, peak power "
                     f"{s0.peak_power:.3g} -> {s1.peak_power:.3g} W ({out[beta].message})")
    return out


__all__ = [
    "MIN_RADIUS",
    "QUANTUM",
    "RANKING_CYCLES",
    "RANKING_STEPS_PER_PERIOD",
    "SINUSOID_STARTS",
    "START_RADIUS",
    "STEPS_PER_PERIOD",
    "PolishResult",
    "PolishRound",
    "SinusoidStart",
    "VortexSamples",
    "corrected_problem",
    "morison_samples",
    "polish_on_vortex_model",
    "polish_optima",
    "polished_problem",
    "quantised",
    "sinusoid_starts",
    "vortex_objective",
    "vortex_problem_for",
    "vortex_samples",
]
