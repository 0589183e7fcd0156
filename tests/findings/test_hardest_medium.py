"""The grid's hardest motions on the medium mesh (campaigns/hardest_medium, its f = 0.5 Hz
run again as one set-up in campaigns/hardest_medium_from_start) and on the coarse mesh at
max Co 1 from the start (campaigns/hardest_coarse_co1), committed as their runs finish:
whether a finer mesh or a smaller time step from t = 0 holds what the coarse mesh
lost from its last writes, and how far the coarse mesh is from the medium one where both
hold."""

from pathlib import Path

import pytest

from mfflap.campaign.compare import compare_records
from mfflap.campaign.execute import campaign_status
from mfflap.identification.data import prepare_case
from mfflap.records.as_run import as_run_since_s
from mfflap.records.record import fixture_dir, read_record, record_paths
from mfflap.toml_io import read_toml

pytestmark = pytest.mark.findings  # shipped research data, not code

CAMPAIGNS = Path(__file__).parents[2] / "campaigns"
MEDIUM = CAMPAIGNS / "hardest_medium"
CO1 = CAMPAIGNS / "hardest_coarse_co1"
CO05 = CAMPAIGNS / "hardest_coarse_co05"


def test_the_medium_campaign_is_the_shipped_set_up_on_the_medium_mesh():
    medium, shipped = (read_toml(d / "campaign.toml")
                       for d in (MEDIUM, fixture_dir("table1_coarse")))
    assert medium["setup"]["mesh"] == "medium"
    assert medium["setup"]["solver"] == shipped["setup"]["solver"]
    for case_id, motion in medium["cases"].items():
        assert motion == shipped["cases"][case_id]
        assert motion["heave_amplitude"] == 0.5 and motion["phase_deg"] == 135.0


@pytest.mark.parametrize("path", record_paths(MEDIUM) + record_paths(CO1) + record_paths(CO05),
                         ids=lambda p: f"{p.parent.name}/{p.stem}")
def test_a_finished_run_of_a_hardest_motion_is_done_and_fit_for_identification(path):
    """What campaign status and identification judge: no numerical burst after the ramp,
    not lost (inside the force bound), so identification takes it as it is. Only the run of
    f = 0.5 Hz on the medium mesh, resumed at max Co 2 from t = 4.5 s, is noted as fitted
    across two set-ups, and campaign status says so (and nothing else)."""
    from mfflap.identification.data import SET_UP_NOTE

    rec = read_record(path)
    assert rec.provenance["mesh"] == ("medium" if path.parent == MEDIUM else "coarse")
    status = {s.case_id: s for s in campaign_status(path.parent)}[path.stem]
    case = prepare_case(rec)
    mixed = [n for n in case.notes if n.startswith(SET_UP_NOTE)]
    assert [n for n in case.notes if n not in mixed] == []  # nothing bridged or despiked
    is_mixed = path.parent == MEDIUM and path.stem == "f0p500_h0p500_phi135p0"
    assert len(mixed) == is_mixed
    assert status.state == "done" and status.mixed_since_s == (4.5 if is_mixed else None)
    assert status.message.startswith("a retry resumed it from t = 4.5 s") == is_mixed
    assert (status.message == "") == (not is_mixed)
    assert case.state.time[-1] == pytest.approx(rec.time[-1], rel=1e-6)


def test_the_max_co_1_campaign_is_the_shipped_set_up_at_max_co_1_with_inlet_outlet():
    co1, shipped = (read_toml(d / "campaign.toml") for d in (CO1, fixture_dir("table1_coarse")))
    solver = co1["setup"]["solver"]
    changed = {k: v for k, v in solver.items() if shipped["setup"]["solver"][k] != v}
    assert changed == {"max_courant": 1.0, "far_field": "inletOutlet"}
    assert co1["setup"]["mesh"] == shipped["setup"]["mesh"] == "coarse"
    for case_id, motion in co1["cases"].items():
        assert motion == shipped["cases"][case_id]


