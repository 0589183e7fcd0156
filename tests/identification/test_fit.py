"""Identification: weights, recovery of known coefficients, bad input."""

import json
from pathlib import Path

import numpy as np
import pytest

from mfflap.campaign.cases import grid_cases
from mfflap.config import IdentificationGrid
from mfflap.errors import ConfigError, MfflapError
from mfflap.hydro import MorisonModel
from mfflap.hydro.loads import Loads
from mfflap.identification import frequency_weights, identify, prepare_cases
from mfflap.identification.data import prepare_case
from mfflap.records.record import CfdRecord, fixture_dir

TRUE = {"normal_drag": 2.0, "tangential_drag": 4.0, "normal_added_mass": 1.2,
        "tangential_added_mass": 0.5}


def synthetic_records(rng, noise=0.05, coefficients=TRUE, subset=None, n=500):
    model = MorisonModel().with_coefficients(coefficients)
    recs = []
    for c in subset or grid_cases(IdentificationGrid(), heave_amplitudes=[0.1, 0.3, 0.5],
                                  phases_deg=[45, 90, 135]):
        t = np.sort(np.concatenate([[0.0, c.duration], rng.uniform(0, c.duration, n - 2)]))
        s = c.motion().sample(t)
        clean = model.loads(s)

        def noisy(a):
            return a + noise * np.std(a) * rng.standard_normal(a.shape)

        loads = Loads(t, noisy(clean.normal_force), noisy(clean.tangential_force),
                      noisy(clean.moment))
        recs.append(CfdRecord(c.case_id, s, loads, c.as_dict()))
    return recs


def test_strategy_weights():
    fs = [0.1, 0.2, 0.5, 1.0, 2.0, 2.0, 0.1]
    assert frequency_weights(fs, "uniform") == pytest.approx({f: 0.2 for f in set(fs)})
    low = frequency_weights(fs, "low")
    assert list(low.values()) == pytest.approx([0.4, 0.3, 0.15, 0.1, 0.05])
    assert list(frequency_weights(fs, "high").values()) == pytest.approx(
        [0.05, 0.1, 0.15, 0.3, 0.4])
    assert frequency_weights(fs, [1, 1, 0, 0, 2])[2.0] == pytest.approx(0.5)
    three = frequency_weights([1, 2, 3], "low")
    assert three[1] > three[2] > three[3] and sum(three.values()) == pytest.approx(1)
    with pytest.raises(ConfigError, match="unknown weighting strategy 'mid'"):
        frequency_weights(fs, "mid")
    with pytest.raises(ConfigError, match="one finite weight >= 0 per distinct frequency"):
        frequency_weights(fs, [1, 2])


@pytest.mark.parametrize("residual_scaling", ["grid", "case"])
@pytest.mark.parametrize("strategy", ["uniform", "low", "high"])
@pytest.mark.slow
def test_recovers_known_coefficients_within_stated_uncertainty(strategy, residual_scaling):
    """Synthetic CFD from the model itself, 5 % noise, uneven adaptive-like time steps."""
    rng = np.random.default_rng(7)
    cases, excluded = prepare_cases(synthetic_records(rng))
    assert not excluded and len(cases) == 45
    res = identify(cases, MorisonModel(), strategy, n_bootstrap=100,
                   residual_scaling=residual_scaling)
    assert res.residual_scaling == residual_scaling
    for name, value in TRUE.items():
        se = res.standard_error[name]
        assert se > 0
        assert abs(res.coefficients[name] - value) < 4 * se + 1e-3 * value, name
    assert np.all(res.metrics["normal_force"]["pearson"] > 0.99)


def test_fixed_terms_and_subset_of_components():
    rng = np.random.default_rng(3)
    cases, _ = prepare_cases(synthetic_records(rng, noise=0.0))
    res = identify(cases, MorisonModel(), components=("tangential_force",),
                   fixed={"normal_drag": 2.0, "normal_added_mass": 1.2}, n_bootstrap=0)
    assert res.fitted_terms == ("tangential_added_mass", "tangential_drag")
    # exact but for the linear resampling of uneven samples onto the uniform base
    assert res.coefficients["tangential_drag"] == pytest.approx(4.0, rel=2e-3)
    assert res.coefficients["tangential_added_mass"] == pytest.approx(0.5, rel=2e-3)
    with pytest.raises(ConfigError, match="unknown terms"):
        identify(cases, MorisonModel(), fixed={"lift": 1.0})
    with pytest.raises(ConfigError, match="cannot fit components"):
        identify(cases, MorisonModel(), components=("thrust",))


