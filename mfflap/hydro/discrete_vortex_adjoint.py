"""The reverse sweep of the discrete-vortex model: exact gradients of its loads.

For cotangents (gF_n, gF_t, gM) of the loads at every step, :func:`vortex_loads_vjp` returns
the gradient of sum_j gF_n,j F_n,j + gF_t,j F_t,j + gM_j M_j with respect to every step's heave,
heave rate, pitch and pitch rate and the time step: the discrete adjoint of the model's march
(:mod:`mfflap.hydro.discrete_vortex`), the same arithmetic run backwards, so the gradient is
that of the discretised model to round-off rather than an approximation of it.

The forward march records the wake before each step (the tape); the sweep goes from the last
step to the first, recomputes each step's solution from its tape and carries the adjoint of
the wake (every free vortex's position and circulation, and the impulse of those that left
the ring) back through the wake's motion, the loads, the shedding, the bound circulation's
solve, the plate's geometry and the ring's far-wake cut-off. Whether a step sheds from the
leading edge is held as it was: the gradient is that of the branch the motion takes, which
is the derivative wherever |A_0| does not sit on the critical value. The tape holds
3 x 2 x (wake steps) numbers per step; the sweep costs three to seven forward marches
(benchmarks/vortex_gradient.py).

References
----------
M. B. Giles and N. A. Pierce (2000), An introduction to the adjoint approach to design,
Flow Turbul. Combust. 65, 393-415 (the discrete adjoint of a time march).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numba
import numpy as np

from mfflap.errors import ConfigError
from mfflap.hydro.discrete_vortex import (
    AUX_DROPPED,
    AUX_DROPPED_ANG,
    AUX_DROPPED_X,
    AUX_DROPPED_Y,
    AUX_LEV_X,
    AUX_LEV_Y,
    AUX_TEV_X,
    AUX_TEV_Y,
    W_A_LEV,
    W_A_TEV,
    W_BOUND,
    W_PX,
    W_PY,
    VortexModelSettings,
    _check_stream,
    _induced,
    _march,
    _quadrature,
    _sheet,
    _solve_step,
    _uniform_time_step,
    _wake_steps_for,
    _wake_velocity,
)
from mfflap.hydro.loads import Loads
from mfflap.kinematics.state import KinematicState
from mfflap.parameters import Fluid, FreeStream, Plate


@numba.njit(cache=True, inline="always")
def _induced_adjoint(x, y, xs, ys, gs, core2, u_bar, v_bar, xs_bar, ys_bar, gs_bar, sign):
    """Reverse of :func:`_induced` for sources of circulation sign * gs: accumulates the
    sources' adjoints and returns the adjoint of the point (x, y)."""
    x_bar = y_bar = 0.0
    for k in range(xs.size):
        if gs[k] != 0.0:
            dx, dy = x - xs[k], y - ys[k]
            r2 = dx * dx + dy * dy + core2
            w = sign * gs[k] / (2 * math.pi * r2)
            w_bar = -u_bar * dy + v_bar * dx
            r2_bar = -w_bar * w / r2
            dx_bar = v_bar * w + 2 * dx * r2_bar
            dy_bar = -u_bar * w + 2 * dy * r2_bar
            gs_bar[k] += sign * w_bar / (2 * math.pi * r2)
            x_bar += dx_bar
            y_bar += dy_bar
            xs_bar[k] -= dx_bar
            ys_bar[k] -= dy_bar
    return x_bar, y_bar


@numba.njit(cache=True, inline="always")
def _sheet_adjoint(x, y, x1, y1, x2, y2, u_bar, v_bar):
    """Reverse of :func:`_sheet`: the adjoints of (x, y, x1, y1, x2, y2). The conjugate
    velocity u - i v = f(z, z1, z2) is holomorphic in each point, so the adjoint of a point
    is (Re, -Im) of (u_bar + i v_bar) df/dz."""
    z, z1, z2 = complex(x, y), complex(x1, y1), complex(x2, y2)
    d = 2j * math.pi * (z2 - z1)
    f = np.log((z - z1) / (z - z2)) / d
    c_bar = complex(u_bar, v_bar)
    g = c_bar * (1 / (z - z1) - 1 / (z - z2)) / d
    g1 = c_bar * (-1 / ((z - z1) * d) + f / (z2 - z1))
    g2 = c_bar * (1 / ((z - z2) * d) - f / (z2 - z1))
    return g.real, -g.imag, g1.real, -g1.imag, g2.real, -g2.imag


