"""Linear unsteady thin-aerofoil theory: hand-derivable limits, and real OpenFOAM against it."""

import json
import math

import numpy as np
import pytest
from click.testing import CliRunner

from mfflap.cli.main import cli
from mfflap.errors import MotionError
from mfflap.hydro.morison import NormalAddedMass
from mfflap.hydro.thin_aerofoil import (
    added_mass_loads,
    jones_theodorsen_function,
    theodorsen_function,
    thin_aerofoil_loads,
    thin_aerofoil_loads_at,
    wagner_filter,
    wagner_function,
)
from mfflap.kinematics.continuous import HarmonicMotion
from mfflap.kinematics.state import KinematicState
from mfflap.parameters import Fluid, FreeStream, Plate, StripGeometry, StripSettings

RHO, CHORD, SPAN = 1000.0, 0.16, 0.18
B = CHORD / 2


def _state(t, pitch=None, heave=None):
    """A state from (value, rate, acceleration) triples of pitch and heave."""
    z = (np.zeros_like(t),) * 3
    p, h = pitch or z, heave or z
    return KinematicState(t, *p, *h)


def test_theodorsen_function_matches_its_tables_and_limits():
    # Theodorsen (1935), NACA Report 496: F + iG at k = 0.5 and 1
    assert theodorsen_function(0.5) == pytest.approx(0.5979 - 0.1507j, abs=1e-4)
    assert theodorsen_function(1.0) == pytest.approx(0.5394 - 0.1003j, abs=1e-4)
    assert abs(theodorsen_function(1e-4) - 1) < 2e-3  # quasi-steady
    assert abs(theodorsen_function(1e3) - 0.5) < 1e-3  # added mass only, half the lift
    with pytest.raises(MotionError, match="reduced frequency"):
        theodorsen_function(0.0)


def test_jones_wagner_function_implies_theodorsen_function_within_1_5_percent():
    k = np.logspace(-2, 1.5, 300)
    assert np.max(np.abs(jones_theodorsen_function(k) - theodorsen_function(k))) < 0.015
    assert wagner_function(0.0) == pytest.approx(0.5)
    assert wagner_function(1e4) == pytest.approx(1.0)


def test_wagner_filter_from_rest_and_from_equilibrium():
    t = np.linspace(0.0, 5.0, 50001)
    u = 0.3
    step = np.ones_like(t)
    from_rest = wagner_filter(step, t, u, CHORD, start="rest")
    assert from_rest[0] == pytest.approx(0.5)  # half the lift at once (added circulation)
    s = 2 * u * t / CHORD
    assert np.max(np.abs(from_rest - wagner_function(s))) < 1e-3
    assert np.allclose(wagner_filter(step, t, u, CHORD, start="equilibrium"), 1.0)
    with pytest.raises(MotionError, match="start"):
        wagner_filter(step, t, u, CHORD, start="later")


def test_still_fluid_limit_is_the_flat_plates_added_mass():
    """U = 0: F_n = -rho pi c^2/4 s hddot, and the added inertia about the leading edge is
    rho pi b^4 s (1/8 + 1) (the plate's about its centre plus m_a b^2)."""
    t = np.linspace(0.0, 1.0, 201)
    w = 2 * np.pi
    trig = (np.sin(w * t), w * np.cos(w * t), -w**2 * np.sin(w * t))
    still = FreeStream(velocity=0.0)
    heave = thin_aerofoil_loads(_state(t, heave=trig), stream=still)
    m_a = RHO * np.pi * CHORD**2 / 4 * SPAN
    assert np.allclose(heave.normal_force, -m_a * trig[2])
    assert np.allclose(heave.moment, -m_a * B * trig[2])  # acting at mid-chord
    pitch = thin_aerofoil_loads(_state(t, pitch=trig), stream=still)
    assert np.allclose(pitch.moment, -9 / 8 * np.pi * RHO * B**4 * SPAN * trig[2])
    assert np.all(heave.tangential_force == 0)


