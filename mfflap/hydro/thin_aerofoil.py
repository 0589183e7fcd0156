"""Linear unsteady thin-aerofoil theory of the plate: the limit of small motions.

Theodorsen's theory of a flat plate in a uniform stream, written in the time domain with
Wagner's function (R. T. Jones' two-exponential approximation), for the plate of this package:
written here for a pitch about the leading edge (Theodorsen's a = -1), heave h along X0,
pitch theta anticlockwise, F_n along e_n and M = sum F_n l about the leading edge (the
model's signs, :class:`~mfflap.hydro.loads.Loads`). A plate pitching about a pivot x_p behind
its leading edge is the same plate with the leading edge heaving h - x_p theta (to first
order), its moment about the pivot M - x_p F_n: the functions below take the pivot of their
plate that way. With semichord b, span s and the normal velocity of the three-quarter-chord
point (Theodorsen's downwash, linearised)

    q(t) = hdot + U theta + (3/2) b thetadot,

and q_W its response through Wagner's function (the circulation lags the motion through the
wake; :func:`wagner_filter`), the loads are

    F_n = -pi rho b^2 s (hddot + U thetadot + b thetaddot) - 2 pi rho U b s q_W
    M   = -pi rho b^3 s (hddot + 3/2 U thetadot + 9/8 b thetaddot) - pi rho U b^2 s q_W.

The first terms are the non-circulatory (added-mass) loads, exact in time; the second the
circulatory lift at the quarter chord. For harmonic motion at reduced frequency k = omega b / U,
q_W -> C(k) q, Theodorsen's function (:func:`theodorsen_function`). The theory assumes an
inviscid, attached flow with a flat wake: small amplitudes (the effective incidence
atan(q / U) of a few degrees). It is a yardstick derivable by hand for the CFD adapters (signs,
frames, span scaling, the moment's reference point) and for the strip model's structure, not a
model of the paper's large motions. It says nothing about the tangential force (the leading-edge
suction is of second order and the blunt plate does not realise it), which is returned as zero.

References
----------
T. Theodorsen (1935), General theory of aerodynamic instability and the mechanism of flutter,
NACA Report 496. R. T. Jones (1940), The unsteady lift of a wing of finite aspect ratio, NACA
Report 681 (the approximation of Wagner's function used here).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace
from typing import Literal

import numpy as np
from scipy.special import hankel2

from mfflap.errors import MotionError
from mfflap.hydro.loads import Loads
from mfflap.kinematics.state import KinematicState
from mfflap.parameters import Fluid, FreeStream, Plate

#: the effective incidence, deg, beyond which the theory is no yardstick: the flow separates
#: from a plate at roughly this incidence, and the theory's linear, attached-flow, flat-wake
#: assumptions fail (the linear check's motions stay at 4-10 deg)
LINEAR_INCIDENCE_LIMIT_DEG = 10.0

#: R. T. Jones' approximation of Wagner's function, Phi(s) = 1 - sum A_i exp(-b_i s), with the
#: reduced time s = 2 U t / c (semichords travelled): pairs (A_i, b_i).
JONES_WAGNER = ((0.165, 0.0455), (0.335, 0.3))

WagnerStart = Literal["rest", "equilibrium"]


def wagner_function(reduced_time: np.ndarray | float) -> np.ndarray:
    """Wagner's function Phi(s) (Jones' approximation): lift after a step in incidence.

    Phi(0) = 1/2 and Phi -> 1 as s -> infinity; s = 2 U t / c.
    """
    s = np.asarray(reduced_time, dtype=float)
    return 1.0 - sum(a * np.exp(-b * s) for a, b in JONES_WAGNER)


def theodorsen_function(reduced_frequency: np.ndarray | float) -> np.ndarray:
    """Theodorsen's function C(k) = H1(k) / (H1(k) + i H0(k)), H Hankel functions of the 2nd kind.

    k = omega b / U > 0 (b the semichord). C -> 1 as k -> 0 and C -> 1/2 as k -> infinity.
    """
    k = np.asarray(reduced_frequency, dtype=float)
    if np.any(~(k > 0)):
        raise MotionError(f"reduced frequency must be > 0, got {reduced_frequency!r}")
    h1, h0 = hankel2(1, k), hankel2(0, k)
    return h1 / (h1 + 1j * h0)


def jones_theodorsen_function(reduced_frequency: np.ndarray | float) -> np.ndarray:
    """The C(k) that Jones' Wagner function implies: 1 - sum A_i i k / (i k + b_i)."""
    ik = 1j * np.asarray(reduced_frequency, dtype=float)
    return 1.0 - sum(a * ik / (ik + b) for a, b in JONES_WAGNER)


