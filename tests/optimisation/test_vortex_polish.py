"""The polish on the discrete-vortex model: Morison with per-sample offsets (its objective and
exact gradient), the offsets that reproduce the vortex model at the centre, and the trust
region that only takes steps the vortex model confirms."""

from __future__ import annotations

import numpy as np
import pytest

from mfflap.errors import ConfigError
from mfflap.hydro.discrete_vortex import VortexModelSettings
from mfflap.hydro.morison import MorisonModel
from mfflap.kinematics.discrete import DiscreteMotion
from mfflap.optimisation.optimise import optimise_ipopt, replace_problem
from mfflap.optimisation.problem import FlappingProblem, SampleOffsets
from mfflap.optimisation.store import read_polish, write_polish
from mfflap.optimisation.vortex_correction import (
    corrected_problem,
    morison_samples,
    vortex_samples,
)
from mfflap.optimisation.vortex_polish import polish_on_vortex_model
from mfflap.optimisation.vortex_problem import VortexFlappingProblem
from mfflap.results import ResultsFile

N_STEPS = 12
#: a short wake and few chord points keep each vortex-model run to milliseconds
QUICK = VortexModelSettings(wake_chords=0.5, chord_points=16)
STEPS_PER_PERIOD = 48


def _motion(scale: float = 1.0, time_step: float = 0.04) -> DiscreteMotion:
    phase = (np.arange(N_STEPS) + 0.5) * np.pi / N_STEPS
    return DiscreteMotion(-25 * scale * np.sin(phase), -5 * scale * np.sin(phase + 1.2),
                          time_step)


def _vortex() -> VortexFlappingProblem:
    return VortexFlappingProblem(QUICK, cycles=2)


def _offsets(rng, n=N_STEPS) -> SampleOffsets:
    return SampleOffsets(rng.normal(0, 2, n), rng.normal(0, 3, n), rng.normal(5, 3, n))


def test_offsets_move_the_objective_by_their_terms_where_no_penalty_bites():
    base = FlappingProblem(MorisonModel(), beta=0.4, max_power=1e6, compiled=False)
    offsets = _offsets(np.random.default_rng(0))
    shifted = replace_problem(base, sample_offsets=offsets)
    motion = _motion()
    expected = base.objective(motion) + np.mean(-0.6 * offsets.thrust + 0.4 * offsets.power)
    assert shifted.objective(motion) == pytest.approx(expected, rel=1e-12)
    # the offsets are constants: the gradient is the model's own
    np.testing.assert_allclose(shifted.gradient(motion).flat(), base.gradient(motion).flat(),
                               rtol=1e-12, atol=1e-14)


def test_the_gradient_with_offsets_and_an_active_power_limit_matches_complex_step():
    """The power penalty sees the peak offsets: its derivative moves with them."""
    problem = replace_problem(FlappingProblem(MorisonModel(), beta=0.2, max_power=2.0),
                              sample_offsets=_offsets(np.random.default_rng(1)))
    motion = _motion()
    excess = morison_samples(problem, motion)[1] + problem.sample_offsets.peak_power - 2.0
    assert 0 < np.sum(excess > 0) < N_STEPS  # the limit bites on part of the cycle
    grad = problem.gradient(motion).flat()
    z = np.real(motion.controls())
    h = 1e-30
    cs = np.array([problem.objective(DiscreteMotion.from_controls(z + 1j * h * e)).imag / h
                   for e in np.eye(z.size)])
    np.testing.assert_allclose(grad, cs, rtol=1e-9, atol=1e-9 * np.max(np.abs(cs)))


def test_offsets_of_another_length_or_not_finite_are_refused():
    problem = FlappingProblem(MorisonModel())
    with pytest.raises(ConfigError, match="sample_offsets"):
        replace_problem(problem, sample_offsets=_offsets(np.random.default_rng(2), 8)
                        ).objective(_motion())
    with pytest.raises(ConfigError, match="finite"):
        SampleOffsets(np.full(4, np.nan), np.zeros(4))
    with pytest.raises(ConfigError, match="optimise_sqp"):
        optimise_ipopt(replace_problem(problem, sample_offsets=_offsets(
            np.random.default_rng(3))), _motion(), min_period=0.2, max_period=5.0)


def test_the_corrected_model_gives_the_vortex_model_s_outputs_at_the_centre():
    problem = FlappingProblem(MorisonModel(), beta=0.3, max_power=3.0)
    motion = _motion()
    corrected, samples = corrected_problem(problem, _vortex(), motion, STEPS_PER_PERIOD)
    thrust, power = morison_samples(problem, motion)
    offsets = corrected.sample_offsets
    np.testing.assert_allclose(thrust + offsets.thrust, samples.thrust, rtol=1e-12)
    np.testing.assert_allclose(power + offsets.power, samples.power, rtol=1e-12)
    np.testing.assert_allclose(power + offsets.peak_power, samples.sample_peaks, rtol=1e-12)
    # each sample's peak covers the sample itself, and together they hold the cycle's peak
    assert np.all(samples.sample_peaks >= samples.power - 1e-12)
    assert samples.peak_power == pytest.approx(samples.sample_peaks.max())
    # and the two models differ here: the correction is not empty
    assert np.max(np.abs(offsets.power)) > 0.05 * np.ptp(power)


