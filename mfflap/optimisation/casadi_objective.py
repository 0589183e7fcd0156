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
    fn = 0
    mo = 0
    for lk in g.positions:
        v = an + td * lk
        fk = -ka * (adn + tdd * lk) - kd * ca.fabs(v) * v
        fn = fn + fk
        mo = mo + fk * lk
    ft = (-c["tangential_added_mass"] * rho * g.volume_tangential * avt
          - 0.5 * rho * c["tangential_drag"] * g.area_tangential * ca.fabs(vt) * vt)
    thrust = fn * s - ft * co
    power = -(fn * co + ft * s) * hd - mo * td
    return {"z": z, "thrust": thrust, "power": power, "heave_position": hp,
            "pitch_acceleration": tdd, "heave_acceleration": hdd}


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
    stage = (-(1 - p.beta) * thrust + p.beta * power
             + 0.5 * p.penalty_power * ca.fmax(power - p.max_power, 0) ** 2
             + 0.5 * p.penalty_heave * ca.fmax(ca.fabs(hp) - p.max_heave, 0) ** 2)
    objective = ca.sum1(stage) / n + smoothness_expr(p, e["pitch_acceleration"],
                                                     e["heave_acceleration"])
    f = ca.Function("J", [z], [objective])
    grad = ca.Function("dJ", [z], [ca.gradient(objective, z)])
    return f, grad


def casadi_gradient(problem: FlappingProblem, motion: DiscreteMotion) -> np.ndarray:
    """Reverse-mode AD gradient [d/d pitch acc, d/d heave acc, d/d dt] of one motion."""
    _, grad = build_objective(problem, motion.n_steps)
    z = np.concatenate([motion.pitch_acceleration, motion.heave_acceleration,
                        [float(motion.time_step)]])
    return np.asarray(grad(z)).ravel()
