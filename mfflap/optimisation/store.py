"""Optimisation results in HDF5, with every setting beside the numbers."""

from __future__ import annotations

import json
from dataclasses import asdict
from typing import TYPE_CHECKING

import numpy as np

from mfflap.optimisation.optimise import OptimisationResult
from mfflap.optimisation.problem import FlappingProblem
from mfflap.results import ResultsFile
from mfflap.sweep import SweepResult

if TYPE_CHECKING:
    from mfflap.optimisation.vortex_polish import PolishResult


def problem_settings(problem: FlappingProblem) -> dict[str, float | str]:
    """The settings of a problem (for attributes)."""
    return {k: getattr(problem, k) for k in ("beta", "max_power", "max_heave", "penalty_power",
                                             "penalty_heave", "smoothing_pitch",
                                             "smoothing_heave", "scheme", "max_pitch",
                                             "max_pitch_rate", "max_pitch_acceleration",
                                             "penalty_pitch")}


def write_result(rf: ResultsFile, group: str, result: OptimisationResult,
                 settings: dict | None = None) -> None:
    """Store one optimised motion: controls, period, summary, history, flags and settings."""
    rf.write_discrete_motion(f"{group}/motion", result.motion)
    rf.write_summary(f"{group}/summary", result.summary)
    rf.write_group(f"{group}/history", {"objective": result.history}, {"objective": "J"})
    g = rf.h5[group]
    attrs = {"beta": result.beta, "method": result.method, "start": result.start,
             "converged": result.converged, "message": result.message,
             "objective": result.objective, "period_s": float(result.motion.period),
             "n_steps": result.motion.n_steps,
             "resampled_max_power_W": result.resampled_max_power,
             "resampled_n_steps": 10 * result.motion.n_steps,
             "flags": json.dumps(result.flags), "n_iterations": result.n_iterations,
             "wall_time_s": result.wall_time_s}
    for k, v in (settings or {}).items():
        attrs[f"setting_{k}"] = v
    g.attrs.update(attrs)


def read_result(rf: ResultsFile, group: str) -> OptimisationResult:
    """Read back :func:`write_result`."""
    g = rf.h5[group]
    a = dict(g.attrs)
    hist, _ = rf.read_group(f"{group}/history")
    return OptimisationResult(
        beta=float(a["beta"]), motion=rf.read_discrete_motion(f"{group}/motion"),
        method=str(a["method"]), start=str(a["start"]), converged=bool(a["converged"]),
        message=str(a["message"]), objective=float(a["objective"]),
        history=hist["objective"], summary=rf.read_summary(f"{group}/summary"),
        resampled_max_power=float(a["resampled_max_power_W"]), flags=json.loads(a["flags"]),
        n_iterations=int(a["n_iterations"]), wall_time_s=float(a["wall_time_s"]))


SWEEP_UNITS = {"frequency": "Hz", "heave_amplitude": "m", "pitch_amplitude": "rad",
               "phase": "rad", "mean_thrust": "N", "mean_power": "W", "efficiency": "1",
               "max_power": "W", "strouhal_number": "1", "feasible": "1"}


def write_sweep(rf: ResultsFile, group: str, sweep: SweepResult, best: int) -> None:
    """Store a sinusoid sweep and the index of its best feasible motion."""
    rf.write_group(group, asdict(sweep), SWEEP_UNITS, {"best_feasible": best})


def read_sweep(rf: ResultsFile, group: str) -> tuple[SweepResult, int]:
    """Read back :func:`write_sweep`."""
    arrays, attrs = rf.read_group(group)
    arrays["feasible"] = np.asarray(arrays["feasible"], dtype=bool)
    return SweepResult(**arrays), int(attrs["best_feasible"])


def beta_label(beta: float) -> str:
    """The label of a beta's optimised motion among a run's motions and back-tests, e.g.
    ``β = 0.5``."""
    return f"β = {beta:g}"


def beta_key(beta: float) -> str:
    """Group name of a beta, e.g. ``beta_0.50``."""
    return f"beta_{beta:.2f}"


def polished_label(beta: float) -> str:
    """The label of a beta's optimum polished on the discrete-vortex model.

    Examples
    --------
    >>> polished_label(0.5)
    'β = 0.5 polished'
    """
    return f"{beta_label(beta)} polished"


#: the per-round figures of a polish in the results file
POLISH_ROUND_UNITS = {"radius": "1", "predicted_decrease": "J", "vortex_decrease": "J",
                      "ratio": "1", "accepted": "1", "vortex_objective": "J",
                      "peak_power": "W"}
#: the vortex model's figures of the start and the polished motion
POLISH_SAMPLE_UNITS = {"thrust": "N", "power": "W", "sample_peaks": "W", "peak_power": "W",
                       "mean_thrust": "N", "mean_power": "W"}


def write_polish(rf: ResultsFile, group: str, result: PolishResult, beta: float) -> None:
    """Store a polish: the polished motion, the vortex model's figures at the start and at
    the end, each round, and why it stopped."""
    rf.write_discrete_motion(f"{group}/motion", result.motion)
    for name, samples in (("start", result.start_samples), ("polished", result.samples)):
        rf.write_group(f"{group}/vortex_{name}", asdict(samples), POLISH_SAMPLE_UNITS)
    rf.write_group(f"{group}/rounds", {k: np.array([float(getattr(r, k))
                                                    for r in result.rounds])
                                       for k in POLISH_ROUND_UNITS}, POLISH_ROUND_UNITS)
    rf.h5[group].attrs.update({"beta": beta, "start_objective": result.start_objective,
                               "objective": result.objective, "message": result.message,
                               "wall_time_s": result.wall_time_s, "start": result.start})


def read_polish(rf: ResultsFile, group: str) -> PolishResult:
    """Read back :func:`write_polish`."""
    from mfflap.optimisation.vortex_correction import VortexSamples
    from mfflap.optimisation.vortex_polish import PolishResult, PolishRound

    def samples(name: str) -> VortexSamples:
        arrays, _ = rf.read_group(f"{group}/vortex_{name}")
        return VortexSamples(**{k: (np.asarray(v) if np.ndim(v) else float(v))
                                for k, v in arrays.items()})

    rounds, _ = rf.read_group(f"{group}/rounds")
    n = len(rounds["radius"])
    a = rf.h5[group].attrs
    return PolishResult(
        rf.read_discrete_motion(f"{group}/motion"), float(a["start_objective"]),
        float(a["objective"]), samples("start"), samples("polished"),
        [PolishRound(**{k: (bool(rounds[k][i]) if k == "accepted" else float(rounds[k][i]))
                        for k in POLISH_ROUND_UNITS}) for i in range(n)],
        str(a["message"]), float(a["wall_time_s"]), str(a["start"]))