def test_unidentifiable_term_is_refused():
    rng = np.random.default_rng(3)
    cases, _ = prepare_cases(synthetic_records(rng))
    with pytest.raises(MfflapError, match="do not determine"):
        # no case data on F_t: its two coefficients are undetermined
        identify(cases, MorisonModel(), components=("normal_force",),
                 fixed={"normal_drag": 2.0, "normal_added_mass": 1.2})


@pytest.mark.slow
def test_a_coefficient_the_data_make_negative_is_held_at_zero_and_said_so(tmp_path):
    """Forces made with C_Dt = -1: the bounded fit holds C_Dt at 0 (the unconstrained fit
    is negative), the others stay near their values, and the CLI and report say it."""
    from click.testing import CliRunner

    from mfflap.cli.main import cli
    from mfflap.records.record import write_record

    rng = np.random.default_rng(5)
    negative = {**TRUE, "tangential_drag": -1.0}
    records = synthetic_records(rng, noise=0.0, coefficients=negative,
                                subset=grid_cases(IdentificationGrid(),
                                                  heave_amplitudes=[0.2, 0.4],
                                                  phases_deg=[90, 135]))
    cases, _ = prepare_cases(records)
    res = identify(cases, MorisonModel(), n_bootstrap=0)
    assert res.at_lower_bound == ("tangential_drag",)
    assert res.coefficients["tangential_drag"] == 0.0
    assert res.coefficients["normal_drag"] == pytest.approx(2.0, rel=0.05)
    # the same data with the true value: nothing held
    records_ok = synthetic_records(rng, noise=0.0, subset=grid_cases(
        IdentificationGrid(), heave_amplitudes=[0.2, 0.4], phases_deg=[90, 135]))
    assert identify(prepare_cases(records_ok)[0], MorisonModel(),
                    n_bootstrap=0).at_lower_bound == ()

    folder = tmp_path / "fixtures"
    for rec in records:
        write_record(folder / f"{rec.name}.h5", rec, single_precision=True)
    case_file = Path(__file__).parents[2] / "cases" / "paper2026.toml"
    out = tmp_path / "id.h5"
    runner = CliRunner()
    res = runner.invoke(cli, ["identify", str(case_file), "--fixtures", str(folder),
                              "--strategy", "uniform", "--bootstrap", "0", "--output",
                              str(out)])
    assert res.exit_code == 0, res.output
    assert "tangential_drag = 0.000 (held at 0)" in res.output
    assert "held at 0: the fit without the bound makes the coefficient negative" in res.output
    res = runner.invoke(cli, ["identify", str(case_file), "--fixtures", str(folder),
                              "--strategy", "uniform", "--bootstrap", "0", "--output",
                              str(out), "--json"])
    assert json.loads(res.stdout)["uniform"]["at_lower_bound"] == ["tangential_drag"]
    res = runner.invoke(cli, ["report", "identification", str(out), "--out",
                              str(tmp_path / "id.html")])
    assert res.exit_code == 0, res.output
    assert "Held at 0: tangential_drag (uniform)" in (tmp_path / "id.html").read_text()


@pytest.mark.parametrize(("components", "message"), [
    ("", "no names"), ("normal_force,normal_force", "normal_force given twice"),
    ("thrust", "thrust: not one of normal_force, tangential_force, moment")])
def test_identify_components_are_checked_by_name(tmp_path, components, message):
    from click.testing import CliRunner

    from mfflap.cli.main import cli

    case_file = Path(__file__).parents[2] / "cases" / "paper2026.toml"
    res = CliRunner().invoke(cli, ["identify", str(case_file), "--components", components,
                                   "--output", str(tmp_path / "id.h5")])
    assert res.exit_code == 2 and "--components" in res.output and message in res.output
    assert not (tmp_path / "id.h5").exists()


