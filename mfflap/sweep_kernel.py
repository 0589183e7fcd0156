"""A fused, compiled kernel for the sinusoidal sweep (numba): one pass per motion.

It evaluates exactly what :func:`mfflap.performance.evaluate_discrete` evaluates for a
harmonic motion converted by :func:`mfflap.kinematics.convert.harmonic_to_discrete` (the
paper's or the midpoint scheme, the Morison model with closed-form strip sums), without the
(motions x N x strips) temporaries of the array version. Tested against it to 1e-9.
"""

from __future__ import annotations

import math

import numba
import numpy as np


@numba.njit(cache=True, inline="always")
def _drag_sums(a, b, n, h):
    """sum |v|v, sum |v|v l and sum |v|^3 over equal strips, v = a + b l (closed form)."""
    if b == 0.0:
        m = n
        first = 1.0 if a > 0 else (-1.0 if a < 0 else 0.0)
        sb = 0.0
    else:
        zero = -a / b
        m = math.ceil((zero / h + 1.0) / 2.0) - 1.0
        m = min(max(m, 0.0), n)
        sb = 1.0 if b > 0 else -1.0
        first = -sb
    w = first - sb
    s0h, s1h = m, h * m * m
    s2h = h * h * m * (4.0 * m * m - 1.0) / 3.0
    s3h = h * h * h * m * m * (2.0 * m * m - 1.0)
    s0t, s1t = n, h * n * n
    s2t = h * h * n * (4.0 * n * n - 1.0) / 3.0
    s3t = h * h * h * n * n * (2.0 * n * n - 1.0)
    aa, ab2, bb = a * a, 2.0 * a * b, b * b
    q0 = w * (aa * s0h + ab2 * s1h + bb * s2h) + sb * (aa * s0t + ab2 * s1t + bb * s2t)
    q1 = w * (aa * s1h + ab2 * s2h + bb * s3h) + sb * (aa * s1t + ab2 * s2t + bb * s3t)
    c0, c1, c2, c3 = a * aa, 3.0 * aa * b, 3.0 * a * bb, b * bb
    cube = (w * (c0 * s0h + c1 * s1h + c2 * s2h + c3 * s3h)
            + sb * (c0 * s0t + c1 * s1t + c2 * s2t + c3 * s3t))
    return q0, q1, cube


@numba.njit(parallel=True, cache=True)
def sweep_kernel(f, ha, ta, ph, n_steps, midpoint, u, chord, n_strips, k_an, k_at, k_dn,
                 k_dt, lbar, l2bar, out):
    """Fill ``out[:, 0:6]`` = mean thrust, mean power, max power, energy residual,
    trailing-edge amplitude, (unused) for every motion.

    k_an = C_an rho V_n, k_at = C_at rho V_t, k_dn = C_Dn rho S_n / (2 n), k_dt = C_Dt rho S_t / 2.
    """
    n = n_steps
    h = chord / (2.0 * n_strips)
    step = math.pi / n
    factor_s = -4.0 * math.sin(step / 2.0) ** 2
    sin_j = np.empty(n)
    cos_j = np.empty(n)
    for j in range(n):
        sin_j[j] = math.sin(step * j)
        cos_j[j] = math.cos(step * j)
    for i in numba.prange(f.shape[0]):
        dt = 1.0 / (2.0 * n * f[i])
        fac = factor_s / (dt * dt)
        cp, sph = math.cos(ph[i]), math.sin(ph[i])
        # x_1 of the closure, for pitch and heave
        sp = 0.0
        sh = 0.0
        wp = 0.0
        wh = 0.0
        for j in range(n):
            ap = fac * ta[i] * sin_j[j]
            ah = fac * ha[i] * (sin_j[j] * cp + cos_j[j] * sph)
            sp += ap
            sh += ah
            wj = (2.0 * (j + 1) - n - 2.0) / 4.0
            wp += wj * ap
            wh += wj * ah
        rp = -0.5 * dt * sp
        rh = -0.5 * dt * sh
        th = dt * dt * wp
        hp = dt * dt * wh
        sum_t = 0.0
        sum_p = 0.0
        sum_d = 0.0
        pmax = -1e300
        te_max = -1e300
        te_min = 1e300
        for j in range(n):
            tdd = fac * ta[i] * sin_j[j]
            hdd = fac * ha[i] * (sin_j[j] * cp + cos_j[j] * sph)
            td = rp + 0.5 * dt * tdd if midpoint else rp
            hd = rh + 0.5 * dt * hdd if midpoint else rh
            s = math.sin(th)
            c = math.cos(th)
            an = hd * c + u * s
            adn = hdd * c - hd * td * s + u * td * c
            vt = hd * s - u * c
            avt = hdd * s + hd * td * c + u * td * s
            q0, q1, cube = _drag_sums(an, td, float(n_strips), h)
            fn = -k_an * (adn + tdd * lbar) - k_dn * q0
            mo = -k_an * (adn * lbar + tdd * l2bar) - k_dn * q1
            ft = -k_at * avt - k_dt * abs(vt) * vt
            thrust = fn * s - ft * c
            power = -(fn * c + ft * s) * hd - mo * td
            sum_t += thrust
            sum_p += power
            sum_d += k_dn * cube + k_dt * abs(vt) ** 3
            if power > pmax:
                pmax = power
            te = hp + chord * s
            te_max = max(te_max, te)
            te_min = min(te_min, te)
            # advance x_j -> x_{j+1} (semi-implicit Euler)
            rp += dt * tdd
            rh += dt * hdd
            th += dt * rp
            hp += dt * rh
        mt = sum_t / n
        mp = sum_p / n
        out[i, 0] = mt
        out[i, 1] = mp
        out[i, 2] = pmax
        out[i, 3] = mp - u * mt - sum_d / n
        out[i, 4] = max(abs(te_max), abs(te_min))


def kernel_constants(model) -> dict[str, float] | None:
    """Constants of a MorisonModel for the kernel; None if its strips are not equal."""
    g, rho, c = model.geometry, model.fluid.density, model.coefficients
    pos = np.asarray(g.positions)
    n = len(pos)
    h = g.chord / (2 * n)
    if not np.allclose(pos, h * (2 * np.arange(1, n + 1) - 1), rtol=1e-12, atol=0):
        return None
    if set(c) != {"normal_added_mass", "tangential_added_mass", "normal_drag",
                  "tangential_drag"}:
        return None
    return {"u": model.stream.velocity, "chord": g.chord, "n_strips": n,
            "k_an": c["normal_added_mass"] * rho * g.volume_normal,
            "k_at": c["tangential_added_mass"] * rho * g.volume_tangential,
            "k_dn": c["normal_drag"] * 0.5 * rho * g.area_normal / n,
            "k_dt": c["tangential_drag"] * 0.5 * rho * g.area_tangential,
            "lbar": float(pos.mean()), "l2bar": float((pos**2).mean())}