def test_a_plate_pitching_about_its_mid_chord_in_still_fluid():
    """U = 0, pivot at mid-chord: no normal force from pitch (the added mass is symmetric
    about the centre) and the flat plate's own added inertia there, rho pi b^4 s / 8."""
    t = np.linspace(0.0, 1.0, 201)
    w = 2 * np.pi
    trig = (np.sin(w * t), w * np.cos(w * t), -w**2 * np.sin(w * t))
    loads = thin_aerofoil_loads(_state(t, pitch=trig), plate=Plate(pivot_chord_fraction=0.5),
                                stream=FreeStream(velocity=0.0))
    assert np.allclose(loads.normal_force, 0.0, atol=1e-12)
    assert np.allclose(loads.moment, -np.pi * RHO * B**4 * SPAN / 8 * trig[2])


@pytest.mark.parametrize("pivot_chord_fraction", [0.25, 0.5])
def test_steady_lift_acts_at_the_quarter_chord_whatever_the_pivot(pivot_chord_fraction):
    """Held at 2 deg about the pivot: the same lift, and M = F_n (c / 4 - x_p) about it."""
    u, theta0 = 1.0, math.radians(2.0)
    t = np.linspace(0.0, 60.0, 60001)
    r = np.clip(t, 0.0, 1.0)
    state = _state(t, pitch=(theta0 * r, theta0 * np.where(t < 1.0, 1.0, 0.0),
                             np.zeros_like(t)))
    plate = Plate(pivot_chord_fraction=pivot_chord_fraction)
    loads = thin_aerofoil_loads(state, plate=plate, stream=FreeStream(velocity=u))
    lift_coefficient = -loads.normal_force[-1] / (0.5 * RHO * u**2 * CHORD * SPAN)
    assert lift_coefficient / theta0 == pytest.approx(2 * np.pi, rel=1e-3)
    arm = CHORD / 4 - plate.pivot_m
    assert loads.moment[-1] == pytest.approx(loads.normal_force[-1] * arm,
                                             abs=1e-3 * abs(loads.normal_force[-1]) * CHORD)


def test_strip_models_added_mass_is_the_theorys_in_f_n_not_in_m():
    """With C_an = 1 the strip sum's normal added mass (V = pi c^2/4 s at mid-chord) is
    potential flow's in F_n; in M it puts 4/3 pi rho b^4 s on thetaddot (potential flow: 9/8)
    and pi rho b^3 s U on thetadot (potential flow: 3/2 of it)."""
    t = np.linspace(0.0, 1.0, 101)
    small = HarmonicMotion(1.0, 1e-4, 1e-4, 0.3).sample(t)  # nonlinear terms ~1e-8
    stream = FreeStream()
    term = NormalAddedMass(StripGeometry.from_settings(Plate(), StripSettings()), Fluid(),
                           stream).regressor(small)
    theory = added_mass_loads(small, stream=stream)
    assert np.allclose(term.normal_force, theory.normal_force, rtol=1e-5, atol=1e-12)
    m_a = np.pi * RHO * B**2 * SPAN
    n = StripSettings().n_strips  # mean of l_k^2 at the strip centres: (c^2/3)(1 - 1/(4n^2))
    strip_inertia = 4 / 3 * (1 - 1 / (4 * n**2))
    strip_minus_theory = -m_a * B * ((1 - 1.5) * stream.velocity * small.pitch_rate
                                     + (strip_inertia - 9 / 8) * B * small.pitch_acceleration)
    assert np.allclose(term.moment - theory.moment, strip_minus_theory, rtol=1e-4, atol=1e-12)


def test_steady_incidence_gives_lift_slope_two_pi_at_the_quarter_chord():
    """Held at 2 deg long enough for the wake to settle: C_L = 2 pi alpha, M = F_n c / 4."""
    u, theta0 = 1.0, math.radians(2.0)
    t = np.linspace(0.0, 60.0, 60001)
    r = np.clip(t, 0.0, 1.0)  # a 1 s ramp to the incidence (rate and acceleration
    rate = np.where(t < 1.0, 1.0, 0.0)  # only in the first second)
    state = _state(t, pitch=(theta0 * r, theta0 * rate, np.zeros_like(t)))
    loads = thin_aerofoil_loads(state, stream=FreeStream(velocity=u))
    lift_coefficient = -loads.normal_force[-1] / (0.5 * RHO * u**2 * CHORD * SPAN)
    assert lift_coefficient / theta0 == pytest.approx(2 * np.pi, rel=1e-3)
    assert loads.moment[-1] == pytest.approx(loads.normal_force[-1] * CHORD / 4, rel=1e-3)
    assert loads.metadata["max_effective_incidence_deg"] == pytest.approx(
        math.degrees(math.atan(theta0 + 0.75 * CHORD * theta0 / u)), rel=1e-3)  # linearised


