"""Campaign records whose identified window mixes two set-ups (a retry resumed the run with
other settings after the identification's start-up): `campaign status` names them, and
`campaign run --rerun-mixed` keeps each aside and reruns its case from t = 0 s as one
set-up (real dask LocalCluster, real OpenFOAM)."""

import json
import shutil
from dataclasses import replace
from pathlib import Path

import pytest
from click.testing import CliRunner

from mfflap.campaign.cases import CfdCase
from mfflap.campaign.execute import CampaignSetup, campaign_status, run_campaign
from mfflap.cli.main import cli
from mfflap.errors import ConfigError
from mfflap.records.as_run import as_run_since_s
from mfflap.records.mixed_set_up import describe_mixed, fitted_from_s, mixed_since_s
from mfflap.records.record import MIXED_SUFFIX, read_record, read_records, write_record

ROOT = Path(__file__).parents[2]
CO2 = ROOT / "campaigns" / "table1_coarse_co2"
MIXED_CO2 = "f2p000_h0p300_phi090p0"  # resumed from t = 1.125 s with inletOutlet
SHORT = CfdCase(1.0, 0.3, 90.0, 10.0, duration=0.04, ramp_time=0.02)


def _resumed_at(path: Path, since_s: float) -> bytes:
    """Make the real record at ``path`` say that a retry resumed its run from ``since_s``
    with the inletOutlet far field (what `run_motion` writes); its new bytes."""
    rec = read_record(path)
    retries = (f"time step collapsed at t = {since_s + 0.001:g} s; resumed from "
               f"t = {since_s:g} s with the inletOutlet far field")
    write_record(path, replace(rec, provenance={**rec.provenance, "retries": retries}))
    return path.read_bytes()


def test_a_record_mixes_two_set_ups_only_if_the_retry_resumed_it_within_the_fitted_window():
    """The shipped max Co 2 run resumed from t = 1.125 s mixes two set-ups after the default
    start-up (0.75 s), not after a start-up of 1.2 s; its rerun from the start (t = 0 s)
    and a run retried before the window never do. The window starts at the ramp's end if
    that is later than the start-up."""
    rec = read_record(CO2 / f"{MIXED_CO2}.h5")
    assert fitted_from_s(rec) == 0.75 and mixed_since_s(rec) == 1.125
    assert mixed_since_s(rec, discard_time_s=1.2) is None and describe_mixed(rec, 1.2) == ""
    assert fitted_from_s(rec, 0.0) == rec.parameters["ramp_time"] == 0.125
    said = describe_mixed(rec)
    assert said.startswith("a retry resumed it from t = 1.125 s with other settings, within "
                           "the identified window from t = 0.75 s (forces beyond")
    assert said.endswith("`campaign run --rerun-mixed` reruns it as one set-up")
    rerun = read_record(ROOT / "campaigns" / "table1_coarse_co2_from_start" / f"{MIXED_CO2}.h5")
    assert mixed_since_s(rerun) is None
    early = replace(rec, provenance={**rec.provenance, "retries": "time step collapsed at "
                                     "t = 0.6 s; resumed from t = 0.5 s with maxCo 2"})
    assert as_run_since_s(early) == 0.5 and mixed_since_s(early) is None