@pytest.mark.parametrize(("name", "lost_at_max_co_2", "end_s"), [
    ("f2p000_h0p500_phi135p0", "from t = 0.464361 s; resumed from t = 0.375 s with maxCo 0.25",
     1.5),
    ("f0p500_h0p500_phi135p0", "the forces leave what the motion can drive, t = 1.638", 6.0),
])
def test_a_motion_lost_from_its_writes_at_max_co_2_held_at_max_co_1_from_the_start(
        name, lost_at_max_co_2, end_s):
    """f = 2 Hz, h = 0.5 m, phi = 135 deg lost its numerics at t = 0.464 s at max Co 2 and
    again from its write at t = 0.375 s at max Co 1, 0.5 and 0.25; f = 0.5 Hz at t = 1.638 s
    and from its write at t = 1.5 s at max Co 1 and 0.5. From t = 0 at max Co 1 (inletOutlet
    from the start) each runs to its end with no retry, inside the bound."""
    failed = read_toml(CAMPAIGNS / "table1_coarse_co2" / f"{name}.failed.toml")
    assert lost_at_max_co_2 in failed["error"]
    rec = read_record(CO1 / f"{name}.h5")
    assert rec.provenance["solver_max_courant"] == 1.0
    assert "retries" not in rec.provenance
    assert rec.time[-1] == pytest.approx(end_s, abs=1e-3)


def test_the_coarse_mesh_is_far_from_the_medium_one_on_the_hardest_motion():
    """f = 1 Hz, h = 0.5 m, phi = 135 deg held on both meshes (coarse at max Co 2): the
    first period after the ramp agrees well, the later ones, dominated by shed vortices,
    do not; the coarse mesh's mean thrust is about half the medium's."""
    name = "f1p000_h0p500_phi135p0.h5"
    medium = read_record(MEDIUM / name)
    coarse = read_record(CAMPAIGNS / "table1_coarse_co2" / name)
    whole = compare_records(medium, coarse)
    assert whole.pearson_normal_force > 0.6
    assert 0.1 < whole.nrmse_normal_force < 0.3
    assert 1.5 < whole.mean_thrust_a_n / whole.mean_thrust_b_n < 2.5
    assert abs(whole.power_difference) < 0.2
    first_period = compare_records(medium, coarse, end_s=1.0)  # the ramp's end to t = 1 s
    later = compare_records(medium, coarse, start_s=1.0)
    assert first_period.nrmse_normal_force < 0.1 < later.nrmse_normal_force
    assert later.nrmse_normal_force > 1.5 * first_period.nrmse_normal_force


def test_the_medium_mesh_carries_f05_through_two_collapsed_time_steps():
    """f = 0.5 Hz, h = 0.5 m, phi = 135 deg, lost by the coarse mesh at max Co 4 and 2, runs
    to its end on the medium mesh after two collapsed time steps (the inletOutlet far field,
    then max Co 2)."""
    medium = read_record(MEDIUM / "f0p500_h0p500_phi135p0.h5")
    assert medium.provenance["retries"].count("time step collapsed") == 2
    assert medium.time[-1] == pytest.approx(6.0, abs=1e-3)


def test_at_f05_the_coarse_mesh_is_nearer_the_medium_one_than_at_f1():
    """Against the medium mesh (the reference), the coarse mesh's run of the same motion at
    half the frequency (max Co 1 from t = 0) is about 12 % NRMSE (F_n) away with mean thrust
    and power within 10 %; at f = 1 Hz (max Co 2) it is 14 % away with half the thrust."""
    name = "f0p500_h0p500_phi135p0.h5"
    f05 = compare_records(read_record(CO1 / name), read_record(MEDIUM / name))
    f1 = compare_records(read_record(CAMPAIGNS / "table1_coarse_co2" /
                                     "f1p000_h0p500_phi135p0.h5"),
                         read_record(MEDIUM / "f1p000_h0p500_phi135p0.h5"))
    assert f05.pearson_normal_force > 0.75
    assert 0.05 < f05.nrmse_normal_force < f1.nrmse_normal_force
    assert abs(f05.thrust_difference) < 0.1 and abs(f05.power_difference) < 0.1
    assert -0.7 < f1.thrust_difference < -0.3


