"""Closed forms of linear unsteady thin-aerofoil theory for harmonic motion, written out here
independently of the models they check: Theodorsen's loads with the exact C(k) and Garrick's
leading-edge suction, for a plate of chord c = 2 b pitching about its leading edge.

With h = Re(h0 e^{i w t}) and theta = Re(theta0 e^{i w t}) (the package's signs: heave of the
leading edge along X0, pitch with the chord along (sin theta, cos theta)), the normal velocity
of the three-quarter-chord point is q = hdot + U theta + (3/2) b thetadot, and

    F_n = -pi rho b^2 s (hddot + U thetadot + b thetaddot) - 2 pi rho U b s C(k) q,
    M   = -pi rho b^3 s (hddot + 3/2 U thetadot + 9/8 b thetaddot) - pi rho U b^2 s C(k) q,
    S   = pi rho c s (C(k) q - (b / 2) thetadot)^2   (the suction, towards the leading edge),

k = w b / U. The mean thrust is mean(F_n theta) + mean(S) to second order and the mean input
power -mean(F_n hdot + M thetadot). Garrick (1936), NACA Report 567; Theodorsen (1935), NACA
Report 496.
"""

from __future__ import annotations

import numpy as np
from scipy.special import hankel2


def theodorsen(k: float) -> complex:
    h1, h0 = hankel2(1, k), hankel2(0, k)
    return complex(h1 / (h1 + 1j * h0))


def harmonic_means(frequency, heave_amplitude, pitch_amplitude, chord, span, density,
                   velocity, pitch_phase=0.0):
    """Complex amplitudes of F_n and M, the mean thrust and the mean power (N, N*m, N, W).

    Heave h0 cos(w t), pitch theta0 cos(w t + pitch_phase).
    """
    w, b = 2 * np.pi * frequency, chord / 2
    k = w * b / velocity
    c_k = theodorsen(k)
    h = heave_amplitude
    th = pitch_amplitude * np.exp(1j * pitch_phase)
    hd, hdd, thd, thdd = 1j * w * h, -w**2 * h, 1j * w * th, -w**2 * th
    q = hd + velocity * th + 1.5 * b * thd
    normal = (-np.pi * density * b**2 * span * (hdd + velocity * thd + b * thdd)
              - 2 * np.pi * density * velocity * b * span * c_k * q)
    moment = (-np.pi * density * b**3 * span * (hdd + 1.5 * velocity * thd + 9 / 8 * b * thdd)
              - np.pi * density * velocity * b**2 * span * c_k * q)
    suction = np.pi * density * chord * span * 0.5 * abs(c_k * q - b / 2 * thd) ** 2
    thrust = 0.5 * np.real(normal * np.conj(th)) + suction
    power = -0.5 * np.real(normal * np.conj(hd) + moment * np.conj(thd))
    # the sizes of the terms whose sums are the means (a mean near zero is a small
    # difference of large terms, and is compared on their scale)
    thrust_scale = 0.5 * abs(normal * np.conj(th)) + suction
    power_scale = 0.5 * (abs(normal * np.conj(hd)) + abs(moment * np.conj(thd)))
    return {"reduced_frequency": k, "normal_force": normal, "moment": moment,
            "thrust": thrust, "power": power, "thrust_scale": thrust_scale,
            "power_scale": power_scale}


def wagner_exact(reduced_time: float) -> float:
    """Wagner's function from Theodorsen's, Phi(s) = (2 / pi) int_0^inf F(k) / k sin(k s) dk
    (s > 0, semichords travelled; F = Re C)."""
    from scipy.integrate import quad

    def integrand(k):
        return (theodorsen(k).real / k) if k > 0 else 1.0

    value, _ = quad(integrand, 0, np.inf, weight="sin", wvar=reduced_time, limit=400)
    return 2 / np.pi * value
