"""Two campaigns compared case by case: on the shipped real runs of two set-ups, against
values derived by hand, with a burst bridged, and the refusals."""

import copy
import dataclasses
import json
import shutil
from pathlib import Path

import h5py
import numpy as np
import pytest
from click.testing import CliRunner

from mfflap.campaign.compare import OutsideWindow, compare_campaigns, compare_records
from mfflap.cli.main import cli
from mfflap.errors import ConfigError, MfflapError
from mfflap.metrics import nrmse, time_mean
from mfflap.performance import thrust_and_power
from mfflap.records.bursts import bridge_load_bursts
from mfflap.records.record import fixture_dir, read_record, read_records, write_record

AFFORDABLE = fixture_dir("small_motion_affordable")
COARSE = fixture_dir("small_motion_coarse")
MEDIUM = fixture_dir("small_motion_medium")
BURSTS = Path(__file__).parents[1] / "data" / "openfoam_v1912" / "bursts"
VARIANTS = Path(__file__).parents[1] / "data" / "openfoam_v1912" / "small_motion_variants"


@pytest.fixture(scope="module")
def record():
    return read_record(sorted(COARSE.glob("*.h5"))[6])  # f = 1 Hz, heave with pitch


def test_two_set_ups_of_the_small_motions():
    """Real runs of the same 11 motions with the affordable set-up and on the coarse mesh:
    F_n within 6 % NRMSE (1-2 % where f >= 1 Hz, measured), in phase, no bursts."""
    result = compare_campaigns(AFFORDABLE, COARSE, start_s=0.5)
    assert len(result.cases) == 11 and not result.only_a and not result.only_b
    for c in result.cases:
        parameters = read_record(COARSE / f"{c.case_id}.h5").parameters
        f = parameters["frequency"]
        fast = f >= 1  # k >= 1.7; the slow motions shed small vortices
                       # (docs/findings/known_limits.md)
        assert c.nrmse_normal_force < (0.025 if fast else 0.07), c
        assert c.pearson_normal_force > (0.995 if fast else 0.97), c
        assert c.pearson_moment > (0.99 if fast else 0.75), c  # slow heave: 0.82
        assert c.n_bursts_a == c.n_bursts_b == 0
        assert c.start_s == 0.5 and c.end_s == pytest.approx(parameters["duration"], rel=0.01)
    summary = result.summary()
    assert summary["median_nrmse_normal_force"] < 0.03
    assert summary["max_nrmse_normal_force"] >= summary["median_nrmse_normal_force"]
    assert 1.0 < summary["cpu_ratio"] < 2.0  # the graded mesh has 40 % more cells


@pytest.mark.parametrize(("folder", "thrust_range"), [
    (COARSE, (-0.12, 0.0)),  # measured -10 to -2 %: more drag than the medium mesh
    (AFFORDABLE, (0.08, 0.18)),  # measured +10 to +16 %: less drag
])
def test_small_motions_against_the_medium_mesh(folder, thrust_range):
    """The medium mesh is the yardstick of the cost target. On the small motions (attached flow) the
    coarse mesh and affordable are both within 3 % F_n NRMSE of it where f >= 1 Hz
    (measured 0.5-1.7 % and 1.2-2.7 %) and within 7 % below; their mean drags differ from it
    in opposite directions."""
    result = compare_campaigns(folder, MEDIUM, start_s=0.5)
    assert len(result.cases) == 11 and not result.only_a and not result.only_b
    for c in result.cases:
        fast = read_record(MEDIUM / f"{c.case_id}.h5").parameters["frequency"] >= 1
        assert c.nrmse_normal_force < (0.03 if fast else 0.07), c
        assert c.pearson_normal_force > (0.995 if fast else 0.97), c
        assert thrust_range[0] < c.thrust_difference < thrust_range[1], c
        assert c.cpu_ratio < 0.75, c  # both cheaper than the medium mesh


