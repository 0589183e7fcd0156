"""Brute-force sweep of sinusoidal motions, the instantaneous-power feasible set, and the
constrained Pareto front (the paper's Figure 4a,b)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mfflap.errors import ConfigError
from mfflap.hydro.morison import MorisonModel
from mfflap.kinematics.convert import harmonic_to_discrete
from mfflap.performance import evaluate_discrete, propulsive_efficiency


@dataclass(frozen=True)
class SweepResult:
    """Per-motion parameters and cycle means of a sinusoidal sweep (1-D arrays)."""

    frequency: np.ndarray  # Hz
    heave_amplitude: np.ndarray  # m
    pitch_amplitude: np.ndarray  # rad
    phase: np.ndarray  # rad
    mean_thrust: np.ndarray  # N
    mean_power: np.ndarray  # W
    efficiency: np.ndarray  # 1
    max_power: np.ndarray  # W, at the N samples
    strouhal_number: np.ndarray  # 1
    feasible: np.ndarray  # bool: max_power <= P_max (and within the pitch envelope)

    def best_feasible(self) -> int:
        """Index of the feasible motion with the largest mean thrust."""
        if not self.feasible.any():
            raise ConfigError("no sinusoid of the sweep satisfies the power limit (and the "
                              "pitch envelope, where one is given)")
        thrust = np.where(self.feasible, self.mean_thrust, -np.inf)
        return int(np.argmax(thrust))


def pareto_front(thrust: np.ndarray, power: np.ndarray) -> np.ndarray:
    """Indices of the points not dominated in (max thrust, min power), by increasing power.

    A point dominates another if its thrust is >= and its power <=, one of them strictly.
    """
    thrust, power = np.asarray(thrust, float), np.asarray(power, float)
    order = np.lexsort((-thrust, power))  # by power, then by larger thrust
    front, best = [], -np.inf
    for i in order:
        if thrust[i] > best:
            front.append(i)
            best = thrust[i]
    return np.asarray(front, dtype=int)


def sinusoid_sweep(model, frequencies, heave_amplitudes, pitch_amplitudes, phases,
                   n_steps: int = 50, max_power: float = 50.0, scheme: str = "paper",
                   chunk: int = 20000, progress=None, compiled: bool = True) -> SweepResult:
    """Evaluate every combination of the given parameter values (a full grid).

    Parameters
    ----------
    frequencies : Hz; heave_amplitudes : m; pitch_amplitudes : rad; phases : rad
    n_steps
        N of the discrete scheme each sinusoid is converted to.
    max_power : W
        P_max of the feasibility test (at the N samples, like the optimiser).
    chunk
        Motions evaluated at once (bounds memory: about chunk x N x strips x 8 bytes).
    progress
        Optional callable ``progress(done, total)``.
    compiled
        Use the fused numba kernel (:mod:`mfflap.sweep_kernel`) when the model is the plain
        Morison model with equal strips; the array version otherwise.
    """
    axes = [np.atleast_1d(np.asarray(v, dtype=float)).ravel() for v in
            (frequencies, heave_amplitudes, pitch_amplitudes, phases)]
    grids = np.meshgrid(*axes, indexing="ij")
    f, h, th, ph = (g.ravel() for g in grids)
    total = f.size
    out = {k: np.empty(total) for k in ("mean_thrust", "mean_power", "efficiency", "max_power",
                                        "strouhal_number")}
    if np.any(f <= 0) or not np.all(np.isfinite(f)):
        raise ConfigError("sweep frequencies must be finite and > 0 Hz", key="frequencies")
    constants = None
    if compiled and scheme in ("paper", "midpoint"):

        # the compiled (numba) kernel loads in about a second: only the compiled path needs it
        from mfflap.sweep_kernel import kernel_constants

        if type(model) is MorisonModel:
            constants = kernel_constants(model)
    if constants is not None:
        # the compiled (numba) kernel loads in about a second: only the compiled path needs it
        from mfflap.sweep_kernel import sweep_grid_kernel

        u = constants["u"]
        res = np.empty((total, 5))
        n_groups = axes[0].size * axes[2].size * axes[3].size  # (f, theta, phi) combinations
        block = max(1, chunk // max(axes[1].size, 1))  # groups per call (progress)
        for start in range(0, n_groups, block):
            stop = min(start + block, n_groups)
            sweep_grid_kernel(*axes, start, stop, n_steps, scheme == "midpoint",
                              constants["u"], constants["chord"], constants["n_strips"],
                              constants["k_an"], constants["k_at"], constants["k_dn"],
                              constants["k_dt"], constants["lbar"], constants["l2bar"], res)
            if progress is not None:
                progress(stop * axes[1].size, total)
        out["mean_thrust"], out["mean_power"], out["max_power"] = res[:, 0], res[:, 1], res[:, 2]
        out["efficiency"] = propulsive_efficiency(u, res[:, 0], res[:, 1])
        out["strouhal_number"] = 2 * f * res[:, 4] / u
        return SweepResult(f, h, th, ph, **out, feasible=out["max_power"] <= max_power)
    for start in range(0, total, chunk):
        sl = slice(start, min(start + chunk, total))
        d = harmonic_to_discrete(f[sl], h[sl], th[sl], ph[sl], n_steps)
        s = evaluate_discrete(model, d, scheme).summary  # type: ignore[arg-type]
        for k in out:
            out[k][sl] = getattr(s, k)
        if progress is not None:
            progress(sl.stop, total)
    return SweepResult(f, h, th, ph, **out, feasible=out["max_power"] <= max_power)
