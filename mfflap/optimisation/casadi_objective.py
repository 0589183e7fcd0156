"""The same penalised objective built symbolically in CasADi, for reverse-mode AD.

CasADi is imported here only. Used to cross-check the hand-written adjoint and, later, by the
IPOPT formulation.
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from mfflap.kinematics.discrete import DiscreteMotion, initial_state_weights
from mfflap.optimisation.problem import FlappingProblem


def symbolic_stages(problem: FlappingProblem, n_steps: int) -> dict[str, ca.SX]:
    """Symbolic z = [pitch acc (N), heave acc (N), dt] and, per step, thrust, input power,
    heave position and the two accelerations, as CasADi SX expressions."""
    n = n_steps
    z = ca.SX.sym("z", 2 * n + 1)
    dt = z[2 * n]
    w = ca.DM(initial_state_weights(n))
    states = {}
    for name, acc in (("pitch", z[:n]), ("heave", z[n:2 * n])):
        rate1 = -0.5 * dt * ca.sum1(acc)
        pos1 = dt**2 * ca.dot(w, acc)
        rates = rate1 + dt * ca.vertcat(0, ca.cumsum(acc)[:-1])
        next_rates = rates + dt * acc  # rate_{j+1}
        positions = pos1 + dt * ca.vertcat(0, ca.cumsum(next_rates)[:-1])
        if problem.scheme == "midpoint":
            rates = rates + 0.5 * dt * acc
        states[name] = (positions, rates, acc)
    th, td, tdd = states["pitch"]
    hp, hd, hdd = states["heave"]
    m = problem.model
    g, rho, u = m.geometry, m.fluid.density, m.stream.velocity
    c = m.coefficients
    s, co = ca.sin(th), ca.cos(th)
    an = hd * co + u * s
    adn = hdd * co - hd * td * s + u * td * co
    vt = hd * s - u * co
    avt = hdd * s + hd * td * co + u * td * s
    kd = 0.5 * rho * c["normal_drag"] * g.area_normal / g.n_strips
    ka = c["normal_added_mass"] * rho * g.volume_normal / g.n_strips
    pos = np.asarray(g.positions)
    n_s = len(pos)
    fn = -ka * (n_s * adn + tdd * pos.sum())
    mo = -ka * (adn * pos.sum() + tdd * (pos**2).sum())
    q0, q1 = _strip_drag_sums(an, td, pos, g.chord)
    fn = fn - kd * q0
    mo = mo - kd * q1
    ft = (-c["tangential_added_mass"] * rho * g.volume_tangential * avt
          - 0.5 * rho * c["tangential_drag"] * g.area_tangential * ca.fabs(vt) * vt)
    thrust = fn * s - ft * co
    power = -(fn * co + ft * s) * hd - mo * td
    return {"z": z, "thrust": thrust, "power": power, "heave_position": hp,
            "pitch_angle": th, "pitch_rate": td,
            "pitch_acceleration": tdd, "heave_acceleration": hdd}


def _strip_drag_sums(a: ca.SX, b: ca.SX, positions: np.ndarray, chord: float
                     ) -> tuple[ca.SX, ca.SX]:
    """sum_k |v_k| v_k and sum_k |v_k| v_k l_k for v_k = a + b l_k, symbolically.

    For equal strips (l_k = c (2k - 1) / 2n) the sign of v_k changes once, at the strip count
    m below l* = -a/b, and the power sums of l_k over the first m strips are polynomials in m
    (sums of odd numbers' powers). This keeps the expression graph O(1) per step instead of
    O(strips), which makes CasADi's Hessian, and so IPOPT, several times cheaper. Unequal
    strips fall back to the strip-by-strip sum.
    """
    n = len(positions)
    h = chord / (2 * n)
    if not np.allclose(positions, h * (2 * np.arange(1, n + 1) - 1), rtol=1e-12, atol=0):
        q0 = q1 = 0
        for lk in positions:
            v = a + b * lk
            q0 = q0 + ca.fabs(v) * v
            q1 = q1 + ca.fabs(v) * v * lk
        return q0, q1

    def sums(m):  # sum over k = 1..m of l_k^p, p = 0..3
        return (m, h * m**2, h**2 * m * (4 * m**2 - 1) / 3, h**3 * m**2 * (2 * m**2 - 1))

    safe_b = ca.if_else(b == 0, 1.0, b)
    zero = -a / safe_b
    # strips with l_k < l*: k < (l*/h + 1)/2
    m = ca.fmin(ca.fmax(ca.ceil((zero / h + 1) / 2) - 1, 0), n)
    m = ca.if_else(b == 0, n, m)
    head, total = sums(m), sums(n)
    aa, ab2, bb = a * a, 2 * a * b, b * b
    f1 = aa * head[0] + ab2 * head[1] + bb * head[2]
    g1 = aa * head[1] + ab2 * head[2] + bb * head[3]
    ft = aa * total[0] + ab2 * total[1] + bb * total[2]
    gt = aa * total[1] + ab2 * total[2] + bb * total[3]
    sb = ca.sign(b)
    first = ca.if_else(b == 0, ca.sign(a), -sb)
    return (first - sb) * f1 + sb * ft, (first - sb) * g1 + sb * gt


def smoothness_expr(problem: FlappingProblem, pitch_acc: ca.SX, heave_acc: ca.SX) -> ca.SX:
    """J_s with its wrap term."""
    out = 0
    for eps, acc in ((problem.smoothing_pitch, pitch_acc), (problem.smoothing_heave, heave_acc)):
        d = acc[1:] - acc[:-1]
        out = out + 0.5 * eps * (ca.sumsqr(d) + (acc[0] + acc[acc.shape[0] - 1]) ** 2)
    return out


def build_objective(problem: FlappingProblem, n_steps: int) -> tuple[ca.Function, ca.Function]:
    """CasADi functions J(z) and dJ/dz(z) with z = [pitch acc (N), heave acc (N), dt]."""
    n = n_steps
    e = symbolic_stages(problem, n)
    z, thrust, power, hp = e["z"], e["thrust"], e["power"], e["heave_position"]
    p = problem
    peak = power
    if p.sample_offsets is not None:
        p._check_offsets(n)
        thrust = thrust + ca.DM(p.sample_offsets.thrust)
        peak = power + ca.DM(p.sample_offsets.peak_power)
        power = power + ca.DM(p.sample_offsets.power)
    stage = (-(1 - p.beta) * thrust + p.beta * power
             + 0.5 * p.penalty_power * ca.fmax(peak - p.max_power, 0) ** 2
             + 0.5 * p.penalty_heave * ca.fmax(ca.fabs(hp) - p.max_heave, 0) ** 2)
    for name, limit in p.pitch_limits.items():
        if np.isfinite(limit):
            stage = stage + 0.5 * p.penalty_pitch * (
                ca.fmax(ca.fabs(e[name]) - limit, 0) / limit) ** 2
    objective = ca.sum1(stage) / n + smoothness_expr(p, e["pitch_acceleration"],
                                                     e["heave_acceleration"])
    if p.linear_modifier is not None:
        objective = objective + ca.dot(ca.DM(p.linear_modifier.gradient),
                                       z - ca.DM(p.linear_modifier.centre))
    f = ca.Function("J", [z], [objective])
    grad = ca.Function("dJ", [z], [ca.gradient(objective, z)])
    return f, grad


def casadi_gradient(problem: FlappingProblem, motion: DiscreteMotion) -> np.ndarray:
    """Reverse-mode AD gradient [d/d pitch acc, d/d heave acc, d/d dt] of one motion."""
    _, grad = build_objective(problem, motion.n_steps)
    z = np.concatenate([motion.pitch_acceleration, motion.heave_acceleration,
                        [float(motion.time_step)]])
    return np.asarray(grad(z)).ravel()
