"""Polishing a case's optima on its discrete-vortex model: each beta's Morison optimum, and
optionally sinusoids the vortex model ranks best as further starts
(:mod:`mfflap.optimisation.vortex_polish` polishes one motion)."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np

from mfflap.errors import ConfigError
from mfflap.kinematics.discrete import DiscreteMotion
from mfflap.optimisation.vortex_correction import (
    VortexSamples,
    vortex_objective,
    vortex_problem_for,
    vortex_samples,
)
from mfflap.optimisation.vortex_polish import PolishResult, PolishRound, polish_on_vortex_model

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
    under-predicts the peak power of large motions several times, so its best sinusoid within P_max
    draws far more on the vortex model (and in CFD).

    Examples
    --------
    >>> from mfflap.config import load_case
    >>> starts = sinusoid_starts(load_case("cases/paper2026.toml"), 50)  # doctest: +SKIP
    >>> len(starts), starts[0].label                                     # doctest: +SKIP
    (144, 'sinusoid f=0.3 Hz h=0.1 m th=30 deg phi=90 deg')
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


def polish_optima(config, optima: dict, model,
                  progress: Callable[[str], None] | None = None,
                  starts: list[SinusoidStart] | None = None) -> dict[float, PolishResult]:
    """Polish each beta's optimum (beta -> OptimisationResult) of the case on its
    discrete-vortex model, Morison being ``model`` (beta -> :class:`PolishResult`).

    Each beta is polished from its Morison optimum. Given ``starts`` (e.g.
    :func:`sinusoid_starts`), it is also polished from the :data:`SINUSOID_STARTS` of them
    with the lowest J on the vortex model, and the polish with the lowest J on the vortex
    model is kept: a polish ends in the optimum nearest its start. The main job does not
    give them: in CFD the polishes from sinusoids drew far more peak power than the vortex
    model predicted, where those from the Morison optimum came within it (docs' findings,
    *The discrete-vortex model*).

    Examples
    --------
    >>> import mfflap
    >>> study = mfflap.Study.from_toml("cases/paper2026.toml")             # doctest: +SKIP
    >>> optima = {0.0: study.optimise(beta=0.0)}                           # doctest: +SKIP
    >>> polished = polish_optima(study.config, optima, study.model)        # doctest: +SKIP
    >>> polished[0.0].start                                                # doctest: +SKIP
    'the Morison optimum'
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
                callback=said, start_label=label, bandwidth_harmonics=o.bandwidth_harmonics))
        out[beta] = min(results, key=lambda r: r.objective)
        if progress is not None:
            s0, s1 = out[beta].start_samples, out[beta].samples
            progress(f"polish beta {beta:g}, kept the one from {out[beta].start}: on the "
                     f"vortex model thrust {s0.mean_thrust:.3g} -> {s1.mean_thrust:.3g} N, "
                     f"mean power {s0.mean_power:.3g} -> {s1.mean_power:.3g} W, peak power "
                     f"{s0.peak_power:.3g} -> {s1.peak_power:.3g} W ({out[beta].message})")
    return out


__all__ = ["RANKING_CYCLES", "RANKING_STEPS_PER_PERIOD", "SINUSOID_STARTS", "SinusoidStart",
           "polish_optima", "sinusoid_starts"]
