"""Run one motion in OpenFOAM and turn the finished case into a :class:`CfdRecord`."""

from __future__ import annotations

import shutil
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from mfflap.cfd.case_inputs import (
    PHYSICAL_KEYS,
    check_case_inputs,
    kept_differences,
    solver_keys,
)
from mfflap.cfd.force_history import to_loads
from mfflap.cfd.imposed_motion import imposed_state
from mfflap.cfd.openfoam.case_lock import case_lock
from mfflap.cfd.openfoam.case_path import check_case_path, empty_case_folder
from mfflap.cfd.openfoam.forces import read_forces
from mfflap.cfd.openfoam.retry_edits import (
    courant_limit,
    far_field,
    lower_courant_limit,
    turbulence_convection,
    use_inlet_outlet_far_field,
    use_upwind_turbulence,
)
from mfflap.cfd.openfoam.retry_log import (
    append_retry,
    budget_retries,
    read_retry_log,
    retry_lines,
)
from mfflap.cfd.openfoam.rewind import rewind_case
from mfflap.cfd.openfoam.runner import RunStopped, run_case
from mfflap.cfd.openfoam.solver_log import solver_provenance
from mfflap.cfd.openfoam.time_folders import latest_solution_time
from mfflap.cfd.openfoam.writer import (
    AnyMeshSpec,
    SolverSettings,
    write_case,
    written_wall_treatment,
)
from mfflap.errors import (
    CfdRunError,
    ConfigError,
    MfflapError,
    RepeatedTimes,
    RunStoppedByWatch,
    SolverDiverged,
)
from mfflap.kinematics.continuous import Motion
from mfflap.parameters import Fluid, FreeStream, Plate
from mfflap.records.bursts import bridge_load_bursts
from mfflap.records.force_envelope import BREACH_FACTOR, EnvelopeBreach, find_envelope_breaches
from mfflap.records.record import CfdRecord
from mfflap.records.retries import (
    FORCES_BEYOND_BOUND,
    RERUN_REQUESTED,
    SAME_LOSS_AGAIN,
    TIMES_REPEAT,
    Retry,
    retries_to_json,
)
from mfflap.toml_io import read_toml


def as_run_settings(case_dir: str | Path) -> dict[str, Any]:
    """The settings a case ran its last stretch with, after any retry changed them.

    A record's ``solver_*`` provenance is the set-up the case was written with; a retry
    (:func:`run_motion`) may since have lowered ``maxCo``, switched the far field to
    inletOutlet or k and epsilon to upwind. These keys say what the case holds now.

    Returns
    -------
    dict
        ``as_run_max_courant`` (system/controlDict), ``as_run_far_field`` ("freestream",
        "inletOutlet" or "other", from 0/U) and ``as_run_turbulence_convection`` (the first
        k or epsilon convection scheme of system/fvSchemes, both written and changed
        together, as a ``SolverSettings.turbulence_convection`` name, or "other") and
        ``as_run_wall_treatment`` (the plate's nut condition in 0/nut, as a
        ``SolverSettings.wall_treatment`` name, or "other").
    """
    case = Path(case_dir)
    return {"as_run_max_courant": courant_limit(case), "as_run_far_field": far_field(case),
            "as_run_turbulence_convection": turbulence_convection(case),
            "as_run_wall_treatment": written_wall_treatment(case)}


def record_from_case(case_dir: str | Path, motion: Motion, name: str,
                     parameters: dict[str, Any], plate: Plate | None = None) -> CfdRecord:
    """Parse a finished OpenFOAM case written by mfflap into a record."""
    case_dir = Path(case_dir)
    meta = read_toml(case_dir / "mfflap_case.toml")
    history = read_forces(case_dir)
    state = imposed_state(motion, history.time, float(meta["ramp_time"]))
    loads = to_loads(history, state, float(meta["span"]), float(meta["depth"]),
                     source=f"openfoam:{name}", frame=str(meta.get("frame", "inertial")))
    prov = {**solver_provenance(case_dir), "mesh": meta["mesh"], "n_cells": meta["n_cells"],
            "force_dialect": history.dialect, "depth_m": meta["depth"], "span_m": meta["span"]}
    for key, value in meta.items():  # how it was run, and what for (plate, fluid, stream)
        if key.startswith("solver_") or (key in PHYSICAL_KEYS and key != "span"):
            prov[key] = value
    prov.update(as_run_settings(case_dir))
    if plate is not None:
        prov["chord_m"] = plate.chord
    return CfdRecord(name, state, loads, parameters, prov, history.force, history.moment)


