"""Run a campaign of CFD cases on dask.distributed, resumably.

State lives in the output folder only:

- ``campaign.toml``: the setup and the list of cases (written once; a rerun must match);
- ``<case_id>.h5``: a finished case (written atomically; never rerun);
- ``<case_id>.failed.toml``: why a case failed (retried only on request);
- ``<case_id>.lost.h5``, ``.mixed.h5``, ``.unreadable.h5``: a record kept aside when its
  case was run again (lost numerics, two set-ups in the identified window, cut short;
  ``<case_id>.2.lost.h5`` and on for a second one: :func:`keep_aside`);
- ``cases/<case_id>/``: the OpenFOAM case while it runs (resumed from its last written time;
  :func:`campaign_status` reports how far its solver got).

A campaign killed at any moment therefore corrupts nothing, and rerunning the same command
continues it. Its solvers write the time step they reached when it is stopped (Ctrl-C,
SIGTERM) or its worker processes are killed outright (the kernel signals each solver as its
worker dies: :func:`mfflap.cfd.openfoam.runner.dies_with_caller`); only a solver killed
itself, or a machine lost, loses what its run computed since its last regular write.
"""

from __future__ import annotations

import math
import shutil
import signal
import threading
import time
import tomllib
import traceback
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

from distributed import WorkerPlugin

from mfflap.atomic_write import stale_temporaries
from mfflap.campaign.cases import CampaignCase
from mfflap.cfd.case_inputs import ADDED_PLATE_SETTINGS, ADDED_SOLVER_SETTINGS
from mfflap.cfd.openfoam.case_lock import CaseBusyError, lock_holder
from mfflap.cfd.openfoam.case_path import check_case_path
from mfflap.cfd.openfoam.retry_log import read_retry_log, request_rerun
from mfflap.cfd.openfoam.run_motion import run_motion
from mfflap.cfd.openfoam.runner import RunStopped, stop_running_solvers, stoppable
from mfflap.cfd.openfoam.solver_log import solver_progress
from mfflap.cfd.openfoam.time_folders import latest_solution_time
from mfflap.cfd.openfoam.writer import SolverSettings
from mfflap.errors import ConfigError, MfflapError
from mfflap.parameters import Fluid, FreeStream, Plate
from mfflap.records.bursts import bridge_load_bursts, find_load_bursts
from mfflap.records.cycle_scatter import add_cycle_scatter
from mfflap.records.force_envelope import find_envelope_breaches
from mfflap.records.mixed_set_up import DEFAULT_DISCARD_TIME_S, describe_mixed, mixed_since_s
from mfflap.records.record import (
    LOST_SUFFIX,
    MIXED_SUFFIX,
    RECORD_SUFFIX,
    UNREADABLE_SUFFIX,
    CfdRecord,
    read_record,
    write_record,
)
from mfflap.records.retries import RERUN_REQUESTED
from mfflap.toml_io import dumps, read_toml


@dataclass(frozen=True)
class CampaignSetup:
    """Everything that is the same for every case of a campaign."""

    mesh: str = "coarse"
    solver: SolverSettings = field(default_factory=SolverSettings)
    plate: Plate = field(default_factory=Plate)
    fluid: Fluid = field(default_factory=Fluid)
    stream: FreeStream = field(default_factory=FreeStream)
    timeout_s: float = 6 * 3600.0
    keep_case_dirs: bool = False
    #: store records in float32 like the shipped fixtures (half the size), so that a fixture
    #: campaign commits each record once instead of at full precision and again compacted
    single_precision: bool = False
    #: a retried run reruns from t = 0 s, one set-up throughout
    #: (:func:`~mfflap.cfd.openfoam.run_motion.run_motion`); how a run is retried, not what it
    #: computes: not in campaign.toml, and a campaign may go on with it changed
    retries_from_start: bool = True

    def as_dict(self) -> dict[str, Any]:
        """Plain nested values for campaign.toml (what the runs depend on, and the time
        limit of the last run; not how the case folders and records are kept)."""
        return {"mesh": self.mesh, "timeout_s": self.timeout_s,
                "solver": asdict(self.solver), "plate": asdict(self.plate),
                "fluid": asdict(self.fluid), "stream": asdict(self.stream)}