@pytest.mark.parametrize("mode", ["heave", "pitch"])
def test_harmonic_motion_settles_to_theodorsens_frequency_response(mode):
    """The time-domain loads of a harmonic motion, once the start has decayed, are
    Theodorsen's complex amplitudes (with the C(k) of Jones' Wagner function)."""
    u, f = 1.0, 2.0
    w = 2 * np.pi * f
    k = w * B / u
    t = np.arange(0.0, 12.0, 2e-4)
    amplitude = 0.01 if mode == "heave" else math.radians(2.0)
    motion = HarmonicMotion(f, amplitude if mode == "heave" else 0.0,
                            0.0 if mode == "heave" else amplitude, phase=0.0)
    loads = thin_aerofoil_loads(motion.sample(t), stream=FreeStream(velocity=u))
    last = t >= t[-1] - 1 / f  # one period, settled
    carrier = np.exp(1j * w * t[last])

    def amplitude_of(x):  # complex amplitude of x = Re(X e^{i w t})
        return 2 * np.mean(x[last] * np.conj(carrier))

    iw, c = 1j * w, jones_theodorsen_function(k)
    # motion = Re(a e^{iwt}) with a = -i amplitude (sin)
    a = -1j * amplitude
    m_a = np.pi * RHO * B**2 * SPAN
    if mode == "heave":
        q = iw * a
        fn = -m_a * iw**2 * a - 2 * np.pi * RHO * u * B * SPAN * c * q
        mo = -m_a * B * iw**2 * a - np.pi * RHO * u * B**2 * SPAN * c * q
    else:
        q = u * a + 1.5 * B * iw * a
        fn = -m_a * (u * iw + B * iw**2) * a - 2 * np.pi * RHO * u * B * SPAN * c * q
        mo = (-m_a * B * (1.5 * u * iw + 9 / 8 * B * iw**2) * a
              - np.pi * RHO * u * B**2 * SPAN * c * q)
    assert amplitude_of(loads.normal_force) == pytest.approx(fn, rel=2e-3)
    assert amplitude_of(loads.moment) == pytest.approx(mo, rel=2e-3)
    # against the exact C(k): Jones' approximation is off by about 0.01 (2 % here)
    assert abs(theodorsen_function(k) - c) < 0.015


def test_loads_at_uneven_times_agree_with_a_fine_grid():
    motion = HarmonicMotion(1.0, 0.005, 0.0, phase=0.0)
    fine = np.linspace(0.0, 2.0, 8001)
    reference = thin_aerofoil_loads(motion.sample(fine))
    rng = np.random.default_rng(3)
    uneven = np.sort(rng.uniform(0.3, 2.0, 97))  # a record that starts late, adaptive steps
    at = thin_aerofoil_loads_at(motion.sample, uneven)
    span = np.ptp(reference.normal_force)
    assert np.max(np.abs(at.normal_force - np.interp(uneven, fine, reference.normal_force))
                  ) < 2e-3 * span
    with pytest.raises(MotionError, match=">= 0"):
        thin_aerofoil_loads_at(motion.sample, np.array([-0.1, 0.5]))
    with pytest.raises(MotionError, match="1-D"):
        thin_aerofoil_loads(HarmonicMotion([1.0, 2.0], 0.01, 0.0).sample(fine))


def test_defaults_are_the_packages_plate_and_fluid():
    assert Plate().chord == CHORD and Plate().span == SPAN and Fluid().density == RHO