LOST_BY_CO2 = ("f0p500_h0p500_phi135p0", "f2p000_h0p500_phi135p0")
POOLED = [CAMPAIGNS / "table1_coarse_co2", *(CO1 / f"{n}.h5" for n in LOST_BY_CO2)]


@pytest.mark.slow
def test_the_two_campaigns_pooled_hold_the_whole_table_1_grid():
    """Max Co 2's 43 records and the max Co 1 runs of the two motions it lost: identification
    from both takes all 45 Table 1 motions and leaves none out. The max Co 1 folder as a
    whole also holds f = 1 Hz, which max Co 2 has too, so pooling the two folders is
    refused, naming both."""
    from mfflap.config import load_case
    from mfflap.errors import MfflapError
    from mfflap.identification.workflow import load_cases

    config = load_case(Path(__file__).parents[2] / "cases" / "paper2026.toml")
    with pytest.raises(MfflapError, match=r"f1p000_h0p500_phi135p0 has a record in .*"
                                          r"table1_coarse_co2 and in .*hardest_coarse_co1"):
        load_cases(config, [CAMPAIGNS / "table1_coarse_co2", CO1])
    cases, excluded = load_cases(config, POOLED)
    shipped = read_toml(fixture_dir("table1_coarse") / "campaign.toml")["cases"]
    assert {c.name for c in cases} == set(shipped) and len(shipped) == 45
    assert excluded == {}


@pytest.mark.slow
def test_the_pooled_identification_report_names_each_records_set_up(tmp_path):
    """`identify` from both folders, then its report: every Table 1 motion is listed with
    the set-up its record came from (max Co 1 and inletOutlet for the two the max Co 2
    campaign lost, max Co 2 for the rest)."""
    import re

    from click.testing import CliRunner

    from mfflap.cli.main import cli

    out = tmp_path / "pooled.h5"
    runner = CliRunner()
    pooled = [arg for path in POOLED for arg in ("--fixtures", str(path))]
    res = runner.invoke(cli, ["identify", str(Path(__file__).parents[2] / "cases" /
                                              "paper2026.toml"), *pooled,
                              "--strategy", "uniform", "--bootstrap", "20",
                              "--output", str(out)])
    assert res.exit_code == 0, res.output
    assert "45 cases from" in res.output and "0 left out" in res.output
    res = runner.invoke(cli, ["report", "identification", str(out),
                              "--out", str(tmp_path / "pooled.html")])
    assert res.exit_code == 0, res.output
    text = (tmp_path / "pooled.html").read_text()
    used = text[text.index("CFD cases used"):]
    used = used[:used.index("</table>")]
    assert "set-up max Co" in used and "max Co at end" in used
    rows = dict(re.findall(r"<tr><td>(f[0-9p]+_h[0-9p]+_phi[0-9p]+)</td>(.*?)</tr>", used))
    assert len(rows) == 45
    # cells after the case: f, h_amp, phi, mesh, cells, max Co, far field, ...
    set_ups = {name: [re.findall(r"<td>([^<]*)</td>", row)[i] for i in (3, 5, 6)]
               for name, row in rows.items()}
    for name, (mesh, max_co, _far_field) in set_ups.items():
        assert mesh == "coarse"
        assert max_co == ("1" if name in LOST_BY_CO2 else "2")
    assert all(set_ups[n][2] == "inletOutlet" for n in LOST_BY_CO2)