def test_gap_and_short_records_are_refused_by_name():
    rng = np.random.default_rng(0)
    rec = synthetic_records(rng, subset=grid_cases(IdentificationGrid(), [1.0], [0.3], [90]))[0]
    keep = (rec.time < 1.2) | (rec.time > 2.0)
    gappy = CfdRecord(rec.name, rec.state.__class__(**{
        k: getattr(rec.state, k)[keep] for k in ("time", "pitch_angle", "pitch_rate",
                                                 "pitch_acceleration", "heave_position",
                                                 "heave_velocity", "heave_acceleration")}),
        Loads(rec.time[keep], rec.loads.normal_force[keep], rec.loads.tangential_force[keep],
              rec.loads.moment[keep]), rec.parameters)
    with pytest.raises(MfflapError, match=rf"record {rec.name}: gap in the force history"):
        prepare_case(gappy)
    cases, excluded = prepare_cases([gappy, rec])
    assert [c.name for c in cases] == [rec.name] and rec.name in excluded
    with pytest.raises(MfflapError, match="remain after discarding"):
        prepare_case(rec, discard_time=2.9)


def _retimed(rec, time, keep=slice(None)):
    """The samples ``keep`` of ``rec`` moved to ``time``: another time-step history."""
    from mfflap.kinematics.state import KinematicState

    state = KinematicState(time=time[keep], **{k: getattr(rec.state, k)[keep] for k in (
        "pitch_angle", "pitch_rate", "pitch_acceleration", "heave_position", "heave_velocity",
        "heave_acceleration")})
    return CfdRecord(rec.name, state, Loads(time[keep], rec.loads.normal_force[keep],
                                            rec.loads.tangential_force[keep],
                                            rec.loads.moment[keep]), rec.parameters)