def test_the_samples_are_the_vortex_model_s_own_period_means():
    samples = vortex_samples(_vortex(), _motion(), STEPS_PER_PERIOD)
    # every sample in both half periods: their mean is the period's mean on the samples,
    # which the mean over the model's own steps approaches
    assert np.mean(samples.thrust) == pytest.approx(samples.mean_thrust,
                                                    abs=0.1 * np.ptp(samples.thrust))
    assert np.mean(samples.power) == pytest.approx(samples.mean_power,
                                                   abs=0.1 * np.ptp(samples.power))


def test_the_polish_lowers_the_vortex_model_s_objective_and_its_power_over_the_limit(
        tmp_path):
    """A motion whose vortex-model peak power is far above P_max: the polish only takes
    rounds the vortex model confirms, and ends with less power over the limit."""
    motion = _motion(scale=1.6)
    vortex = _vortex()
    start = vortex_samples(vortex, motion, STEPS_PER_PERIOD)
    max_power = 0.4 * start.peak_power
    problem = FlappingProblem(MorisonModel(), beta=0.0, max_power=max_power)
    seen = []
    result = polish_on_vortex_model(problem, vortex, motion, min_period=0.3, max_period=3.0,
                                    max_rounds=4, steps_per_period=STEPS_PER_PERIOD,
                                    callback=lambda k, r: seen.append(k))
    assert seen == list(range(1, len(result.rounds) + 1))
    assert result.n_accepted >= 1 and result.moved_from(motion)
    assert result.objective < result.start_objective
    taken = [r.vortex_objective for r in result.rounds if r.accepted]
    assert all(b < a for a, b in zip([result.start_objective, *taken], taken, strict=False))

    def over(samples):
        return np.sum(np.maximum(samples.sample_peaks - max_power, 0) ** 2)

    assert over(result.samples) < 0.5 * over(result.start_samples)
    with ResultsFile(tmp_path / "polish.h5", "w") as rf:
        write_polish(rf, "polished/beta_0.00", result, 0.0)
    with ResultsFile(tmp_path / "polish.h5") as rf:
        back = read_polish(rf, "polished/beta_0.00")
    np.testing.assert_allclose(back.motion.controls(), result.motion.controls())
    assert back.rounds == result.rounds and back.message == result.message
    np.testing.assert_array_equal(back.samples.sample_peaks, result.samples.sample_peaks)


def test_a_polish_needs_a_round():
    with pytest.raises(ConfigError, match="max_rounds"):
        polish_on_vortex_model(FlappingProblem(MorisonModel()), _vortex(), _motion(),
                               min_period=0.3, max_period=3.0, max_rounds=0)


def _quick_case(**optimisation):
    from dataclasses import replace
    from pathlib import Path

    from mfflap.config import load_case

    config = load_case(Path(__file__).parents[2] / "cases" / "paper2026.toml",
                       ["vortex.wake_chords=0.5", "vortex.chord_points=16"])
    return replace(config, optimisation=replace(config.optimisation, **optimisation))


def test_the_sinusoid_starts_cover_the_case_s_periods_and_pitch_limit():
    from mfflap.optimisation.vortex_polish_study import sinusoid_starts

    config = _quick_case(min_period=1.0, max_period=2.5, max_pitch_deg=50.0)
    starts = sinusoid_starts(config, N_STEPS)
    assert len({s.label for s in starts}) == len(starts) >= 30
    periods = np.array([float(s.motion.period) for s in starts])
    assert periods.min() == pytest.approx(1.0) and periods.max() == pytest.approx(2.5)
    pitch = np.array([np.max(np.abs(s.motion.trajectory()["pitch_angle"])) for s in starts])
    assert np.degrees(pitch.max()) <= 50.0 + 1e-6 and "th=60" not in " ".join(
        s.label for s in starts)


def test_a_polish_from_several_starts_keeps_the_lowest_objective_on_the_vortex_model():
    from types import SimpleNamespace

    from mfflap.optimisation.study import problem_for
    from mfflap.optimisation.vortex_correction import vortex_problem_for
    from mfflap.optimisation.vortex_polish_study import SinusoidStart, polish_optima

    config = _quick_case(max_power=3.0)
    model = MorisonModel()
    optimum = SimpleNamespace(motion=_motion(scale=1.6))
    ranking = vortex_problem_for(config, 0.0)
    starts = [SinusoidStart(f"small {k}", m, vortex_samples(ranking, m))
              for k, m in enumerate((_motion(0.5, 0.05), _motion(0.8, 0.03)))]
    told = []
    kept = polish_optima(config, {0.0: optimum}, model, told.append, starts)[0.0]
    alone = polish_on_vortex_model(problem_for(config, 0.0, model),
                                   vortex_problem_for(config, 0.0), optimum.motion,
                                   min_period=config.optimisation.min_period,
                                   max_period=config.optimisation.max_period)
    assert kept.objective <= alone.objective
    assert kept.start in {"the Morison optimum", "small 0", "small 1"}
    assert any(line.startswith(f"polish beta 0, kept the one from {kept.start}")
               for line in told)


def test_the_rounding_grid_does_not_move_with_the_motion_s_round_off():
    """Two runs whose optima differ in round-off have scales that differ in round-off too;
    the grid is the scale taken down to a power of two, so both round to one motion."""
    from mfflap.optimisation.vortex_polish import QUANTUM, quantised

    motion = _motion()
    scales = motion.control_scales()
    nudged = DiscreteMotion.from_controls(np.real(motion.controls()) * (1 + 1e-12))
    a, b = quantised(motion, scales), quantised(nudged, nudged.control_scales())
    np.testing.assert_array_equal(a.controls(), b.controls())
    assert np.max(np.abs(a.controls() - motion.controls()) / scales) <= QUANTUM
