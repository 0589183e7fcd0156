"""Thrust, input power and cycle means from loads and the motion that produced them.

One function serves the model and the CFD side alike: :func:`thrust_and_power` takes body-frame
loads and the kinematic state on the same time base.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from mfflap.errors import MotionError
from mfflap.hydro.loads import Loads
from mfflap.kinematics.discrete import DiscreteMotion, Scheme
from mfflap.kinematics.state import KinematicState


def thrust_and_power(loads: Loads, state: KinematicState) -> tuple[np.ndarray, np.ndarray]:
    """Thrust (along -Y0) and the power the actuators put into the fluid.

    F_thrust = F_n sin(theta) - F_t cos(theta);
    P_in = -(F_n cos(theta) + F_t sin(theta)) hdot - M thetadot.

    Returns
    -------
    thrust : ndarray, N
    input_power : ndarray, W
    """
    s, c = np.sin(state.pitch_angle), np.cos(state.pitch_angle)
    fn, ft, mo = loads.normal_force, loads.tangential_force, loads.moment
    if np.shape(fn) != state.shape:
        raise MotionError(f"loads of shape {np.shape(fn)} do not match the state {state.shape}")
    thrust = fn * s - ft * c
    power = -(fn * c + ft * s) * state.heave_velocity - mo * state.pitch_rate
    return thrust, power


def body_to_global(loads: Loads, state: KinematicState) -> tuple[np.ndarray, np.ndarray]:
    """Force components along X0 (heave) and Y0 (stream), N."""
    s, c = np.sin(state.pitch_angle), np.cos(state.pitch_angle)
    fx = loads.normal_force * c + loads.tangential_force * s
    fy = -loads.normal_force * s + loads.tangential_force * c
    return fx, fy


def global_to_body(force_x: np.ndarray, force_y: np.ndarray,
                   pitch_angle: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Inverse of :func:`body_to_global`: (F_n, F_t) from (F_X0, F_Y0)."""
    s, c = np.sin(pitch_angle), np.cos(pitch_angle)
    return force_x * c - force_y * s, force_x * s + force_y * c


def strouhal_number(frequency, trailing_edge_half_excursion, free_stream_velocity: float):
    """St = 2 f A / U with A the trailing-edge half excursion (m); infinite in still water
    (U = 0, a plate flapping on the spot) and NaN if it does not move either, without a
    warning."""
    with np.errstate(divide="ignore", invalid="ignore"):  # 0 / 0: NaN, undefined
        return 2 * np.asarray(frequency) * np.asarray(trailing_edge_half_excursion) / (
            free_stream_velocity)


def thrust_gain(mean_thrust: float, baseline_thrust: float) -> float | None:
    """Mean-thrust gain over a baseline, T / T_baseline - 1 (fraction).

    None when the baseline makes no thrust (T_baseline <= 0, or not finite): a ratio to a
    drag is no gain (a drag of 0.07 N cut to 0.01 N would read -85 %).
    """
    if not (np.isfinite(baseline_thrust) and baseline_thrust > 0.0):
        return None
    return float(mean_thrust) / float(baseline_thrust) - 1.0


def no_thrust_gain_reason(baseline_thrust: float, baseline: str) -> str:
    """Why :func:`thrust_gain` gave None, for a report line."""
    return (f"{baseline} makes no thrust ({float(baseline_thrust):.4g} N), so there is no "
            "gain over it to give")


@dataclass(frozen=True)
class CycleSummary:
    """Cycle-mean performance of one or many motions (arrays over leading motion axes).

    Attributes
    ----------
    mean_thrust : N
    mean_power : W
    efficiency : 1
        eta = U mean_thrust / mean_power where the actuators put power in (mean power > 0);
        NaN where they do not (the stream drives the plate: energy extraction, or no power
        at all), where a ratio would read as an efficiency but is none.
    strouhal_number : 1
    max_power : W
        Largest instantaneous input power over the samples.
    energy_residual : W
        P - U F - D (zero for an exact, energy-consistent model; see docs/theory.md).
    frequency : Hz
    trailing_edge_amplitude : m
    """

    mean_thrust: np.ndarray
    mean_power: np.ndarray
    efficiency: np.ndarray
    strouhal_number: np.ndarray
    max_power: np.ndarray
    energy_residual: np.ndarray
    frequency: np.ndarray
    trailing_edge_amplitude: np.ndarray

    UNITS: ClassVar[dict[str, str]] = {
             "mean_thrust": "N", "mean_power": "W", "efficiency": "1", "strouhal_number": "1",
             "max_power": "W", "energy_residual": "W", "frequency": "Hz",
             "trailing_edge_amplitude": "m"}

    @property
    def regime(self) -> str:
        """What the cycle does, for one motion: "propulsion" (thrust for input power),
        "drag" (input power, no net thrust), "energy extraction" (the stream drives the
        plate) or "free thrust" (thrust without input power: a model outside its range)."""
        thrust, power = float(np.real(self.mean_thrust)), float(np.real(self.mean_power))
        if power > 0:
            return "propulsion" if thrust > 0 else "drag"
        return "energy extraction" if thrust <= 0 else "free thrust"

    def __repr__(self) -> str:
        parts = []
        for k, unit in self.UNITS.items():
            v = np.real(np.asarray(getattr(self, k)))
            unit = "" if unit == "1" else f" {unit}"
            if v.ndim == 0:
                parts.append(f"{k}={float(v):.4g}{unit}")
            else:
                parts.append(f"{k}={np.nanmin(v):.4g}..{np.nanmax(v):.4g}{unit}"
                             if np.isfinite(v).any() else f"{k}=nan")
        shape = "" if np.ndim(self.mean_thrust) == 0 else f"{np.shape(self.mean_thrust)} "
        return f"CycleSummary({shape}{', '.join(parts)})"

    def as_dict(self) -> dict[str, float | list]:
        """JSON-friendly dict."""
        out = {}
        for k in self.UNITS:
            v = np.real(np.asarray(getattr(self, k)))
            out[k] = float(v) if v.ndim == 0 else v.tolist()
        return out


