"""The force bound of a moving plate: derived by hand, real runs inside it, runs that lost
their numerics outside it, and identification leaving those out."""

from pathlib import Path

import numpy as np
import pytest

from mfflap.errors import MfflapError
from mfflap.hydro.loads import Loads
from mfflap.identification.data import ENVELOPE_NOTE, prepare_case
from mfflap.kinematics.state import KinematicState
from mfflap.parameters import Fluid, FreeStream, Plate
from mfflap.records.bursts import bridge_load_bursts, find_load_bursts
from mfflap.records.force_envelope import (
    BREACH_FACTOR,
    FLOW_START_STEPS,
    MAX_NORMAL_FORCE_COEFFICIENT,
    envelope_ratio,
    find_envelope_breaches,
    normal_force_bound_n,
)
from mfflap.records.record import fixture_dir, read_record, read_records

ROOT = Path(__file__).parents[2]
#: Table 1 runs (max Co 4) that lost their numerics, as first shipped, kept as test data;
#: the fixtures now hold their reruns
LOST_DATA = ROOT / "tests" / "data" / "openfoam_v1912" / "lost_numerics"
LOST = {"f1p000_h0p500_phi135p0": 0.79, "f0p500_h0p500_phi135p0": 4.0}
#: and the one whose burst's slower aftermath (t = 3.09-3.14 s) leaves the bound briefly
AFTERMATH = "f0p500_h0p300_phi090p0"
PLATE, FLUID, STREAM = Plate(), Fluid(), FreeStream()


def _state(time, heave=None, pitch=None):
    """A KinematicState from heave and pitch functions of time returning (x, x', x'')."""
    zero = np.zeros_like(time)
    h = heave(time) if heave else (zero, zero, zero)
    p = pitch(time) if pitch else (zero, zero, zero)
    return KinematicState(time, p[0], p[1], p[2], h[0], h[1], h[2])


def test_a_plate_at_rest_is_bounded_by_its_drag_in_the_stream():
    time = np.linspace(0.0, 2.0, 201)
    bound = normal_force_bound_n(_state(time), PLATE, FLUID, STREAM)
    by_hand = (0.5 * FLUID.density * PLATE.chord * PLATE.span
               * MAX_NORMAL_FORCE_COEFFICIENT * STREAM.velocity**2)
    np.testing.assert_allclose(bound, by_hand, rtol=1e-12)


def test_a_heaving_plate_is_bounded_by_added_mass_and_drag_over_the_convective_time():
    omega, amplitude = 2 * np.pi * 0.5, 0.2
    time = np.sort(np.random.default_rng(0).uniform(0.0, 6.0, 3000))
    heave = lambda t: (amplitude * np.sin(omega * t), amplitude * omega * np.cos(omega * t),  # noqa: E731
                       -amplitude * omega**2 * np.sin(omega * t))
    bound = normal_force_bound_n(_state(time, heave), PLATE, FLUID, STREAM)
    added_mass_kg = FLUID.density * np.pi * (PLATE.chord / 2) ** 2 * PLATE.span
    drag = 0.5 * FLUID.density * PLATE.chord * PLATE.span * MAX_NORMAL_FORCE_COEFFICIENT
    local = (added_mass_kg * amplitude * omega**2 * np.abs(np.sin(omega * time))
             + drag * (STREAM.velocity + amplitude * omega * np.abs(np.cos(omega * time)))**2)
    memory_s = PLATE.chord / STREAM.velocity
    # brute force: the largest local bound within one convective time either side
    brute = np.array([local[np.abs(time - t) <= memory_s].max() for t in time])
    np.testing.assert_allclose(bound, brute, rtol=0.01)
    assert np.all(bound >= local)


@pytest.mark.slow
def test_every_real_run_that_kept_its_numerics_stays_inside_the_bound():
    """All shipped fixtures and real test records, bursts bridged, but those above (the
    shipped fixtures are reruns of the lost ones); the optimised motions' back-tests apart
    from the runs of prescribed motions."""
    folders = [p for p in (ROOT / "data" / "mfflap_data" / "fixtures").iterdir() if p.is_dir()]
    optimised = [r for f in folders if f.name.startswith(("backtest", "cfd_repeatability"))
                 for r in read_records(f)]
    prescribed = [r for f in folders if not f.name.startswith(("backtest", "cfd_repeatability"))
                  for r in read_records(f)]
    prescribed += [read_record(p) for p in sorted((ROOT / "tests" / "data").rglob("*.h5"))
                   if p.parent.name not in ("bursts", "lost_numerics")]
    assert len(optimised) > 50 and len(prescribed) > 100

    def worst(records):
        out = []
        for rec in records:
            if rec.name == AFTERMATH:
                continue
            loads, _ = bridge_load_bursts(rec.loads, rec.time >= 0)
            plate = Plate(chord=rec.provenance.get("chord_m", PLATE.chord),
                          span=rec.provenance.get("span_m", PLATE.span))
            out.append(float(envelope_ratio(rec.state, loads, plate, FLUID, STREAM).max()))
        return np.array(out)

    by_motion, by_optimum = worst(prescribed), worst(optimised)
    # the closest real run (f = 2 Hz, h = 0.5 m) comes within a factor of about 1.1 of the
    # breach level; a run of a prescribed motion (identification sets, small motions, test
    # records) typically uses about 60 % of the bound, an optimised motion, which runs at
    # P_max, about 85 % of it
    assert max(by_motion.max(), by_optimum.max()) < BREACH_FACTOR
    assert np.median(by_motion) < 0.7 < np.median(by_optimum) < 1.0