@numba.njit(cache=True)
def _march_adjoint(heave, heave_rate, pitch, pitch_rate, chord, pivot, velocity, density,
                   span, time_step, critical_lesp, core2, n_points, wake_steps, tape_wake,
                   tape_aux, tape_flags, tape_impulse, g_normal, g_tangential, g_moment):
    """The reverse sweep (module docstring): returns the adjoints of heave, heave rate,
    pitch, pitch rate (one per step) and of the time step."""
    n_times = heave.size
    n_wake = 2 * wake_steps
    x_chord, fourier, sheet = _quadrature(chord, velocity, n_points)
    kelvin_scale = math.pi * chord * velocity
    scale = density * span / time_step
    h_bar, hd_bar = np.zeros(n_times), np.zeros(n_times)
    th_bar, thd_bar = np.zeros(n_times), np.zeros(n_times)
    dt_bar = 0.0
    xs_bar, ys_bar, gs_bar = np.zeros(n_wake), np.zeros(n_wake), np.zeros(n_wake)
    aux_bar = np.zeros(8)
    prev_bar, prev2_bar = np.zeros(3), np.zeros(3)
    xs, ys, gs, g1 = np.empty(n_wake), np.empty(n_wake), np.empty(n_wake), np.empty(n_wake)
    aux = np.empty(8)
    work = np.empty((7, n_points))
    prev_imp, prev2_imp = np.zeros(3), np.zeros(3)
    px_bar, py_bar, bound_bar = np.empty(n_points), np.empty(n_points), np.empty(n_points)
    for j in range(n_times - 1, -1, -1):
        slot, lev_slot = j % wake_steps, wake_steps + j % wake_steps
        shift = velocity * time_step * j
        xs[:], ys[:], gs[:] = tape_wake[j, 0], tape_wake[j, 1], tape_wake[j, 2]
        aux[:] = tape_aux[j]
        lev_was_shed = tape_flags[j, 0]
        prev_imp[:] = 0.0
        prev2_imp[:] = 0.0
        if j >= 1:
            prev_imp[:] = tape_impulse[j - 1]
        if j >= 2:
            prev2_imp[:] = tape_impulse[j - 2]
        res = _solve_step(j, heave, heave_rate, pitch, pitch_rate, chord, pivot, velocity,
                          density, span, time_step, critical_lesp, core2, wake_steps, x_chord,
                          fourier, sheet, xs, ys, gs, aux, lev_was_shed, prev_imp, prev2_imp,
                          work)
        shed, gam_tev, gam_lev = res[3], res[4], res[5]
        imp_x, imp_y, ang = res[7], res[8], res[9]
        c, s_, tx, ty, tex, tey, lex, ley, k_tev, k_lev = res[10]
        h, hd, thd = heave[j], heave_rate[j], pitch_rate[j]
        lx, ly = pivot * (1 - c), h - pivot * s_  # the leading edge
        px, py, bound = work[W_PX], work[W_PY], work[W_BOUND]
        a_tev, a_lev = work[W_A_TEV], work[W_A_LEV]
        g1[:] = gs
        g1[slot] = g1[lev_slot] = 0.0  # the ring after the drop, before this step's vortices
        px_bar[:] = 0.0
        py_bar[:] = 0.0
        bound_bar[:] = 0.0
        c_bar = s_bar = shift_bar = lx_bar = ly_bar = 0.0
        # the last shed vortices' positions, taken after the wake moved
        xs_bar[slot] += aux_bar[AUX_TEV_X]
        ys_bar[slot] += aux_bar[AUX_TEV_Y]
        xs_bar[lev_slot] += aux_bar[AUX_LEV_X]
        ys_bar[lev_slot] += aux_bar[AUX_LEV_Y]
        # the wake's motion: x' = x + dt (U + u(x)) for every free vortex
        xb2, yb2, gb2 = xs_bar.copy(), ys_bar.copy(), gs_bar.copy()
        for k in range(n_wake):
            if gs[k] != 0.0:
                uk, vk = _wake_velocity(k, xs, ys, gs, work, velocity, core2)
                dt_bar += xs_bar[k] * uk + ys_bar[k] * vk
                ub, vb = time_step * xs_bar[k], time_step * ys_bar[k]
                a, b = _induced_adjoint(xs[k], ys[k], px, py, bound, core2, ub, vb, px_bar,
                                        py_bar, bound_bar, -1.0)
                xb2[k] += a
                yb2[k] += b
                a, b = _induced_adjoint(xs[k], ys[k], xs, ys, gs, core2, ub, vb, xb2, yb2,
                                        gb2, 1.0)
                xb2[k] += a
                yb2[k] += b
        # the loads from the impulse's backward difference, turned into the plate's axes
        if j == 0:
            fx, fy, mo = -scale * imp_x, -scale * imp_y, scale * ang / 2
        else:
            fx = -scale * (1.5 * imp_x - 2 * prev_imp[0] + 0.5 * prev2_imp[0])
            fy = -scale * (1.5 * imp_y - 2 * prev_imp[1] + 0.5 * prev2_imp[1])
            mo = scale * (1.5 * ang - 2 * prev_imp[2] + 0.5 * prev2_imp[2]) / 2
        gn, gt, gm = g_normal[j], g_tangential[j], g_moment[j]
        fx_bar = -gn * s_ + gt * c + gm * h
        fy_bar = gn * c + gt * s_ + gm * (shift - pivot)
        mo_bar = gm
        s_bar += -gn * fx + gt * fy
        c_bar += gn * fy + gt * fx
        h_bar[j] += gm * fx
        shift_bar += gm * fy
        dt_bar -= (fx_bar * fx + fy_bar * fy + mo_bar * mo) / time_step
        weight = 1.0 if j == 0 else 1.5
        imp_bar = np.array([-weight * scale * fx_bar, -weight * scale * fy_bar,
                            weight * scale * mo_bar / 2]) + prev_bar
        new_prev_bar = prev2_bar.copy()
        new_prev2_bar = np.zeros(3)
        if j > 0:
            new_prev_bar += np.array([2 * scale * fx_bar, 2 * scale * fy_bar, -scale * mo_bar])
            new_prev2_bar[:] = np.array([-0.5 * scale * fx_bar, -0.5 * scale * fy_bar,
                                         0.25 * scale * mo_bar])
        # the impulse of the wake and of the bound sheet
        ibx, iby, iba = imp_bar[0], imp_bar[1], imp_bar[2]
        for k in range(n_wake):
            if gs[k] != 0.0:
                xr = xs[k] - shift
                gb2[k] += ibx * ys[k] - iby * xr + iba * (xr * xr + ys[k] * ys[k])
                yb2[k] += ibx * gs[k] + iba * 2 * gs[k] * ys[k]
                xr_bar = -iby * gs[k] + iba * 2 * gs[k] * xr
                xb2[k] += xr_bar
                shift_bar -= xr_bar
        for i in range(n_points):
            xr = px[i] - shift
            bound_bar[i] += -ibx * py[i] + iby * xr - iba * (xr * xr + py[i] * py[i])
            py_bar[i] += -ibx * bound[i] - iba * 2 * bound[i] * py[i]
            xr_bar = iby * bound[i] - iba * 2 * bound[i] * xr
            px_bar[i] += xr_bar
            shift_bar -= xr_bar
        aux_bar[AUX_DROPPED_X] += ibx
        aux_bar[AUX_DROPPED_Y] += iby
        aux_bar[AUX_DROPPED_ANG] += iba
        # this step's shed vortices at the centres of their sheets
        tx_bar = tex_bar = xb2[slot] / 2
        ty_bar = tey_bar = yb2[slot] / 2
        gam_tev_bar, gam_lev_bar = gb2[slot], gb2[lev_slot]
        lex_bar = lx_bar = xb2[lev_slot] / 2
        ley_bar = ly_bar = yb2[lev_slot] / 2
        for k in (slot, lev_slot):
            xb2[k] = yb2[k] = gb2[k] = 0.0
        # the bound circulation and the solve for the shed circulations
        coeffs_bar = sheet.T @ bound_bar
        a_known_bar = coeffs_bar.copy()
        a_tev_bar = gam_tev * coeffs_bar
        a_lev_bar = gam_lev * coeffs_bar
        gam_tev_bar += coeffs_bar @ a_tev
        gam_lev_bar += coeffs_bar @ a_lev
        if shed:
            det = a_tev[0] * (1 - k_lev) - a_lev[0] * (1 - k_tev)
            lam0 = (gam_tev_bar * (1 - k_lev) - (1 - k_tev) * gam_lev_bar) / det
            lam1 = (a_tev[0] * gam_lev_bar - a_lev[0] * gam_tev_bar) / det
            a_tev_bar[0] -= lam0 * gam_tev
            a_lev_bar[0] -= lam0 * gam_lev
            a_known_bar[0] -= lam0
            k_tev_bar, k_lev_bar = lam1 * gam_tev, lam1 * gam_lev
        else:
            lam1 = gam_tev_bar / (1 - k_tev)
            k_tev_bar, k_lev_bar = lam1 * gam_tev, 0.0
        k_known_bar, free_bar = lam1, -lam1
        for k in range(n_wake):
            if g1[k] != 0.0:
                gb2[k] += free_bar
        aux_bar[AUX_DROPPED] += free_bar
        for a_bar, k_bar in ((a_known_bar, k_known_bar), (a_tev_bar, k_tev_bar),
                             (a_lev_bar, k_lev_bar)):
            a_bar[0] += kelvin_scale * k_bar
            a_bar[1] += kelvin_scale * k_bar / 2
        w_known_bar = fourier.T @ a_known_bar
        w_tev_bar = fourier.T @ a_tev_bar
        w_lev_bar = fourier.T @ a_lev_bar
        # the shed sheets' velocity on the plate
        for i in range(n_points):
            wb = w_tev_bar[i]
            u, v = _sheet(px[i], py[i], tx, ty, tex, tey)
            s_bar -= wb * u
            c_bar += wb * v
            adj = _sheet_adjoint(px[i], py[i], tx, ty, tex, tey, -wb * s_, wb * c)
            px_bar[i] += adj[0]
            py_bar[i] += adj[1]
            tx_bar += adj[2]
            ty_bar += adj[3]
            tex_bar += adj[4]
            tey_bar += adj[5]
            wb = w_lev_bar[i]
            u, v = _sheet(px[i], py[i], lx, ly, lex, ley)
            s_bar -= wb * u
            c_bar += wb * v
            adj = _sheet_adjoint(px[i], py[i], lx, ly, lex, ley, -wb * s_, wb * c)
            px_bar[i] += adj[0]
            py_bar[i] += adj[1]
            lx_bar += adj[2]
            ly_bar += adj[3]
            lex_bar += adj[4]
            ley_bar += adj[5]
        # the sheets reach two thirds of the way to the last shed vortices
        tx_bar += tex_bar / 3
        ty_bar += tey_bar / 3
        aux_bar[AUX_TEV_X] = 2 * tex_bar / 3
        aux_bar[AUX_TEV_Y] = 2 * tey_bar / 3
        if lev_was_shed:
            lx_bar += lex_bar / 3
            ly_bar += ley_bar / 3
            aux_bar[AUX_LEV_X] = 2 * lex_bar / 3
            aux_bar[AUX_LEV_Y] = 2 * ley_bar / 3
        else:
            # lex = lx + dt (U - pivot s theta'), ley = ly - dt (h' - pivot c theta')
            lx_bar += lex_bar
            ly_bar += ley_bar
            dt_bar += ((velocity - pivot * s_ * thd) * lex_bar
                       - (hd - pivot * c * thd) * ley_bar)
            s_bar -= time_step * pivot * thd * lex_bar
            c_bar += time_step * pivot * thd * ley_bar
            thd_bar[j] += time_step * pivot * (c * ley_bar - s_ * lex_bar)
            hd_bar[j] -= time_step * ley_bar
            aux_bar[AUX_LEV_X] = aux_bar[AUX_LEV_Y] = 0.0
        # the normal velocity the plate cancels: its motion, the stream and the wake
        for i in range(n_points):
            wu, wv = _induced(px[i], py[i], xs, ys, g1, core2)
            wb = w_known_bar[i]
            s_bar += wb * (-velocity - wu)
            c_bar += wb * (-hd + wv)
            hd_bar[j] -= wb * c
            thd_bar[j] -= wb * (x_chord[i] - pivot)
            a, b = _induced_adjoint(px[i], py[i], xs, ys, g1, core2, -wb * s_, wb * c, xb2,
                                    yb2, gb2, 1.0)
            px_bar[i] += a
            py_bar[i] += b
        # the plate's points and trailing edge, lx + x c and ly + x s, and the leading edge
        for i in range(n_points):
            c_bar += px_bar[i] * x_chord[i]
            s_bar += py_bar[i] * x_chord[i]
            lx_bar += px_bar[i]
            ly_bar += py_bar[i]
        c_bar += tx_bar * chord
        s_bar += ty_bar * chord
        lx_bar += tx_bar
        ly_bar += ty_bar
        c_bar -= pivot * lx_bar
        s_bar -= pivot * ly_bar
        h_bar[j] += ly_bar
        th_bar[j] += -c_bar * s_ + s_bar * c
        # the oldest vortices left the ring at this step's start
        for k in (slot, lev_slot):
            g0 = tape_wake[j, 2, k]
            if g0 != 0.0:
                x0, y0 = tape_wake[j, 0, k], tape_wake[j, 1, k]
                xr = x0 - shift
                gb2[k] = (aux_bar[AUX_DROPPED] + aux_bar[AUX_DROPPED_X] * y0
                          - aux_bar[AUX_DROPPED_Y] * xr
                          + aux_bar[AUX_DROPPED_ANG] * (xr * xr + y0 * y0))
                yb2[k] = aux_bar[AUX_DROPPED_X] * g0 + aux_bar[AUX_DROPPED_ANG] * 2 * g0 * y0
                xr_bar = -aux_bar[AUX_DROPPED_Y] * g0 + aux_bar[AUX_DROPPED_ANG] * 2 * g0 * xr
                xb2[k] = xr_bar
                shift_bar -= xr_bar
        dt_bar += velocity * j * shift_bar
        xs_bar[:], ys_bar[:], gs_bar[:] = xb2, yb2, gb2
        prev_bar[:], prev2_bar[:] = new_prev_bar, new_prev2_bar
    # the last trailing-edge vortex before the first step
    th0 = pitch[0]
    th_bar[0] += (chord - pivot) * (-math.sin(th0) * aux_bar[AUX_TEV_X]
                                    + math.cos(th0) * aux_bar[AUX_TEV_Y])
    h_bar[0] += aux_bar[AUX_TEV_Y]
    hd_bar[0] -= 1.5 * time_step * aux_bar[AUX_TEV_Y]
    dt_bar += 1.5 * velocity * aux_bar[AUX_TEV_X] - 1.5 * heave_rate[0] * aux_bar[AUX_TEV_Y]
    return h_bar, hd_bar, th_bar, thd_bar, dt_bar