@dataclass
class CaseStatus:
    """Where one case stands."""

    case_id: str
    #: "done" | "lost" | "failed" | "running" (by a process holding its run lock: another
    #: campaign given the same folder, a ``cfd run`` of its case) | "busy" (this campaign
    #: left it to that process) | "started" (stopped part-way) | "pending" | "unreadable"
    #: (a record that cannot be read)
    state: str
    message: str = ""
    #: a started case: the share of its end time its solver has simulated (0-1)
    fraction_simulated: float | None = None
    #: a done case whose identified window mixes two set-ups: the flow time, s, from which a
    #: retry resumed its run with other settings (:mod:`mfflap.records.mixed_set_up`)
    mixed_since_s: float | None = None


def _failed_path(out: Path, case_id: str) -> Path:
    return out / f"{case_id}.failed.toml"


def _bound_setup(manifest: dict[str, Any]) -> tuple[Plate, Fluid, FreeStream]:
    """Plate, fluid and stream of a campaign manifest (the force bound's)."""
    setup = manifest.get("setup", {})
    return (Plate(**setup.get("plate", {})), Fluid(**setup.get("fluid", {})),
            FreeStream(**setup.get("stream", {})))


def lost_numerics(rec: CfdRecord, plate: Plate, fluid: Fluid, stream: FreeStream,
                  max_lost_share: float = 0.05) -> str | None:
    """Why a finished record's run counts as lost, or None.

    A run is lost where its forces leave what the motion can drive
    (:mod:`mfflap.records.force_envelope`) and those stretches with its numerical bursts cover
    more than ``max_lost_share`` of the time after its ramp: what identification leaves out
    (:func:`mfflap.identification.data.prepare_case`; shorter stretches it bridges).
    """
    after_ramp = rec.time >= float(rec.parameters.get("ramp_time", 0.0))
    loads, bursts = bridge_load_bursts(rec.loads, after_ramp)
    breaches = find_envelope_breaches(rec.state, loads, plate, fluid, stream,
                                      window=after_ramp)
    span_s = rec.time[-1] - rec.time[after_ramp][0] if after_ramp.any() else 0.0
    lost_s = sum(b.duration_s for b in breaches) + sum(b.duration_s for b in bursts)
    if not breaches or lost_s <= max_lost_share * span_s:
        return None
    return (f"its forces leave what the motion can drive, {breaches[0].describe()}; "
            "identification leaves it out; --retry-failed reruns it")


def run_one(case: CampaignCase, out_dir: str, setup: CampaignSetup) -> CaseStatus:
    """Run one case on a worker: resume or start its OpenFOAM run, write its record.

    Never raises for a CFD failure: the failure is written beside the records and returned.
    """
    out = Path(out_dir)
    record_path = out / f"{case.case_id}{RECORD_SUFFIX}"
    if record_path.exists():
        return CaseStatus(case.case_id, "done", "already finished")
    case_dir = out / "cases" / case.case_id
    solver = SolverSettings(**{**asdict(setup.solver), "write_interval": case.duration / 4})
    try:
        with stoppable():  # a stopped campaign starts nothing more of it on this worker
            record = run_motion(case_dir, case.motion(), case.case_id,
                                {"kind": case.kind, **case.as_dict()}, case.duration,
                                mesh=setup.mesh, ramp_time=case.ramp_time, solver=solver,
                                plate=setup.plate, fluid=setup.fluid, stream=setup.stream,
                                timeout_s=setup.timeout_s,
                                retries_from_start=setup.retries_from_start)
        write_record(record_path, record, single_precision=setup.single_precision)
        add_cycle_scatter(record_path, record)
    except CaseBusyError as exc:  # not a failure: the process running it records it
        return CaseStatus(case.case_id, "busy", str(exc).splitlines()[0])
    except RunStopped as exc:  # the campaign was stopped: resumed by the next run
        return CaseStatus(case.case_id, "started", str(exc).splitlines()[0])
    except Exception as exc:  # a failed case must not stop the campaign
        tail = getattr(exc, "log_tail", "") or traceback.format_exc(limit=3)
        _failed_path(out, case.case_id).write_text(
            dumps({"case_id": case.case_id, "error": str(exc), "log_tail": tail[-4000:]}))
        return CaseStatus(case.case_id, "failed", str(exc).splitlines()[0])
    _failed_path(out, case.case_id).unlink(missing_ok=True)
    if not setup.keep_case_dirs:
        shutil.rmtree(case_dir, ignore_errors=True)
    cpu = record.provenance.get("cpu_time_s", 0.0)
    return CaseStatus(case.case_id, "done", f"{cpu:.0f} s CPU")


