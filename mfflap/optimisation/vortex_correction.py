"""The discrete-vortex model's correction of Morison, sample by sample.

The vortex model runs a motion (its N-step half period resampled to about 200 steps a
period, repeated from rest) and gives its last period's thrust and input power at the
motion's N samples, each the mean of the two half periods, and the largest power over each
sample's share of the cycle. Those less Morison's at the same samples are
:class:`~mfflap.optimisation.problem.SampleOffsets`: Morison with them gives the vortex
model's outputs at that motion exactly (a zeroth-order output correction), its P_max
penalty seeing the vortex model's largest power near each sample. The polish
(:mod:`mfflap.optimisation.vortex_polish`) optimises that corrected model.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mfflap.errors import ConfigError
from mfflap.hydro.discrete_vortex import vortex_loads
from mfflap.kinematics.convert import resample
from mfflap.kinematics.discrete import DiscreteMotion
from mfflap.optimisation.optimise import replace_problem
from mfflap.optimisation.problem import FlappingProblem, SampleOffsets
from mfflap.optimisation.vortex_problem import VortexFlappingProblem
from mfflap.performance import thrust_and_power

#: the vortex model's time steps per period (the model ladder's)
STEPS_PER_PERIOD = 200


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
    state = _rounded(vortex.repeated_states(fine))
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


#: the vortex model's kinematics are rounded to this share of each signal's largest value
STATE_QUANTUM = 1e-9


def _rounded(state):
    """``state`` with its angles, rates and accelerations rounded to :data:`STATE_QUANTUM`
    of each one's largest magnitude: the resampling's spline solve rounds differently with
    BLAS's thread count, and the chaotic wake would carry that into the period means."""
    from dataclasses import replace as replaced

    out = {}
    for key in ("pitch_angle", "pitch_rate", "pitch_acceleration", "heave_position",
                "heave_velocity", "heave_acceleration"):
        x = np.asarray(getattr(state, key), dtype=float)
        step = STATE_QUANTUM * 2.0 ** np.floor(np.log2(max(float(np.max(np.abs(x))), 1e-300)))
        out[key] = np.round(x / step) * step
    return replaced(state, **out)


def morison_samples(problem: FlappingProblem, motion: DiscreteMotion
                    ) -> tuple[np.ndarray, np.ndarray]:
    """Morison's thrust (N) and input power (W) at the motion's N samples.

    Examples
    --------
    >>> from mfflap.hydro.morison import MorisonModel
    >>> from mfflap.kinematics.convert import harmonic_to_discrete
    >>> motion = harmonic_to_discrete(1.0, 0.1, 0.3, np.pi / 2, 20)
    >>> thrust, power = morison_samples(FlappingProblem(MorisonModel()), motion)
    >>> thrust.shape, power.shape
    ((20,), (20,))
    """
    state = motion.states(problem.scheme)  # type: ignore[arg-type]
    thrust, power = thrust_and_power(problem.model.loads(state), state)
    return np.asarray(thrust, dtype=float), np.asarray(power, dtype=float)


def corrected_problem(problem: FlappingProblem, vortex: VortexFlappingProblem,
                      motion: DiscreteMotion, steps_per_period: int = STEPS_PER_PERIOD
                      ) -> tuple[FlappingProblem, VortexSamples]:
    """``problem`` with the offsets that make Morison give the vortex model's outputs at
    ``motion``, and those outputs.

    Examples
    --------
    >>> from mfflap.hydro.discrete_vortex import VortexModelSettings
    >>> from mfflap.hydro.morison import MorisonModel
    >>> from mfflap.kinematics.convert import harmonic_to_discrete
    >>> motion = harmonic_to_discrete(1.0, 0.1, 0.3, np.pi / 2, 20)
    >>> vortex = VortexFlappingProblem(VortexModelSettings(wake_chords=0.5,
    ...                                                    chord_points=16), cycles=2)
    >>> corrected, samples = corrected_problem(FlappingProblem(MorisonModel()), vortex,
    ...                                        motion, steps_per_period=40)
    >>> thrust, _ = morison_samples(corrected, motion)
    >>> bool(np.allclose(thrust + corrected.sample_offsets.thrust, samples.thrust))
    True
    """
    samples = vortex_samples(vortex, motion, steps_per_period)
    return corrected_by(problem, motion, samples), samples


def corrected_by(problem: FlappingProblem, motion: DiscreteMotion,
                 samples: VortexSamples) -> FlappingProblem:
    """``problem`` with the offsets from Morison's outputs at ``motion`` to the vortex
    model's ``samples`` of it (:func:`corrected_problem` without running the model)."""
    thrust, power = morison_samples(problem, motion)
    return replace_problem(problem, sample_offsets=SampleOffsets(
        samples.thrust - thrust, samples.power - power, samples.sample_peaks - power))


def vortex_objective(problem: FlappingProblem, motion: DiscreteMotion,
                     samples: VortexSamples) -> float:
    """J of ``problem`` with the vortex model's ``samples`` of ``motion`` for Morison's
    (what the polish judges a motion by).

    Examples
    --------
    >>> from mfflap.hydro.discrete_vortex import VortexModelSettings
    >>> from mfflap.hydro.morison import MorisonModel
    >>> from mfflap.kinematics.convert import harmonic_to_discrete
    >>> motion = harmonic_to_discrete(1.0, 0.1, 0.3, np.pi / 2, 20)
    >>> vortex = VortexFlappingProblem(VortexModelSettings(wake_chords=0.5,
    ...                                                    chord_points=16), cycles=2)
    >>> problem = FlappingProblem(MorisonModel())
    >>> corrected, samples = corrected_problem(problem, vortex, motion, 40)
    >>> bool(np.isclose(vortex_objective(problem, motion, samples),
    ...                 corrected.objective(motion)))
    True
    """
    return float(corrected_by(problem, motion, samples).objective(motion))


def vortex_problem_for(config, beta: float) -> VortexFlappingProblem:
    """The case's optimisation problem of ``beta`` on its discrete-vortex model ([vortex],
    the plate, fluid and stream; three periods from rest).

    Examples
    --------
    >>> from mfflap.config import CaseConfig
    >>> vortex_problem_for(CaseConfig(), 0.5).beta
    0.5
    """
    o = config.optimisation
    return VortexFlappingProblem(config.vortex, plate=config.plate, fluid=config.fluid,
                                 stream=config.flow, beta=beta, max_power=o.max_power,
                                 max_heave=o.max_heave, penalty_power=o.penalty_power,
                                 penalty_heave=o.penalty_heave,
                                 smoothing_pitch=o.smoothing_pitch,
                                 smoothing_heave=o.smoothing_heave)


__all__ = ["STATE_QUANTUM", "STEPS_PER_PERIOD", "VortexSamples", "corrected_by",
           "corrected_problem",
           "morison_samples", "vortex_objective", "vortex_problem_for", "vortex_samples"]
