"""A discrete-vortex model of the plate and its wake: the LDVM of Ramesh et al. (2014).

The plate is a thin flat plate with a bound vortex sheet written as a Glauert series,

    gamma(phi) = 2 U [A_0 (1 + cos phi) / sin phi + sum_n A_n sin(n phi)],
    x = (c / 2) (1 - cos phi),

x the distance from the leading edge (clockwise-positive sheet strength, U the free-stream
speed used as the reference speed). The coefficients follow from the no-penetration
condition at the plate, where the sheet cancels the normal velocity W(x) of the flow relative
to the plate (free stream, the plate's own heave and pitch, and the velocity the free vortices
induce):

    A_0 = (1 / (pi U)) int_0^pi W dphi,   A_n = -(2 / (pi U)) int_0^pi W cos(n phi) dphi.

Every step the plate sheds a vortex from its trailing edge, whose strength keeps the total
circulation zero (Kelvin); when the leading-edge suction parameter A_0 exceeds its critical
value in magnitude, the plate also sheds a vortex from its leading edge, whose strength holds
|A_0| at the critical value. The free vortices move with the local flow (regularised point
vortices, forward Euler).

The loads follow from the rate of change of the vortex impulse of the whole flow, bound and
free vortices alike, in the frame of the fluid at rest (Wu 1981):

    F = -rho d/dt sum_k Gamma_k (y_k, -x_k),   M_O = (rho / 2) d/dt sum_k Gamma_k |r_k|^2,

moved to the pivot, with the derivative taken by the second-order backward difference.
This is exact for the discretised flow and holds with leading-edge shedding. The pressure-jump
form delta p = rho [V_t gamma + d/dt int_0^x gamma dx'] with the suction pi rho c U^2 A_0^2
(Ramesh et al.) gives the same loads in attached flow, but it takes the potential jump at the
leading edge as zero, which it is not once vorticity leaves there: on a heaving plate that
sheds from its leading edge it returns a negative mean input power.

The integrals over the chord are midpoint sums in phi, which are spectrally accurate for the
smooth integrands of this model; the bound sheet acts on the free vortices as the same
midpoint vortices. The circulation shed in a step acts on the plate as a uniform sheet from
the edge to two-thirds of the way to the previous vortex (Ramesh et al. place a point vortex
at a third of that distance, the sheet's centre), and moves on as a point vortex at the
sheet's centre. The wake is kept in a ring of the vortices shed in the most recent steps (the
far-wake cut-off); older vortices leave the ring, and their circulation and impulse stay in
the balances as if they drifted with the stream, so that the cost per step stays bounded
however long the record.

Frames and signs are the package's (:class:`~mfflap.hydro.loads.Loads`): the stream along
+Y0, heave h of the pivot (:attr:`~mfflap.parameters.Plate.pivot_m` behind the leading edge)
along X0, pitch theta about it with the chord along (sin theta, cos theta); F_n along
e_n = (cos theta, -sin theta), F_t along the chord from the leading to the trailing edge, M
about the pivot. Inside, the kernel works in the
plane (x, y) = (Y0, X0), with circulation anticlockwise positive there.

References
----------
K. Ramesh, A. Gopalarathnam, K. Granlund, M. V. Ol and J. R. Edwards (2014),
Discrete-vortex method with novel shedding criterion for unsteady aerofoil flows with
intermittent leading-edge vortex shedding, J. Fluid Mech. 751, 500-538.
J. C. Wu (1981), Theory for aerodynamic force and moment in viscous flows, AIAA J. 19(4),
432-441.
"""

from __future__ import annotations

import cmath
import math
from dataclasses import dataclass, field

import numba
import numpy as np

from mfflap.errors import ConfigError, MotionError
from mfflap.hydro.loads import Loads
from mfflap.kinematics.state import KinematicState
from mfflap.parameters import ATTACHED_FLOW as ATTACHED_FLOW  # re-exported with the model
from mfflap.parameters import Fluid, FreeStream, Plate, VortexModelSettings