def _with_added_settings(setup: dict[str, Any]) -> dict[str, Any]:
    setup = dict(setup)
    if isinstance(setup.get("solver"), dict):
        setup["solver"] = {**ADDED_SOLVER_SETTINGS, **setup["solver"]}
    if isinstance(setup.get("plate"), dict):
        setup["plate"] = {**ADDED_PLATE_SETTINGS, **setup["plate"]}
    return setup


def check_same_setup(out_dir: str | Path, setup: CampaignSetup) -> None:
    """Refuse a campaign folder that holds a campaign with another setup (nothing to check
    in a new folder). The time limit per case is not part of it: no result depends on it,
    and a case that timed out is rerun with a longer one.

    Raises
    ------
    ConfigError
        Naming the manifest and every setting that differs, with both values (the first
        four).
    """
    manifest = Path(out_dir) / "campaign.toml"
    had = manifest_setup(out_dir)
    if had is None:
        return
    asked = read_toml_text(dumps({"setup": setup.as_dict()}))["setup"]
    asked.pop("timeout_s")
    if had != asked:
        differences = _differences(had, asked)
        raise ConfigError(f"{manifest}: this folder holds a campaign with another setup "
                          f"({'; '.join(differences[:4])}"
                          f"{'; ...' if len(differences) > 4 else ''}); its cases would mix "
                          "with this one's: use a new output folder, or the folder's own "
                          "settings", key="setup")


def check_same_cases(out_dir: str | Path, cases: Sequence[CampaignCase]) -> None:
    """Refuse cases that a campaign folder lists under the same id with other values (a
    case id keeps the frequency, heave and phase; the duration, start-up ramp and pitch ramp
    rate come from the case file's [identification] too): the folder's record or run of
    that id is of the case it lists, and would be taken for the one asked.

    Raises
    ------
    ConfigError
        Naming the manifest, the first case that differs and each value, both ways.
    """
    manifest = Path(out_dir) / "campaign.toml"
    if not manifest.exists():
        return
    listed = read_toml(manifest).get("cases", {})
    for c in cases:
        had = listed.get(c.case_id)
        asked = read_toml_text(dumps({"case": c.as_dict()}))["case"]
        if isinstance(had, dict) and had != asked:
            differences = _differences(had, asked)
            raise ConfigError(f"this folder holds case {c.case_id} with other "
                              f"values ({'; '.join(differences[:4])}); its record or run is "
                              "of that case and would be taken for this one: use a new output "
                              "folder, or the folder's own values (the case file's "
                              "[identification])", source=str(manifest),
                              key=f"cases.{c.case_id}")


def _write_manifest(out: Path, cases: Sequence[CampaignCase], setup: CampaignSetup) -> None:
    manifest = out / "campaign.toml"
    wanted = {"setup": setup.as_dict(), "cases": {c.case_id: c.as_dict() for c in cases}}
    if manifest.exists():
        check_same_setup(out, setup)
        check_same_cases(out, cases)
        merged = {**read_toml(manifest).get("cases", {}), **wanted["cases"]}
        wanted["cases"] = merged
    tmp = manifest.with_suffix(".toml.tmp")
    tmp.write_text(dumps(wanted))
    tmp.replace(manifest)