def wagner_filter(values: np.ndarray, time: np.ndarray, velocity: float | np.ndarray,
                  chord: float,
                  start: WagnerStart = "equilibrium") -> np.ndarray:
    """Response of Wagner's lag to ``values`` (last axis is time): sum over the input's history.

    y(s) = x(s_0) Phi(s - s_0) + int dx/ds' Phi(s - s') ds' in the state-space form of
    Phi = 1 - sum A_i exp(-b_i s): y = (1 - sum A_i) x + sum A_i b_i z_i with
    dz_i/ds = x - b_i z_i, integrated exactly for an input held from each sample to the next.

    Parameters
    ----------
    values : ndarray
        The quasi-steady quantity (incidence, normal velocity or force), shape (..., n_times).
    time : ndarray, s
        Increasing sample times, shape (n_times,) or that of ``values``.
    velocity : m/s
        The speed the wake is laid down at: the free stream's U (s = 2 U t / c), or one per
        sample, shape (n_times,) (s = 2 / c times its integral over time, trapezoidal).
    chord : m
    start : {"equilibrium", "rest"}
        "equilibrium": the input oscillated about its mean before the first sample (the
        gap diagnosis's cycles, cut from runs that started long before): the lag's states
        start at the mean's equilibrium. Starting them at the first sample's value instead
        leaves a transient as slow as the slowest lag (about 22 semichords, seconds of a
        run), which on the shipped small-motion CFD hid most of the wake's lag. "rest":
        the input was zero before and steps to its first value (y = x / 2 there, Wagner's
        start from rest).
    """
    if start not in ("equilibrium", "rest"):
        raise MotionError(f"start must be 'equilibrium' or 'rest', got {start!r}")
    x = np.asarray(values, dtype=float)
    t = np.asarray(time, dtype=float)
    v = np.asarray(velocity, dtype=float)
    if v.ndim == 0:
        s = 2 * v * (t - t[..., :1]) / chord
    else:
        steps = 0.5 * (v[..., 1:] + v[..., :-1]) * np.diff(t, axis=-1)
        s = 2 / chord * np.concatenate([np.zeros((*steps.shape[:-1], 1)), np.cumsum(
            steps, axis=-1)], axis=-1)
    ds = np.diff(s, axis=-1)
    if np.any(ds < 0):
        raise MotionError("wagner_filter needs increasing sample times")
    y = (1 - sum(a for a, _ in JONES_WAGNER)) * x
    for a, b in JONES_WAGNER:
        z = np.empty_like(x)
        z[..., 0] = x.mean(axis=-1) / b if start == "equilibrium" else 0.0
        decay = np.exp(-b * ds)
        for n in range(x.shape[-1] - 1):
            z[..., n + 1] = z[..., n] * decay[..., n] + x[..., n] * (1 - decay[..., n]) / b
        y = y + a * b * z
    return y


def three_quarter_chord_velocity(state: KinematicState, free_stream_velocity: float,
                                 chord: float) -> np.ndarray:
    """Theodorsen's downwash q = hdot + U theta + (3/4) c thetadot, linearised, m/s (h and
    its rates those of the leading edge)."""
    return (state.heave_velocity + free_stream_velocity * state.pitch_angle
            + 0.75 * chord * state.pitch_rate)


def _check_single_motion(state: KinematicState) -> np.ndarray:
    t = np.asarray(state.time, dtype=float)
    if t.ndim != 1 or np.shape(state.pitch_angle) != t.shape:
        raise MotionError("linear thin-aerofoil theory needs one motion on a 1-D time base, "
                          f"got time {t.shape} and states {np.shape(state.pitch_angle)}")
    return t


def _leading_edge_state(state: KinematicState, pivot_m: float) -> KinematicState:
    """The state of the leading edge of a plate whose pivot, ``pivot_m`` behind it, moves as
    ``state`` (first order in the pitch: the leading edge heaves h - x_p theta)."""
    if not pivot_m:
        return state
    return replace(state, heave_position=state.heave_position - pivot_m * state.pitch_angle,
                   heave_velocity=state.heave_velocity - pivot_m * state.pitch_rate,
                   heave_acceleration=(state.heave_acceleration
                                       - pivot_m * state.pitch_acceleration))


def _about_pivot(loads: Loads, pivot_m: float) -> Loads:
    """Loads with their moment moved from the leading edge to the pivot, M - x_p F_n."""
    if not pivot_m:
        return loads
    return replace(loads, moment=loads.moment - pivot_m * loads.normal_force)


def added_mass_loads(state: KinematicState, plate: Plate | None = None,
                     fluid: Fluid | None = None, stream: FreeStream | None = None) -> Loads:
    """The non-circulatory loads of the theory, exact in time (module docstring).

    F_n = -pi rho b^2 s (hddot + U thetadot + b thetaddot),
    M = -pi rho b^3 s (hddot + 3/2 U thetadot + 9/8 b thetaddot) about the leading edge
    (moved to the plate's pivot); tangential force zero.
    """
    plate, fluid, stream = plate or Plate(), fluid or Fluid(), stream or FreeStream()
    t = _check_single_motion(state)
    state = _leading_edge_state(state, plate.pivot_m)
    u, b = stream.velocity, plate.chord / 2
    hdd, td, tdd = state.heave_acceleration, state.pitch_rate, state.pitch_acceleration
    mass = np.pi * fluid.density * b**2 * plate.span
    normal = -mass * (hdd + u * td + b * tdd)
    moment = -mass * b * (hdd + 1.5 * u * td + 9 / 8 * b * tdd)
    return _about_pivot(Loads(t, normal, np.zeros_like(normal), moment,
                              source="thin_aerofoil_added_mass"), plate.pivot_m)


