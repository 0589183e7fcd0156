"""Compiled (numba) objective and discrete-adjoint gradient of one motion.

The same J and the same adjoint as :class:`mfflap.optimisation.problem.FlappingProblem`
(whose array code is the reference and stays in use for complex steps and batches), written
as two O(N) passes: the forward sweep of the semi-implicit Euler steps with the stage costs
and their partials, and the backward adjoint sweep of both degrees of freedom. It covers the
four-term Morison model with equal strips (:func:`mfflap.sweep_kernel.kernel_constants`);
the drag strip sums are closed-form
(:func:`mfflap.sweep_kernel.drag_sums_and_abs`). Tested against the array code to rounding.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from mfflap.sweep_kernel import drag_sums, drag_sums_and_abs, kernel_constants


@numba.njit(cache=True)
def objective_and_gradient(pitch_acc, heave_acc, dt, midpoint, want_gradient, u, chord,
                           n_strips, k_an, k_at, k_dn, k_dt, lbar, l2bar, beta, max_power,
                           max_heave, penalty_power, penalty_heave, smoothing_pitch,
                           smoothing_heave, max_pitch, max_pitch_rate, max_pitch_acc,
                           penalty_pitch, thrust_offset, power_offset, peak_offset, grad_out):
    """J(u, dt); with ``want_gradient`` also fills ``grad_out`` = [dJ/d pitch_acc (N),
    dJ/d heave_acc (N), dJ/d dt].

    ``thrust_offset``, ``power_offset`` and ``peak_offset`` are the per-sample offsets of
    :class:`~mfflap.optimisation.problem.SampleOffsets` (N each), or empty arrays for none.

    k_an = C_an rho V_n, k_at = C_at rho V_t, k_dn = C_Dn rho S_n / (2 n), k_dt = C_Dt rho S_t / 2
    (the constants of :func:`mfflap.sweep_kernel.kernel_constants`).
    """
    n = pitch_acc.shape[0]
    h = chord / (2.0 * n_strips)
    ns = float(n_strips)
    # initial state of the antisymmetric closure
    sp = 0.0
    sh = 0.0
    wp = 0.0
    wh = 0.0
    for j in range(n):
        wj = (2.0 * (j + 1) - n - 2.0) / 4.0
        sp += pitch_acc[j]
        sh += heave_acc[j]
        wp += wj * pitch_acc[j]
        wh += wj * heave_acc[j]
    # one forward pass: states, stage costs and (with the gradient) the stage partials,
    # kept per step in one row of ``work`` = [pitch rate, heave velocity, dL/d theta,
    # dL/d theta rate, dL/d theta acc, dL/d heave velocity, dL/d heave acc, dL/d heave]
    work = np.empty((n if want_gradient else 0, 8))
    rp = -0.5 * dt * sp
    rh = -0.5 * dt * sh
    th = dt * dt * wp
    hp = dt * dt * wh
    total = 0.0
    w_thrust = -(1.0 - beta)
    has_offsets = thrust_offset.shape[0] == n
    for j in range(n):
        tdd = pitch_acc[j]
        hdd = heave_acc[j]
        td = rp + 0.5 * dt * tdd if midpoint else rp
        hd = rh + 0.5 * dt * hdd if midpoint else rh
        s = math.sin(th)
        c = math.cos(th)
        an = hd * c + u * s
        adn = hdd * c - hd * td * s + u * td * c
        vt = hd * s - u * c
        avt = hdd * s + hd * td * c + u * td * s
        if want_gradient:
            q0, q1, a0, a1, a2 = drag_sums_and_abs(an, td, ns, h)
        else:
            q0, q1 = drag_sums(an, td, ns, h)
            a0 = a1 = a2 = 0.0
        fn = -k_an * (adn + tdd * lbar) - k_dn * q0
        mo = -k_an * (adn * lbar + tdd * l2bar) - k_dn * q1
        ft = -k_at * avt - k_dt * abs(vt) * vt
        thrust = fn * s - ft * c
        power = -(fn * c + ft * s) * hd - mo * td
        peak = power
        if has_offsets:
            thrust_j = thrust + thrust_offset[j]
            power_j = power + power_offset[j]
            peak = power + peak_offset[j]
        else:
            thrust_j = thrust
            power_j = power
        excess_p = max(peak - max_power, 0.0)
        excess_h = max(abs(hp) - max_heave, 0.0)
        # the pitch envelope: relative excesses (0 where the limit is inf)
        e_th = max(abs(th) - max_pitch, 0.0) / max_pitch
        e_td = max(abs(td) - max_pitch_rate, 0.0) / max_pitch_rate
        e_tdd = max(abs(tdd) - max_pitch_acc, 0.0) / max_pitch_acc
        total += (w_thrust * thrust_j + beta * power_j
                  + 0.5 * penalty_power * excess_p * excess_p
                  + 0.5 * penalty_heave * excess_h * excess_h
                  + 0.5 * penalty_pitch * (e_th * e_th + e_td * e_td + e_tdd * e_tdd))
        if want_gradient:
            d0, d1, d2 = 2.0 * a0, 2.0 * a1, 2.0 * a2
            w_power = beta + penalty_power * excess_p
            abs_vt2 = 2.0 * abs(vt)
            fc_fs = fn * c + ft * s
            row = work[j]
            row[0] = rp
            row[1] = rh
            # theta
            d_an = -hd * s + u * c
            d_adn = -hdd * s - hd * td * c - u * td * s
            fn_z = -k_an * d_adn - k_dn * d0 * d_an
            mo_z = -k_an * d_adn * lbar - k_dn * d1 * d_an
            ft_z = -k_at * adn - k_dt * abs_vt2 * an
            t_z = fn_z * s - ft_z * c + fc_fs
            p_z = -(fn_z * c + ft_z * s) * hd - mo_z * td - (-fn * s + ft * c) * hd
            row[2] = w_thrust * t_z + w_power * p_z
            # theta rate
            d_adn = -hd * s + u * c
            fn_z = -k_an * d_adn - k_dn * d1
            mo_z = -k_an * d_adn * lbar - k_dn * d2
            ft_z = -k_at * an
            t_z = fn_z * s - ft_z * c
            p_z = -(fn_z * c + ft_z * s) * hd - mo_z * td - mo
            row[3] = w_thrust * t_z + w_power * p_z
            # theta acceleration
            fn_z = -k_an * lbar
            mo_z = -k_an * l2bar
            row[4] = w_thrust * fn_z * s + w_power * (-(fn_z * c) * hd - mo_z * td)
            # heave velocity
            d_adn = -td * s
            fn_z = -k_an * d_adn - k_dn * d0 * c
            mo_z = -k_an * d_adn * lbar - k_dn * d1 * c
            ft_z = -k_at * td * c - k_dt * abs_vt2 * s
            t_z = fn_z * s - ft_z * c
            p_z = -(fn_z * c + ft_z * s) * hd - mo_z * td - fc_fs
            row[5] = w_thrust * t_z + w_power * p_z
            # heave acceleration
            fn_z = -k_an * c
            mo_z = -k_an * c * lbar
            ft_z = -k_at * s
            t_z = fn_z * s - ft_z * c
            p_z = -(fn_z * c + ft_z * s) * hd - mo_z * td
            row[6] = w_thrust * t_z + w_power * p_z
            # heave position (penalty only)
            row[7] = penalty_heave * excess_h * (1.0 if hp > 0 else (-1.0 if hp < 0 else 0.0))
            # the pitch envelope's share of the pitch angle, rate and acceleration partials
            if e_th > 0.0:
                row[2] += penalty_pitch * e_th / max_pitch * (1.0 if th > 0 else -1.0)
            if e_td > 0.0:
                row[3] += penalty_pitch * e_td / max_pitch_rate * (1.0 if td > 0 else -1.0)
            if e_tdd > 0.0:
                row[4] += penalty_pitch * e_tdd / max_pitch_acc * (1.0 if tdd > 0 else -1.0)
        # advance x_j -> x_{j+1} (semi-implicit Euler)
        rp += dt * tdd
        rh += dt * hdd
        th += dt * rp
        hp += dt * rh
    value = total / n
    # smoothness with its wrap term
    for eps, acc in ((smoothing_pitch, pitch_acc), (smoothing_heave, heave_acc)):
        ss = (acc[0] + acc[n - 1]) ** 2
        for j in range(n - 1):
            ss += (acc[j + 1] - acc[j]) ** 2
        value += 0.5 * eps * ss
    if not want_gradient:
        return value
    # backward adjoint sweep of both degrees of freedom, lambda_{N+1} = 0
    inv_n = 1.0 / n
    grad_dt = 0.0
    lp_p = 0.0  # pitch: lambda of the angle and of the rate at step j+1
    lr_p = 0.0
    lp_h = 0.0  # heave: lambda of the position and of the velocity
    lr_h = 0.0
    for j in range(n - 1, -1, -1):
        row = work[j]
        ap = pitch_acc[j]
        ah = heave_acc[j]
        gr_p = row[3] * inv_n
        gr_h = row[5] * inv_n
        ga_p = row[4] * inv_n
        ga_h = row[6] * inv_n
        if midpoint:  # hydro rate = rate_j + dt acc_j / 2
            ga_p += 0.5 * dt * gr_p
            ga_h += 0.5 * dt * gr_h
            grad_dt += 0.5 * (gr_p * ap + gr_h * ah)
        grad_out[j] = ga_p + dt * lr_p + dt * dt * lp_p
        grad_out[n + j] = ga_h + dt * lr_h + dt * dt * lp_h
        grad_dt += (ap * lr_p + (row[0] + 2.0 * dt * ap) * lp_p
                    + ah * lr_h + (row[1] + 2.0 * dt * ah) * lp_h)
        lr_p += gr_p + dt * lp_p
        lr_h += gr_h + dt * lp_h
        lp_p += row[2] * inv_n
        lp_h += row[7] * inv_n
    # chain through x_1(u, dt): rate_1 = -(dt/2) sum acc, angle_1 = dt^2 sum_j w_j acc_j;
    # and the smoothness term
    grad_dt += -0.5 * (sp * lr_p + sh * lr_h) + 2.0 * dt * (wp * lp_p + wh * lp_h)
    for j in range(n):
        wj = (2.0 * (j + 1) - n - 2.0) / 4.0
        grad_out[j] += -0.5 * dt * lr_p + dt * dt * wj * lp_p
        grad_out[n + j] += -0.5 * dt * lr_h + dt * dt * wj * lp_h
    for off, eps, acc in ((0, smoothing_pitch, pitch_acc), (n, smoothing_heave, heave_acc)):
        if eps != 0.0:
            for j in range(n - 1):
                d = acc[j + 1] - acc[j]
                grad_out[off + j] -= eps * d
                grad_out[off + j + 1] += eps * d
            wrap = acc[0] + acc[n - 1]
            grad_out[off] += eps * wrap
            grad_out[off + n - 1] += eps * wrap
    grad_out[2 * n] = grad_dt
    return value


def problem_constants(problem) -> tuple | None:
    """Arguments after ``want_gradient`` for :func:`objective_and_gradient`, or None when
    the problem's model is not the plain four-term Morison model with equal strips."""
    k = kernel_constants(problem.model)
    if k is None:
        return None
    return (float(k["u"]), float(k["chord"]), int(k["n_strips"]), float(k["k_an"]),
            float(k["k_at"]), float(k["k_dn"]), float(k["k_dt"]), float(k["lbar"]),
            float(k["l2bar"]), problem.beta, problem.max_power, problem.max_heave,
            problem.penalty_power, problem.penalty_heave, problem.smoothing_pitch,
            problem.smoothing_heave, problem.max_pitch, problem.max_pitch_rate,
            problem.max_pitch_acceleration, problem.penalty_pitch,
            *((_NO_OFFSETS,) * 3 if problem.sample_offsets is None else (
                problem.sample_offsets.thrust, problem.sample_offsets.power,
                problem.sample_offsets.peak_power)))


_NO_OFFSETS = np.empty(0)