@pytest.mark.openfoam
@pytest.mark.parametrize(("motion", "pivot_chord_fraction", "max_nrmse", "min_pearson"), [
    ({"heave_amplitude": 0.005, "pitch_amplitude_deg": 0.0, "phase_deg": 0.0}, 0.0, 0.06, 0.99),
    ({"heave_amplitude": 0.0, "pitch_amplitude_deg": 2.0, "phase_deg": 90.0}, 0.0, 0.06, 0.99),
    # about the mid-chord the pitch drives about half the normal force (effective incidence
    # 3.4 deg, not 7.6 deg), so the same viscous departures are a larger share of it:
    # measured 6.0 % NRMSE, Pearson 0.985 in F_n; 2.3 %, 0.999 in M
    ({"heave_amplitude": 0.0, "pitch_amplitude_deg": 2.0, "phase_deg": 90.0}, 0.5, 0.08, 0.98),
], ids=["heave-5mm", "pitch-2deg", "pitch-2deg-about-mid-chord"])
def test_real_openfoam_small_motions_match_linear_theory(tmp_path, motion,
                                                         pivot_chord_fraction, max_nrmse,
                                                         min_pearson):
    """Two cycles of a small heave or pitch at f = 1 Hz (k = 1.7, effective incidence below
    8 deg) on the coarse mesh: the CFD's F_n and M about the moving pivot, through the whole
    adapter chain (motion table, frames, span scaling, moment transfer, the mesh placed about
    the pivot), follow Theodorsen's theory in amplitude and phase. Measured: 3-4 % NRMSE,
    Pearson 0.996-0.997, the same on the medium mesh; the strip model, which has no
    circulation, is 21-24 % off."""
    case = tmp_path / "small.toml"
    case.write_text("[motion]\nkind = \"harmonic\"\nfrequency = 1.0\n" + "".join(
        f"{key} = {value}\n" for key, value in motion.items())
        + f"[plate]\npivot_chord_fraction = {pivot_chord_fraction}\n")
    runner = CliRunner()
    case_dir = tmp_path / "of"
    res = runner.invoke(cli, ["cfd", "write", str(case), str(case_dir), "--cycles", "2",
                              "--ramp-time", "0.25"])
    assert res.exit_code == 0, res.output
    res = runner.invoke(cli, ["cfd", "run", str(case_dir), "--timeout", "600"])
    assert res.exit_code == 0, res.output
    res = runner.invoke(cli, ["cfd", "parse", str(case_dir), "--case-file", str(case),
                              "--discard", "0.5", "--thin-aerofoil", "--json"])
    assert res.exit_code == 0, res.output
    out = json.loads(res.stdout)
    theory = out["thin_aerofoil"]
    assert theory["max_effective_incidence_deg"] < 10
    for name in ("normal_force", "moment"):
        assert theory[f"nrmse_{name}"] < max_nrmse, (name, theory)
        assert theory[f"pearson_{name}"] > min_pearson, (name, theory)
    assert out["nrmse_normal_force"] > 3 * theory["nrmse_normal_force"]
    assert out["cfd_mean_power"] == pytest.approx(theory["mean_power"], rel=0.3)


def test_wagner_filter_clocked_by_a_varying_speed_and_started_at_the_mean():
    """The wake's clock is the distance travelled: a constant speed given per sample is the
    scalar speed, twice the speed runs the lag twice as fast; a periodic input started at
    its mean's equilibrium has no slow transient, unlike one started at its first value."""
    t = np.linspace(0.0, 20.0, 4001)
    x = (t >= 1.0).astype(float)
    u = 0.3
    same = wagner_filter(x, t, np.full_like(t, u), CHORD, start="rest")
    assert np.allclose(same, wagner_filter(x, t, u, CHORD, start="rest"), atol=1e-12)
    fast = wagner_filter(x, t, np.full_like(t, 2 * u), CHORD, start="rest")
    later = (t > 1.0) & (t < 10.0)  # the slow run at twice the time since the step
    assert np.allclose(fast[later], np.interp(1.0 + 2 * (t[later] - 1.0), t, same),
                       atol=5e-3)
    periodic = np.cos(2 * np.pi * 0.5 * t) + 0.2
    long_t = np.linspace(0.0, 60.0, 12001)  # 40 s earlier: the same phase, settled
    settled = wagner_filter(np.cos(2 * np.pi * 0.5 * long_t) + 0.2, long_t, u,
                            CHORD)[-len(t):]
    from_mean = wagner_filter(periodic, t, u, CHORD)
    from_first = wagner_filter(periodic, t, u, CHORD, start="rest")  # a far start
    early = t < 4.0
    assert np.max(np.abs(from_mean - settled)[early]) < 0.5 * np.max(
        np.abs(from_first - settled)[early])