@dataclass(frozen=True)
class VortexRun:
    """What the discrete-vortex model computed, step by step.

    Attributes
    ----------
    loads : Loads
        F_n, F_t (N) and M about the pivot (N*m) at every step.
    leading_edge_suction_parameter : ndarray
        A_0 after shedding (reference speed U), dimensionless.
    trailing_edge_circulation, leading_edge_circulation : ndarray, m^2/s
        The circulation shed each step (anticlockwise positive in the (Y0, X0) plane).
    total_circulation : ndarray, m^2/s
        Bound plus free circulation, including the vortices that left the wake ring: zero up
        to round-off (Kelvin's theorem).
    wake_position : ndarray, m
        The free vortices at the end, shape (n, 2) as (Y0, X0), the most recent first.
    wake_circulation : ndarray, m^2/s
        Their circulations, shape (n,).
    """

    loads: Loads
    leading_edge_suction_parameter: np.ndarray
    trailing_edge_circulation: np.ndarray
    leading_edge_circulation: np.ndarray
    total_circulation: np.ndarray
    wake_position: np.ndarray
    wake_circulation: np.ndarray
    settings: VortexModelSettings = field(default_factory=VortexModelSettings)


def _uniform_time_step(time: np.ndarray) -> float:
    t = np.asarray(time, dtype=float)
    if t.ndim != 1 or t.size < 2:
        raise MotionError(f"the discrete-vortex model needs one motion of >= 2 samples, got "
                          f"time of shape {t.shape}")
    dt = np.diff(t)
    if not np.all(dt > 0) or np.ptp(dt) > 1e-9 * dt.mean():
        raise MotionError("the discrete-vortex model needs a uniform, increasing time base")
    return float(dt.mean())


@numba.njit(cache=True, inline="always")
def _induced(x, y, xs, ys, gs, core2):
    """Velocity at (x, y) of the regularised point vortices (xs, ys) of circulation gs."""
    u = v = 0.0
    for k in range(xs.size):
        if gs[k] != 0.0:
            dx, dy = x - xs[k], y - ys[k]
            w = gs[k] / (2 * math.pi * (dx * dx + dy * dy + core2))
            u -= w * dy
            v += w * dx
    return u, v


@numba.njit(cache=True, inline="always")
def _sheet(x, y, x1, y1, x2, y2):
    """Velocity at (x, y) of a uniform vortex sheet of unit circulation from 1 to 2."""
    z = complex(x, y)
    z1, z2 = complex(x1, y1), complex(x2, y2)
    w = cmath.log((z - z1) / (z - z2)) / (2j * math.pi * (z2 - z1))
    return w.real, -w.imag


#: the layout of the wake's scalar state in the kernels' ``aux`` array: the circulation and
#: the impulse (x, y, angular) of the vortices that left the ring, and the last shed
#: vortices' positions
AUX_DROPPED, AUX_DROPPED_X, AUX_DROPPED_Y, AUX_DROPPED_ANG = 0, 1, 2, 3
AUX_TEV_X, AUX_TEV_Y, AUX_LEV_X, AUX_LEV_Y = 4, 5, 6, 7
#: rows of the kernels' ``work`` array: what one step's solution leaves for the loads, the
#: wake's motion and the reverse sweep
W_PX, W_PY, W_BOUND, W_A_KNOWN, W_A_TEV, W_A_LEV, W_COEFFS = 0, 1, 2, 3, 4, 5, 6


@numba.njit(cache=True)
def _quadrature(chord, velocity, n_points):
    """The chord's midpoints in phi, the map from normal velocity to the Glauert
    coefficients (A = fourier @ W) and from these to the bound vortices (sheet @ A)."""
    phi = (np.arange(n_points) + 0.5) * math.pi / n_points
    dphi = math.pi / n_points
    x_chord = chord / 2 * (1 - np.cos(phi))
    fourier = np.empty((n_points, n_points))
    sheet = np.empty((n_points, n_points))  # clockwise bound circulation
    for i in range(n_points):
        fourier[0, i] = dphi / (math.pi * velocity)
        sheet[i, 0] = velocity * chord * dphi * (1 + math.cos(phi[i]))
        for n in range(1, n_points):
            fourier[n, i] = -2 * dphi / (math.pi * velocity) * math.cos(n * phi[i])
            sheet[i, n] = velocity * chord * dphi * math.sin(n * phi[i]) * math.sin(phi[i])
    return x_chord, fourier, sheet