def _forces_beyond_bound(record: CfdRecord, ramp_time: float, plate: Plate | None,
                         fluid: Fluid | None, stream: FreeStream | None,
                         factor: float) -> EnvelopeBreach | None:
    """The first stretch after the ramp whose forces the motion cannot have driven."""
    loads, _ = bridge_load_bursts(record.loads, record.time >= 0.0)
    breaches = find_envelope_breaches(record.state, loads, plate or Plate(), fluid or Fluid(),
                                      stream or FreeStream(), window=record.time >= ramp_time,
                                      factor=factor)
    return breaches[0] if breaches else None


#: two breaches of the force bound this close in flow time, as a fraction of the convective
#: time c / U, are the same loss (:func:`run_motion`)
SAME_BREACH_FRACTION = 0.02

def _bound_watch(case_dir: Path, motion: Motion, ramp_time: float, plate: Plate | None,
                 fluid: Fluid | None, stream: FreeStream | None, factor: float
                 ) -> Callable[[], ForcesBeyondBound | None]:
    """A check of a running case's forces so far against the bound, for
    :func:`mfflap.cfd.openfoam.runner.run_case`'s ``watch``: the breach to stop for, or
    None."""
    def watch() -> ForcesBeyondBound | None:
        try:
            meta = read_toml(case_dir / "mfflap_case.toml")
            history = read_forces(case_dir)
            state = imposed_state(motion, history.time, float(meta["ramp_time"]))
            loads = to_loads(history, state, float(meta["span"]), float(meta["depth"]),
                             source="watch", frame=str(meta.get("frame", "inertial")))
        except (MfflapError, ValueError, OSError):  # no output yet, or a line being written
            return None
        record = CfdRecord("watch", state, loads, {})
        breach = _forces_beyond_bound(record, ramp_time, plate, fluid, stream, factor)
        return None if breach is None else ForcesBeyondBound(breach)
    return watch


@dataclass(frozen=True)
class ForcesBeyondBound:
    """Why the force-bound watch stopped a run: the first stretch of its forces beyond what
    the motion can drive (what a :class:`~mfflap.errors.RunStoppedByWatch` carries as its
    reason, on which a retry is decided)."""

    breach: EnvelopeBreach

    def __str__(self) -> str:
        return f"the forces leave what the motion can drive, {self.breach.describe()}"


def _apply_next_remedy(case_dir: Path, n_done: int, max_retries: int) -> str:
    """Change the case for its next retry; return what changed: the inletOutlet far field
    first (if it had the freestream one), then half the Courant limit, the last time also
    first-order upwind k and epsilon."""
    if not n_done and use_inlet_outlet_far_field(case_dir):
        return "the inletOutlet far field"
    note = f"maxCo {lower_courant_limit(case_dir):g}"
    if n_done == max_retries - 1 and use_upwind_turbulence(case_dir):
        note += " and first-order upwind k and epsilon"
    return note


def _retry(case_dir: Path, retries: list[Retry], n_earlier: int, cause: str,
           failed_at_s: float, rewind_before_s: float | None,
           progress: Callable[[str], None] | None, max_retries: int,
           max_courant: float | None = None) -> None:
    """Ready a case for its next retry and keep it: rewound to its last written time before
    ``rewind_before_s`` (None: it resumes from its last written time as it is), changed by
    the next remedy (:func:`_apply_next_remedy`) and logged (:func:`_keep_retry`) with where
    it resumes."""
    resume = (rewind_case(case_dir, rewind_before_s) if rewind_before_s is not None
              else latest_solution_time(case_dir) or 0)
    remedy = _apply_next_remedy(case_dir, n_earlier + len(retries), max_retries)
    _keep_retry(case_dir, retries, n_earlier, Retry(cause, failed_at_s, float(resume), remedy,
                                                    max_courant), progress, max_retries)


def _keep_retry(case_dir: Path, retries: list[Retry], n_earlier: int, retry: Retry,
                progress: Callable[[str], None] | None, max_retries: int) -> None:
    """Keep one retry in ``retries`` and the case's log (so that a run resumed by a later call
    still records it) and tell ``progress`` of it."""
    retries.append(retry)
    append_retry(case_dir, retry)
    if progress is not None:
        progress(f"retry {n_earlier + len(retries)} of {max_retries}: {retry.describe()}")


def _earlier_breach(retries: list[Retry]) -> tuple[float, float] | None:
    """(flow time s, Courant limit) of the last loss of the bound in ``retries``, or None."""
    for r in reversed(retries):
        if r.cause in (FORCES_BEYOND_BOUND, SAME_LOSS_AGAIN):
            return float(r.failed_at_s), float(r.max_courant)
    return None


