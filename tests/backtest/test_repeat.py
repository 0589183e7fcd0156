"""How far two OpenFOAM runs of one motion agree: the noise floor under every back-test.

Two real coarse-mesh pimpleFoam runs of the same optimised motion (round 3's beta = 0.5 of
the first-order rounds, key 4a429ce3a09cada1): the one the rounds use
(``backtest_first_order``) and a first run of it (``cfd_repeatability``, made by an earlier
version of the rounds that found the same optimum), each case written from the optimiser's
output: their motion tables are identical, their controlDicts differ only in the 13th digit
of endTime and writeInterval (the period as recomputed from the same optimum). With an
adjustable time step that lands on the write times, the time steps differ, and the flow
separates the difference into the forces (docs/findings/optimised_motions.md, "First-order
corrections").
"""

import numpy as np
import pytest

from mfflap.backtest.compare import compare_last_cycle
from mfflap.errors import ConfigError
from mfflap.hydro import MorisonModel
from mfflap.records.record import fixture_dir, read_record


def _runs():
    name = "backtest_4a429ce3a09cada1"
    return [read_record(fixture_dir("cfd_repeatability") / f"{name}_first_run.h5"),
            read_record(fixture_dir("backtest_first_order") / f"{name}.h5")]


def test_two_runs_of_one_motion_agree_early_and_part_in_the_last_cycle():
    a, b = _runs()
    assert a.parameters["motion_key"] == b.parameters["motion_key"]
    period = a.parameters["period"]
    assert abs(b.parameters["period"] - period) < 1e-12 * period
    assert a.provenance["n_time_steps"] != b.provenance["n_time_steps"]
    t_ramp = a.parameters["ramp_time"]
    t = np.linspace(0.05, t_ramp, 200)  # the start-up ramp: the same forces
    late = np.linspace(a.time[-1] - period, a.time[-1], 400)  # the last cycle: not
    for k in range(2):
        early_a = np.interp(t, a.time, a.raw_force[:, k])
        early_b = np.interp(t, b.time, b.raw_force[:, k])
        assert np.max(np.abs(early_a - early_b)) < 0.01 * np.max(np.abs(early_a))
    last_a = np.interp(late, a.time, a.raw_force[:, 0])
    last_b = np.interp(late, b.time, b.raw_force[:, 0])
    assert np.max(np.abs(last_a - last_b)) > 0.1 * np.max(np.abs(last_a))
    means = [compare_last_cycle(r, MorisonModel(), period, 50.0) for r in (a, b)]
    thrust = [m.cfd_mean_thrust for m in means]
    power = [m.cfd_mean_power for m in means]
    # the last cycle's means, what the rounds compare, 2-3 % apart
    assert 0.02 < abs(thrust[1] - thrust[0]) / np.mean(thrust) < 0.04
    assert 0.01 < abs(power[1] - power[0]) / np.mean(power) < 0.03


def test_a_rerun_of_the_same_case_repeats_it_bit_for_bit():
    """Round 2's beta = 0 optimum of the trust series, run again from a case written anew
    (copy 0 of `mfflap backtest --repeat`): every time and force the same, so the spread
    above is the flow's sensitivity to a hair's change of the case, not a solver that
    differs from one run to the next."""
    name = "backtest_f85edc06d9cf46a0"
    first = read_record(fixture_dir("backtest_trust_region") / f"{name}.h5")
    again = read_record(fixture_dir("cfd_repeatability") / f"{name}_copy0.h5")
    assert again.provenance["n_time_steps"] == first.provenance["n_time_steps"] > 8000
    assert np.array_equal(again.time, first.time)
    assert np.array_equal(again.raw_force, first.raw_force)
    assert np.array_equal(again.raw_moment, first.raw_moment)