def test_at_f1_the_later_periods_are_converged_in_neither_time_step_nor_mesh():
    """f = 1 Hz, h = 0.5 m, phi = 135 deg on the coarse mesh at max Co 1 and 2 and on the
    medium mesh: the first 0.75 s after the ramp agree within 10 % NRMSE (F_n) against the
    medium mesh, but over the whole run the two coarse runs are as far from each other as
    each is from the medium run, and their mean thrusts straddle the medium run's."""
    name = "f1p000_h0p500_phi135p0.h5"
    co1, co2 = read_record(CO1 / name), read_record(CAMPAIGNS / "table1_coarse_co2" / name)
    medium = read_record(MEDIUM / name)
    assert "retries" not in co1.provenance and co1.time[-1] == pytest.approx(3.0, abs=1e-3)
    between_time_steps = compare_records(co1, co2)
    to_medium = [compare_records(rec, medium) for rec in (co1, co2)]
    early = [compare_records(rec, medium, end_s=1.0) for rec in (co1, co2)]
    assert all(c.nrmse_normal_force < 0.1 for c in early)
    assert all(0.1 < c.nrmse_normal_force < 0.2 for c in to_medium)
    assert between_time_steps.nrmse_normal_force > max(c.nrmse_normal_force
                                                       for c in to_medium)
    thrust_co1, thrust_co2 = (c.mean_thrust_a_n for c in to_medium)
    assert thrust_co2 < to_medium[0].mean_thrust_b_n < thrust_co1


def test_the_max_co_05_campaign_is_the_max_co_1_one_at_half_its_courant_limit():
    co05, co1 = (read_toml(d / "campaign.toml") for d in (CO05, CO1))
    solver = co05["setup"]["solver"]
    changed = {k: v for k, v in solver.items() if co1["setup"]["solver"][k] != v}
    assert changed == {"max_courant": 0.5}
    assert co05["setup"]["mesh"] == co1["setup"]["mesh"] == "coarse"
    assert co05["cases"] == {"f1p000_h0p500_phi135p0":
                             co1["cases"]["f1p000_h0p500_phi135p0"]}


def test_at_f1_halving_the_courant_limit_converges_the_first_period_and_not_the_rest():
    """f = 1 Hz, h = 0.5 m, phi = 135 deg on the coarse mesh at max Co 2, 1 and 0.5: over the
    first 0.75 s after the ramp each halving brings it nearer the medium mesh; over the whole
    run max Co 0.5 is as far from max Co 1 as the medium mesh is from the coarse one, and
    the mean thrust jumps about with the limit instead of settling."""
    name = "f1p000_h0p500_phi135p0.h5"
    runs = {co: read_record(folder / name) for co, folder in
            ((2.0, CAMPAIGNS / "table1_coarse_co2"), (1.0, CO1), (0.5, CO05))}
    assert runs[0.5].provenance["solver_max_courant"] == 0.5
    assert "retries" not in runs[0.5].provenance
    assert runs[0.5].time[-1] == pytest.approx(3.0, abs=1e-3)
    medium = read_record(MEDIUM / name)
    early = [compare_records(runs[co], medium, end_s=1.0).nrmse_normal_force
             for co in (2.0, 1.0, 0.5)]
    assert early[0] > early[1] > early[2]
    assert early[2] < 0.06
    assert compare_records(runs[0.5], runs[1.0], end_s=1.0).nrmse_normal_force < 0.06
    halved = compare_records(runs[0.5], runs[1.0])
    assert halved.nrmse_normal_force > 0.08
    to_medium = compare_records(runs[0.5], medium)
    assert 0.1 < to_medium.nrmse_normal_force < 0.2
    thrust = {co: compare_records(rec, medium).mean_thrust_a_n for co, rec in runs.items()}
    # not monotone in the limit: max Co 1 above the medium mesh, 2 and 0.5 well below it
    assert thrust[1.0] > to_medium.mean_thrust_b_n > max(thrust[0.5], thrust[2.0])
    assert abs(thrust[0.5] - thrust[1.0]) > 0.5 * to_medium.mean_thrust_b_n


