"""The adjoint of the kinematic integration: partial derivatives of an objective with respect
to the N states of a :class:`~mfflap.kinematics.discrete.DiscreteMotion` chained into its
controls (every step's accelerations) and its time step.

The states follow from the controls by the semi-implicit Euler steps of
:func:`~mfflap.kinematics.discrete.integrate` from the closed-form initial state x_1(u, dt)
of the antisymmetric closure. A backward sweep with lambda_{N+1} = 0 carries the states'
partials to the accelerations at fixed x_1, and the linear map x_1(u, dt) is then chained
in; the ``"midpoint"`` scheme's rate rate_j + dt acc_j / 2 is chained first. Any model whose
objective is a function of the states can use it (the Morison and the discrete-vortex
problems do).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mfflap.kinematics.discrete import DiscreteMotion, initial_state_weights


@dataclass(frozen=True)
class Gradient:
    """dJ/d(controls) and dJ/d(time step).

    pitch_acceleration : shape (..., N), units of J per rad/s^2
    heave_acceleration : shape (..., N)
    time_step : shape (...)
    """

    pitch_acceleration: np.ndarray
    heave_acceleration: np.ndarray
    time_step: np.ndarray

    def flat(self) -> np.ndarray:
        """[d/d pitch (N), d/d heave (N), d/d dt] of one motion."""
        return np.concatenate([self.pitch_acceleration, self.heave_acceleration,
                               np.atleast_1d(self.time_step)])


def chain_state_partials(motion: DiscreteMotion, partials: dict[str, np.ndarray],
                         scheme: str = "paper",
                         trajectory: dict[str, np.ndarray] | None = None) -> Gradient:
    """The gradient with respect to the controls and the time step of an objective whose
    partial derivatives with respect to the motion's N states are ``partials``.

    Parameters
    ----------
    motion : DiscreteMotion
    partials : dict
        dJ/d(state_j), shape (..., N), for "th" (pitch angle), "td" (pitch rate), "tdd"
        (pitch acceleration), "hp" (heave), "hd" (heave velocity) and "hdd" (heave
        acceleration); the rates are the ones the model sees (the scheme's).
    scheme : "paper" or "midpoint"
    trajectory : dict, optional
        :meth:`DiscreteMotion.trajectory`, if the caller has it.

    Returns
    -------
    Gradient

    Examples
    --------
    J = the mean pitch angle, against a central difference in the first step's pitch
    acceleration:

    >>> import numpy as np
    >>> motion = DiscreteMotion(np.sin(np.arange(8.0)), np.cos(np.arange(8.0)), 0.05)
    >>> zero = np.zeros(8)
    >>> parts = {"th": np.full(8, 1 / 8), "td": zero, "tdd": zero, "hp": zero, "hd": zero,
    ...          "hdd": zero}
    >>> grad = chain_state_partials(motion, parts)
    >>> def mean_pitch(acc):
    ...     return DiscreteMotion(acc, motion.heave_acceleration, 0.05).states().pitch_angle.mean()
    >>> e = np.zeros(8); e[0] = 1e-6
    >>> a = motion.pitch_acceleration
    >>> fd = (mean_pitch(a + e) - mean_pitch(a - e)) / 2e-6
    >>> bool(abs(grad.pitch_acceleration[0] - fd) < 1e-8)
    True
    """
    n = motion.n_steps
    dt = np.asarray(motion.time_step, dtype=float)
    dtc = dt[..., None]
    tr = motion.trajectory() if trajectory is None else trajectory
    grads = {}
    grad_dt = np.zeros(dt.shape)
    for dof, acc, rate_key, g_rate, g_pos, g_acc in (
        ("pitch", motion.pitch_acceleration, "pitch_rate",
         partials["td"], partials["th"], partials["tdd"]),
        ("heave", motion.heave_acceleration, "heave_velocity",
         partials["hd"], partials["hp"], partials["hdd"]),
    ):
        if scheme == "midpoint":
            # hydro rate = rate_j + dt acc_j / 2
            g_acc = g_acc + 0.5 * dtc * g_rate
            grad_dt = grad_dt + 0.5 * (g_rate * acc).sum(-1)
        # backward sweep, lambda_{N+1} = 0: lam_p_j = sum_{i>=j} g_pos_i,
        # lam_r_j = g_rate_j + lam_r_{j+1} + dt lam_p_{j+1}
        lam_p = np.flip(np.cumsum(np.flip(g_pos, -1), -1), -1)
        lam_p_next = np.concatenate([lam_p[..., 1:], np.zeros_like(lam_p[..., :1])], -1)
        lam_r = np.flip(np.cumsum(np.flip(g_rate + dtc * lam_p_next, -1), -1), -1)
        lam_r_next = np.concatenate([lam_r[..., 1:], np.zeros_like(lam_r[..., :1])], -1)
        rate = tr[rate_key][..., :-1]
        g_u = g_acc + dtc * lam_r_next + dtc**2 * lam_p_next
        grad_dt = grad_dt + (acc * lam_r_next + (rate + 2 * dtc * acc) * lam_p_next).sum(-1)
        # chain through x_1(u, dt): rate_1 = -(dt/2) sum acc, pos_1 = dt^2 sum w_j acc_j
        w = initial_state_weights(n)
        g_u = g_u + lam_r[..., :1] * (-0.5 * dtc) + lam_p[..., :1] * dtc**2 * w
        grad_dt = grad_dt + lam_r[..., 0] * (-0.5 * acc.sum(-1)) + lam_p[..., 0] * (
            2 * dt * (acc @ w))
        grads[dof] = g_u
    return Gradient(grads["pitch"], grads["heave"], grad_dt)


def smoothness(motion: DiscreteMotion, smoothing_pitch: float, smoothing_heave: float):
    """J_s = 1/2 eps sum_{j<N} (acc_{j+1} - acc_j)^2 + 1/2 eps (acc_1 + acc_N)^2 for pitch and
    heave (the wrap term: acc_{N+1} = -acc_1 by the antisymmetric closure), shape (...)."""
    out = 0.0
    for eps, a in ((smoothing_pitch, motion.pitch_acceleration),
                   (smoothing_heave, motion.heave_acceleration)):
        d = np.diff(a, axis=-1)
        wrap = a[..., 0] + a[..., -1]
        out = out + 0.5 * eps * ((d**2).sum(axis=-1) + wrap**2)
    return out


def smoothness_gradient(motion: DiscreteMotion, smoothing_pitch: float,
                        smoothing_heave: float) -> dict[str, np.ndarray]:
    """dJ_s/d(pitch and heave accelerations): {"pitch": ..., "heave": ...}, shape (..., N)."""
    out = {}
    for dof, eps, acc in (("pitch", smoothing_pitch, motion.pitch_acceleration),
                          ("heave", smoothing_heave, motion.heave_acceleration)):
        gs = np.zeros(np.shape(acc))
        if eps != 0:
            d = np.diff(acc, axis=-1)
            gs[..., :-1] -= eps * d
            gs[..., 1:] += eps * d
            wrap = acc[..., 0] + acc[..., -1]
            gs[..., 0] += eps * wrap
            gs[..., -1] += eps * wrap
        out[dof] = gs
    return out


__all__ = ["Gradient", "chain_state_partials", "smoothness", "smoothness_gradient"]