def test_the_repeatability_of_the_two_runs_is_their_spread_of_last_cycle_means():
    from mfflap.backtest.repeat import repeatability_of

    a, b = _runs()
    rep = repeatability_of([a, b], "β = 0.5", MorisonModel(), a.parameters["period"], 50.0)
    direct = [compare_last_cycle(r, MorisonModel(), a.parameters["period"], 50.0)
              for r in (a, b)]
    thrust = [d.cfd_mean_thrust for d in direct]
    assert list(rep.mean_thrust) == thrust
    assert rep.thrust_spread == pytest.approx(abs(thrust[1] - thrust[0]) / np.mean(thrust))
    assert 0.02 < rep.thrust_spread < 0.04 and 0.01 < rep.power_spread < 0.03
    assert rep.share == rep.thrust_spread and rep.key == "4a429ce3a09cada1"
    assert rep.describe().startswith("β = 0.5: 2 runs, mean thrust 8.802, 9.05 N (spread 2.78%)")
    assert rep.as_dict()["share"] == rep.share


def test_a_repeatability_needs_two_runs_of_one_motion():
    from mfflap.backtest.repeat import repeatability_of
    from mfflap.records.record import backtest_fixture_dirs, record_paths

    a, _ = _runs()
    with pytest.raises(ConfigError, match="two runs or more") as err:
        repeatability_of([a], "x", MorisonModel(), 1.0, 50.0)
    assert err.value.key == "repeat"
    other = read_record(next(p for p in record_paths(backtest_fixture_dirs()[0])))
    with pytest.raises(ConfigError, match="different motions"):
        repeatability_of([a, other], "x", MorisonModel(), 1.0, 50.0)


def test_each_copy_differs_in_its_courant_limit_alone():
    from dataclasses import asdict

    from mfflap.backtest.repeat import REPEAT_PERTURBATION, copy_settings
    from mfflap.cfd.openfoam.writer import SolverSettings

    base = SolverSettings(max_courant=2.0)
    assert copy_settings(base, 0) == base
    second = copy_settings(base, 2)
    assert second.max_courant == 2.0 * (1 + 2 * REPEAT_PERTURBATION)
    changed = {k for k, v in asdict(second).items() if asdict(base)[k] != v}
    assert changed == {"max_courant"}
    assert copy_settings(None, 1).max_courant == pytest.approx(
        SolverSettings().max_courant * (1 + REPEAT_PERTURBATION), rel=1e-15)


@pytest.mark.slow
def test_repeat_needs_live_runs_and_two_copies(tmp_path, optimisation_file):
    from click.testing import CliRunner

    from mfflap.cli.main import cli

    res = CliRunner().invoke(cli, ["backtest", str(optimisation_file), "--repeat", "3"])
    assert res.exit_code == 2 and "--repeat applies only to live runs" in res.output
    res = CliRunner().invoke(cli, ["backtest", str(optimisation_file), "--live", "--repeat",
                                   "1", "--work", str(tmp_path / "w")])
    assert res.exit_code == 2 and "must be 2 or more runs" in res.output
    assert not (tmp_path / "w").exists()


def _write_copies(folder, key: str, motion, copies: int, shift_share: float = 0.0) -> None:
    """Copies 0 .. copies-1 of ``motion``'s run saved as ``backtest_<key>_copy<k>.h5``, each
    at its copy's Courant limit, their cycle begun ``shift_share`` of a period into the
    motion's, with loads that differ a little from copy to copy."""
    from dataclasses import replace

    from mfflap.backtest.repeat import copy_settings
    from mfflap.backtest.run import cfd_motion
    from mfflap.hydro.loads import Loads
    from mfflap.records.record import CfdRecord, write_record

    spline = cfd_motion(motion)
    t = np.linspace(0.0, 3 * spline.period, 1201)
    state = spline.sample(t + shift_share * spline.period)
    state = replace(state, time=t, heave_position=state.heave_position
                    - state.heave_position[0])
    folder.mkdir(exist_ok=True)
    for k in range(copies):
        loads = Loads(t, (10.0 + 0.1 * k) * np.sin(2 * np.pi * t / spline.period) + 2.0,
                      np.full_like(t, -1.0 - 0.01 * k), 0.5 * np.cos(2 * np.pi * t / spline.period))
        write_record(folder / f"backtest_{key}_copy{k}.h5", CfdRecord(
            f"backtest_{key}_copy{k}", state, loads,
            {"kind": "table", "period": spline.period, "ramp_time": 0.0, "motion_key": key,
             "n_cycles": 3.0, "copy": k},
            {"solver_max_courant": copy_settings(None, k).max_courant}))


