"""The optimisation problem of :mod:`mfflap.optimisation.problem` on the discrete-vortex model.

The periodic motion (N steps of half a period, the second half the first's negative, as for
Morison) is repeated from rest for ``cycles`` periods; J is the mean over the last period of

    L_j = -(1 - beta) F_thrust,j + beta P_in,j + 1/2 sigma_P max(0, P_in,j - P_max)^2
          + 1/2 sigma_h max(0, |h_j| - h_max)^2,

plus the smoothness J_s of the Morison problem. Its gradient with respect to every step's
accelerations and the time step is exact: the load cotangents of the last period go through
the discrete-vortex model's reverse sweep (:mod:`mfflap.hydro.discrete_vortex_adjoint`), the
state cotangents of every repeated period fold back onto the N states, and the kinematic
integration's adjoint (:mod:`mfflap.optimisation.state_adjoint`) carries them to the
controls.

Being exact, the gradient carries the free wake's sensitivity: with leading-edge shedding
the derivative of the last period with respect to the first grows by orders of magnitude a
period (docs' findings, *The discrete-vortex model*), so more start-up periods make it
less useful for steering the settled cycle, not more accurate.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from mfflap.errors import ConfigError
from mfflap.hydro.discrete_vortex import VortexModelSettings, vortex_loads
from mfflap.hydro.discrete_vortex_adjoint import record_vortex_run
from mfflap.kinematics.discrete import DiscreteMotion
from mfflap.kinematics.state import KinematicState
from mfflap.optimisation.state_adjoint import (
    Gradient,
    chain_state_partials,
    smoothness,
    smoothness_gradient,
)
from mfflap.parameters import Fluid, FreeStream, Plate
from mfflap.performance import thrust_and_power


@dataclass
class VortexFlappingProblem:
    """beta-weighted thrust/power objective with power, heave and smoothness penalties, on
    the discrete-vortex model (the parameters as for
    :class:`~mfflap.optimisation.problem.FlappingProblem`).

    Attributes
    ----------
    settings : VortexModelSettings
    plate, fluid, stream
    cycles : int
        Periods run from rest; J is the last one's mean (at least 2).
    beta, max_power (W), max_heave (m), penalty_power (1/W), penalty_heave (N/m^2),
    smoothing_pitch, smoothing_heave
        As for the Morison problem.

    Examples
    --------
    >>> import numpy as np
    >>> n = 20
    >>> phase = (np.arange(n) + 0.5) * np.pi / n
    >>> motion = DiscreteMotion(-20 * np.sin(phase), -4 * np.sin(phase + 1.2), 0.025)
    >>> problem = VortexFlappingProblem(VortexModelSettings(wake_chords=0.5,
    ...                                                     chord_points=16), cycles=2)
    >>> value, grad = problem.value_and_gradient(motion)
    >>> grad.shape
    (41,)
    """

    settings: VortexModelSettings = field(default_factory=VortexModelSettings)
    plate: Plate = field(default_factory=Plate)
    fluid: Fluid = field(default_factory=Fluid)
    stream: FreeStream = field(default_factory=FreeStream)
    cycles: int = 3
    beta: float = 0.0
    max_power: float = 50.0
    max_heave: float = 0.5
    penalty_power: float = 10.0
    penalty_heave: float = 1.0e4
    smoothing_pitch: float = 1e-4
    smoothing_heave: float = 1e-2

    def __post_init__(self) -> None:
        checks = [
            ("cycles", self.cycles, isinstance(self.cycles, int) and 2 <= self.cycles <= 100,
             "an integer in [2, 100]"),
            ("beta", self.beta, 0 <= self.beta <= 1, "[0, 1]"),
            ("max_power", self.max_power, self.max_power > 0, "(0, inf) W"),
            ("max_heave", self.max_heave, self.max_heave > 0, "(0, inf) m"),
            ("penalty_power", self.penalty_power, self.penalty_power >= 0, "[0, inf)"),
            ("penalty_heave", self.penalty_heave, self.penalty_heave >= 0, "[0, inf)"),
            ("smoothing_pitch", self.smoothing_pitch, self.smoothing_pitch >= 0, "[0, inf)"),
            ("smoothing_heave", self.smoothing_heave, self.smoothing_heave >= 0, "[0, inf)"),
        ]
        for name, value, ok, allowed in checks:
            if not (ok and np.isfinite(value)):
                raise ConfigError(f"value {value!r} is not allowed; allowed: {allowed}",
                                  key=f"optimisation.{name}")

    def repeated_states(self, motion: DiscreteMotion) -> KinematicState:
        """The motion's states over ``cycles`` periods from t = 0 s (2 N steps a period)."""
        _check_single(motion)
        half = motion.states("paper")
        out = {}
        for key in ("pitch_angle", "pitch_rate", "pitch_acceleration", "heave_position",
                    "heave_velocity", "heave_acceleration"):
            x = np.asarray(getattr(half, key), dtype=float)
            out[key] = np.tile(np.concatenate([x, -x]), self.cycles)
        n_total = 2 * motion.n_steps * self.cycles
        return KinematicState(time=np.arange(n_total) * float(motion.time_step), **out)

    def _loads(self, state: KinematicState):
        return vortex_loads(state, self.plate, self.fluid, self.stream, self.settings)

    def _stage_terms(self, state, loads):
        thrust, power = thrust_and_power(loads, state)
        excess_p = np.maximum(power - self.max_power, 0.0)
        excess_h = np.maximum(np.abs(state.heave_position) - self.max_heave, 0.0)
        cost = (-(1 - self.beta) * thrust + self.beta * power
                + 0.5 * self.penalty_power * excess_p**2
                + 0.5 * self.penalty_heave * excess_h**2)
        return cost, excess_p, excess_h

    def objective(self, motion: DiscreteMotion) -> float:
        """J: the last period's mean stage cost plus J_s."""
        state = self.repeated_states(motion)
        cost, _, _ = self._stage_terms(state, self._loads(state))
        period = 2 * motion.n_steps
        return float(cost[-period:].mean()
                     + smoothness(motion, self.smoothing_pitch, self.smoothing_heave))

    def value_and_gradient(self, motion: DiscreteMotion) -> tuple[float, np.ndarray]:
        """J and the flat gradient [d/d pitch acc (N), d/d heave acc (N), d/d dt]."""
        value, grad = self._value_and_gradient(motion)
        return value, grad.flat()

    def packed_value_and_gradient(self, z: np.ndarray, want_gradient: bool = True
                                  ) -> tuple[float, np.ndarray | None]:
        """J and its flat gradient at the packed controls z = [pitch (N), heave (N), dt]."""
        motion = DiscreteMotion.from_controls(np.asarray(z, dtype=float))
        if not want_gradient:
            return self.objective(motion), None
        return self.value_and_gradient(motion)

    def gradient(self, motion: DiscreteMotion) -> Gradient:
        """The exact gradient of :meth:`objective` (module docstring)."""
        return self._value_and_gradient(motion)[1]

    def _value_and_gradient(self, motion: DiscreteMotion) -> tuple[float, Gradient]:
        n = motion.n_steps
        period = 2 * n
        state = self.repeated_states(motion)
        n_total = state.time.size
        # one forward run with its tape: the loads the cotangents depend on, then the sweep
        run = record_vortex_run(state, self.plate, self.fluid, self.stream, self.settings)
        loads = run.loads
        cost, excess_p, excess_h = self._stage_terms(state, loads)
        weight = np.zeros(n_total)
        weight[-period:] = 1.0 / period
        th, td, hd = state.pitch_angle, state.pitch_rate, state.heave_velocity
        s, c = np.sin(th), np.cos(th)
        fn, ft, mo = loads.normal_force, loads.tangential_force, loads.moment
        d_thrust = -(1 - self.beta) * weight
        d_power = (self.beta + self.penalty_power * excess_p) * weight
        vjp = run.gradient(d_thrust * s - d_power * c * hd, -d_thrust * c - d_power * s * hd,
                           -d_power * td)
        g_th = vjp.pitch_angle + d_thrust * (fn * c + ft * s) + d_power * (fn * s - ft * c) * hd
        g_td = vjp.pitch_rate - d_power * mo
        g_hd = vjp.heave_velocity - d_power * (fn * c + ft * s)
        g_hp = vjp.heave_position + self.penalty_heave * excess_h * np.sign(
            state.heave_position) * weight
        partials = {name: _fold(g, n) for name, g in (
            ("th", g_th), ("td", g_td), ("hp", g_hp), ("hd", g_hd))}
        partials["tdd"] = partials["hdd"] = np.zeros(n)  # the model sees no acceleration
        chained = chain_state_partials(motion, partials, "paper")
        smooth = smoothness_gradient(motion, self.smoothing_pitch, self.smoothing_heave)
        value = float(cost[-period:].mean() + smoothness(
            motion, self.smoothing_pitch, self.smoothing_heave))
        # t_i = i dt: the time step enters the model itself as well as the states
        return value, Gradient(chained.pitch_acceleration + smooth["pitch"],
                               chained.heave_acceleration + smooth["heave"],
                               np.asarray(chained.time_step + vjp.time_step))


def _fold(tiled: np.ndarray, n_steps: int) -> np.ndarray:
    """Cotangents of the repeated states folded onto the N states: each period's first half
    is the states, its second half their negatives."""
    periods = tiled.reshape(-1, 2, n_steps)
    return periods[:, 0].sum(axis=0) - periods[:, 1].sum(axis=0)


def _check_single(motion: DiscreteMotion) -> None:
    if np.ndim(motion.pitch_acceleration) != 1 or np.ndim(motion.time_step) != 0:
        raise ConfigError("the discrete-vortex problem takes one motion at a time, not a "
                          "batch", key="motion")


__all__ = ["VortexFlappingProblem"]