def test_status_and_a_dry_run_name_the_mixed_run_of_a_real_campaign(tmp_path):
    """`campaign status` calls the mixed run done, says since when and how to rerun it, and
    counts it; `--discard-time` past its resume does not. A dry run with --rerun-mixed says
    it is to be rerun, without touching the folder."""
    out = tmp_path / "campaign"
    out.mkdir()
    for name in ("campaign.toml", f"{MIXED_CO2}.h5", "f1p000_h0p300_phi090p0.h5"):
        shutil.copy(CO2 / name, out / name)
    status = {s.case_id: s for s in campaign_status(out)}
    assert status[MIXED_CO2].state == "done" and status[MIXED_CO2].mixed_since_s == 1.125
    assert "--rerun-mixed" in status[MIXED_CO2].message
    assert status["f1p000_h0p300_phi090p0"].mixed_since_s is None
    res = CliRunner().invoke(cli, ["campaign", "status", str(out)])
    assert res.exit_code == 0, res.output
    assert ("1 done mixing two set-ups in the fitted window (`campaign run --rerun-mixed` "
            "reruns them as one set-up)") in res.output
    later = CliRunner().invoke(cli, ["campaign", "status", str(out), "--discard-time", "1.2",
                                     "--json"])
    assert later.exit_code == 0 and '"mixed_since_s": null' in later.output
    assert "1.125" not in later.output.split(MIXED_CO2)[1].split("}")[0]
    before = {p.name: p.read_bytes() for p in out.iterdir()}
    case = ROOT / "cases" / "paper2026.toml"
    dry = CliRunner().invoke(cli, ["campaign", "run", str(case), "--out", str(out), "--dry-run",
                                   "--setup", "coarse_co2",
                                   "--set", "identification.frequencies=[1, 2]",
                                   "--set", "identification.heave_amplitudes=[0.3]",
                                   "--set", "identification.phases_deg=[90]",
                                   "--rerun-mixed"])
    assert dry.exit_code == 0, dry.output
    lines = {line.split()[0]: line for line in dry.output.splitlines()}
    assert lines[MIXED_CO2].endswith("done (two set-ups from t = 1.125 s; to be rerun)")
    assert lines["f1p000_h0p300_phi090p0"].endswith("done")
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before


@pytest.mark.openfoam
def test_rerun_mixed_keeps_the_record_aside_and_reruns_the_case_from_the_start(tmp_path):
    """A real short run made to say a retry resumed it from t = 0.03 s: after a start-up of
    0.025 s it mixes two set-ups. A plain rerun of the campaign keeps it; --rerun-mixed
    without retries from the start is refused and loses nothing; with them the record is
    kept as .mixed.h5, the kept case folder is written anew (not taken as finished), and
    the new record ran one set-up."""
    out = tmp_path / "camp"
    setup = CampaignSetup(timeout_s=900.0, keep_case_dirs=True, retries_from_start=False)
    run_campaign([SHORT], out, setup, progress=False)
    path = out / f"{SHORT.case_id}.h5"
    mixed = _resumed_at(path, 0.03)
    (status,) = campaign_status(out, discard_time_s=0.025)
    assert status.state == "done" and status.mixed_since_s == 0.03
    assert campaign_status(out)[0].mixed_since_s is None  # the default start-up is later
    (again,) = run_campaign([SHORT], out, setup, progress=False, discard_time_s=0.025)
    assert again.message == "already finished"
    with pytest.raises(ConfigError, match="needs retries from the start") as err:
        run_campaign([SHORT], out, setup, progress=False, rerun_mixed=True,
                     discard_time_s=0.025)
    assert err.value.key == "rerun_mixed" and path.read_bytes() == mixed
    marker = out / "cases" / SHORT.case_id / "finished_run_marker"
    marker.write_text("the finished run's folder")
    (rerun,) = run_campaign([SHORT], out, replace(setup, retries_from_start=True),
                            progress=False, rerun_mixed=True, discard_time_s=0.025)
    assert rerun.state == "done" and rerun.message.endswith("s CPU")
    assert (out / f"{SHORT.case_id}{MIXED_SUFFIX}").read_bytes() == mixed
    assert not marker.exists()
    record = read_record(path)
    assert not record.provenance.get("retries") and record.provenance["retries_from_start"]
    assert record.time[0] < 0.005 and record.time[-1] == pytest.approx(SHORT.duration)
    (after,) = campaign_status(out, discard_time_s=0.025)
    assert after.state == "done" and after.mixed_since_s is None and after.message == ""
    assert [r.name for r in read_records(out)] == [SHORT.case_id]  # not the one kept aside