def test_adaptive_time_step_is_not_a_gap_but_a_missing_stretch_is():
    # like a real run (f1p000_h0p500_phi135p0 of tests/data/openfoam_v1912/lost_numerics):
    # the step grows 20 % a step from 1.2e-4 s to 2.8e-3 s at the start, then falls to
    # 2.9e-5 s (there because the run lost its numerics), a hundred times below its early
    # size; the time base alone must not refuse it
    rng = np.random.default_rng(1)
    rec = synthetic_records(rng, subset=grid_cases(IdentificationGrid(), [1.0], [0.3], [90]))[0]
    n = len(rec.time)
    grow = 1.2e-4 * 1.2 ** np.arange(18)
    steps = np.concatenate([grow, np.full(12, grow[-1]), np.geomspace(grow[-1], 2.9e-5, 25)])
    steps = np.concatenate([steps, np.full(n - 1 - len(steps), 2.9e-5)])
    steps *= 3.0 / steps.sum()  # the same 3 s run
    time = np.concatenate([[0.0], np.cumsum(steps)])
    assert steps.max() / np.median(steps) > 50  # the old global-median test refused this
    assert prepare_case(_retimed(rec, time)).name == rec.name
    # nor is a sudden hundredfold drop of the step
    sudden = np.concatenate([np.full(40, 2.8e-3), np.full(n - 41, 2.8e-5)])
    sudden *= 3.0 / sudden.sum()
    assert prepare_case(_retimed(rec, np.concatenate([[0.0], np.cumsum(sudden)]))).name
    # 40 samples missing among the small steps (a killed run's lost stretch): refused, with
    # the times of the gap
    cut = np.r_[0:n // 2, n // 2 + 40:n]
    with pytest.raises(MfflapError, match=rf"record {rec.name}: gap .* times the steps"):
        prepare_case(_retimed(rec, time, cut))


@pytest.mark.slow
def test_identify_cli_report_and_hdf5_round_trip(tmp_path):
    """CLI on a folder of real HDF5 records (synthetic forces), a failed case named."""
    from click.testing import CliRunner

    from mfflap.cli.main import cli
    from mfflap.identification.store import read_identification
    from mfflap.records.record import write_record
    from mfflap.results import ResultsFile

    rng = np.random.default_rng(11)
    folder = tmp_path / "fixtures"
    for rec in synthetic_records(rng, subset=grid_cases(IdentificationGrid(),
                                                         heave_amplitudes=[0.2, 0.4],
                                                         phases_deg=[90, 135])):
        write_record(folder / f"{rec.name}.h5", rec, single_precision=True)
    (folder / "f9p000_h0p100_phi090p0.failed.toml").write_text(
        'case_id = "f9p000_h0p100_phi090p0"\nerror = "pimpleFoam diverged"\n')
    case_file = Path(__file__).parents[2] / "cases" / "paper2026.toml"
    out = tmp_path / "id.h5"
    runner = CliRunner()
    res = runner.invoke(cli, ["identify", str(case_file), "--fixtures", str(folder),
                              "--output", str(out), "--bootstrap", "50", "--json"])
    assert res.exit_code == 0, res.output
    summary = json.loads(res.stdout)
    assert set(summary) == {"uniform", "low", "high"}
    assert summary["uniform"]["coefficients"]["normal_drag"] == pytest.approx(2.0, rel=0.02)
    assert "f9p000_h0p100_phi090p0" in summary["low"]["excluded"]
    with ResultsFile(out) as rf:
        back = read_identification(rf, "identification/low")
        assert "paper2026" in rf.config_toml
    assert back.coefficients == pytest.approx(summary["low"]["coefficients"])
    assert back.weights[0.1] == pytest.approx(0.4)
    html_path = tmp_path / "id.html"
    res = runner.invoke(cli, ["report", "identification", str(out), "--out", str(html_path)])
    assert res.exit_code == 0, res.output
    text = html_path.read_text()
    assert text.count("<img") >= 10 and "pimpleFoam diverged" in text
    assert "CFD cases used" in text and "f1p000_h0p200_phi090p0" in text
    assert "Sensitivity to the frequency weighting" in text


def test_one_step_cfd_glitch_is_removed_and_reported():
    rng = np.random.default_rng(5)
    rec = synthetic_records(rng, noise=0.0, subset=grid_cases(IdentificationGrid(), [1.0],
                                                              [0.3], [90]), n=3000)[0]
    clean = prepare_case(rec)
    assert clean.notes == []
    i = int(np.searchsorted(rec.time, 1.94))
    rec.loads.normal_force[i] += 40 * np.ptp(rec.loads.normal_force)
    glitched = prepare_case(rec)
    # a one-step glitch is the shortest numerical burst: bridged, and reported with its time
    assert len(glitched.notes) == 1 and glitched.notes[0].startswith("1 numerical burst")
    assert "t = 1.9" in glitched.notes[0]
    np.testing.assert_allclose(glitched.cfd.normal_force, clean.cfd.normal_force,
                               atol=2e-2 * np.ptp(clean.cfd.normal_force))


@pytest.mark.slow
def test_several_record_folders_pool_and_fill_failed_cases(tmp_path):
    """Two folders pool their records; a case failed in one and done in the other is used,
    one failed everywhere stays out, and one recorded twice is refused naming both files."""
    from click.testing import CliRunner

    from mfflap.cli.main import cli
    from mfflap.identification.workflow import load_cases
    from mfflap.records.record import write_record
    from mfflap.results import ResultsFile

    rng = np.random.default_rng(5)
    recs = synthetic_records(rng, subset=grid_cases(IdentificationGrid(),
                                                    heave_amplitudes=[0.2, 0.4],
                                                    phases_deg=[90, 135]))
    first, second = tmp_path / "campaign_a", tmp_path / "campaign_b"
    moved = recs[3].name
    for i, rec in enumerate(recs):
        write_record((second if i == 3 else first) / f"{rec.name}.h5", rec)
    (first / f"{moved}.failed.toml").write_text(
        f'case_id = "{moved}"\nerror = "forces beyond the bound"\n')
    (second / "f9p000_h0p100_phi090p0.failed.toml").write_text(
        'case_id = "f9p000_h0p100_phi090p0"\nerror = "pimpleFoam diverged"\n')
    config = _paper_case()
    only_first, excluded_first = load_cases(config, first)
    assert moved not in {c.name for c in only_first} and moved in excluded_first
    pooled, excluded = load_cases(config, [first, second])
    assert {c.name for c in pooled} == {r.name for r in recs}
    assert moved not in excluded
    assert "pimpleFoam diverged" in excluded["f9p000_h0p100_phi090p0"]
    assert str(second) in excluded["f9p000_h0p100_phi090p0"]

    out = tmp_path / "id.h5"
    runner = CliRunner()
    res = runner.invoke(cli, ["identify", str(_PAPER), "--fixtures", str(first),
                              "--fixtures", str(second), "--strategy", "uniform",
                              "--bootstrap", "20", "--output", str(out)])
    assert res.exit_code == 0, res.output
    assert f"{len(recs)} cases from {first}, {second}; 1 left out" in res.output
    with ResultsFile(out) as rf:
        assert rf.h5["identification"].attrs["source"] == f"{first}\n{second}"
    html_path = tmp_path / "id.html"
    res = runner.invoke(cli, ["report", "identification", str(out), "--out", str(html_path)])
    assert res.exit_code == 0, res.output
    assert f"{first}, {second}" in html_path.read_text()

    write_record(second / f"{recs[0].name}.h5", recs[0])
    with pytest.raises(MfflapError, match=f"{recs[0].name} has a record in {first} and in "
                                          f"{second}"):
        load_cases(config, [first, second])
    picked, excluded = load_cases(config, [first, second / f"{moved}.h5"])
    assert {c.name for c in picked} == {r.name for r in recs} and excluded == {}


_PAPER = Path(__file__).parents[2] / "cases" / "paper2026.toml"


def _paper_case():
    from mfflap.config import load_case

    return load_case(_PAPER)


def _shipped_cases():
    """The 43 usable Table 1 cases of the shipped ``table1_coarse`` records (max Co 4, the
    log-law wall functions): a real set whose fit has an influential case and a tangential
    drag at its bound."""
    from mfflap.config import load_case
    from mfflap.identification.workflow import load_cases

    case = load_case(Path(__file__).parents[2] / "cases" / "paper2026.toml")
    return case, *load_cases(case, [fixture_dir("table1_coarse")])


@pytest.mark.parametrize("strategy", ["uniform", "low", [1.0, 2.0, 3.0, 0.5, 1.0]])
@pytest.mark.slow
def test_each_cases_refit_without_it_is_identify_run_without_it(strategy):
    """The leave-one-out rows are the fits `identify` makes of the other cases (the
    table1_coarse records; the case of the largest forces, and the first and last)."""
    case, cases, _ = _shipped_cases()
    res = identify(cases, case.morison_model(), strategy, n_bootstrap=0)
    assert res.leave_one_out.shape == (len(cases), len(res.fitted_terms))
    largest = [c.name for c in cases].index("f2p000_h0p500_phi135p0")
    for i in (0, largest, len(cases) - 1):
        rest = cases[:i] + cases[i + 1:]
        alone = identify(rest, case.morison_model(), strategy, n_bootstrap=0)
        assert res.leave_one_out[i] == pytest.approx(
            [alone.coefficients[n] for n in res.fitted_terms], rel=1e-9, abs=1e-12)


def test_the_most_influential_case_is_named_with_how_far_it_moves_the_coefficient():
    """On the table1_coarse records the normal drag rests most on f = 2 Hz, h = 0.5 m,
    phi = 135 deg (5.05, and 5.53 without it), about one bootstrap standard error; a held term
    that no case moves is not listed."""
    from mfflap.identification.fit import most_influential

    case, cases, _ = _shipped_cases()
    res = identify(cases, case.morison_model(), "uniform", n_bootstrap=200)
    found = {i.term: i for i in most_influential(res)}
    drag = found["normal_drag"]
    assert drag.case == "f2p000_h0p500_phi135p0"
    assert (drag.value, drag.value_without) == pytest.approx((5.05, 5.53), abs=0.01)
    assert drag.relative_change == pytest.approx(0.095, abs=0.002)
    assert drag.in_standard_errors == pytest.approx(
        (5.53 - 5.05) / res.standard_error["normal_drag"], rel=0.01)
    assert str(drag).startswith("normal_drag: f2p000_h0p500_phi135p0 (5.05 -> 5.53, +9.5%")
    # every listed change is the largest over the cases
    for inf in found.values():
        j = res.fitted_terms.index(inf.term)
        assert abs(inf.change) == pytest.approx(
            np.nanmax(np.abs(res.leave_one_out[:, j] - inf.value)))
    assert "tangential_drag" in res.at_lower_bound and "tangential_drag" not in found


def test_a_frequency_of_one_case_drops_out_of_its_refit_and_one_case_has_none():
    """Leaving out the only case of a frequency refits the others with their own weights;
    a single case leaves nothing to refit: NaN, and nothing is named."""
    from mfflap.identification.fit import most_influential

    rng = np.random.default_rng(3)
    records = synthetic_records(rng, subset=grid_cases(
        IdentificationGrid(frequencies=[0.5, 1.0, 2.0]), heave_amplitudes=[0.1, 0.3],
        phases_deg=[90]))
    records = [r for r in records if not (r.name.startswith("f2p000") and "h0p300" in r.name)]
    cases, _ = prepare_cases(records)
    res = identify(cases, MorisonModel(), "uniform", n_bootstrap=0)
    lone = [c.name for c in cases].index("f2p000_h0p100_phi090p0")
    rest = cases[:lone] + cases[lone + 1:]
    alone = identify(rest, MorisonModel(), "uniform", n_bootstrap=0)
    assert res.leave_one_out[lone] == pytest.approx(
        [alone.coefficients[n] for n in res.fitted_terms], rel=1e-9)
    single = identify(cases[:1], MorisonModel(), "uniform", n_bootstrap=0)
    assert np.all(np.isnan(single.leave_one_out)) and most_influential(single) == []


@pytest.mark.slow
def test_the_refits_are_stored_reported_and_printed(tmp_path):
    """`mfflap identify` prints the case that moves each coefficient most and keeps the
    refits in its HDF5 file; the report tabulates and draws them; a file written before
    they were kept reads back without them and reports without the table."""
    from click.testing import CliRunner

    from mfflap.cli.main import cli
    from mfflap.identification.store import read_identification
    from mfflap.results import ResultsFile

    case_file = Path(__file__).parents[2] / "cases" / "paper2026.toml"
    out = tmp_path / "id.h5"
    runner = CliRunner()
    table1_coarse = str(fixture_dir("table1_coarse"))  # 43 cases, one that moves C_Dn most
    res = runner.invoke(cli, ["identify", str(case_file), "--fixtures", table1_coarse,
                              "--strategy", "uniform", "--residual-scaling", "grid",
                              "--bootstrap", "50", "--output", str(out)])
    assert res.exit_code == 0, res.output
    assert ("left out, moves most: normal_added_mass: f2p000_h0p500_phi045p0" in res.output
            and "normal_drag: f2p000_h0p500_phi135p0 (5.05 -> 5.53, +9.5%" in res.output)
    res = runner.invoke(cli, ["identify", str(case_file), "--fixtures", table1_coarse,
                              "--strategy", "uniform", "--residual-scaling", "grid",
                              "--bootstrap", "50", "--output", str(tmp_path / "j.h5"),
                              "--json"])
    moved = json.loads(res.stdout)["uniform"]["most_influential"]["normal_drag"]
    assert moved["case"] == "f2p000_h0p500_phi135p0"
    assert moved["relative_change"] == pytest.approx(0.095, abs=0.002)
    with ResultsFile(out) as rf:
        back = read_identification(rf, "identification/uniform")
        assert rf.units("identification/uniform")["leave_one_out"] == "1"
    assert back.leave_one_out.shape == (43, 4)
    html = tmp_path / "id.html"
    assert runner.invoke(cli, ["report", "identification", str(out), "--out",
                               str(html)]).exit_code == 0
    text = html.read_text()
    assert "<th>most influential case</th>" in text
    assert ("<td>normal_drag</td><td>5.05</td><td>f2p000_h0p500_phi135p0</td><td>5.531</td>"
            "<td>+9.5%</td>") in text
    assert "Coefficients refitted without each case (uniform weighting)" in text
    with ResultsFile(out, "a") as rf:  # as a file written before the refits were kept
        del rf.h5["identification/uniform/leave_one_out"]
    with ResultsFile(out) as rf:
        assert read_identification(rf, "identification/uniform").leave_one_out.size == 0
    assert runner.invoke(cli, ["report", "identification", str(out), "--out",
                               str(html)]).exit_code == 0
    assert "most influential case" not in html.read_text()


def _mean_square_nrmse(cases, model, weights, components=("normal_force", "tangential_force",
                                                          "moment")) -> float:
    """sum over cases of w_f / n_f times the sum of the components' squared NRMSE."""
    from mfflap.identification.fit import score

    metrics = score(cases, model, components)
    freqs = np.array([c.frequency for c in cases])
    total = 0.0
    for i, f in enumerate(freqs):
        share = weights[f] / np.sum(np.isclose(freqs, f))
        total += share * sum(metrics[k]["nrmse"][i] ** 2 for k in components)
    return total


def test_case_scaling_fits_the_mean_square_nrmse_and_every_run_weighs_alike():
    """With residual_scaling="case" the fit is the least weighted mean square NRMSE: every
    step of a coefficient off it (within its bound) raises it, and the grid-scaled fit's
    coefficients give more. On the table1_coarse records no run then moves the normal drag by
    more than 4 % (f = 2 Hz, h = 0.5 m, phi = 135 deg moves it by 9.5 % with grid scaling),
    the bootstrap spreads narrow and the tangential drag is determined
    (docs/findings/known_limits.md)."""
    from mfflap.identification.fit import most_influential

    case, cases, _ = _shipped_cases()
    base = case.morison_model()
    by_case = identify(cases, base, "uniform", n_bootstrap=200, residual_scaling="case")
    on_grid = identify(cases, base, "uniform", n_bootstrap=200)
    best = _mean_square_nrmse(cases, by_case.model(base), by_case.weights)
    assert _mean_square_nrmse(cases, on_grid.model(base), on_grid.weights) > best * 1.01
    for name, value in by_case.coefficients.items():
        for step in (-0.02, 0.02):
            moved = dict(by_case.coefficients, **{name: max(0.0, value * (1 + step))})
            assert _mean_square_nrmse(cases, base.with_coefficients(moved),
                                      by_case.weights) > best
    assert by_case.coefficients["tangential_drag"] > 3 * by_case.standard_error[
        "tangential_drag"] > 0
    assert on_grid.coefficients["tangential_drag"] == 0.0
    for term in ("normal_added_mass", "normal_drag"):
        assert by_case.standard_error[term] < 0.6 * on_grid.standard_error[term]
    drag = {i.term: i for i in most_influential(by_case)}["normal_drag"]
    assert abs(drag.relative_change) < 0.04


@pytest.mark.slow
def test_the_residual_scaling_comes_from_the_case_file_or_the_command_line(tmp_path):
    """[identification] residual_scaling is checked by key; the CLI option overrides it;
    the HDF5 file keeps it (an older file without it reads as grid) and the report says
    it."""
    from click.testing import CliRunner

    from mfflap.cli.main import cli
    from mfflap.config import load_case
    from mfflap.identification.store import read_identification
    from mfflap.results import ResultsFile

    text = (Path(__file__).parents[2] / "cases" / "paper2026.toml").read_text()
    marker = "[identification]  # Table 1\n"
    assert marker in text
    bad = tmp_path / "bad.toml"
    bad.write_text(text.replace(marker, marker + 'residual_scaling = "rms"\n'))
    with pytest.raises(ConfigError, match="not allowed") as err:
        load_case(bad)
    assert err.value.key == "identification.residual_scaling"
    with pytest.raises(ConfigError, match="choose one of grid, case") as err:
        identify(_shipped_cases()[1], MorisonModel(), residual_scaling="rms")
    assert err.value.key == "identification.residual_scaling"
    by_case = tmp_path / "case.toml"
    by_case.write_text(text.replace(marker, marker + 'residual_scaling = "case"\n'))
    runner = CliRunner()
    for case_file, option, expected in ((by_case, [], "case"),
                                        (by_case, ["--residual-scaling", "grid"], "grid")):
        out = tmp_path / f"{expected}.h5"
        res = runner.invoke(cli, ["identify", str(case_file), "--strategy", "uniform",
                                  "--bootstrap", "10", "--output", str(out), *option])
        assert res.exit_code == 0, res.output
        said = {"case": "each component of each case by its range in that case",
                "grid": "each component by its RMS over every case"}[expected]
        assert f"residuals scaled {said}" in res.output
        with ResultsFile(out) as rf:
            assert read_identification(rf, "identification/uniform").residual_scaling == (
                expected)
        html = tmp_path / f"{expected}.html"
        assert runner.invoke(cli, ["report", "identification", str(out), "--out",
                                   str(html)]).exit_code == 0
        assert f"Residuals scaled {said}" in html.read_text()
    with ResultsFile(tmp_path / "case.h5", "a") as rf:  # as written before the choice
        del rf.h5["identification/uniform"].attrs["residual_scaling"]
    with ResultsFile(tmp_path / "case.h5") as rf:
        assert read_identification(rf, "identification/uniform").residual_scaling == "grid"


@pytest.mark.slow
def test_a_case_can_be_left_out_by_name_and_its_fit_is_the_refit_without_it(tmp_path):
    """`identify --exclude CASE` fits without that case (the jackknife's row for it), lists
    it among the cases left out with the reason; a name that is none of the cases is
    refused by the option's name, listing the cases, before anything is written."""
    from click.testing import CliRunner

    from mfflap.cli.main import cli

    case_file = Path(__file__).parents[2] / "cases" / "paper2026.toml"
    runner = CliRunner()
    table1_coarse = str(fixture_dir("table1_coarse"))  # 43 cases, one that moves C_Dn most
    full = json.loads(runner.invoke(cli, [
        "identify", str(case_file), "--fixtures", table1_coarse, "--strategy", "uniform",
        "--residual-scaling", "grid", "--bootstrap", "0", "--output",
        str(tmp_path / "all.h5"), "--json"]).stdout)["uniform"]
    res = runner.invoke(cli, ["identify", str(case_file), "--fixtures", table1_coarse,
                              "--strategy", "uniform", "--residual-scaling", "grid",
                              "--bootstrap", "0", "--exclude", "f2p000_h0p500_phi135p0",
                              "--output", str(tmp_path / "without.h5"), "--json"])
    assert res.exit_code == 0, res.output
    without = json.loads(res.stdout)["uniform"]
    assert without["n_cases"] == full["n_cases"] - 1 == 42
    assert without["excluded"]["f2p000_h0p500_phi135p0"] == "left out on request (--exclude)"
    moved = full["most_influential"]["normal_drag"]
    assert moved["case"] == "f2p000_h0p500_phi135p0"
    assert without["coefficients"]["normal_drag"] == pytest.approx(moved["value_without"],
                                                                   rel=1e-9)
    res = runner.invoke(cli, ["identify", str(case_file), "--fixtures", table1_coarse,
                              "--exclude", "f2p000_h0p500_phi136p0",
                              "--output", str(tmp_path / "typo.h5")])
    assert res.exit_code == 2
    assert "Invalid value for --exclude: no case 'f2p000_h0p500_phi136p0' among the 43" in (
        res.output)
    assert "f2p000_h0p500_phi135p0" in res.output and not (tmp_path / "typo.h5").exists()


def test_a_pooled_back_test_weighs_as_its_own_frequency_and_a_case_of_none_is_refused():
    """A back-test record (a periodic motion: a period, no frequency) is a frequency of its
    own, 1 / period; before, its frequency was NaN and it took the lowest frequency's share
    (with only such records the fit divided by zero). A record of neither is refused."""
    from mfflap.backtest.run import cfd_motion
    from mfflap.cfd.imposed_motion import imposed_state
    from mfflap.identification.data import CaseData
    from mfflap.kinematics.convert import harmonic_to_discrete

    model = MorisonModel().with_coefficients(TRUE)
    cases = []
    for i, (f, h) in enumerate([(0.8, 0.2), (1.3, 0.1), (2.1, 0.05)]):
        spline = cfd_motion(harmonic_to_discrete(f, h, np.deg2rad(30), np.deg2rad(90), 40))
        t = np.linspace(0, 3 * spline.period, 900)
        state = imposed_state(spline, t, 0.5 * spline.period)
        cases.append(CfdRecord(f"backtest_{i}", state, model.loads(state),
                               {"kind": "periodic_spline", "period": spline.period}))
    prepared, excluded = prepare_cases(cases, discard_time=0.0)
    assert not excluded
    assert [c.frequency for c in prepared] == pytest.approx([0.8, 1.3, 2.1], rel=1e-6)
    res = identify(prepared, MorisonModel(), "uniform", n_bootstrap=0)
    assert res.coefficients == pytest.approx(TRUE, rel=1e-3)  # the model's own forces
    bare = CaseData("no_frequency", {"kind": "external"}, prepared[0].state, prepared[0].cfd)
    with pytest.raises(ConfigError, match="no_frequency: the record gives neither a frequency "
                                          "nor a period"):
        identify([*prepared, bare], MorisonModel(), "uniform", n_bootstrap=0)