@numba.njit(cache=True)
def _initial_aux(heave0, heave_rate0, pitch0, chord, pivot, velocity, time_step):
    """The wake's scalar state before the first step (the previous trailing-edge vortex
    one and a half steps of stream behind the trailing edge)."""
    aux = np.zeros(8)
    aux[AUX_TEV_X] = pivot + (chord - pivot) * math.cos(pitch0) + 1.5 * time_step * velocity
    aux[AUX_TEV_Y] = heave0 + (chord - pivot) * math.sin(pitch0) - 1.5 * time_step * heave_rate0
    return aux


@numba.njit(cache=True)
def _solve_step(j, heave, heave_rate, pitch, pitch_rate, chord, pivot, velocity, density, span,
                time_step, critical_lesp, core2, wake_steps, x_chord, fourier, sheet,
                xs, ys, gs, aux, lev_was_shed, prev_imp, prev2_imp, work):
    """One step up to the wake's motion: the oldest vortices leave the ring, the bound
    circulation and the shed vortices follow from no penetration and Kelvin, the shed
    vortices join the ring (xs, ys, gs and aux updated in place) and the loads follow from
    the impulse. ``work`` receives the plate's points, bound vortices and coefficients.

    Returns (F_n, F_t, M, shed, gam_tev, gam_lev, total circulation, imp_x, imp_y, ang,
    geometry): geometry = (c, s, tx, ty, tex, tey, lex, ley, k_tev, k_lev).
    """
    n_points = x_chord.size
    slot = j % wake_steps
    kelvin_scale = math.pi * chord * velocity
    # the oldest vortices leave the ring; their circulation stays in Kelvin's balance
    shift = velocity * time_step * j
    for k in (slot, wake_steps + slot):
        if gs[k] != 0.0:
            xr = xs[k] - shift
            aux[AUX_DROPPED] += gs[k]
            aux[AUX_DROPPED_X] += gs[k] * ys[k]
            aux[AUX_DROPPED_Y] -= gs[k] * xr
            aux[AUX_DROPPED_ANG] += gs[k] * (xr * xr + ys[k] * ys[k])
            gs[k] = 0.0
    c, s_ = math.cos(pitch[j]), math.sin(pitch[j])
    # the leading edge: the pivot, at (pivot, heave) in the stream's frame, lies `pivot`
    # along the chord behind it
    lx, ly = pivot * (1 - c), heave[j] - pivot * s_
    tx, ty = lx + chord * c, ly + chord * s_
    px, py = work[W_PX], work[W_PY]
    w_known = np.empty(n_points)
    w_tev, w_lev = np.empty(n_points), np.empty(n_points)
    for i in range(n_points):
        px[i], py[i] = lx + x_chord[i] * c, ly + x_chord[i] * s_
        wu, wv = _induced(px[i], py[i], xs, ys, gs, core2)
        w_known[i] = (-velocity * s_ - heave_rate[j] * c - pitch_rate[j] * (x_chord[i] - pivot)
                      - wu * s_ + wv * c)
    # the circulation shed in this step: a uniform sheet from each edge
    tex = tx + (aux[AUX_TEV_X] - tx) * (2 / 3)
    tey = ty + (aux[AUX_TEV_Y] - ty) * (2 / 3)
    if lev_was_shed:
        lex = lx + (aux[AUX_LEV_X] - lx) * (2 / 3)
        ley = ly + (aux[AUX_LEV_Y] - ly) * (2 / 3)
    else:
        # one step of the flow past the leading edge, which moves at
        # (pivot sin theta theta', h' - pivot cos theta theta')
        lex = lx + time_step * (velocity - pivot * s_ * pitch_rate[j])
        ley = ly - time_step * (heave_rate[j] - pivot * c * pitch_rate[j])
    for i in range(n_points):
        u, v = _sheet(px[i], py[i], tx, ty, tex, tey)
        w_tev[i] = -u * s_ + v * c
        u, v = _sheet(px[i], py[i], lx, ly, lex, ley)
        w_lev[i] = -u * s_ + v * c
    a_known, a_tev, a_lev = work[W_A_KNOWN], work[W_A_TEV], work[W_A_LEV]
    a_known[:] = fourier @ w_known
    a_tev[:] = fourier @ w_tev
    a_lev[:] = fourier @ w_lev
    k_known = kelvin_scale * (a_known[0] + a_known[1] / 2)
    k_tev = kelvin_scale * (a_tev[0] + a_tev[1] / 2)
    k_lev = kelvin_scale * (a_lev[0] + a_lev[1] / 2)
    free_total = gs.sum() + aux[AUX_DROPPED]
    gam_tev = (k_known - free_total) / (1 - k_tev)
    gam_lev = 0.0
    a0_trial = a_known[0] + gam_tev * a_tev[0]
    shed = abs(a0_trial) > critical_lesp
    if shed:
        target = critical_lesp if a0_trial > 0 else -critical_lesp
        det = a_tev[0] * (1 - k_lev) - a_lev[0] * (1 - k_tev)
        rhs0, rhs1 = target - a_known[0], k_known - free_total
        gam_tev = (rhs0 * (1 - k_lev) - a_lev[0] * rhs1) / det
        gam_lev = (a_tev[0] * rhs1 - (1 - k_tev) * rhs0) / det
    coeffs, bound = work[W_COEFFS], work[W_BOUND]
    coeffs[:] = a_known + gam_tev * a_tev + gam_lev * a_lev
    bound[:] = sheet @ coeffs
    # the shed sheets become point vortices at their centres
    xs[slot], ys[slot], gs[slot] = (tx + tex) / 2, (ty + tey) / 2, gam_tev
    xs[wake_steps + slot], ys[wake_steps + slot] = (lx + lex) / 2, (ly + ley) / 2
    gs[wake_steps + slot] = gam_lev
    total = -kelvin_scale * (coeffs[0] + coeffs[1] / 2) + gs.sum() + aux[AUX_DROPPED]
    # the loads from the rate of change of the vortex impulse, in the frame of the fluid
    # at rest (x' = x - U t): every vortex, bound and free, with those that left the ring
    imp_x, imp_y = aux[AUX_DROPPED_X], aux[AUX_DROPPED_Y]
    ang = aux[AUX_DROPPED_ANG]
    for k in range(2 * wake_steps):
        if gs[k] != 0.0:
            xr = xs[k] - shift
            imp_x += gs[k] * ys[k]
            imp_y -= gs[k] * xr
            ang += gs[k] * (xr * xr + ys[k] * ys[k])
    for i in range(n_points):
        xr = px[i] - shift
        imp_x -= bound[i] * py[i]
        imp_y += bound[i] * xr
        ang -= bound[i] * (xr * xr + py[i] * py[i])
    scale = density * span / time_step
    if j == 0:  # the plate at rest, and the fluid with it, before t_0
        fx, fy, mo = -scale * imp_x, -scale * imp_y, scale * ang / 2
    else:
        fx = -scale * (1.5 * imp_x - 2 * prev_imp[0] + 0.5 * prev2_imp[0])
        fy = -scale * (1.5 * imp_y - 2 * prev_imp[1] + 0.5 * prev2_imp[1])
        mo = scale * (1.5 * ang - 2 * prev_imp[2] + 0.5 * prev2_imp[2]) / 2
    normal = -fx * s_ + fy * c
    tangential = fx * c + fy * s_
    # about the pivot: M_P = M_O - (r_P x F)
    moment = mo - ((pivot - shift) * fy - heave[j] * fx)
    geometry = (c, s_, tx, ty, tex, tey, lex, ley, k_tev, k_lev)
    return (normal, tangential, moment, shed, gam_tev, gam_lev, total, imp_x, imp_y, ang,
            geometry)