@dataclass(frozen=True)
class Evaluation:
    """A motion's state, loads, thrust, power and cycle summary."""

    state: KinematicState
    loads: Loads
    thrust: np.ndarray
    input_power: np.ndarray
    summary: CycleSummary


def propulsive_efficiency(u: float, f: np.ndarray, p: np.ndarray) -> np.ndarray:
    """U F / P where the mean input power is positive, else NaN (CycleSummary)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(np.real(p) > 0, u * f / np.where(np.real(p) > 0, p, 1), np.nan)


def evaluate_states(model, state: KinematicState, frequency, trailing_edge_amplitude=None
                    ) -> Evaluation:
    """Evaluate a force model on states that sample one period uniformly.

    Parameters
    ----------
    model
        A :class:`~mfflap.hydro.base.ForceModel` (with ``stream`` and ``plate``).
    state
        Uniform samples of one period (or of a half period for antisymmetric motions).
    frequency : Hz
    trailing_edge_amplitude : m, optional
        Defaults to half the range of the sampled trailing-edge excursion.
    """
    state.check_finite()
    loads = model.loads(state)
    thrust, power = thrust_and_power(loads, state)
    u = model.stream.velocity
    if trailing_edge_amplitude is None:
        te = np.real(state.trailing_edge_position(model.plate.chord, model.plate.pivot_m))
        trailing_edge_amplitude = 0.5 * (te.max(axis=-1) - te.min(axis=-1))
    mf, mp = thrust.mean(axis=-1), power.mean(axis=-1)
    if hasattr(model, "dissipation"):
        residual = np.real(mp - u * mf - model.dissipation(state).mean(axis=-1))
    else:
        residual = np.full(np.shape(mf), np.nan)
    summary = CycleSummary(
        mean_thrust=np.real(mf),
        mean_power=np.real(mp),
        efficiency=propulsive_efficiency(u, np.real(mf), np.real(mp)),
        strouhal_number=strouhal_number(frequency, trailing_edge_amplitude, u),
        max_power=np.real(power).max(axis=-1),
        energy_residual=residual,
        frequency=np.asarray(frequency, dtype=float),
        trailing_edge_amplitude=np.asarray(trailing_edge_amplitude),
    )
    return Evaluation(state, loads, thrust, power, summary)


def evaluate_discrete(model, motion: DiscreteMotion, scheme: Scheme = "paper") -> Evaluation:
    """Evaluate a discrete half-cycle motion (antisymmetry makes the half cycle enough).

    The trailing-edge amplitude uses the half cycle's samples and their mirror images.
    """
    state = motion.states(scheme)
    te = np.real(state.trailing_edge_position(model.plate.chord, model.plate.pivot_m))
    amplitude = np.maximum(np.abs(te.max(axis=-1)), np.abs(te.min(axis=-1)))
    return evaluate_states(model, state, np.real(motion.frequency), amplitude)



def discrete_means(model, motion: DiscreteMotion, scheme: Scheme = "paper"
                   ) -> tuple[float, float]:
    """(mean thrust N, mean input power W) of ``motion`` as the optimiser sees them: the
    model at the motion's N samples of ``scheme``.

    They differ from the model on the continuous kinematics CFD imposes (the back-test's
    means, :func:`mfflap.backtest.compare.compare_last_cycle`) by the scheme's
    discretisation, which for a motion of almost no net power is not small: the ``paper``
    scheme's energy error is 8-9 % of the beta = 1 optimum's -0.1 W.
    """
    s = evaluate_discrete(model, motion, scheme).summary
    return float(s.mean_thrust), float(s.mean_power)

def evaluate_motion(model, motion, period: float, n_samples: int = 400) -> Evaluation:
    """Evaluate a continuous periodic motion with its exact derivatives over one period."""
    if n_samples < 4:
        raise MotionError(f"n_samples must be >= 4, got {n_samples}")
    t = np.arange(n_samples) * (period / n_samples)
    return evaluate_states(model, motion.sample(t), 1.0 / period)