def test_the_medium_mesh_carries_f2_and_the_coarse_one_follows_only_its_first_period():
    """f = 2 Hz, h = 0.5 m, phi = 135 deg on the medium mesh: two collapsed time steps (the
    second rerun from t = 0 with inletOutlet, then max Co 2), to its end inside the bound.
    The coarse mesh at max Co 1 follows it to t = 0.75 s within 10 % NRMSE (F_n), about
    20 % over the whole run, with mean thrust within 10 %."""
    name = "f2p000_h0p500_phi135p0.h5"
    medium = read_record(MEDIUM / name)
    retries = medium.provenance["retries"]
    assert retries.count("time step collapsed") == 2
    assert "resumed from t = 0 s with the inletOutlet far field" in retries
    assert medium.time[-1] == pytest.approx(1.5, abs=1e-3)
    coarse = read_record(CO1 / name)
    early = compare_records(coarse, medium, end_s=0.75)
    whole = compare_records(coarse, medium)
    assert early.nrmse_normal_force < 0.1 < whole.nrmse_normal_force < 0.3
    assert whole.pearson_normal_force > 0.7
    assert abs(whole.thrust_difference) < 0.1


FROM_START = CAMPAIGNS / "hardest_medium_from_start"


def test_the_medium_run_of_f05_rerun_as_one_set_up_ran_max_co_2_throughout():
    """`campaign run --retries-from-start` of f = 0.5 Hz on the medium mesh: its time step
    collapsed where the campaign's run's did (t = 1.69299 s, freestream: one deterministic
    run up to there), again at t = 1.788 s with the inletOutlet far field from t = 0 s
    (where the resumed run went on to 5.25 s), and from t = 0 s at max Co 2 it ran
    through, inside the force bound, for 4055 s of CPU against 2370 s."""
    mixed, rerun = (read_record(d / "f0p500_h0p500_phi135p0.h5") for d in (MEDIUM, FROM_START))
    assert [p.stem for p in record_paths(FROM_START)] == ["f0p500_h0p500_phi135p0"]
    assert read_toml(FROM_START / "campaign.toml")["setup"] == {
        **read_toml(MEDIUM / "campaign.toml")["setup"],
        "solver": {**read_toml(MEDIUM / "campaign.toml")["setup"]["solver"],
                   "wall_treatment": "log_law"}}
    assert rerun.parameters == mixed.parameters
    assert as_run_since_s(mixed) == 4.5 and as_run_since_s(rerun) == 0.0
    assert rerun.provenance["retries"] == (
        "time step collapsed at t = 1.6929851 s; resumed from t = 0 s with the inletOutlet "
        "far field; time step collapsed at t = 1.7883628 s; resumed from t = 0 s with maxCo 2")
    assert mixed.provenance["retries"].startswith("time step collapsed at t = 1.69299 s;")
    assert rerun.provenance["as_run_max_courant"] == 2.0
    assert rerun.provenance["as_run_far_field"] == "inletOutlet"
    assert rerun.time[-1] == pytest.approx(6.0, abs=1e-3)
    assert rerun.provenance["cpu_time_s"] > 1.5 * mixed.provenance["cpu_time_s"]
    (status,) = campaign_status(FROM_START)
    assert (status.state, status.message, status.mixed_since_s) == ("done", "", None)