@numba.njit(cache=True)
def _wake_velocity(k, xs, ys, gs, work, velocity, core2):
    """The velocity of free vortex k: the stream, the bound sheet and the other vortices."""
    u, v = _induced(xs[k], ys[k], work[W_PX], work[W_PY], -work[W_BOUND], core2)
    uw, vw = _induced(xs[k], ys[k], xs, ys, gs, core2)
    return velocity + u + uw, v + vw


@numba.njit(cache=True)
def _advect(slot, xs, ys, gs, aux, work, velocity, time_step, core2, move_u, move_v):
    """The free vortices move with the local flow (forward Euler); the last shed vortices'
    positions are kept for the next step's sheets."""
    wake_steps = xs.size // 2
    for k in range(2 * wake_steps):
        if gs[k] != 0.0:
            move_u[k], move_v[k] = _wake_velocity(k, xs, ys, gs, work, velocity, core2)
    for k in range(2 * wake_steps):
        if gs[k] != 0.0:
            xs[k] += time_step * move_u[k]
            ys[k] += time_step * move_v[k]
    aux[AUX_TEV_X], aux[AUX_TEV_Y] = xs[slot], ys[slot]
    aux[AUX_LEV_X], aux[AUX_LEV_Y] = xs[wake_steps + slot], ys[wake_steps + slot]