@pytest.mark.openfoam
def test_campaign_run_rerun_mixed_reads_the_start_up_from_the_case_file(tmp_path):
    """`mfflap campaign run --rerun-mixed` (half a period at 2 Hz on the coarse mesh, real
    OpenFOAM): a run resumed at t = 0.2 s mixes two set-ups after the case file's
    discard_time = 0.15 s, and is rerun with retries from the start, which the flag sets."""
    text = (ROOT / "cases" / "paper2026.toml").read_text()
    case = tmp_path / "short.toml"
    case.write_text(text.replace("n_cycles = 3.0", "n_cycles = 0.5\ndiscard_time = 0.15"))
    out = tmp_path / "camp"
    args = ["campaign", "run", str(case), "--out", str(out),
            "--set", "identification.frequencies=[2]",
            "--set", "identification.heave_amplitudes=[0.1]",
            "--set", "identification.phases_deg=[90]"]
    first = CliRunner().invoke(cli, args)
    assert first.exit_code == 0, first.output
    (path,) = out.glob("*.h5")
    mixed = _resumed_at(path, 0.2)
    status = CliRunner().invoke(cli, ["campaign", "status", str(out), "--discard-time", "0.15"])
    assert "1 done mixing two set-ups" in status.output
    rerun = CliRunner().invoke(cli, [*args, "--rerun-mixed"])
    assert rerun.exit_code == 0, rerun.output
    assert "1/1 cases done" in rerun.stdout
    assert (out / f"{path.stem}{MIXED_SUFFIX}").read_bytes() == mixed
    record = read_record(path)
    assert record.provenance["retries_from_start"] is True
    assert mixed_since_s(record, 0.15) is None


def test_a_record_kept_aside_twice_keeps_both(tmp_path):
    """A case lost, mixed or cut short a second time keeps its earlier record kept aside:
    the next goes to <case>.2<suffix>, then .3, and none of them is a record of the folder."""
    from mfflap.campaign.execute import keep_aside
    from mfflap.records.record import LOST_SUFFIX, record_paths

    path = tmp_path / f"{MIXED_CO2}.h5"
    kept = []
    for n in range(3):
        path.write_bytes(f"run {n}".encode())
        kept.append(keep_aside(path, LOST_SUFFIX))
        assert not path.exists()
    assert [p.name for p in kept] == [f"{MIXED_CO2}{LOST_SUFFIX}", f"{MIXED_CO2}.2{LOST_SUFFIX}",
                                      f"{MIXED_CO2}.3{LOST_SUFFIX}"]
    assert [p.read_bytes() for p in kept] == [b"run 0", b"run 1", b"run 2"]
    assert record_paths(tmp_path) == []



@pytest.mark.slow
def test_identify_names_the_cases_it_fitted_across_two_set_ups(tmp_path):
    """`mfflap identify` on the max Co 2 campaign says on the terminal, and in its JSON,
    which case it fitted across two set-ups and how to rerun it; on the shipped fixtures
    (none retried part-way) it names none."""
    case = str(ROOT / "cases" / "paper2026.toml")
    args = ["identify", case, "--strategy", "uniform", "--bootstrap", "0",
            "--output", str(tmp_path / "identification.h5")]
    res = CliRunner().invoke(cli, [*args, "--fixtures", str(CO2)])
    assert res.exit_code == 0, res.output
    assert (f"1 case(s) fitted across two set-ups (a retry resumed the run with other settings "
            f"within its fitted window): {MIXED_CO2}; `mfflap campaign run --rerun-mixed` "
            "reruns them as one set-up") in res.output
    as_json = CliRunner().invoke(cli, [*args, "--fixtures", str(CO2), "--json"])
    assert json.loads(as_json.stdout)["uniform"]["mixed_set_up"] == [MIXED_CO2]
    shipped = CliRunner().invoke(cli, [*args, "--json"])
    assert json.loads(shipped.stdout)["uniform"]["mixed_set_up"] == []