@pytest.mark.parametrize(("variant", "setup_name", "mesh", "convection", "fast_f_n_limit",
                          "thrust_range"), [
    # measured: F_n 0.6-1.8 % where f >= 1 Hz, thrust -0.7 to +3.4 %
    ("graded_reference_solver", "reference", "graded", None, 0.02, (-0.04, 0.04)),
    # 1.1-2.3 %, +10.1 to +15.9 %
    ("graded_pimple_lust", "reference", "graded", "LUST", 0.025, (0.08, 0.18)),
    # 0.8-2.2 %, -3.4 to +2.6 %
    ("graded_piso_linearupwind", "affordable", None, "linearUpwind", 0.025, (-0.04, 0.04)),
    # 1.1-3.5 %, -3.4 to +2.5 %
    ("medium_affordable_solver", "affordable", "medium", None, 0.04, (-0.04, 0.04)),
    # 1.0-3.0 %, -9.5 to -2.8 %: PISO alone on the medium mesh, more drag
    ("medium_piso", "medium_piso", None, None, 0.035, (-0.12, 0.0)),
])
@pytest.mark.slow
def test_what_moves_affordables_small_motion_drag(variant, setup_name, mesh, convection,
                                                  fast_f_n_limit, thrust_range):
    """affordable's three changes from the reference taken apart on the small motions
    (docs/findings/linear_theory.md): each run set is what its cfd linear-check
    options make, and the 10-16 % lower drag comes with LUST on the graded mesh only."""
    from mfflap.campaign.execute import manifest_setup
    from mfflap.cfd.openfoam.setups import mesh_and_solver

    folder = VARIANTS / variant
    spec, solver = mesh_and_solver(mesh, setup_name)
    if convection is not None:
        solver = dataclasses.replace(solver, velocity_convection=convection)
    made = manifest_setup(folder)  # with the settings added since, at their runs' values
    assert made["mesh"] == spec.name
    assert made["solver"] == dataclasses.asdict(solver)
    result = compare_campaigns(folder, MEDIUM, start_s=0.5)
    assert len(result.cases) == 11 and not result.only_a and not result.only_b
    for c in result.cases:
        fast = read_record(MEDIUM / f"{c.case_id}.h5").parameters["frequency"] >= 1
        assert c.nrmse_normal_force < (fast_f_n_limit if fast else 0.08), c
        assert thrust_range[0] < c.thrust_difference < thrust_range[1], c
        assert c.n_bursts_a == c.n_bursts_b == 0


def test_against_values_derived_by_hand(record):
    """A record against itself is 0 / 1; a constant offset d on F_n gives NRMSE d / range;
    a mean thrust scaled by 1.1 gives +10 %."""
    same = compare_records(record, record)
    assert same.nrmse_normal_force == 0 and same.pearson_moment == pytest.approx(1.0)
    assert same.start_s == record.parameters["ramp_time"] and same.thrust_difference == 0
    shifted = copy.deepcopy(record)
    offset = 0.05
    shifted.loads.normal_force[:] += offset
    keep = record.time >= record.parameters["ramp_time"]
    f_n = record.loads.normal_force[keep]
    result = compare_records(shifted, record)
    assert result.nrmse_normal_force == pytest.approx(offset / np.ptp(f_n), rel=1e-9)
    assert result.pearson_normal_force == pytest.approx(1.0)
    assert result.nrmse_tangential_force == 0
    scaled = copy.deepcopy(record)
    scaled.loads.tangential_force[:] *= 1.1
    scaled.loads.normal_force[:] *= 1.1
    scaled.loads.moment[:] *= 1.1
    thrust, _ = thrust_and_power(record.loads, record.state)
    mean_thrust = time_mean(record.time[keep], thrust[keep])
    assert result.mean_thrust_b_n == pytest.approx(mean_thrust)
    assert compare_records(scaled, record).thrust_difference == pytest.approx(
        0.1 * np.sign(mean_thrust), rel=1e-6)
    # a reference with no thrust or no CPU time recorded: nan, not a division error
    still = dataclasses.replace(result, mean_thrust_b_n=0.0, cpu_time_b_s=float("nan"))
    assert np.isnan(still.thrust_difference) and np.isnan(still.cpu_ratio)
    assert result.cpu_ratio == 1.0 and result.power_difference == pytest.approx(
        (result.mean_power_a_w - result.mean_power_b_w) / abs(result.mean_power_b_w))