@numba.njit(cache=True)
def _march(heave, heave_rate, pitch, pitch_rate, chord, pivot, velocity, density, span,
           time_step, critical_lesp, core2, n_points, wake_steps, tape_wake, tape_aux,
           tape_flags, tape_impulse):
    """The model's time march (module docstring); returns the step outputs and the wake.

    The tape arrays, when they have a row per step (else zero rows), receive the wake before
    each step (xs, ys, gs), its scalar state, whether the previous and this step shed from
    the leading edge and the step's impulse: what the reverse sweep needs.
    """
    n_times = heave.size
    x_chord, fourier, sheet = _quadrature(chord, velocity, n_points)
    taping = tape_wake.shape[0] == n_times
    xs = np.zeros(2 * wake_steps)  # trailing-edge vortices first, then leading-edge ones
    ys = np.zeros(2 * wake_steps)
    gs = np.zeros(2 * wake_steps)
    out = np.zeros((7, n_times))
    work = np.empty((7, n_points))
    move_u, move_v = np.empty(2 * wake_steps), np.empty(2 * wake_steps)
    aux = _initial_aux(heave[0], heave_rate[0], pitch[0], chord, pivot, velocity, time_step)
    lev_was_shed = False
    prev_imp, prev2_imp = np.zeros(3), np.zeros(3)
    for j in range(n_times):
        if taping:
            tape_wake[j, 0], tape_wake[j, 1], tape_wake[j, 2] = xs, ys, gs
            tape_aux[j] = aux
            tape_flags[j, 0] = lev_was_shed
        res = _solve_step(j, heave, heave_rate, pitch, pitch_rate, chord, pivot, velocity,
                          density, span, time_step, critical_lesp, core2, wake_steps, x_chord,
                          fourier, sheet, xs, ys, gs, aux, lev_was_shed, prev_imp, prev2_imp,
                          work)
        out[0, j], out[1, j], out[2, j] = res[0], res[1], res[2]
        out[3, j], out[4, j], out[5, j] = work[W_COEFFS, 0], res[4], res[5]
        out[6, j] = res[6]
        if taping:
            tape_flags[j, 1] = res[3]
            tape_impulse[j, 0], tape_impulse[j, 1], tape_impulse[j, 2] = res[7], res[8], res[9]
        prev2_imp[:] = prev_imp
        prev_imp[0], prev_imp[1], prev_imp[2] = res[7], res[8], res[9]
        _advect(j % wake_steps, xs, ys, gs, aux, work, velocity, time_step, core2, move_u,
                move_v)
        lev_was_shed = res[3]
    return out, xs, ys, gs