def _last_resume_s(retries: list[Retry]) -> float:
    """The written time the last retry of the bound in ``retries`` resumed from, s (0 if none
    or from the start)."""
    for r in reversed(retries):
        if r.cause == SAME_LOSS_AGAIN:
            return 0.0
        if r.cause == FORCES_BEYOND_BOUND:
            return float(r.resumed_from_s)
    return 0.0


def _retries_tried(case_dir: Path) -> str:
    """The case's retries so far (its retry log, across calls) in one line, or ''."""
    retries, earlier = read_retry_log(case_dir)
    lines = retry_lines(retries, earlier)
    n_retries = len(earlier) + sum(r.cause != RERUN_REQUESTED for r in retries)
    if not n_retries:
        return ""
    return f"after {n_retries} retr{'y' if n_retries == 1 else 'ies'}: " + "; ".join(lines)


def _write_case_whole(case_dir: Path, write: Callable[[Path], object]) -> None:
    """Write a case into ``case_dir``, whose run lock the caller holds, so that a process
    killed part-way leaves no case that looks written: ``write`` fills a sibling
    ``<name>.writing`` folder, whatever else the case folder held goes (a half-written or
    half-moved case; the lock file stays), and the new files move in, mfflap_case.toml last.
    """
    tmp = case_dir.with_name(case_dir.name + ".writing")
    shutil.rmtree(tmp, ignore_errors=True)
    write(tmp)
    empty_case_folder(case_dir)
    marker = "mfflap_case.toml"
    for new in sorted(tmp.iterdir(), key=lambda path: path.name == marker):
        new.rename(case_dir / new.name)
    tmp.rmdir()


def check_written_for(case_dir: Path, motion: Motion, end_time: float, ramp_time: float,
                      mesh: str | AnyMeshSpec, solver: SolverSettings, plate: Plate | None,
                      fluid: Fluid | None, stream: FreeStream | None) -> None:
    """Refuse to resume a case written before for another run.

    A work folder is used again by a later back-test or study: a case of the same name
    written for another plate, fluid, stream, motion, duration, mesh or solver setting
    would be resumed (or, finished, read) as this run's. What its mfflap_case.toml does
    not keep (a case of an earlier mfflap) is not compared.

    Raises
    ------
    ConfigError
        Naming the first key that differs, both values and the folder.
    """
    kept = case_dir / "mfflap_case.toml"
    meta = read_toml(kept)
    advice = ("its results are not this run's: delete that folder, or give another work "
              "folder, to run this one")
    check_case_inputs(kept, meta, None, motion, plate or Plate(), fluid or Fluid(),
                      stream or FreeStream(), advice=advice, given_as="asked")
    asked = {"mesh": mesh if isinstance(mesh, str) else mesh.name, "end_time": end_time,
             "ramp_time": ramp_time, **solver_keys(solver)}
    for key, written, value in kept_differences(meta, asked)[:1]:
        raise ConfigError(f"{case_dir} was written for {key} = {written!r}, this run asks "
                          f"{value!r} ({kept}); {advice}", key=key)