def test_numerical_bursts_are_bridged_and_counted():
    """A real run with numerical bursts (f = 0.5 Hz, h = 0.3 m, phi = 90 deg, max Co 4)
    against the same run with them bridged beforehand: counted in B only, and the two then
    agree, where taken as they are they are orders of magnitude apart."""
    raw = read_record(BURSTS / "f0p500_h0p300_phi090p0.h5")
    start = raw.parameters["ramp_time"]
    clean = copy.deepcopy(raw)
    clean.loads, found = bridge_load_bursts(raw.loads, raw.time >= start)
    assert found
    result = compare_records(clean, raw)
    assert result.n_bursts_a == 0 and result.n_bursts_b == len(found)
    assert result.nrmse_normal_force < 1e-9 and result.nrmse_moment < 1e-9
    keep = raw.time >= start
    as_they_are = nrmse(clean.loads.normal_force[keep], raw.loads.normal_force[keep])
    assert as_they_are > 1e-3  # the bursts set the range


def test_refusals_name_the_case_and_key(record, tmp_path):
    other = copy.deepcopy(record)
    other.parameters = {**record.parameters, "frequency": 2.0}
    with pytest.raises(ConfigError, match=rf"frequency: {record.name}: .*different motions"):
        compare_records(other, record)
    with pytest.raises(OutsideWindow, match=rf"{record.name}: fewer than two common"):
        compare_records(record, record, start_s=record.time[-1] + 1.0)
    with pytest.raises(ConfigError, match="end_s: the comparison ends"):
        compare_campaigns(COARSE, COARSE, start_s=2.0, end_s=1.0)
    single = copy.deepcopy(record)
    single.parameters = {**record.parameters, "storage": "float32"}
    assert compare_records(single, record).nrmse_normal_force == 0  # storage is not motion
    with pytest.raises(MfflapError, match="no finished case in common"):
        compare_campaigns(COARSE, fixture_dir("backtest"))


def test_campaigns_of_another_plate_or_stream_are_not_compared(tmp_path):
    """Set-ups are compared on one flow: a folder whose campaign.toml (or a record's
    provenance) says another stream or chord is refused, naming the case and both values."""
    faster = tmp_path / "faster"
    shutil.copytree(COARSE, faster)
    manifest = faster / "campaign.toml"
    text = manifest.read_text()
    assert "[setup.stream]\nvelocity = 0.3\n" in text
    manifest.write_text(text.replace("[setup.stream]\nvelocity = 0.3\n",
                                     "[setup.stream]\nvelocity = 0.5\n"))
    first = sorted(p.stem for p in COARSE.glob("*.h5"))[0]
    with pytest.raises(ConfigError, match=rf"flow\.velocity: case {first} ran for flow\."
                                          rf"velocity = 0\.3 in {AFFORDABLE} and 0\.5 in "
                                          rf"{faster}: a comparison of two set-ups needs"):
        compare_campaigns(AFFORDABLE, faster)
    record = read_record(COARSE / f"{first}.h5")
    record.provenance["chord_m"] = 0.2  # a record that says its own plate
    shorter = tmp_path / "shorter"
    shorter.mkdir()
    write_record(shorter / f"{first}.h5", record)
    res = CliRunner().invoke(cli, ["campaign", "compare", str(COARSE), str(shorter)])
    assert res.exit_code == 2, res.output
    assert f"ran for plate.chord = 0.16 in {COARSE} and 0.2 in {shorter}" in " ".join(
        res.output.split())