def test_shipped_runs_that_lost_their_numerics_are_found_where_bursts_are_not():
    # f = 1 Hz, h = 0.5 m, phi = 135 deg at max Co 4: from t = 0.8 s F_n grows to tens of
    # kN (the motion drives about 0.6 kN) and stays there to the end, with no jump sharp
    # enough for a numerical burst
    rec = read_record(LOST_DATA / "f1p000_h0p500_phi135p0.h5")
    assert find_load_bursts(rec.loads) == []
    assert np.abs(rec.loads.normal_force).max() > 5e4
    breaches = find_envelope_breaches(rec.state, rec.loads, PLATE, FLUID, STREAM)
    assert len(breaches) == 1
    assert 0.7 < breaches[0].start_s < LOST[rec.name] + 0.05 and breaches[0].end_s == 3.0
    assert breaches[0].peak_ratio > 50
    # f = 0.5 Hz, h = 0.5 m, phi = 135 deg: a smooth hump of F_n to 780 N for 0.4 s (3.8
    # times the bound) after a retry with the inletOutlet far field; its bursts bridged
    rec = read_record(LOST_DATA / "f0p500_h0p500_phi135p0.h5")
    loads, bursts = bridge_load_bursts(rec.loads, rec.time >= 0)
    assert bursts and all(b.end_s < 1.0 for b in bursts)
    (breach,) = find_envelope_breaches(rec.state, loads, PLATE, FLUID, STREAM)
    assert breach.start_s == pytest.approx(LOST[rec.name], abs=0.02)
    assert 0.4 < breach.duration_s < 0.5 and 3.5 < breach.peak_ratio < 4.0


def test_a_growing_oscillation_injected_into_a_real_run_is_found_from_its_growth():
    rec = read_record(fixture_dir("table1_coarse") / "f1p000_h0p300_phi090p0.h5")
    t = rec.time
    assert find_envelope_breaches(rec.state, rec.loads, PLATE, FLUID, STREAM) == []
    scale = np.ptp(rec.loads.normal_force)
    growth = np.where(t > 2.5, np.exp((t - 2.5) / 0.05) - 1.0, 0.0)
    lost = Loads(t, rec.loads.normal_force + scale * 0.05 * growth * np.sin(2 * np.pi * 150 * t),
                 rec.loads.tangential_force, rec.loads.moment, source="injected")
    breaches = find_envelope_breaches(rec.state, lost, PLATE, FLUID, STREAM)
    assert len(breaches) == 1 and 2.5 < breaches[0].start_s < 2.85
    assert breaches[0].end_s == t[-1]


def test_the_stream_starting_impulsively_is_not_judged_but_the_same_spike_later_is():
    """A real coarse run of a motion starting at rest (ramp 0) gives 4.5 and 3.3 times the
    bound at its first two time steps, the flow's start: the first FLOW_START_STEPS samples
    are left unjudged, the same spike one sample later is found."""
    time = np.linspace(1.2e-4, 0.03, 60)
    state = _state(time)
    bound = normal_force_bound_n(state, PLATE, FLUID, STREAM)
    normal = 0.5 * bound
    for first in (0, FLOW_START_STEPS - 2, FLOW_START_STEPS):
        spiked = normal.copy()
        spiked[first:first + 2] = [4.5 * bound[first], 3.3 * bound[first + 1]]
        loads = Loads(time, spiked, np.zeros_like(time), np.zeros_like(time))
        breaches = find_envelope_breaches(state, loads, PLATE, FLUID, STREAM)
        if first + 2 <= FLOW_START_STEPS:
            assert breaches == []
        else:
            (breach,) = breaches
            assert breach.peak_s == time[first] and breach.peak_ratio == pytest.approx(4.5)


def test_identification_leaves_a_lost_run_out_and_bridges_a_short_stretch():
    rec = read_record(LOST_DATA / "f1p000_h0p500_phi135p0.h5")
    with pytest.raises(MfflapError, match=r"f1p000_h0p500_phi135p0: its forces leave what "
                       r"the motion can drive .* first t = 0\.7"):
        prepare_case(rec)
    # the slower aftermath of the burst at t = 3.09 s of f = 0.5 Hz, h = 0.3 m, phi = 90 deg
    # (docs/findings/known_limits.md): 0.04 s beyond the bound, bridged and listed
    rec = read_record(fixture_dir("table1_coarse") / f"{AFTERMATH}.h5")
    case = prepare_case(rec)
    note = next(n for n in case.notes if ENVELOPE_NOTE in n)
    assert "t = 3.09" in note
    keep = (case.cfd.time > 3.09) & (case.cfd.time < 3.14)
    assert np.abs(case.cfd.normal_force[keep]).max() < 100.0  # not the +-270 N swings