@dataclass(frozen=True)
class VortexLoadsGradient:
    """The loads of a discrete-vortex run and the gradient of a weighted sum of them.

    Attributes
    ----------
    loads : Loads
        The run's F_n, F_t (N) and M about the pivot (N*m).
    heave_position, heave_velocity, pitch_angle, pitch_rate : ndarray
        d(sum) / d(each step's h [m], h' [m/s], theta [rad], theta' [rad/s]), in the sum's
        units per unit of each.
    time_step : float
        d(sum) / d(dt) at fixed samples of the motion, per second.
    """

    loads: Loads
    heave_position: np.ndarray
    heave_velocity: np.ndarray
    pitch_angle: np.ndarray
    pitch_rate: np.ndarray
    time_step: float


def vortex_loads_vjp(state: KinematicState, normal_weight: np.ndarray,
                     tangential_weight: np.ndarray, moment_weight: np.ndarray,
                     plate: Plate | None = None, fluid: Fluid | None = None,
                     stream: FreeStream | None = None,
                     settings: VortexModelSettings | None = None) -> VortexLoadsGradient:
    """The gradient of sum_j (a_j F_n,j + b_j F_t,j + c_j M_j) of the discrete-vortex model
    with respect to the motion's samples and the time step, by the reverse sweep.

    Parameters
    ----------
    state : KinematicState
        The motion, as for :func:`~mfflap.hydro.discrete_vortex.simulate_vortex_model`.
    normal_weight, tangential_weight, moment_weight : ndarray
        a_j (1/N), b_j (1/N) and c_j (1/(N*m)) for every sample, or the loads' cotangents.
    plate, fluid, stream, settings
        As for the forward model.

    Returns
    -------
    VortexLoadsGradient

    Examples
    --------
    The gradient of the mean normal force with respect to the heave rate, against a
    central difference:

    >>> import numpy as np
    >>> from dataclasses import replace
    >>> from mfflap.kinematics.continuous import HarmonicMotion
    >>> state = HarmonicMotion(frequency=1.0, heave_amplitude=0.1,
    ...                        pitch_amplitude=0.3).sample(0.01 + np.arange(100) / 100)
    >>> settings = VortexModelSettings(wake_chords=0.5, chord_points=16,
    ...                                core_radius_chords=0.1)
    >>> a, zero = np.full(100, 1 / 100), np.zeros(100)
    >>> grad = vortex_loads_vjp(state, a, zero, zero, settings=settings)
    >>> from mfflap.hydro.discrete_vortex import vortex_loads
    >>> def mean_fn(rate):
    ...     moved = replace(state, heave_velocity=rate)
    ...     return vortex_loads(moved, settings=settings).normal_force.mean()
    >>> e = np.zeros(100); e[40] = 1e-6
    >>> fd = (mean_fn(state.heave_velocity + e) - mean_fn(state.heave_velocity - e)) / 2e-6
    >>> bool(abs(grad.heave_velocity[40] - fd) < 1e-5 * abs(fd))
    True
    """
    return record_vortex_run(state, plate, fluid, stream, settings).gradient(
        normal_weight, tangential_weight, moment_weight)