def test_command_writes_hdf5_with_both_manifests_and_a_figure(tmp_path):
    a = tmp_path / "a"
    shutil.copytree(AFFORDABLE, a)
    extra = read_records(COARSE)[0]
    write_record(tmp_path / "b_only.h5", extra)  # not in a campaign folder: ignored
    (a / f"{extra.name}.h5").unlink()  # a case only B has
    out, fig = tmp_path / "cmp.h5", tmp_path / "cmp.png"
    res = CliRunner().invoke(cli, ["campaign", "compare", str(a), str(COARSE), "--start",
                                   "0.5", "--output", str(out), "--figure", str(fig),
                                   "--json"])
    assert res.exit_code == 0, res.output
    data = json.loads(res.stdout)
    assert len(data["cases"]) == 10 and data["only_b"] == [extra.name]
    assert all(c["cpu_ratio"] == pytest.approx(c["cpu_time_a_s"] / c["cpu_time_b_s"])
               for c in data["cases"])
    with h5py.File(out) as h5:
        assert h5.attrs["kind"] == "campaign_comparison"
        manifests = h5["inputs"].attrs["config_toml"]
        assert manifests.count("[setup]") == 2 and 'mesh = "graded"' in manifests
        assert h5["cases/nrmse_normal_force"].attrs["units"] == "1"
        assert h5["cases/mean_thrust_a_n"].attrs["units"] == "N"
        assert len(h5["cases/nrmse_moment"]) == 10
    assert fig.stat().st_size > 10_000
    res = CliRunner().invoke(cli, ["campaign", "compare", str(a), str(COARSE)])
    assert res.exit_code == 0 and "only in B: 1 case(s)" in res.output


def test_cases_that_end_before_the_window_are_listed_not_fatal(tmp_path):
    """The small motions run 1.5 to 8 s: from t = 3 s only the f <= 0.5 Hz cases (4 and
    8 s) have forces to compare; the six others are listed as outside the window."""
    result = compare_campaigns(AFFORDABLE, COARSE, start_s=3.0)
    assert sorted(c.case_id for c in result.cases) == sorted(
        r.name for r in read_records(COARSE) if r.time[-1] >= 4.0)
    assert len(result.outside_window) == 6
    assert all("fewer than two common samples from t = 3 s" in why
               for why in result.outside_window.values())
    out = tmp_path / "cmp.h5"
    res = CliRunner().invoke(cli, ["campaign", "compare", str(AFFORDABLE), str(COARSE),
                                   "--start", "3", "--output", str(out)])
    assert res.exit_code == 0, res.output
    assert "outside the window: 6 case(s)" in res.output
    with h5py.File(out) as h5:
        assert json.loads(h5["cases"].attrs["outside_window"]) == result.outside_window
    res = CliRunner().invoke(cli, ["campaign", "compare", str(AFFORDABLE), str(COARSE),
                                   "--start", "3", "--json"])
    assert json.loads(res.stdout)["outside_window"] == result.outside_window
    # a history asked for of a case outside the window says so
    res = CliRunner().invoke(cli, ["campaign", "compare", str(AFFORDABLE), str(COARSE),
                                   "--start", "3", "--histories", str(tmp_path / "h"),
                                   "--case", "harmonic_f2p000_h0p0000_th1p00_phi090p0"])
    assert res.exit_code != 0
    assert ("harmonic_f2p000_h0p0000_th1p00_phi090p0: fewer than two common samples from "
            "t = 3 s to 1.5 s (the records end at 1.5 and 1.5 s): outside the window "
            "compared") in res.output
    # no case in the window at all, and a window that ends before it starts
    res = CliRunner().invoke(cli, ["campaign", "compare", str(AFFORDABLE), str(COARSE),
                                   "--start", "100"])
    assert res.exit_code != 0 and "no case of the 11 in common" in res.output
    res = CliRunner().invoke(cli, ["campaign", "compare", str(AFFORDABLE), str(COARSE),
                                   "--start", "3", "--end", "2"])
    assert res.exit_code == 2 and "--end 2 is not after --start 3" in res.output