def setting_differences(a: dict[str, Any], b: dict[str, Any],
                        prefix: str = "") -> list[tuple[str, Any, Any]]:
    """``(dotted key, value in a, value in b)`` for every setting of two nested set-up
    tables that differs (None where one lacks it), in key order."""
    out = []
    for key in sorted(set(a) | set(b)):
        in_a, in_b = a.get(key), b.get(key)
        if isinstance(in_a, dict) and isinstance(in_b, dict):
            out += setting_differences(in_a, in_b, f"{prefix}{key}.")
        elif in_a != in_b:
            out.append((f"{prefix}{key}", in_a, in_b))
    return out


def _differences(had: dict[str, Any], asked: dict[str, Any]) -> list[str]:
    """``key: folder's value, asked value`` for every setting that differs (nested)."""
    return [f"{key}: {a!r} in the folder, {b!r} asked"
            for key, a, b in setting_differences(had, asked)]


def manifest_setup(out_dir: str | Path) -> dict[str, Any] | None:
    """The ``[setup]`` of a campaign folder's campaign.toml with the solver settings added
    since it was written at the values its runs used, without the time limit per case (no
    result depends on it); None if the folder has no campaign.toml."""
    manifest = Path(out_dir) / "campaign.toml"
    if not manifest.is_file():
        return None
    setup = _with_added_settings(read_toml(manifest).get("setup", {}))
    setup.pop("timeout_s", None)
    return setup


def read_toml_text(text: str) -> dict[str, Any]:
    """Parse TOML text (round-trip helper for comparing manifests)."""
    return tomllib.loads(text)


def keep_aside(record_path: Path, suffix: str) -> Path:
    """Move a case's record out of the folder's records (its case is to run again) to
    ``<case_id><suffix>``, or ``<case_id>.<n><suffix>`` with the first free n >= 2 if an
    earlier one was kept aside so (a case lost twice keeps both); where it went."""
    case_id = record_path.name.removesuffix(RECORD_SUFFIX)
    target = record_path.with_name(f"{case_id}{suffix}")
    n = 2
    while target.exists():
        target = record_path.with_name(f"{case_id}.{n}{suffix}")
        n += 1
    record_path.replace(target)
    return target


def read_finished_record(path: Path) -> tuple[CfdRecord | None, str | None]:
    """The record at ``path``, or None and why it cannot be read (the error's first line)."""
    try:
        return read_record(path), None
    except MfflapError as err:
        return None, str(err).splitlines()[0]


def campaign_status(out_dir: str | Path,
                    discard_time_s: float = DEFAULT_DISCARD_TIME_S) -> list[CaseStatus]:
    """Status of every case listed in ``out_dir/campaign.toml``.

    A finished case's message names its numerical bursts (:mod:`mfflap.records.bursts`), if any,
    and a retry that resumed its run with other settings after ``discard_time_s`` (the
    identification's start-up; its ``mixed_since_s``: :mod:`mfflap.records.mixed_set_up`);
    a finished case whose forces leave what the motion can drive is "lost"
    (:func:`lost_numerics`).
    A record that cannot be read (cut short by a copy or a full disk) is "unreadable": its
    message says why, and the next :func:`run_campaign` keeps it aside and runs the case
    again.
    A case without a record whose run lock a process holds (:mod:`mfflap.cfd.openfoam.case_lock`)
    is "running": its message names the process and, once its solver has begun, how far it
    got. A case whose OpenFOAM run has begun but has no record yet and that nobody runs is
    "started" (stopped, to be resumed): its message gives the simulated time the solver's
    log reached, the time step there, the last written time a rerun resumes from and the
    retries so far.
    """
    out = Path(out_dir)
    manifest = out / "campaign.toml"
    if not manifest.exists():
        raise MfflapError(f"{out}: no campaign.toml (not a campaign folder)")
    statuses = []
    manifest_data = read_toml(manifest)
    bound = _bound_setup(manifest_data)
    for case_id in manifest_data.get("cases", {}):
        if (out / f"{case_id}{RECORD_SUFFIX}").exists():
            rec, why = read_finished_record(out / f"{case_id}{RECORD_SUFFIX}")
            if rec is None:
                statuses.append(CaseStatus(
                    case_id, "unreadable", f"{why}; `mfflap campaign run` keeps it as "
                    f"{case_id}{UNREADABLE_SUFFIX} and runs the case again"))
                continue
            lost = lost_numerics(rec, *bound)
            if lost is not None:
                statuses.append(CaseStatus(case_id, "lost", lost))
                continue
            bursts = find_load_bursts(rec.loads)
            said = [f"{len(bursts)} numerical burst(s), bridged when identified; first "
                    f"{bursts[0].describe()}"] if bursts else []
            if mixed := describe_mixed(rec, discard_time_s):
                said.append(mixed)
            statuses.append(CaseStatus(case_id, "done", "; ".join(said),
                                       mixed_since_s=mixed_since_s(rec, discard_time_s)))
        elif (holder := lock_holder(out / "cases" / case_id)) is not None:
            progress = _started(out / "cases" / case_id)
            statuses.append(CaseStatus(
                case_id, "running", f"by {holder}" + (f"; {progress[0]}" if progress else ""),
                progress[1] if progress else None))
        elif _failed_path(out, case_id).exists():
            info = read_toml(_failed_path(out, case_id))
            error = str(info.get("error", "")).splitlines()
            statuses.append(CaseStatus(case_id, "failed", error[0] if error else ""))
        elif (progress := _started(out / "cases" / case_id)) is not None:
            statuses.append(CaseStatus(case_id, "started", *progress))
        else:
            statuses.append(CaseStatus(case_id, "pending"))
    return statuses