def test_repeat_takes_the_copies_saved_for_the_same_motion_found_with_other_round_off(
        tmp_path, monkeypatch):
    """``--repeat`` looks saved copies up as the back-test looks records up: a motion with
    none of its own key takes a whole set of another key's whose motion lies within the
    look-up's tolerance of it, or is the same periodic motion shifted in time, and says so
    (on OpenBLAS's Haswell kernels the trust series' round 2 beta = 0.5 optimum came out as
    51f7bd629f61b45e, within the tolerance of 34cd2b07c53664ae, whose copies ship, and ran
    them again for twenty minutes). A set that lacks a copy asked for, or of a motion
    further off, is not taken: the copies run, under the motion's own key."""
    import mfflap.backtest.repeat as repeat_module
    from mfflap.backtest.repeat import repeat_runs
    from mfflap.backtest.run import motion_key
    from mfflap.kinematics.convert import harmonic_to_discrete
    from mfflap.kinematics.discrete import DiscreteMotion

    ran = []

    def run_backtest_case(motion, label, name, **kwargs):
        ran.append(name)
        raise RuntimeError(f"would run {name} in OpenFOAM")

    monkeypatch.setattr(repeat_module, "run_backtest_case", run_backtest_case)
    motion = harmonic_to_discrete(0.8, 0.3, 0.5, 1.5, 40)

    def scaled(factor: float) -> DiscreteMotion:
        return DiscreteMotion(factor * motion.pitch_acceleration, motion.heave_acceleration,
                              motion.time_step)

    near, far = scaled(1.001), scaled(1.01)
    saved = tmp_path / "saved"
    _write_copies(saved, "before", motion, 2)

    def repeat(m, copies=2, folder=saved):
        said = []
        found = repeat_runs(m, "β = 0.5", MorisonModel(), 50.0, copies=copies,
                            work_dir=tmp_path / "w", save_to=folder, progress=said.append)
        return found, said

    found, said = repeat(near)
    assert ran == [] and found.key == "before" and found.sources == (
        "backtest_before_copy0", "backtest_before_copy1")
    assert said == [f"copy {k} of 2: taken from {saved / f'backtest_before_copy{k}.h5'} "
                    "(saved for before: a motion within the look-up's tolerance of this one)"
                    for k in range(2)]
    np.testing.assert_allclose(found.mean_thrust, repeat(motion)[0].mean_thrust, rtol=0)
    # the same periodic motion, its saved cycle begun a quarter period later
    shifted = tmp_path / "shifted"
    _write_copies(shifted, "later", motion, 2, shift_share=0.25)
    found, said = repeat(near, folder=shifted)
    assert found.key == "later" and "(saved for later: the same periodic motion shifted in " \
        "time by" in said[0] and ran == []
    # three copies asked for, two saved: all three run, as the motion's own
    with pytest.raises(RuntimeError, match="would run"):
        repeat(near, copies=3)
    assert ran == [f"backtest_{motion_key(near)}_copy0"]
    # a motion 1 % off is another motion
    with pytest.raises(RuntimeError, match="would run"):
        repeat(far)
    assert ran[-1] == f"backtest_{motion_key(far)}_copy0"
    # a copy of the motion's own key comes first: the rest of its set then runs
    _write_copies(saved, motion_key(near), near, 1)
    with pytest.raises(RuntimeError, match="would run"):
        repeat(near)
    assert ran[-1] == f"backtest_{motion_key(near)}_copy1"
