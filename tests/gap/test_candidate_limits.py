"""Each gap candidate against the limit of the theory it is named for
(mfflap.gap.candidates), at unit coefficient, on motions where the theory's answer is a
closed form."""

import numpy as np
import pytest

from mfflap.gap.candidates.base import FlowContext
from mfflap.gap.diagnose import default_candidates
from mfflap.hydro.thin_aerofoil import JONES_WAGNER
from mfflap.kinematics.state import KinematicState
from mfflap.parameters import Fluid, FreeStream, Plate

PLATE, FLUID, STREAM = Plate(), Fluid(), FreeStream()
CANDIDATES = default_candidates(FlowContext(PLATE, FLUID, STREAM))
C, S, RHO, U = PLATE.chord, PLATE.span, FLUID.density, STREAM.velocity
Q_AREA = 0.5 * RHO * U**2 * C * S


def _state(t, pitch=0.0, pitch_rate=0.0, heave_velocity=0.0):
    """A plate at the leading edge's origin with the given (constant or per-sample) motion."""
    z = np.zeros_like(t)
    return KinematicState(t, z + pitch, z + pitch_rate, z, z, z + heave_velocity, z)


def test_circulatory_lift_is_thin_aerofoil_theory_at_small_steady_incidence():
    """F_n = -2 pi alpha q S (a = 2 pi) at c/4, with the incidence of the 3/4-chord point:
    a pitch rate adds 3/4 c thetadot / U to it."""
    t = np.linspace(0.0, 1.0, 11)
    alpha = np.radians(1.0)
    loads = CANDIDATES["circulatory_lift"].regressor(_state(t, pitch=alpha))
    expected = -Q_AREA * np.sin(alpha) * np.cos(alpha)  # per unit lift slope
    assert loads.normal_force == pytest.approx(expected, rel=1e-12)
    assert loads.moment == pytest.approx(0.25 * C * loads.normal_force)
    rate = 0.1
    turning = CANDIDATES["circulatory_lift"].regressor(_state(t, pitch_rate=rate))
    assert turning.normal_force == pytest.approx(-0.5 * RHO * C * S * U * 0.75 * C * rate)


def test_wake_lag_of_a_harmonic_incidence_is_jones_approximation_of_theodorsen():
    """A small harmonic pitch about the leading edge at reduced frequency k = w c / 2U:
    once settled, the lagged lift is the quasi-steady one through Jones' C(k) =
    1 - sum A_i i k / (i k + b_i), amplitude and phase."""
    k = 0.5
    omega = 2 * k * U / C
    t = np.linspace(0.0, 40 * 2 * np.pi / omega, 40001)
    amplitude = np.radians(0.5)
    theta = amplitude * np.sin(omega * t)
    state = KinematicState(t, theta, amplitude * omega * np.cos(omega * t),
                           -amplitude * omega**2 * np.sin(omega * t), *(np.zeros_like(t),) * 3)
    lagged = CANDIDATES["wake_lag"].regressor(state).normal_force
    steady = CANDIDATES["circulatory_lift"].regressor(state).normal_force
    late = t > t[-1] / 2
    basis = np.exp(1j * omega * t[late])
    ratio = (lagged[late] @ basis.conj()) / (steady[late] @ basis.conj())
    jones = 1 - sum(a * 1j * k / (1j * k + b) for a, b in JONES_WAGNER)
    assert abs(ratio) == pytest.approx(abs(jones), rel=0.01)
    assert np.angle(ratio) == pytest.approx(np.angle(jones), abs=0.01)


def test_rotational_lift_is_the_pitch_rate_at_three_quarter_chord_about_mid_chord():
    t = np.linspace(0.0, 1.0, 11)
    rate = 0.2
    loads = CANDIDATES["pitch_rate_lift"].regressor(_state(t, pitch_rate=rate))
    assert loads.normal_force == pytest.approx(-0.5 * RHO * C * S * U * rate * 0.5 * C)


def test_the_vortex_normal_force_grows_with_incidence_to_polhamus_at_90_degrees():
    """C_N,v = K_v sin^2 alpha: at 90 deg the full K_v q S, at 30 deg a quarter of it, and
    rising all the way (the vortex lift K_v cos a sin^2 a would fall above 55 deg)."""
    t = np.linspace(0.0, 1.0, 3)
    angles = np.radians([10.0, 30.0, 55.0, 75.0, 90.0])
    normal = np.array([CANDIDATES["leading_edge_vortex"].regressor(
        _state(t, pitch=a)).normal_force[0] for a in angles])
    assert normal[-1] == pytest.approx(-Q_AREA)
    assert normal[1] == pytest.approx(-Q_AREA * 0.25)
    assert np.all(np.diff(np.abs(normal)) > 0)


