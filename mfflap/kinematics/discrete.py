"""The discrete half-cycle scheme of the paper (docs/theory.md).

Controls u_j = [pitch_acceleration_j, heave_acceleration_j], j = 1..N, and the time step
dt define the whole periodic, half-cycle antisymmetric motion:

- semi-implicit Euler: rate_{j+1} = rate_j + dt acc_j, angle_{j+1} = angle_j + dt rate_{j+1};
- closure x_{N+1} = -x_1, which fixes the initial state
  rate_1 = -(dt/2) sum_j acc_j, angle_1 = (dt^2/4) sum_j (2j - N - 2) acc_j;
- period T = 2 N dt; the second half-cycle is the first with the sign flipped.

Arrays may be complex (complex-step differentiation) and batched over leading axes.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np

from mfflap.errors import MotionError, shown
from mfflap.kinematics.state import KinematicState

#: ``"paper"``: hydrodynamics at the backward-difference rate of step j (the paper's scheme).
#: ``"midpoint"``: at the step-midpoint rate rate_j + dt acc_j / 2 (energy-consistent).
Scheme = Literal["paper", "midpoint"]
SCHEMES: tuple[str, ...] = ("paper", "midpoint")


def initial_state_weights(n_steps: int) -> np.ndarray:
    """Weights w_j = (2j - N - 2) / 4, j = 1..N, so that angle_1 = dt^2 sum_j w_j acc_j."""
    j = np.arange(1, n_steps + 1)
    return (2 * j - n_steps - 2) / 4.0


def integrate(acceleration: np.ndarray, time_step: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Rates and angles (or velocities and positions) at steps j = 1..N+1.

    Parameters
    ----------
    acceleration : ndarray, shape (..., N)
    time_step : ndarray, shape (...)

    Returns
    -------
    rate, value : ndarray, shape (..., N+1)
        The last column is x_{N+1}, equal to -x_1 by construction.
    """
    n = acceleration.shape[-1]
    dt = np.asarray(time_step)[..., None]
    rate1 = -0.5 * dt[..., 0] * acceleration.sum(axis=-1)
    value1 = dt[..., 0] ** 2 * (acceleration @ initial_state_weights(n))
    rate = np.concatenate(
        [rate1[..., None], rate1[..., None] + dt * np.cumsum(acceleration, axis=-1)], axis=-1
    )
    value = np.concatenate(
        [value1[..., None], value1[..., None] + dt * np.cumsum(rate[..., 1:], axis=-1)], axis=-1
    )
    return rate, value