def _simulated(case_dir: Path) -> tuple[float, float, float] | None:
    """(time reached, time step, end time) of a case's OpenFOAM run in s, or None if its
    solver has not begun."""
    reached = solver_progress(case_dir)
    if reached is None or not (case_dir / "mfflap_case.toml").is_file():
        return None
    return (*reached, float(read_toml(case_dir / "mfflap_case.toml")["end_time"]))


def _share(time_s: float, end_s: float) -> float:
    return min(max(time_s / end_s, 0.0), 1.0) if end_s > 0 else 0.0


def fraction_simulated(out_dir: str | Path, case_ids: Sequence[str]) -> dict[str, float]:
    """Share of its end time each started case's solver has simulated (0-1), by case id;
    cases without a run folder or solver log are left out."""
    shares = {}
    for case_id in case_ids:
        reached = _simulated(Path(out_dir) / "cases" / case_id)
        if reached is not None:
            shares[case_id] = _share(reached[0], reached[2])
    return shares


def retries_in_flight(out_dir: str | Path, case_ids: Sequence[str]) -> str:
    """What the progress bar says of the runs in flight that were retried: ``<case>: retry
    <n>, <how it goes on>`` for the last of ``case_ids`` that was (a rerun from t = 0 s
    takes its share simulated back to nothing, so the bar steps back), '' if none was."""
    said = ""
    for case_id in case_ids:
        retries, earlier = read_retry_log(Path(out_dir) / "cases" / case_id)
        retries = [r for r in retries if r.cause != RERUN_REQUESTED]
        if retries:
            said = (f"{case_id}: retry {len(earlier) + len(retries)}, "
                    f"{retries[-1].restart()}")
        elif earlier:
            said = f"{case_id}: retry {len(earlier)}, {earlier[-1].rsplit('; ', 1)[-1]}"
    return said


def _started(case_dir: Path) -> tuple[str, float] | None:
    """How far a case's OpenFOAM run got (a message and the simulated share), or None if its
    solver has not begun."""
    reached = _simulated(case_dir)
    if reached is None:
        return None
    time_s, step_s, end_s = reached
    resume = latest_solution_time(case_dir)
    logged, earlier = read_retry_log(case_dir)
    retries = len(earlier) + sum(r.cause != RERUN_REQUESTED for r in logged)
    share = _share(time_s, end_s)
    return (f"t = {time_s:.4g} of {end_s:.4g} s simulated ({share:.0%}), time step "
            f"{step_s:.2g} s; a rerun resumes from t = {resume or 0} s"
            + (f"; {retries} retr{'y' if retries == 1 else 'ies'}" if retries else ""), share)