def test_a_run_that_lost_its_numerics_is_timed_and_left_out_of_the_medians():
    """The first shipped f = 1 Hz, h = 0.5 m, phi = 135 deg run lost its numerics from t = 0.79 s
    to its end (mfflap.records.force_envelope): compared with itself, both sides carry the lost
    time, and a campaign comparison's medians are those of the other cases."""
    from mfflap.campaign.compare import CampaignComparison

    lost = read_record(Path(__file__).parents[1] / "data" / "openfoam_v1912" / "lost_numerics"
                       / "f1p000_h0p500_phi135p0.h5")
    kept = read_record(fixture_dir("table1_coarse") / "f1p000_h0p300_phi090p0.h5")
    bad = compare_records(lost, lost)
    assert bad.lost_a_s == bad.lost_b_s == pytest.approx(3.0 - 0.79, abs=0.02)
    good = compare_records(kept, kept)
    assert good.lost_a_s == good.lost_b_s == 0.0
    worse = dataclasses.replace(bad, nrmse_normal_force=5.0)  # what a lost run does to it
    summary = CampaignComparison("a", "b", [worse, good], [], []).summary()
    assert summary["n_cases_compared"] == 1
    assert summary["max_nrmse_normal_force"] == good.nrmse_normal_force


def test_a_comparison_can_end_before_the_records_do(record):
    """One period after the ramp, not the whole run: the window's end is kept, the metrics
    are those of that window alone, and an end before the start is refused by name."""
    period_s = 1.0 / float(record.parameters["frequency"])
    start = float(record.parameters["ramp_time"])
    shifted = copy.deepcopy(record)
    late = shifted.time > start + period_s
    shifted.loads.normal_force[late] += 100.0  # differs only after the first period
    first = compare_records(shifted, record, end_s=start + period_s)
    assert first.end_s == pytest.approx(start + period_s)
    assert first.nrmse_normal_force == 0.0
    assert compare_records(shifted, record).nrmse_normal_force > 0.1
    with pytest.raises(ConfigError, match="ends") as info:
        compare_records(record, record, end_s=start)
    assert info.value.key == "end_s"
    res = CliRunner().invoke(cli, ["campaign", "compare", str(COARSE), str(COARSE), "--end",
                                   str(start + period_s), "--json"])
    assert res.exit_code == 0, res.output
    assert {c["end_s"] for c in json.loads(res.stdout)["cases"]} == {start + period_s}
    # a folder compared with itself: said, since every number is then 0
    assert (f"warning: {COARSE} and {COARSE} are the same folder: each case is compared "
            "with itself, so every difference below is 0") in " ".join(res.stderr.split())
    res = CliRunner().invoke(cli, ["campaign", "compare", str(AFFORDABLE), str(COARSE),
                                   "--json"])
    assert res.exit_code == 0 and "same folder" not in res.stderr


CAMPAIGNS = Path(__file__).parents[2] / "campaigns"


def test_history_figures_draw_both_records_as_recorded(tmp_path):
    """The history overlay of a real medium/coarse pair: each panel holds both records'
    own samples (not resampled, not bridged), the thrust panel the thrust of each record's
    loads and motion, and the command writes one PNG for the chosen case."""
    from matplotlib.image import imread

    from mfflap.campaign.history_plot import PANELS, history_figure

    a_dir, b_dir = CAMPAIGNS / "hardest_coarse_co1", CAMPAIGNS / "hardest_medium"
    name = "f0p500_h0p500_phi135p0"
    a, b = read_record(a_dir / f"{name}.h5"), read_record(b_dir / f"{name}.h5")
    case = compare_records(a, b)
    fig = history_figure(a, b, case, ("coarse", "medium"))
    for ax, (key, _) in zip(fig.axes, PANELS, strict=True):
        (line_b, line_a) = ax.lines
        for line, rec in ((line_a, a), (line_b, b)):
            expected = (thrust_and_power(rec.loads, rec.state)[0] if key == "thrust"
                        else getattr(rec.loads, key))
            np.testing.assert_array_equal(line.get_xdata(), rec.time)
            np.testing.assert_array_equal(line.get_ydata(), expected)
        assert line_b.get_label() == "medium" and line_a.get_label() == "coarse"
    assert f"NRMSE {100 * case.nrmse_normal_force:.1f} %" == fig.axes[0].get_title("right")

    out = tmp_path / "histories"
    res = CliRunner().invoke(cli, ["campaign", "compare", str(a_dir), str(b_dir),
                                   "--histories", str(out), "--case", name])
    assert res.exit_code == 0, res.output
    assert [p.name for p in out.iterdir()] == [f"{name}.png"]
    assert imread(out / f"{name}.png").shape[:2] == (900, 1000)