def circulatory_loads(state: KinematicState, plate: Plate | None = None,
                      fluid: Fluid | None = None, stream: FreeStream | None = None) -> Loads:
    """The circulatory loads of the theory for a motion from rest (module docstring).

    F_n = -2 pi rho U b s q_W at the quarter chord (M = F_n (c / 4 - x_p)), q_W the downwash
    :func:`three_quarter_chord_velocity` through Wagner's lag from rest; tangential force
    zero. ``metadata`` as :func:`thin_aerofoil_loads`.
    """
    plate, fluid, stream = plate or Plate(), fluid or Fluid(), stream or FreeStream()
    t = _check_single_motion(state)
    state = _leading_edge_state(state, plate.pivot_m)
    u, b = stream.velocity, plate.chord / 2
    q = three_quarter_chord_velocity(state, u, plate.chord)
    q_lagged = wagner_filter(q, t, u, plate.chord, start="rest")
    normal = -2 * np.pi * fluid.density * u * b * plate.span * q_lagged
    incidence = np.degrees(np.arctan2(np.abs(q), u))
    metadata = {"max_effective_incidence_deg": float(np.max(incidence, initial=0.0)),
                "reduced_time_span": float(2 * u * (t[-1] - t[0]) / plate.chord)}
    return _about_pivot(Loads(t, normal, np.zeros_like(normal), normal * b / 2,
                              source="thin_aerofoil_circulatory", metadata=metadata),
                        plate.pivot_m)


def thin_aerofoil_loads(state: KinematicState, plate: Plate | None = None,
                        fluid: Fluid | None = None, stream: FreeStream | None = None) -> Loads:
    """Loads of linear unsteady thin-aerofoil theory (module docstring) for a motion from rest.

    Parameters
    ----------
    state : KinematicState
        The motion sampled from its start (the plate at rest in the stream before the first
        sample), on one increasing time base of shape (n_times,). The circulation follows
        the samples held between them, so the time step should resolve the motion (a few
        hundred samples per period give the lag to better than 1 %).
    plate, fluid, stream
        The package's defaults if omitted. The plate's thickness is ignored (thin plate).

    Returns
    -------
    Loads
        :func:`added_mass_loads` + :func:`circulatory_loads`: F_n and M (tangential force
        zero), ``source="thin_aerofoil"``; ``metadata`` holds
        ``max_effective_incidence_deg`` = max |atan(q / U)|, the check that the motion is
        small enough for the theory (a few degrees), and the reduced-time span of the record.
    """
    circulatory = circulatory_loads(state, plate, fluid, stream)
    total = added_mass_loads(state, plate, fluid, stream) + circulatory
    return Loads(total.time, total.normal_force, total.tangential_force, total.moment,
                 source="thin_aerofoil", metadata=circulatory.metadata)


def thin_aerofoil_loads_at(sample: Callable[[np.ndarray], KinematicState], times: np.ndarray,
                           plate: Plate | None = None, fluid: Fluid | None = None,
                           stream: FreeStream | None = None,
                           max_time_step_s: float = 1e-3) -> Loads:
    """:func:`thin_aerofoil_loads` of a motion that starts from rest at t = 0, at ``times``.

    The wake's lag is integrated from t = 0 on the given times merged with a grid no coarser
    than ``max_time_step_s``, so a coarse or uneven time base (a CFD solver's adaptive steps,
    a record that starts after t = 0) loses nothing.

    Parameters
    ----------
    sample : callable
        Maps times (s, from 0) to the imposed :class:`KinematicState`, e.g.
        ``lambda t: imposed_state(motion, t, ramp_time)``.
    times : ndarray, s
        Where the loads are wanted; non-negative.
    """
    t = np.asarray(times, dtype=float)
    if t.ndim != 1 or t.size == 0 or not np.all(np.isfinite(t)) or t.min() < 0:
        raise MotionError("thin_aerofoil_loads_at needs finite times >= 0 on a 1-D axis")
    if not max_time_step_s > 0:
        raise MotionError(f"max_time_step_s must be > 0, got {max_time_step_s!r}")
    n = max(int(np.ceil(t.max() / max_time_step_s)), 1) + 1
    grid = np.union1d(np.linspace(0.0, t.max(), n), t)
    loads = thin_aerofoil_loads(sample(grid), plate, fluid, stream)
    pick = np.searchsorted(grid, t)
    return Loads(t, loads.normal_force[pick], loads.tangential_force[pick], loads.moment[pick],
                 source=loads.source, metadata=loads.metadata)