def _status_of(future: Any, case_id: str, out: Path) -> CaseStatus:
    """A finished task's case status; a task that did not return one fails its case alone.

    :func:`run_one` returns every CFD failure as a status, so what arrives here as an error is
    the worker process dying under the run (dask's KilledWorker once it died on
    ``distributed.scheduler.allowed-failures`` + 1 workers: the out-of-memory killer, a
    nanny's memory limit) or a bug. It is written beside the records like any failure, and
    the other cases go on. A task the scheduler cancelled (the scheduler lost) stops the
    campaign: rerunning the command resumes it.
    """
    # dask.distributed takes about a second to load: only a campaign run needs it
    from distributed import KilledWorker

    if future.status == "cancelled":
        raise MfflapError(f"{out}: the dask scheduler dropped case {case_id} (scheduler "
                          "lost?); rerun the same command to resume the campaign")
    exc = future.exception()
    if exc is None:
        return future.result()
    if isinstance(exc, KilledWorker):  # its text (kept in the log tail) is long
        retries = getattr(exc, "allowed_failures", None)
        workers = f" on {retries + 1} workers" if isinstance(retries, int) else ""
        error = (f"its dask worker process died under the run{workers} (the out-of-memory "
                 "killer, a nanny's memory limit?); --retry-failed reruns it from its last "
                 "written time")
    else:
        error = f"its task raised {type(exc).__name__}: {exc}"
    _failed_path(out, case_id).write_text(dumps({
        "case_id": case_id, "error": error,
        "log_tail": "".join(traceback.format_exception(exc))[-4000:]}))
    return CaseStatus(case_id, "failed", error.splitlines()[0])


#: how long a Ctrl-C'd campaign waits for the solvers in flight to write and stop, s
WRITE_GRACE_S = 60.0


#: how long a stopped campaign waits for its workers to let go of the cases they ran, s
RELEASE_WAIT_S = 10.0


def _wait_for_release(out: Path, case_ids: Sequence[str]) -> None:
    """Wait up to :data:`RELEASE_WAIT_S` for the run locks of ``case_ids`` to be free.

    A worker lets go of its case a moment after its solver stopped. The workers of a
    cluster that outlives the campaign (``scheduler_address``) are not stopped with it, so
    without this wait the campaign's last status could still call such a case running
    rather than stopped part-way. A case another campaign runs costs the whole wait.
    """
    deadline = time.monotonic() + RELEASE_WAIT_S
    while (any(lock_holder(out / "cases" / case_id) for case_id in case_ids)
           and time.monotonic() < deadline):
        time.sleep(0.1)


class IgnoreInterrupt(WorkerPlugin):
    """A dask worker plugin: the LocalCluster's worker processes ignore SIGINT.

    They share the terminal's process group, so a Ctrl-C would otherwise kill them at once
    and their solvers with them, unwritten. :func:`run_campaign` catches it in the main
    process instead and asks every worker to have its solvers write and stop
    (:func:`mfflap.cfd.openfoam.runner.stop_running_solvers`) before it closes the cluster.
    """

    def setup(self, worker: object) -> None:
        if threading.current_thread() is threading.main_thread():
            signal.signal(signal.SIGINT, signal.SIG_IGN)


def _check_scheduler_address(address: str) -> None:
    """Refuse a scheduler address dask cannot parse (ConfigError, key scheduler_address)."""
    # dask.distributed takes about a second to load: only a campaign run needs it
    from distributed.comm.addressing import get_address_host_port

    try:
        get_address_host_port(address)
    except ValueError as err:
        raise ConfigError(f"{address!r} is not a dask scheduler address ({err}); e.g. "
                          "tcp://10.0.0.5:8786", key="scheduler_address") from err