def test_added_mass_coupling_is_the_potential_flow_munk_moment():
    """A plate at incidence alpha in a steady stream: M = -m_a v_n v_t, the Munk moment
    rho pi (c/2)^2 s U^2 sin(alpha) cos(alpha) (nose-up sign convention of the model)."""
    t = np.linspace(0.0, 1.0, 3)
    alpha = np.radians(10.0)
    loads = CANDIDATES["added_mass_coupling"].regressor(_state(t, pitch=alpha))
    mass = RHO * np.pi * (C / 2) ** 2 * S
    assert loads.moment == pytest.approx(mass * U**2 * np.sin(alpha) * np.cos(alpha))
    assert loads.normal_force == pytest.approx(0.0)


def test_skin_friction_is_the_turbulent_flat_plate_law_on_both_faces():
    t = np.linspace(0.0, 1.0, 3)
    loads = CANDIDATES["turbulent_skin_friction"].regressor(_state(t))
    re = U * C / FLUID.kinematic_viscosity
    expected = 0.5 * RHO * 2 * C * S * 0.074 * re**-0.2 * U**2  # drag on the plate, along +t
    assert loads.tangential_force == pytest.approx(expected)


def test_laminar_skin_friction_is_blasius_on_both_faces():
    t = np.linspace(0.0, 1.0, 3)
    loads = CANDIDATES["laminar_skin_friction"].regressor(_state(t))
    re = U * C / FLUID.kinematic_viscosity
    expected = 0.5 * RHO * 2 * C * S * 1.328 / np.sqrt(re) * U**2
    assert loads.tangential_force == pytest.approx(expected)
    assert CANDIDATES["laminar_skin_friction"].family == "skin friction"
    assert CANDIDATES["turbulent_skin_friction"].family == "skin friction"


def test_dynamic_stall_takes_nothing_from_attached_flow():
    """Below the break incidence the flow stays attached (x = 1): no lift is lost."""
    t = np.linspace(0.0, 5.0, 51)
    loads = CANDIDATES["dynamic_stall"].regressor(_state(t, pitch=np.radians(3.0)))
    attached = Q_AREA * np.sin(np.radians(3.0))
    assert np.max(np.abs(loads.normal_force)) < 1e-4 * attached


def test_dynamic_stall_in_steady_flow_is_kirchhoff_on_the_static_separation_curve():
    """Held at incidence alpha long enough, x = x0(alpha), and the lift lost is
    a sin(alpha) [((1 + sqrt x0)/2)^2 - 1] q S: at 90 deg (x0 = 0) three quarters of the
    attached normal force, at the break incidence (x0 = 1/2) 1 - ((1 + 0.707)/2)^2."""
    from mfflap.gap.candidates.dynamic_stall import BREAK_INCIDENCE_RAD, static_separation

    assert static_separation(np.array([BREAK_INCIDENCE_RAD]))[0] == pytest.approx(0.5)
    t = np.linspace(0.0, 5.0, 51)
    for alpha, kept in ((np.pi / 2, 0.25), (BREAK_INCIDENCE_RAD, ((1 + 0.5**0.5) / 2)**2)):
        fn = CANDIDATES["dynamic_stall"].regressor(_state(t, pitch=alpha)).normal_force
        assert fn == pytest.approx(Q_AREA * np.sin(alpha) * (1.0 - kept), rel=1e-9)


def test_dynamic_stall_separates_with_the_convective_lag_of_the_relative_flow():
    """A step from attached flow to 40 deg: the separation state relaxes as
    exp(-t V / (2 c)) (tau1 = 2 convective times), so the lift lost reaches
    1 - 1/e of its steady value after 2 c / V, and twice as fast at twice the speed."""
    from mfflap.gap.candidates.dynamic_stall import separation_state

    for speed in (U, 2 * U):
        t = np.linspace(0.0, 20 * C / speed, 2001)
        alpha = np.where(t > 0, np.radians(40.0), 0.0)
        x = separation_state(t, alpha, np.zeros_like(t), np.full_like(t, speed), C)
        x0 = 1.0 / (1.0 + np.exp(57.0 * (np.radians(40.0) - np.radians(15.0))))
        at_tau = np.interp(2 * C / speed, t, x)
        assert (1 - at_tau) / (1 - x0) == pytest.approx(1 - np.exp(-1.0), rel=2e-2)