def test_at_f05_the_medium_mesh_is_not_converged_in_time_step_the_coarse_one_holds_means():
    """The campaign's medium run (max Co 4 to t = 4.5 s) is 13.5 % NRMSE (F_n) from the one
    at max Co 2 throughout, 11.5 % already in the half second after the ramp, before any
    retry: at this motion the medium mesh is not converged in time step. Its mean thrust
    is 4 % lower. The coarse mesh at max Co 1 (inletOutlet from t = 0 s, as the rerun) is
    11.2 % from the rerun, with mean thrust and power within 1 % (3.4 and 5.9 % from the
    mixed run)."""
    name = "f0p500_h0p500_phi135p0.h5"
    mixed, rerun, coarse = (read_record(d / name) for d in (MEDIUM, FROM_START, CO1))
    whole = compare_records(mixed, rerun)
    assert 0.12 < whole.nrmse_normal_force < 0.15 and 0.13 < whole.nrmse_moment < 0.16
    assert -0.05 < whole.thrust_difference < -0.03
    first = compare_records(mixed, rerun, end_s=1.0)
    assert 0.10 < first.nrmse_normal_force < 0.13
    against_rerun, against_mixed = compare_records(coarse, rerun), compare_records(coarse, mixed)
    assert 0.10 < against_rerun.nrmse_normal_force < against_mixed.nrmse_normal_force < 0.13
    assert abs(against_rerun.thrust_difference) < 0.01
    assert abs(against_rerun.power_difference) < 0.01
    assert abs(against_mixed.thrust_difference) > 0.03
    assert abs(against_mixed.power_difference) > 0.05


CO1_MEDIUM = CAMPAIGNS / "hardest_medium_co1"


def test_at_f05_the_medium_mesh_at_max_co_1_moves_again_and_its_means_do_not_settle():
    """The medium mesh at max Co 1 with inletOutlet from t = 0 s (the time-step study the
    11.5 % above called for) runs through with no retry. Against it, max Co 2 from t = 0 s
    is 18.3 % NRMSE (F_n) away, 9.4 % over the half second after the ramp, with 16.5 %
    more mean thrust; the three medium runs' mean thrusts (4.60, 4.79, 4.12 N) do not
    settle as the time step shrinks. The coarse mesh at max Co 1, whose means matched max
    Co 2 within 1 %, is 15 % from it: that match is one draw within the medium mesh's own
    time-step scatter."""
    name = "f0p500_h0p500_phi135p0.h5"
    co1 = read_record(CO1_MEDIUM / name)
    co2, mixed, coarse = (read_record(d / name) for d in (FROM_START, MEDIUM, CO1))
    setup = read_toml(CO1_MEDIUM / "campaign.toml")["setup"]
    from_start = read_toml(FROM_START / "campaign.toml")["setup"]
    changed = {k: v for k, v in setup["solver"].items() if from_start["solver"][k] != v}
    assert changed == {"max_courant": 1.0, "far_field": "inletOutlet"}
    assert setup["mesh"] == co1.provenance["mesh"] == "medium"
    assert "retries" not in co1.provenance
    assert co1.provenance["as_run_max_courant"] == 1.0
    assert co1.time[-1] == pytest.approx(6.0, abs=1e-3)
    (status,) = campaign_status(CO1_MEDIUM)
    assert (status.state, status.message) == ("done", "")
    assert prepare_case(co1).notes == []  # no burst bridged, not lost
    whole = compare_records(co2, co1)
    assert 0.17 < whole.nrmse_normal_force < 0.20 and 0.15 < whole.nrmse_moment < 0.19
    assert 0.15 < whole.thrust_difference < 0.18 and 0.15 < whole.power_difference < 0.18
    assert 0.08 < compare_records(co2, co1, end_s=1.0).nrmse_normal_force < 0.11
    thrusts = [compare_records(r, co1).mean_thrust_a_n for r in (mixed, co2, co1)]
    assert thrusts[2] < thrusts[0] < thrusts[1]  # max Co 4 then 2, max Co 2, max Co 1
    coarse_to_co1, coarse_to_co2 = compare_records(coarse, co1), compare_records(coarse, co2)
    assert 0.14 < coarse_to_co1.nrmse_normal_force < 0.17
    assert 0.14 < coarse_to_co1.thrust_difference < 0.17
    assert abs(coarse_to_co2.thrust_difference) < 0.01
