"""Compiled (numba) objective and discrete-adjoint gradient of one motion.

The same J and the same adjoint as :class:`mfflap.optimisation.problem.FlappingProblem`
(whose array code is the reference and stays in use for complex steps and batches), written
as three O(N) loops: the forward sweep of the semi-implicit Euler steps, the stage partials,
and the backward adjoint sweep. It covers the four-term Morison model with equal strips
(:func:`mfflap.sweep_kernel.kernel_constants`); the drag strip sums are closed-form
(:func:`mfflap.sweep_kernel.drag_sums`). Tested against the array code to rounding.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from mfflap.sweep_kernel import drag_abs_sums, drag_sums


@numba.njit(cache=True)
def objective_and_gradient(pitch_acc, heave_acc, dt, midpoint, want_gradient, u, chord,
                           n_strips, k_an, k_at, k_dn, k_dt, lbar, l2bar, beta, max_power,
                           max_heave, penalty_power, penalty_heave, smoothing_pitch,
                           smoothing_heave, grad_out):
    """J(u, dt); with ``want_gradient`` also fills ``grad_out`` = [dJ/d pitch_acc (N),
    dJ/d heave_acc (N), dJ/d dt].

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
    rate_p = np.empty(n)
    rate_h = np.empty(n)
    ang = np.empty(n)
    pos = np.empty(n)
    rp = -0.5 * dt * sp
    rh = -0.5 * dt * sh
    th = dt * dt * wp
    hp = dt * dt * wh
    for j in range(n):
        rate_p[j] = rp
        rate_h[j] = rh
        ang[j] = th
        pos[j] = hp
        rp += dt * pitch_acc[j]
        rh += dt * heave_acc[j]
        th += dt * rp
        hp += dt * rh
    # stage costs and their partials
    total = 0.0
    g_th = np.empty(n)
    g_td = np.empty(n)
    g_tdd = np.empty(n)
    g_hd = np.empty(n)
    g_hdd = np.empty(n)
    g_hp = np.empty(n)
    w_thrust = -(1.0 - beta)
    for j in range(n):
        tdd = pitch_acc[j]
        hdd = heave_acc[j]
        td = rate_p[j] + 0.5 * dt * tdd if midpoint else rate_p[j]
        hd = rate_h[j] + 0.5 * dt * hdd if midpoint else rate_h[j]
        s = math.sin(ang[j])
        c = math.cos(ang[j])
        an = hd * c + u * s
        adn = hdd * c - hd * td * s + u * td * c
        vt = hd * s - u * c
        avt = hdd * s + hd * td * c + u * td * s
        q0, q1 = drag_sums(an, td, ns, h)
        fn = -k_an * (adn + tdd * lbar) - k_dn * q0
        mo = -k_an * (adn * lbar + tdd * l2bar) - k_dn * q1
        ft = -k_at * avt - k_dt * abs(vt) * vt
        thrust = fn * s - ft * c
        power = -(fn * c + ft * s) * hd - mo * td
        excess_p = max(power - max_power, 0.0)
        excess_h = max(abs(pos[j]) - max_heave, 0.0)
        total += (w_thrust * thrust + beta * power + 0.5 * penalty_power * excess_p * excess_p
                  + 0.5 * penalty_heave * excess_h * excess_h)
        if not want_gradient:
            continue
        a0, a1, a2 = drag_abs_sums(an, td, ns, h)
        d0, d1, d2 = 2.0 * a0, 2.0 * a1, 2.0 * a2
        w_power = beta + penalty_power * excess_p
        abs_vt2 = 2.0 * abs(vt)
        fc_fs = fn * c + ft * s
        # theta
        d_an = -hd * s + u * c
        d_adn = -hdd * s - hd * td * c - u * td * s
        fn_z = -k_an * d_adn - k_dn * d0 * d_an
        mo_z = -k_an * d_adn * lbar - k_dn * d1 * d_an
        ft_z = -k_at * adn - k_dt * abs_vt2 * an
        t_z = fn_z * s - ft_z * c + fc_fs
        p_z = -(fn_z * c + ft_z * s) * hd - mo_z * td - (-fn * s + ft * c) * hd
        g_th[j] = w_thrust * t_z + w_power * p_z
        # theta rate
        d_adn = -hd * s + u * c
        fn_z = -k_an * d_adn - k_dn * d1
        mo_z = -k_an * d_adn * lbar - k_dn * d2
        ft_z = -k_at * an
        t_z = fn_z * s - ft_z * c
        p_z = -(fn_z * c + ft_z * s) * hd - mo_z * td - mo
        g_td[j] = w_thrust * t_z + w_power * p_z
        # theta acceleration
        fn_z = -k_an * lbar
        mo_z = -k_an * l2bar
        t_z = fn_z * s
        p_z = -(fn_z * c) * hd - mo_z * td
        g_tdd[j] = w_thrust * t_z + w_power * p_z
        # heave velocity
        d_adn = -td * s
        fn_z = -k_an * d_adn - k_dn * d0 * c
        mo_z = -k_an * d_adn * lbar - k_dn * d1 * c
        ft_z = -k_at * td * c - k_dt * abs_vt2 * s
        t_z = fn_z * s - ft_z * c
        p_z = -(fn_z * c + ft_z * s) * hd - mo_z * td - fc_fs
        g_hd[j] = w_thrust * t_z + w_power * p_z
        # heave acceleration
        fn_z = -k_an * c
        mo_z = -k_an * c * lbar
        ft_z = -k_at * s
        t_z = fn_z * s - ft_z * c
        p_z = -(fn_z * c + ft_z * s) * hd - mo_z * td
        g_hdd[j] = w_thrust * t_z + w_power * p_z
        # heave position (penalty only)
        sgn = 1.0 if pos[j] > 0 else (-1.0 if pos[j] < 0 else 0.0)
        g_hp[j] = penalty_heave * excess_h * sgn
    value = total / n
    # smoothness with its wrap term
    for eps, acc in ((smoothing_pitch, pitch_acc), (smoothing_heave, heave_acc)):
        ss = (acc[0] + acc[n - 1]) ** 2
        for j in range(n - 1):
            ss += (acc[j + 1] - acc[j]) ** 2
        value += 0.5 * eps * ss
    if not want_gradient:
        return value
    grad_dt = 0.0
    for dof in range(2):
        if dof == 0:
            acc, rate, g_rate, g_pos, g_acc, eps = (pitch_acc, rate_p, g_td, g_th, g_tdd,
                                                    smoothing_pitch)
            off = 0
        else:
            acc, rate, g_rate, g_pos, g_acc, eps = (heave_acc, rate_h, g_hd, g_hp, g_hdd,
                                                    smoothing_heave)
            off = n
        # backward sweep, lambda_{N+1} = 0
        lam_p_next = 0.0
        lam_r_next = 0.0
        sum_acc = 0.0
        sum_wacc = 0.0
        for j in range(n - 1, -1, -1):
            gr = g_rate[j] / n
            ga = g_acc[j] / n
            if midpoint:  # hydro rate = rate_j + dt acc_j / 2
                ga += 0.5 * dt * gr
                grad_dt += 0.5 * gr * acc[j]
            grad_out[off + j] = ga + dt * lam_r_next + dt * dt * lam_p_next
            grad_dt += acc[j] * lam_r_next + (rate[j] + 2.0 * dt * acc[j]) * lam_p_next
            lam_p = g_pos[j] / n + lam_p_next
            lam_r = gr + dt * lam_p_next + lam_r_next
            lam_p_next = lam_p
            lam_r_next = lam_r
            sum_acc += acc[j]
            sum_wacc += (2.0 * (j + 1) - n - 2.0) / 4.0 * acc[j]
        # chain through x_1(u, dt): rate_1 = -(dt/2) sum acc, pos_1 = dt^2 sum w_j acc_j
        for j in range(n):
            wj = (2.0 * (j + 1) - n - 2.0) / 4.0
            grad_out[off + j] += -0.5 * dt * lam_r_next + dt * dt * wj * lam_p_next
        grad_dt += -0.5 * sum_acc * lam_r_next + 2.0 * dt * sum_wacc * lam_p_next
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
    from mfflap.sweep_kernel import kernel_constants

    k = kernel_constants(problem.model)
    if k is None:
        return None
    return (float(k["u"]), float(k["chord"]), int(k["n_strips"]), float(k["k_an"]),
            float(k["k_at"]), float(k["k_dn"]), float(k["k_dt"]), float(k["lbar"]),
            float(k["l2bar"]), problem.beta, problem.max_power, problem.max_heave,
            problem.penalty_power, problem.penalty_heave, problem.smoothing_pitch,
            problem.smoothing_heave)