@dataclass(frozen=True, eq=False)
class TapedVortexRun:
    """A forward run of the discrete-vortex model with its tape: its loads, and the gradient
    of any weighted sum of them by the reverse sweep (:meth:`gradient`), without running the
    model forward again. Made by :func:`record_vortex_run`.

    Attributes
    ----------
    loads : Loads
        The run's F_n, F_t (N) and M about the pivot (N*m).
    """

    loads: Loads
    _time: np.ndarray
    _kinematics: tuple
    _constants: tuple
    _tape: tuple

    def gradient(self, normal_weight: np.ndarray, tangential_weight: np.ndarray,
                 moment_weight: np.ndarray) -> VortexLoadsGradient:
        """The gradient of sum_j (a_j F_n,j + b_j F_t,j + c_j M_j), as
        :func:`vortex_loads_vjp` returns it."""
        n_times = self._time.size
        weights = [np.ascontiguousarray(w, dtype=float) for w in (
            normal_weight, tangential_weight, moment_weight)]
        for name, w in zip(("normal_weight", "tangential_weight", "moment_weight"), weights,
                           strict=True):
            if w.shape != (n_times,):
                raise ConfigError(f"{name} must have one value per sample ({n_times}), got "
                                  f"shape {w.shape}", key=name)
        h_bar, hd_bar, th_bar, thd_bar, dt_bar = _march_adjoint(
            *self._kinematics, *self._constants, *self._tape, *weights)
        return VortexLoadsGradient(self.loads, h_bar, hd_bar, th_bar, thd_bar, float(dt_bar))