def _check_stream(stream: FreeStream) -> None:
    if not stream.velocity > 0:
        raise ConfigError("the discrete-vortex model needs a stream: flow.velocity > 0",
                          key="flow.velocity")


def _wake_steps_for(settings: VortexModelSettings, plate: Plate, stream: FreeStream,
                    time_step: float, n_times: int) -> int:
    """The wake ring's length: the settings' cut-off, at most the motion's samples."""
    return min(settings.wake_steps(plate.chord, stream.velocity, time_step), n_times)


def _no_tape() -> tuple[np.ndarray, ...]:
    return (np.zeros((0, 3, 1)), np.zeros((0, 8)), np.zeros((0, 2), dtype=np.bool_),
            np.zeros((0, 3)))


def simulate_vortex_model(state: KinematicState, plate: Plate | None = None,
                          fluid: Fluid | None = None, stream: FreeStream | None = None,
                          settings: VortexModelSettings | None = None) -> VortexRun:
    """Run the discrete-vortex model through a motion that starts from rest.

    Parameters
    ----------
    state : KinematicState
        One motion on a uniform time base from its start: the plate, at rest in the stream
        before the first sample, takes the first sample's position (a motion that starts at
        rest from zero pitch and heave starts smoothly).
    plate, fluid, stream
        The package's defaults if omitted; the plate's thickness is ignored (thin plate).
    settings
        :class:`VortexModelSettings`; its defaults if omitted.

    Returns
    -------
    VortexRun

    Examples
    --------
    >>> import numpy as np
    >>> from mfflap.kinematics.continuous import HarmonicMotion
    >>> motion = HarmonicMotion(frequency=0.5, heave_amplitude=0.01, pitch_amplitude=0.0,
    ...                         phase=np.pi / 2)
    >>> run = simulate_vortex_model(motion.sample(np.arange(400) * 0.01))
    >>> bool(np.max(np.abs(run.total_circulation)) < 1e-12)
    True
    """
    plate, fluid, stream = plate or Plate(), fluid or Fluid(), stream or FreeStream()
    settings = settings or VortexModelSettings()
    dt = _uniform_time_step(state.time)
    _check_stream(stream)
    n_times = np.size(state.time)
    wake_steps = _wake_steps_for(settings, plate, stream, dt, n_times)
    kinematics = (np.ascontiguousarray(getattr(state, k), dtype=float) for k in (
        "heave_position", "heave_velocity", "pitch_angle", "pitch_rate"))
    out, xs, ys, gs = _march(*kinematics, plate.chord, plate.pivot_m, stream.velocity,
                             fluid.density, plate.span, dt, settings.critical_lesp,
                             (settings.core_radius_chords * plate.chord) ** 2,
                             settings.chord_points, wake_steps, *_no_tape())
    normal, tangential, moment, a0, gam_tev, gam_lev, total = out
    slot = n_times % wake_steps
    order = (slot - 1 - np.arange(wake_steps)) % wake_steps
    order = np.concatenate([order, wake_steps + order])
    keep = gs[order] != 0
    position, circulation = np.column_stack([xs, ys])[order][keep], gs[order][keep]
    loads = Loads(np.asarray(state.time, dtype=float), normal, tangential, moment,
                  source="discrete_vortex")
    return VortexRun(loads, a0, gam_tev, gam_lev, total, position, circulation, settings)


def vortex_loads(state: KinematicState, plate: Plate | None = None, fluid: Fluid | None = None,
                 stream: FreeStream | None = None,
                 settings: VortexModelSettings | None = None) -> Loads:
    """The loads of :func:`simulate_vortex_model`.

    Examples
    --------
    >>> import numpy as np
    >>> from mfflap.kinematics.continuous import HarmonicMotion
    >>> state = HarmonicMotion(frequency=1.0, heave_amplitude=0.3,
    ...                        pitch_amplitude=np.radians(20)).sample(np.arange(600) / 200)
    >>> loads = vortex_loads(state, settings=VortexModelSettings(wake_chords=1.0))
    >>> loads.normal_force.shape
    (600,)
    """
    return simulate_vortex_model(state, plate, fluid, stream, settings).loads