def run_motion(case_dir: str | Path, motion: Motion, name: str, parameters: dict[str, Any],
               end_time: float, *, mesh: str | AnyMeshSpec = "coarse", ramp_time: float = 0.0,
               solver: SolverSettings | None = None, plate: Plate | None = None,
               fluid: Fluid | None = None, stream: FreeStream | None = None,
               timeout_s: float = 6 * 3600.0, y_plus: bool = False,
               n_procs: int = 1, max_retries: int = 3,
               min_time_step: float = 1e-7,
               force_bound_factor: float = BREACH_FACTOR,
               bound_watch_every_s: float = 60.0,
               progress: Callable[[str], None] | None = None,
               progress_every_s: float = 60.0,
               retries_from_start: bool = False) -> CfdRecord:
    """Write (unless already written), run or resume, and parse one OpenFOAM case.

    Fields are written four times per run so that a killed run resumes from its last
    written time instead of from zero. A run whose time step collapses (an instability held
    at the Courant limit), or whose Courant number explodes, is resumed from its last
    written time before that, up to ``max_retries`` times: first with the inletOutlet far
    field (:func:`use_inlet_outlet_far_field`) if it had the freestream one, then with half
    the Courant limit, the last time also with first-order upwind convection of k and
    epsilon. A run that finishes with forces after
    its ramp beyond ``force_bound_factor`` times what the motion can drive
    (:mod:`mfflap.records.force_envelope`: it lost its numerics gradually) is retried the same
    way from its last written time before that (:func:`rewind_case`); its forces are
    checked every ``bound_watch_every_s`` seconds while it runs, so that such a run stops
    there instead of computing its lost stretch to the end. A time step that collapsed for
    a moment only and recovered stops the run too (:func:`run_case` reads every step), and
    its retry resumes from the last written time before the collapse, so that no field
    written after it is kept. A run whose force log's times repeat (its time step fell below
    the written precision, not below ``min_time_step``, and it ran on to its end time) is
    retried the same way from its last written time before that. A run that leaves the
    bound at the same flow time (within :data:`SAME_BREACH_FRACTION` of c / U) after its
    Courant limit was lowered is rerun once from t = 0 with the settings it has then (the
    flow at its last written time may have been spoiled already: f = 1 Hz, h = 0.5 m,
    phi = 135 deg lost at max Co 4 failed that way from t = 0.75 s at max Co 2 and 1, and
    ran through at max Co 2 from the start). It is not retried further if it leaves the
    bound there again, or if its last retry already ran from t = 0: no smaller time step
    cures a loss that does not move with the time step. The retries are recorded in the
    case (:mod:`~mfflap.cfd.openfoam.retry_log`) and in the record's provenance, those of
    earlier calls that resumed the same case included: the case's settings changed there, not in
    mfflap_case.toml. They also count against ``max_retries``, and an earlier call's
    breach against the same-flow-time rule: a run resumed after its process was killed has
    what is left of its budget, unless :func:`request_rerun` gave it a new one.
    ``progress``, if given, is told every ``progress_every_s`` seconds how far the solver
    has got (:func:`mfflap.cfd.openfoam.runner.run_case`).

    ``retries_from_start``: every retry reruns the case from t = 0 s with its changed
    settings instead of resuming from a written time, so that the record ran one set-up
    throughout (a back-test compared with another one's, :mod:`mfflap.records.as_run`):
    resumed part-way, the cycles before the retry ran with the settings before it (on the
    coarse mesh, max Co 2 instead of 4 moved a settled mean thrust by 7 %). It costs the
    flow time run before the retry again. A loss of the bound at the same flow time after
    a lower Courant limit then ends the retries (it ran from t = 0 already).

    Raises
    ------
    ConfigError
        Before anything is made, if ``case_dir``'s path holds characters OpenFOAM strips
        (:func:`~mfflap.cfd.openfoam.case_path.check_case_path`).
    CfdRunError
        For a run that fails or diverges otherwise, or still does after ``max_retries``
        retries, or whose forces still leave the bound then, or leave it again at the same
        flow time with a lower Courant limit (the message says where, and the retries).
    """
    case_dir = check_case_path(case_dir)  # before the lock file makes the folder
    solver = solver or SolverSettings(write_interval=end_time / 4)
    with case_lock(case_dir):  # no other run in this case while this one writes or retries
        if (case_dir / "mfflap_case.toml").exists():  # resumed: only if it is this run
            check_written_for(case_dir, motion, end_time, ramp_time, mesh, solver, plate,
                              fluid, stream)
        else:
            _write_case_whole(case_dir, lambda tmp: write_case(
                tmp, motion, end_time, mesh=mesh, plate=plate, fluid=fluid, stream=stream,
                solver=solver, ramp_time=ramp_time, y_plus=y_plus))
        started = time.perf_counter()
        # what earlier calls spent of the budget: a run resumed after its process was
        # killed goes on with what is left of it
        retries, n_earlier = budget_retries(case_dir)
        same_breach_s = (SAME_BREACH_FRACTION * (plate or Plate()).chord
                         / abs((stream or FreeStream()).velocity))
        last_breach = _earlier_breach(retries)  # (flow time s, the Courant limit then)
        watch = _bound_watch(case_dir, motion, ramp_time, plate, fluid, stream, force_bound_factor)
        while True:
            try:
                run_case(case_dir, timeout_s=timeout_s, n_procs=n_procs,
                         min_time_step=min_time_step, watch=watch,
                         watch_every_s=bound_watch_every_s, progress=progress,
                         progress_every_s=progress_every_s)
            except RunStopped:  # asked to write and stop (a campaign's Ctrl-C): no retry
                raise
            except CfdRunError as exc:
                bound_stop = (isinstance(exc, RunStoppedByWatch)
                              and isinstance(exc.reason, ForcesBeyondBound))
                if bound_stop and n_earlier + len(retries) < max_retries:
                    pass  # stopped early by the bound: rewound and retried below
                elif not isinstance(exc, SolverDiverged) or n_earlier + len(retries) >= max_retries:
                    tried = _retries_tried(case_dir)
                    if not tried:
                        raise
                    raise CfdRunError(f"{getattr(exc, '_message', exc)}; {tried}", case=exc.case,
                                      log_tail=exc.log_tail) from exc
                else:  # rewound before the remedy: it rewrites the kept fields
                    # (an instability either way, which the same remedies cure; a brief one
                    # is seen after it: fields written since are spoiled)
                    _retry(case_dir, retries, n_earlier, exc.kind, exc.time_s,
                           0.0 if retries_from_start else exc.time_s, progress, max_retries)
                    continue
            try:
                record = record_from_case(case_dir, motion, name, parameters, plate)
            except RepeatedTimes as exc:
                # the time step fell below the written precision for a while (at t >= 10 s,
                # 1e-6 s with 8 digits: not below the runner's min_time_step) and the run went
                # on to its end time, its forces there possibly in the 1e9 N
                at = (f"time step collapsed at t = {exc.time_s!r} s (the force log's times "
                      "repeat there)")
                if n_earlier + len(retries) >= max_retries:
                    tried = _retries_tried(case_dir)
                    raise CfdRunError(f"{at}{f'; {tried}' if tried else ''}",
                                      case=str(case_dir)) from exc
                _retry(case_dir, retries, n_earlier, TIMES_REPEAT, exc.time_s,
                       0.0 if retries_from_start else exc.time_s, progress, max_retries)
                continue
            breach = _forces_beyond_bound(record, ramp_time, plate, fluid, stream,
                                          force_bound_factor)
            if breach is None:
                break
            max_co = courant_limit(case_dir)
            same_time = (last_breach is not None
                         and abs(breach.start_s - last_breach[0]) <= same_breach_s)
            if same_time and any(r.cause == SAME_LOSS_AGAIN for r in retries):
                raise CfdRunError(
                    f"the forces leave what the motion can drive, {breach.describe()}, where they "
                    f"left it before the run was rerun from t = 0 s (t = {last_breach[0]:.6g} s):"
                    f" the mesh, the far field or the turbulence model does not hold this motion "
                    f"at max Co {max_co:g}; {_retries_tried(case_dir)}", case=str(case_dir))
            if n_earlier + len(retries) >= max_retries:
                raise CfdRunError(f"the forces leave what the motion can drive, {breach.describe()}"
                                  f": the run lost its numerics, and {len(retries)} retries did "
                                  f"not cure it; {_retries_tried(case_dir)}", case=str(case_dir))
            if same_time and max_co < last_breach[1] and _last_resume_s(retries) > 0.0:
                # the same loss from the last written time whatever the time step: that flow may
                # have been spoiled already; one rerun from the start with the settings it has now
                rewind_case(case_dir, 0.0)
                _keep_retry(case_dir, retries, n_earlier,
                            Retry(SAME_LOSS_AGAIN, breach.start_s, 0.0, f"max Co {max_co:g}",
                                  max_co, last_breach[1]), progress, max_retries)
                last_breach = (breach.start_s, max_co)
                continue
            if same_time and max_co < last_breach[1]:  # and the last retry ran from t = 0
                raise CfdRunError(
                    f"the forces leave what the motion can drive, {breach.describe()}, where they "
                    f"left it at max Co {last_breach[1]:g} (t = {last_breach[0]:.6g} s): "
                    f"the loss does not move with the time step (max Co {max_co:g}, run from "
                    "t = 0 s), so no smaller one cures it: the mesh, the far field or the "
                    f"turbulence model does not hold this motion; {_retries_tried(case_dir)}",
                    case=str(case_dir))
            last_breach = (breach.start_s, max_co)
            _retry(case_dir, retries, n_earlier, FORCES_BEYOND_BOUND, breach.start_s,
                   0.0 if retries_from_start else breach.start_s, progress, max_retries,
                   max_courant=max_co)
        logged, earlier = read_retry_log(case_dir)
        if logged or earlier:
            record.provenance["retries"] = "; ".join(retry_lines(logged, earlier))
        if logged:
            record.provenance["retry_log"] = retries_to_json(logged)
        if record.time[-1] < 0.98 * end_time:
            raise CfdRunError(f"the run stopped at t = {record.time[-1]:.4g} s before endTime "
                              f"{end_time:.4g} s", case=str(case_dir))
        record.provenance["retries_from_start"] = retries_from_start
        record.provenance["n_processes"] = n_procs
        record.provenance["wall_time_this_session_s"] = time.perf_counter() - started
        return record
