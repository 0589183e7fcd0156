"""A fused, compiled kernel for the sinusoidal sweep (numba): the whole grid in one pass.

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
def _split(a, b, n, h):
    """Strips l_k = h (2k - 1), k = 1..n, of v = a + b l: the count m of the first run
    (one sign), the sign weight w of that run relative to the rest, and the rest's sign sb.
    Any sum_k sign(v_k) P(v_k, l_k) is w * P(first m strips) + sb * P(all strips)."""
    if b == 0.0:
        return n, (1.0 if a > 0 else (-1.0 if a < 0 else 0.0)), 0.0
    zero = -a / b
    m = math.ceil((zero / h + 1.0) / 2.0) - 1.0
    m = min(max(m, 0.0), n)
    sb = 1.0 if b > 0 else -1.0
    return m, -2.0 * sb, sb


@numba.njit(cache=True, inline="always")
def _power_sums(m, h):
    """sum_{k<=m} l_k^p for p = 0..3, l_k = h (2k - 1)."""
    return (m, h * m * m, h * h * m * (4.0 * m * m - 1.0) / 3.0,
            h * h * h * m * m * (2.0 * m * m - 1.0))


@numba.njit(cache=True, inline="always")
def _square_sums(a, b, w, sb, hs, ts):
    """sum_k |v_k| v_k and sum_k |v_k| v_k l_k from the split (w, sb) and the power sums of
    the first run (hs) and of all strips (ts)."""
    aa, ab2, bb = a * a, 2.0 * a * b, b * b
    q0 = w * (aa * hs[0] + ab2 * hs[1] + bb * hs[2]) + sb * (aa * ts[0] + ab2 * ts[1]
                                                             + bb * ts[2])
    q1 = w * (aa * hs[1] + ab2 * hs[2] + bb * hs[3]) + sb * (aa * ts[1] + ab2 * ts[2]
                                                             + bb * ts[3])
    return q0, q1


@numba.njit(cache=True, inline="always")
def drag_sums(a, b, n, h):
    """sum_k |v_k| v_k and sum_k |v_k| v_k l_k over n equal strips, v = a + b l (closed form)."""
    m, w, sb = _split(a, b, n, h)
    return _square_sums(a, b, w, sb, _power_sums(m, h), _power_sums(n, h))


@numba.njit(cache=True, inline="always")
def drag_sums_and_abs(a, b, n, h):
    """:func:`drag_sums` and sum_k |v_k| l_k^p for p = 0, 1, 2 (their derivatives), with one
    split of the strips."""
    m, w, sb = _split(a, b, n, h)
    hs, ts = _power_sums(m, h), _power_sums(n, h)
    q0, q1 = _square_sums(a, b, w, sb, hs, ts)
    return (q0, q1, w * (a * hs[0] + b * hs[1]) + sb * (a * ts[0] + b * ts[1]),
            w * (a * hs[1] + b * hs[2]) + sb * (a * ts[1] + b * ts[2]),
            w * (a * hs[2] + b * hs[3]) + sb * (a * ts[2] + b * ts[3]))


@numba.njit(cache=True, inline="always")
def _sums_and_cube_given_split(a, b, m, w, sb, h, n):
    """sum |v|v, sum |v|v l and sum |v|^3 over n equal strips, v = a + b l, for the split
    (m, w, sb) of :func:`_split` (the caller may hoist the b-only part of the split)."""
    hs, ts = _power_sums(m, h), _power_sums(n, h)
    q0, q1 = _square_sums(a, b, w, sb, hs, ts)
    c0, c1, c2, c3 = a * a * a, 3.0 * a * a * b, 3.0 * a * b * b, b * b * b
    cube = (w * (c0 * hs[0] + c1 * hs[1] + c2 * hs[2] + c3 * hs[3])
            + sb * (c0 * ts[0] + c1 * ts[1] + c2 * ts[2] + c3 * ts[3]))
    return q0, q1, cube


@numba.njit(cache=True, inline="always")
def _integrate_unit_step(acc, position, rate):
    """The semi-implicit Euler steps with the antisymmetric closure at dt = 1: fill
    ``position`` and ``rate`` (at dt, rate / dt and acc / dt^2 with the same positions)."""
    n = acc.shape[0]
    s_a = 0.0
    s_w = 0.0
    for j in range(n):
        s_a += acc[j]
        s_w += (2.0 * (j + 1) - n - 2.0) / 4.0 * acc[j]
    r = -0.5 * s_a
    x = s_w
    for j in range(n):
        position[j] = x
        rate[j] = r
        r += acc[j]
        x += r


@numba.njit(cache=True)
def _pitch_sequences(ta, n):
    """Per pitch amplitude: angle, its sine and cosine, R and A with rate = R / dt and
    acceleration = A / dt^2 (the discrete harmonic's angles do not depend on dt)."""
    step = math.pi / n
    factor = -4.0 * math.sin(step / 2.0) ** 2
    out = np.empty((ta.shape[0], 5, n))
    for i in range(ta.shape[0]):
        for j in range(n):
            out[i, 4, j] = factor * ta[i] * math.sin(step * j)
        _integrate_unit_step(out[i, 4], out[i, 0], out[i, 3])
        for j in range(n):
            out[i, 1, j] = math.sin(out[i, 0, j])
            out[i, 2, j] = math.cos(out[i, 0, j])
    return out


@numba.njit(cache=True)
def _heave_sequences(ph, n):
    """Per phase, for unit heave amplitude: position P, V and B with velocity = V / dt and
    acceleration = B / dt^2."""
    step = math.pi / n
    factor = -4.0 * math.sin(step / 2.0) ** 2
    out = np.empty((ph.shape[0], 3, n))
    for i in range(ph.shape[0]):
        cp, sph = math.cos(ph[i]), math.sin(ph[i])
        for j in range(n):
            out[i, 2, j] = factor * (math.sin(step * j) * cp + math.cos(step * j) * sph)
        _integrate_unit_step(out[i, 2], out[i, 0], out[i, 1])
    return out


@numba.njit(parallel=True, cache=True)
def sweep_grid_kernel(f, ha, ta, ph, start, stop, n_steps, midpoint, u, chord, n_strips, k_an,
                      k_at, k_dn, k_dt, lbar, l2bar, out):
    """Evaluate the grid f x ha x ta x ph (C order, like ``np.meshgrid(..., indexing="ij")``
    raveled) for the (f, ta, ph) combinations ``start <= g < stop`` (g = (i_f nt + i_t) np
    + i_p) and every heave amplitude; ``out[motion, 0:5]`` = mean thrust, mean power, max
    power, energy residual, trailing-edge amplitude, with ``out`` the whole grid's rows.

    A discrete harmonic of N steps at dt = 1 / (2 N f) has angles and positions that do not
    depend on f, rates that scale with 1/dt and accelerations with 1/dt^2 (see
    :func:`mfflap.kinematics.convert.harmonic_to_discrete`): the sequences are computed once
    per pitch amplitude and per phase, so the grid loop needs no sine or cosine. The pitch
    quantities are shared by all heave amplitudes, which form the innermost, vectorisable
    loop. k_an = C_an rho V_n, k_at = C_at rho V_t, k_dn = C_Dn rho S_n / (2 n),
    k_dt = C_Dt rho S_t / 2.
    """
    n = n_steps
    h = chord / (2.0 * n_strips)
    ns = float(n_strips)
    pitch = _pitch_sequences(ta, n)
    heave = _heave_sequences(ph, n)
    nh, nt, npp = ha.shape[0], ta.shape[0], ph.shape[0]
    for g in numba.prange(start, stop):
        i_p = g % npp
        i_t = (g // npp) % nt
        i_f = g // (npp * nt)
        inv_dt = 2.0 * n * f[i_f]
        inv_dt2 = inv_dt * inv_dt
        sum_t = np.zeros(nh)
        sum_p = np.zeros(nh)
        sum_d = np.zeros(nh)
        pmax = np.full(nh, -1e300)
        te_max = np.full(nh, -1e300)
        te_min = np.full(nh, 1e300)
        for j in range(n):
            s = pitch[i_t, 1, j]
            c = pitch[i_t, 2, j]
            tdd = pitch[i_t, 4, j] * inv_dt2
            if midpoint:
                td = (pitch[i_t, 3, j] + 0.5 * pitch[i_t, 4, j]) * inv_dt
                vel = (heave[i_p, 1, j] + 0.5 * heave[i_p, 2, j]) * inv_dt
            else:
                td = pitch[i_t, 3, j] * inv_dt
                vel = heave[i_p, 1, j] * inv_dt
            acc = heave[i_p, 2, j] * inv_dt2
            pos = heave[i_p, 0, j]
            us, utc = u * s, u * td * c
            # the strips' sign split depends on a through -a / b only
            if td == 0.0:
                sb = 0.0
                inv_b = 0.0
            else:
                sb = 1.0 if td > 0 else -1.0
                inv_b = 1.0 / td
            for k in range(nh):
                amp = ha[k]
                hd = amp * vel
                hdd = amp * acc
                an = hd * c + us
                adn = hdd * c - hd * td * s + utc
                vt = hd * s - u * c
                avt = hdd * s + hd * td * c + u * td * s
                if td == 0.0:
                    m = ns
                    w = 1.0 if an > 0 else (-1.0 if an < 0 else 0.0)
                else:
                    m = math.ceil((-an * inv_b / h + 1.0) / 2.0) - 1.0
                    m = min(max(m, 0.0), ns)
                    w = -2.0 * sb
                q0, q1, cube = _sums_and_cube_given_split(an, td, m, w, sb, h, ns)
                fn = -k_an * (adn + tdd * lbar) - k_dn * q0
                mo = -k_an * (adn * lbar + tdd * l2bar) - k_dn * q1
                ft = -k_at * avt - k_dt * abs(vt) * vt
                power = -(fn * c + ft * s) * hd - mo * td
                sum_t[k] += fn * s - ft * c
                sum_p[k] += power
                sum_d[k] += k_dn * cube + k_dt * abs(vt) * vt * vt
                pmax[k] = max(pmax[k], power)
                te = amp * pos + chord * s
                te_max[k] = max(te_max[k], te)
                te_min[k] = min(te_min[k], te)
        for k in range(nh):
            row = ((i_f * nh + k) * nt + i_t) * npp + i_p
            mt = sum_t[k] / n
            mp = sum_p[k] / n
            out[row, 0] = mt
            out[row, 1] = mp
            out[row, 2] = pmax[k]
            out[row, 3] = mp - u * mt - sum_d[k] / n
            out[row, 4] = max(abs(te_max[k]), abs(te_min[k]))


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