@dataclass(frozen=True)
class DiscreteMotion:
    """Half-cycle controls and time step: the optimiser's design variables.

    Parameters
    ----------
    pitch_acceleration : ndarray, rad/s^2, shape (..., N)
    heave_acceleration : ndarray, m/s^2, shape (..., N)
    time_step : float or ndarray, s, shape (...)
    """

    pitch_acceleration: np.ndarray
    heave_acceleration: np.ndarray
    time_step: float | np.ndarray

    def __post_init__(self) -> None:
        pa, ha = np.asarray(self.pitch_acceleration), np.asarray(self.heave_acceleration)
        if pa.shape != ha.shape or pa.ndim < 1:
            raise MotionError(
                f"pitch and heave accelerations must share a shape (..., N); got {pa.shape} "
                f"and {ha.shape}"
            )
        if pa.shape[-1] < 2:
            raise MotionError(f"a half cycle needs N >= 2 steps, got N = {pa.shape[-1]}")
        for name, a in (("pitch_acceleration", pa), ("heave_acceleration", ha),
                        ("time_step", np.asarray(self.time_step))):
            if not np.all(np.isfinite(a)):
                raise MotionError(f"{name} has non-finite values")
        dt = np.asarray(self.time_step)
        if np.any(np.real(dt) <= 0):
            raise MotionError(f"time_step must be > 0 s, got {self.time_step!r}")
        object.__setattr__(self, "pitch_acceleration", pa)
        object.__setattr__(self, "heave_acceleration", ha)

    @property
    def n_steps(self) -> int:
        """N, the number of steps in a half cycle."""
        return int(self.pitch_acceleration.shape[-1])

    def controls(self) -> np.ndarray:
        """The optimiser's design vector (2N + 1,): the N pitch accelerations, the N heave
        accelerations, then the time step (complex values kept, for complex-step checks).

        Examples
        --------
        >>> d = DiscreteMotion(np.array([1.0, -1.0]), np.array([2.0, -2.0]), 0.01)
        >>> d.controls().tolist()
        [1.0, -1.0, 2.0, -2.0, 0.01]
        >>> DiscreteMotion.from_controls(d.controls()) == d
        True
        """
        return np.concatenate([self.pitch_acceleration, self.heave_acceleration,
                               np.asarray(self.time_step).reshape(1)])

    @classmethod
    def from_controls(cls, controls: np.ndarray) -> DiscreteMotion:
        """The motion of a design vector (:meth:`controls`)."""
        z = np.asarray(controls)
        if z.ndim != 1 or z.size < 5 or z.size % 2 == 0:
            raise MotionError(f"a design vector holds 2N + 1 values (N >= 2), got shape "
                              f"{z.shape}")
        n = (z.size - 1) // 2
        dt = z[2 * n]
        return cls(z[:n], z[n:2 * n], dt.item() if np.isrealobj(z) else dt)

    def control_scales(self) -> np.ndarray:
        """The scale of each control (2N + 1,): the peak |pitch acceleration| and the peak
        |heave acceleration| (each at least 1e-3) and the time step, the units the
        optimisers scale the design vector by and a trust region's radius is measured in."""
        n = self.n_steps
        peak_pitch = max(float(np.max(np.abs(np.real(self.pitch_acceleration)))), 1e-3)
        peak_heave = max(float(np.max(np.abs(np.real(self.heave_acceleration)))), 1e-3)
        return np.concatenate([np.full(n, peak_pitch), np.full(n, peak_heave),
                               [float(np.real(self.time_step))]])

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, DiscreteMotion):
            return NotImplemented
        return (np.array_equal(self.pitch_acceleration, other.pitch_acceleration)
                and np.array_equal(self.heave_acceleration, other.heave_acceleration)
                and np.array_equal(self.time_step, other.time_step))

    __hash__ = None  # arrays: not hashable

    @property
    def period(self) -> np.ndarray:
        """T = 2 N dt, s."""
        return 2 * self.n_steps * np.asarray(self.time_step)

    @property
    def frequency(self) -> np.ndarray:
        """1/T, Hz."""
        return 1.0 / self.period

    def initial_state(self) -> dict[str, np.ndarray]:
        """x_1 from the antisymmetric closure (rates and positions of pitch and heave)."""
        pr, pa = integrate(self.pitch_acceleration, self.time_step)
        hr, hp = integrate(self.heave_acceleration, self.time_step)
        return {"pitch_rate": pr[..., 0], "pitch_angle": pa[..., 0],
                "heave_velocity": hr[..., 0], "heave_position": hp[..., 0]}

    def trajectory(self) -> dict[str, np.ndarray]:
        """States x_1..x_{N+1}, each array of shape (..., N+1)."""
        pr, pa = integrate(self.pitch_acceleration, self.time_step)
        hr, hp = integrate(self.heave_acceleration, self.time_step)
        return {"pitch_rate": pr, "pitch_angle": pa, "heave_velocity": hr, "heave_position": hp}

    def states(self, scheme: Scheme = "paper",
               trajectory: dict[str, np.ndarray] | None = None) -> KinematicState:
        """The N states at which the hydrodynamic model is evaluated, t_j = (j-1) dt.

        Parameters
        ----------
        scheme
            ``"paper"`` uses the step's rate x_j; ``"midpoint"`` uses
            rate_j + dt acc_j / 2 (the energy-consistent variant of docs/theory.md).
        trajectory
            :meth:`trajectory` if the caller has it already (saves integrating twice).
        """
        if scheme not in SCHEMES:
            raise MotionError(f"unknown scheme {shown(scheme)}; allowed: {', '.join(SCHEMES)}")
        tr = self.trajectory() if trajectory is None else trajectory
        dt = np.asarray(self.time_step)[..., None]
        pr, hr = tr["pitch_rate"][..., :-1], tr["heave_velocity"][..., :-1]
        if scheme == "midpoint":
            pr = pr + 0.5 * dt * self.pitch_acceleration
            hr = hr + 0.5 * dt * self.heave_acceleration
        n = self.n_steps
        time = np.real(np.arange(n) * np.asarray(self.time_step)[..., None])
        if np.ndim(self.time_step) == 0:
            time = time.reshape(n)
        else:
            time = np.broadcast_to(time, self.pitch_acceleration.shape).copy()
        return KinematicState(
            time=time,
            pitch_angle=tr["pitch_angle"][..., :-1],
            pitch_rate=pr,
            pitch_acceleration=self.pitch_acceleration,
            heave_position=tr["heave_position"][..., :-1],
            heave_velocity=hr,
            heave_acceleration=self.heave_acceleration,
        )

    def full_cycle_positions(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Pitch angle and heave over the full period at t_i = i dt, i = 0..2N-1.

        Returns
        -------
        time : ndarray, s, shape (2N,) (scalar time step only)
        pitch_angle, heave_position : ndarray, shape (..., 2N)
        """
        tr = self.trajectory()
        pa, hp = tr["pitch_angle"][..., :-1], tr["heave_position"][..., :-1]
        dt = float(np.real(self.time_step))
        return (np.arange(2 * self.n_steps) * dt, np.concatenate([pa, -pa], axis=-1),
                np.concatenate([hp, -hp], axis=-1))

    def take(self, index) -> DiscreteMotion:
        """One motion (or a sub-batch) out of a batch."""
        return DiscreteMotion(self.pitch_acceleration[index], self.heave_acceleration[index],
                              np.asarray(self.time_step)[index])