def run_campaign(cases: Sequence[CampaignCase], out_dir: str | Path,
                 setup: CampaignSetup | None = None, *, n_workers: int = 1,
                 scheduler_address: str | None = None, retry_failed: bool = False,
                 rerun_mixed: bool = False,
                 discard_time_s: float = DEFAULT_DISCARD_TIME_S, progress: bool = True,
                 on_result: Callable[[CaseStatus], None] | None = None,
                 poll_s: float = 10.0) -> list[CaseStatus]:
    """Run the cases that are not finished yet on a dask cluster; return every case's status.

    Parameters
    ----------
    n_workers
        Worker processes of the LocalCluster (one OpenFOAM run each; two serial runs give
        more throughput than one run on two ranks here).
    scheduler_address
        Address of an existing dask scheduler (e.g. one started by dask-jobqueue's
        SLURMCluster); a LocalCluster is started when None.
    retry_failed
        Rerun cases that failed before (otherwise they stay failed and are reported), and
        cases whose finished run lost its numerics (:func:`lost_numerics`; the record is
        kept as ``<case_id>.lost.h5``).
    rerun_mixed
        Rerun from t = 0 s the finished cases whose run a retry resumed with other settings
        after ``discard_time_s`` (the identification's start-up: two set-ups in the
        identified window, :mod:`mfflap.records.mixed_set_up`), their records kept as
        ``<case_id>.mixed.h5`` and any case folder kept (``keep_case_dirs``) written anew.
        Needs ``setup.retries_from_start``: retried part-way again, the rerun would mix the
        same two set-ups.
    on_result
        Called with each case's status as it finishes (e.g. to commit results).
    progress
        Show a progress bar counted in cases, fractions of the runs in flight included
        (the simulated share of each, read from its solver log every ``poll_s`` seconds), so
        that runs of an hour show that they move.

    Raises
    ------
    ConfigError
        Before the folder is made: no case, a case listed twice, no worker, a time limit
        that is not a finite time > 0 s, a scheduler address dask cannot parse, a folder
        path OpenFOAM cannot read, or ``rerun_mixed`` without ``setup.retries_from_start``.
    MfflapError
        If the scheduler at ``scheduler_address`` cannot be reached.
    """
    # dask.distributed takes about a second to load: only a campaign run needs it
    from dask.distributed import Client, LocalCluster, as_completed

    setup = setup or CampaignSetup()
    if scheduler_address is None and n_workers < 1:
        raise ConfigError(f"a campaign needs at least one worker, got {n_workers!r}",
                          key="n_workers")
    if not (math.isfinite(setup.timeout_s) and setup.timeout_s > 0):
        raise ConfigError(f"the time limit per case must be a finite time > 0 s, got "
                          f"{setup.timeout_s!r}", key="timeout_s")
    if scheduler_address is not None:
        _check_scheduler_address(scheduler_address)
    if rerun_mixed and not setup.retries_from_start:
        raise ConfigError("rerunning the runs that mix two set-ups needs retries from the "
                          "start (retries_from_start; a case file's [cfd] retries_from_start, "
                          "true unless it says false): a rerun retried part-way would mix "
                          "the same two set-ups again",
                          key="rerun_mixed")
    ids = [c.case_id for c in cases]
    if not ids:
        raise ConfigError("the campaign has no cases", key="cases")
    if len(set(ids)) != len(ids):
        raise ConfigError(f"the campaign lists a case twice: "
                          f"{sorted({i for i in ids if ids.count(i) > 1})}", key="cases")
    out = check_case_path(out_dir)  # every case runs below it
    out.mkdir(parents=True, exist_ok=True)
    _write_manifest(out, cases, setup)
    # a record half-written when its writer was killed; another process's record being
    # written is left alone
    for stale in stale_temporaries(out, RECORD_SUFFIX):
        stale.unlink(missing_ok=True)
    results: dict[str, CaseStatus] = {}
    todo = []
    bound = (setup.plate, setup.fluid, setup.stream)
    for c in cases:
        record = out / f"{c.case_id}{RECORD_SUFFIX}"
        if record.exists():  # read once: unreadable, or lost and asked to rerun, is kept aside
            rec, _ = read_finished_record(record)
            if rec is None:
                keep_aside(record, UNREADABLE_SUFFIX)  # the case reruns
            elif retry_failed and lost_numerics(rec, *bound) is not None:
                keep_aside(record, LOST_SUFFIX)
            elif (rerun_mixed and mixed_since_s(rec, discard_time_s) is not None
                  and lock_holder(out / "cases" / c.case_id) is None):
                # a kept case folder holds the finished run: it would be taken again
                shutil.rmtree(out / "cases" / c.case_id, ignore_errors=True)
                keep_aside(record, MIXED_SUFFIX)
        if record.exists():
            results[c.case_id] = CaseStatus(c.case_id, "done", "already finished")
        elif _failed_path(out, c.case_id).exists() and not retry_failed:
            info = read_toml(_failed_path(out, c.case_id))
            error = str(info.get("error", "")).splitlines()
            results[c.case_id] = CaseStatus(c.case_id, "failed", error[0] if error else "")
        else:
            if _failed_path(out, c.case_id).exists():  # asked for: a new budget of retries
                request_rerun(out / "cases" / c.case_id)
            todo.append(c)
    if todo:
        cluster = None
        if scheduler_address is None:
            # the scheduler's HTTP server on a free local port: with the default (8787) a
            # second campaign on the same machine warns that the port is taken
            cluster = LocalCluster(n_workers=n_workers, threads_per_worker=1, processes=True,
                                   dashboard_address="127.0.0.1:0")
        try:
            client = Client(scheduler_address or cluster)
        except (OSError, TimeoutError) as err:  # the scheduler is not there (30 s timeout)
            if scheduler_address is None:
                raise
            raise MfflapError(f"cannot reach the dask scheduler at {scheduler_address}: {err}; "
                              f"start it (e.g. `dask scheduler`) or check the address; the "
                              f"campaign in {out} ran nothing and resumes when given one"
                              ) from err
        futures: list[Any] = []
        try:
            if cluster is not None:  # its workers share this terminal's Ctrl-C
                client.register_plugin(IgnoreInterrupt(), name="mfflap-ignore-sigint")
            case_ids = {f"mfflap-{c.case_id}": c.case_id for c in todo}
            futures = [client.submit(run_one, c, str(out), setup, key=f"mfflap-{c.case_id}",
                                     pure=False) for c in todo]
            bar = None
            if progress:
                # only a campaign run with a progress bar needs it
                from tqdm import tqdm

                bar = tqdm(total=len(todo), desc="CFD cases", unit="case",
                           bar_format="{l_bar}{bar}| {n:.2f}/{total} [{elapsed}<{remaining}"
                                      "{postfix}]")
            finished: list[str] = []
            last = ""
            polled = 0.0
            pending = as_completed(futures)
            while not pending.is_empty():
                if not pending.has_ready():
                    if bar is not None and time.monotonic() - polled >= poll_s:
                        # the runs in flight count with their simulated share
                        polled = time.monotonic()
                        running = [c.case_id for c in todo if c.case_id not in finished]
                        bar.n = len(finished) + sum(fraction_simulated(out, running).values())
                        retried = retries_in_flight(out, running)
                        bar.set_postfix_str("; ".join(filter(None, (last, retried)))[:100])
                    time.sleep(0.1)
                    continue
                for fut in pending.next_batch(block=False):
                    status = _status_of(fut, case_ids[fut.key], out)
                    results[status.case_id] = status
                    finished.append(status.case_id)
                    last = f"{status.case_id}: {status.state} {status.message}"[:60]
                    if on_result is not None:
                        on_result(status)
                if bar is not None:
                    bar.n = len(finished)
                    bar.set_postfix_str(last)
            if bar is not None:
                bar.close()
        except KeyboardInterrupt:  # the cases in flight write where they are, then stop
            try:  # first the queued cases: a worker a stopped case frees starts none of them
                client.cancel(futures)
            except Exception:  # scheduler gone: nothing more starts
                pass
            try:
                client.run(stop_running_solvers, WRITE_GRACE_S)
            except Exception:  # workers gone: their solvers die with them
                pass
            _wait_for_release(out, [c.case_id for c in todo if c.case_id not in results])
            raise
        finally:
            client.close()
            if cluster is not None:
                cluster.close()
    return [results[c.case_id] for c in cases]