def record_vortex_run(state: KinematicState, plate: Plate | None = None,
                      fluid: Fluid | None = None, stream: FreeStream | None = None,
                      settings: VortexModelSettings | None = None) -> TapedVortexRun:
    """Run the discrete-vortex model forward keeping the tape its reverse sweep needs (the
    wake before every step: 3 x 2 x (wake steps) numbers a step).

    Examples
    --------
    >>> import numpy as np
    >>> from mfflap.kinematics.continuous import HarmonicMotion
    >>> state = HarmonicMotion(frequency=1.0, heave_amplitude=0.1,
    ...                        pitch_amplitude=0.3).sample(0.01 + np.arange(50) / 100)
    >>> run = record_vortex_run(state, settings=VortexModelSettings(wake_chords=0.5))
    >>> weight = np.full(50, 1 / 50)
    >>> grad = run.gradient(weight, 0 * weight, 0 * weight)  # d(mean F_n)
    >>> grad.pitch_rate.shape
    (50,)
    """
    plate, fluid, stream = plate or Plate(), fluid or Fluid(), stream or FreeStream()
    settings = settings or VortexModelSettings()
    _check_stream(stream)
    dt = _uniform_time_step(state.time)
    n_times = np.size(state.time)
    wake_steps = _wake_steps_for(settings, plate, stream, dt, n_times)
    kinematics = tuple(np.ascontiguousarray(getattr(state, k), dtype=float) for k in (
        "heave_position", "heave_velocity", "pitch_angle", "pitch_rate"))
    constants = (plate.chord, plate.pivot_m, stream.velocity, fluid.density, plate.span, dt,
                 settings.critical_lesp, (settings.core_radius_chords * plate.chord) ** 2,
                 settings.chord_points, wake_steps)
    tape = (np.empty((n_times, 3, 2 * wake_steps)), np.empty((n_times, 8)),
            np.empty((n_times, 2), dtype=np.bool_), np.empty((n_times, 3)))
    out, _, _, _ = _march(*kinematics, *constants, *tape)
    time = np.asarray(state.time, dtype=float)
    loads = Loads(time, out[0], out[1], out[2], source="discrete_vortex")
    return TapedVortexRun(loads, time, kinematics, constants, tape)


__all__ = ["TapedVortexRun", "VortexLoadsGradient", "record_vortex_run", "vortex_loads_vjp"]