def test_history_figures_refuse_a_case_not_run_by_both(tmp_path):
    # the max Co 0.5 campaign ran f = 1 Hz alone
    a_dir, b_dir = CAMPAIGNS / "hardest_coarse_co05", CAMPAIGNS / "hardest_medium"
    res = CliRunner().invoke(cli, ["campaign", "compare", str(a_dir), str(b_dir),
                                   "--histories", str(tmp_path / "h"),
                                   "--case", "f2p000_h0p500_phi135p0"])
    assert res.exit_code != 0
    assert "f2p000_h0p500_phi135p0: not run by both" in res.output
    assert "compared: f1p000_h0p500_phi135p0" in res.output
    assert not (tmp_path / "h").exists() or not any((tmp_path / "h").iterdir())
    res = CliRunner().invoke(cli, ["campaign", "compare", str(a_dir), str(b_dir),
                                   "--case", "f1p000_h0p500_phi135p0"])
    assert res.exit_code == 2 and "give --histories DIR" in res.output


@pytest.mark.slow
def test_the_comparison_says_what_separates_the_two_set_ups(tmp_path):
    """From the two campaign.toml: the settings that differ, both values, in text and JSON;
    a setting neither manifest names (both written before the wall treatment was kept) is
    at the value their runs used, and so no difference; the time limit is none either."""
    lust = VARIANTS / "graded_pimple_lust"
    result = compare_campaigns(lust, COARSE, start_s=0.5)
    assert result.setup_differences == [("mesh", "graded", "coarse"),
                                        ("solver.pressure_solver", "GAMG", "PCG"),
                                        ("solver.velocity_convection", "LUST", "linearUpwind")]
    text = CliRunner().invoke(cli, ["campaign", "compare", str(lust), str(COARSE)])
    assert text.exit_code == 0, text.output
    assert text.output.splitlines()[0] == (
        "set-ups differ in: mesh ('graded' in A, 'coarse' in B); solver.pressure_solver "
        "('GAMG' in A, 'PCG' in B); solver.velocity_convection ('LUST' in A, "
        "'linearUpwind' in B)")
    data = json.loads(CliRunner().invoke(cli, ["campaign", "compare", str(lust), str(COARSE),
                                               "--json"]).stdout)
    assert data["setup_differences"][0] == {"setting": "mesh", "a": "graded", "b": "coarse"}
    # a rerun of the same set-up with the wall treatment written out and another time limit
    same = tmp_path / "same"
    shutil.copytree(COARSE, same)
    manifest = same / "campaign.toml"
    manifest.write_text(manifest.read_text().replace(
        'frame = "inertial"\n', 'frame = "inertial"\nwall_treatment = "log_law"\n').replace(
        "timeout_s = 3600.0", "timeout_s = 60.0"))
    assert compare_campaigns(COARSE, same).setup_differences == []
    assert CliRunner().invoke(cli, ["campaign", "compare", str(COARSE), str(same)]
                              ).output.splitlines()[0] == (
        "set-ups: the same mesh and solver settings")
    manifest.write_text(manifest.read_text().replace('"log_law"', '"all_y_plus"'))
    assert compare_campaigns(COARSE, same).setup_differences == [
        ("solver.wall_treatment", "log_law", "all_y_plus")]
    manifest.unlink()
    assert compare_campaigns(COARSE, same).setup_differences is None
    assert "set-ups: not both known" in CliRunner().invoke(
        cli, ["campaign", "compare", str(COARSE), str(same)]).output
