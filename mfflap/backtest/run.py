"""Run (or find) the CFD of an optimised motion and compare it with the model.

The CFD comes, in this order, from: a live OpenFOAM run (``live=True`` and OpenFOAM
installed), or a precomputed record keyed by :func:`motion_key` in the fixture folders. A
motion with neither is reported as not back-tested, with the reason; it is never skipped
silently.
"""

from __future__ import annotations

import hashlib
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np
from scipy.optimize import minimize_scalar

from mfflap.backtest.compare import BacktestComparison, compare_last_cycle
from mfflap.cfd.case_inputs import kept_differences, solver_keys
from mfflap.cfd.openfoam.case_lock import CaseBusyError
from mfflap.cfd.openfoam.run_motion import run_motion
from mfflap.cfd.openfoam.runner import openfoam_available
from mfflap.cfd.openfoam.writer import AnyMeshSpec, SolverSettings
from mfflap.errors import MfflapError
from mfflap.kinematics.continuous import PeriodicSplineMotion
from mfflap.kinematics.convert import to_spline
from mfflap.kinematics.discrete import DiscreteMotion
from mfflap.records.as_run import as_run_since_s
from mfflap.records.inputs import folder_setup, input_mismatches
from mfflap.records.record import CfdRecord, read_record, read_record_parameters, write_record
from mfflap.toml_io import dumps, read_toml


def motion_key(motion: DiscreteMotion, digits: int = 4) -> str:
    """A short hash of a motion's period and full-cycle pitch and heave (rounded).

    Rounding to ``digits`` significant digits (relative to each signal's amplitude) keeps the
    key stable against last-bit differences between machines.
    """
    _, pitch, heave = motion.full_cycle_positions()
    h = hashlib.sha256()
    for arr in (np.atleast_1d(motion.period), pitch, heave):
        arr = np.real(np.asarray(arr, dtype=float))
        scale = max(float(np.max(np.abs(arr))), 1e-12)
        h.update((np.round(arr / scale, digits) + 0.0).tobytes())  # + 0.0: no -0.0
        h.update(f"{scale:.{digits}g}".encode())
    return h.hexdigest()[:16]


@dataclass
class BacktestOutcome:
    """What happened to one motion's back-test."""

    label: str
    key: str
    status: str  # "back-tested" | "not back-tested"
    source: str  # "live OpenFOAM" | "fixture <path>" | reason it is missing
    record: CfdRecord | None = None
    comparison: BacktestComparison | None = None


def cfd_motion(motion: DiscreteMotion) -> PeriodicSplineMotion:
    """The continuous motion imposed in CFD (periodic spline through the full cycle)."""
    return to_spline(motion)


@dataclass(frozen=True)
class FixtureMatch:
    """A record of a motion's CFD: its path and the time shift of its cycle.

    ``shift_s`` is 0 for a record of the motion as asked, else the s (-period/2 < s <=
    period/2) with the record's imposed motion at time t that of the motion asked at
    t + s: the same periodic motion shifted in time. A periodic optimum is defined up to
    such a shift when nothing in the problem fixes its phase (beta = 1's least power:
    a start changed in its 12th digit moved it 1.4 s along its 10 s cycle, J by 1e-8), so
    machines that round differently find it at other phases. Its cycle means are the
    same; the comparison is made on the record's own kinematics
    (:func:`~mfflap.backtest.compare.compare_last_cycle`).
    """

    path: Path
    shift_s: float = 0.0

    def shift_note(self) -> str:
        """``the same periodic motion shifted in time by <s> s``, or "" without a shift."""
        if self.shift_s == 0.0:
            return ""
        return f"the same periodic motion shifted in time by {self.shift_s:+.4g} s"

    def describe(self) -> str:
        """``fixture <name>``, with the shift when there is one."""
        note = self.shift_note()
        return f"fixture {self.path.name}" + (f" ({note})" if note else "")


def _kinematics_within(rec: CfdRecord, spline: PeriodicSplineMotion,
                       tolerance: float) -> bool:
    """Whether a record's imposed kinematics after its start-up ramp are ``spline``'s (the
    heave less its value at t = 0, where the CFD starts) within ``tolerance`` of each
    signal's range."""
    ref = spline.sample(rec.time)
    scale_p = max(np.ptp(ref.pitch_angle), 1e-9)
    scale_h = max(np.ptp(ref.heave_position), 1e-9)
    after = rec.time >= float(rec.parameters.get("ramp_time", 0.0))
    dp = np.max(np.abs(rec.state.pitch_angle[after] - ref.pitch_angle[after])) / scale_p
    h0 = spline.sample(np.array([0.0])).heave_position[0]
    dh = np.max(np.abs(rec.state.heave_position[after] - (ref.heave_position[after]
                                                          - h0))) / scale_h
    return bool(dp < tolerance and dh < tolerance)


def cycle_shift(rec: CfdRecord, spline: PeriodicSplineMotion, tolerance: float = 2e-3,
                n_samples: int = 512) -> float | None:
    """The time shift s (-period/2 < s <= period/2) with the record's imposed motion over its
    last period that of ``spline`` at t + s within ``tolerance`` of each signal's range
    (heave about its mean, so that the CFD's zero displacement at t = 0 drops out), or None
    (:func:`closest_cycle_shift`)."""
    found = closest_cycle_shift(rec, spline, n_samples)
    return None if found is None or found[1] >= tolerance else found[0]


def closest_cycle_shift(rec: CfdRecord, spline: PeriodicSplineMotion,
                        n_samples: int = 512) -> tuple[float, float] | None:
    """The time shift s (-period/2 < s <= period/2) that brings ``spline`` at t + s closest
    to the record's imposed motion over its last period, and that distance: the larger of
    pitch's and heave's (about its mean) greatest difference as a share of its range.

    The shift is found on ``n_samples`` shifts, then refined between the neighbours of the
    best. None for a record whose last period does not follow its start-up ramp.
    """
    period = spline.period
    t_end = float(rec.time[-1])
    if t_end - period < float(rec.parameters.get("ramp_time", 0.0)) - 1e-12:
        return None
    t = t_end - period + period * np.arange(n_samples) / n_samples
    pitch = np.interp(t, rec.time, rec.state.pitch_angle)
    heave = np.interp(t, rec.time, rec.state.heave_position)
    heave = heave - heave.mean()
    cycle = spline.sample(period * np.arange(n_samples) / n_samples)
    scale_p = max(np.ptp(cycle.pitch_angle), 1e-9)
    scale_h = max(np.ptp(cycle.heave_position), 1e-9)

    def distance(shift: float) -> float:
        ref = spline.sample(t + shift)  # periodic: any t
        return max(np.max(np.abs(pitch - ref.pitch_angle)) / scale_p,
                   np.max(np.abs(heave - (ref.heave_position - ref.heave_position.mean())))
                   / scale_h)

    step = period / n_samples
    grid = step * np.arange(n_samples)
    best = grid[int(np.argmin([distance(s) for s in grid]))]
    fine = minimize_scalar(distance, bounds=(best - step, best + step), method="bounded",
                           options={"xatol": 1e-6 * period})
    shift, found = ((float(fine.x), float(fine.fun)) if fine.fun < distance(best)
                    else (float(best), distance(best)))
    shift = float(np.mod(shift, period))
    return (shift - period if shift > period / 2 else shift), found


def matching_fixture(key: str, motion: DiscreteMotion, folders: Sequence[Path],
                     tolerance: float = 2e-3, suffix: str = "") -> FixtureMatch | None:
    """The record of ``motion``'s CFD in ``folders``: one of its key; else one whose imposed
    kinematics after the start-up ramp lie within ``tolerance`` of its own; else one of the
    same periodic motion shifted in time, the closest if several (:func:`cycle_shift`);
    else None. Records are named ``backtest_<key><suffix>.h5`` (``suffix`` "_copy0": the
    first copies of :func:`mfflap.backtest.repeat.repeat_runs`)."""
    for folder in folders:
        exact = folder / f"backtest_{key}{suffix}.h5"
        if exact.exists():
            return FixtureMatch(exact)
    spline = cfd_motion(motion)
    candidates = []
    for folder in folders:
        for path in sorted(folder.glob(f"backtest_*{suffix}.h5")):
            period = float(read_record_parameters(path).get("period", -1))
            if abs(period - spline.period) > tolerance * spline.period:
                continue  # not read whole: most records of a folder are other motions'
            rec = read_record(path)
            if _kinematics_within(rec, spline, tolerance):
                return FixtureMatch(path)
            candidates.append((path, rec))
    shifted = [(found[1], found[0], path) for path, rec in candidates
               if (found := closest_cycle_shift(rec, spline)) is not None
               and found[1] < tolerance]
    if not shifted:
        return None
    _, shift, path = min(shifted, key=lambda m: m[0])
    return FixtureMatch(path, shift)


def _other_set_up(record: CfdRecord, mesh: str | AnyMeshSpec,
                  solver: SolverSettings | None, n_cycles: float = 3.0,
                  retries_from_start: bool = False) -> str | None:
    """How a fixture's run differs from the live run asked for (its mesh, a solver setting
    its provenance gives, fewer periods, with ``retries_from_start`` a retry part-way), or
    None: then it is the CFD that run would have been (a longer run holds the shorter one's
    cycles after its own start-up too)."""
    had_cycles = float(record.parameters.get("n_cycles", 3.0))
    if had_cycles < n_cycles - 1e-9:
        return f"for {had_cycles:g} periods, not {n_cycles:g} as asked"
    if retries_from_start and (since := as_run_since_s(record)) > 0.0:
        return (f"with a retry that resumed it from t = {since:.4g} s, not one set-up "
                "throughout as --retries-from-start asks")
    asked_mesh = mesh if isinstance(mesh, str) else mesh.name
    had_mesh = record.provenance.get("mesh")
    if had_mesh is not None and had_mesh != asked_mesh:
        return f"on mesh {had_mesh!r}, not {asked_mesh!r} as asked"
    asked = solver_keys(solver or SolverSettings(), leave_out=("write_interval",))
    for key, had, value in kept_differences(record.provenance, asked)[:1]:
        return f"with {key.removeprefix('solver_')} = {had!r}, not {value!r} as asked"
    return None


def _done_before(motion: DiscreteMotion, key: str, folders: Sequence[str | Path], model,
                 mesh: str | AnyMeshSpec, solver: SolverSettings | None,
                 n_cycles: float = 3.0, retries_from_start: bool = False
                 ) -> tuple[CfdRecord | None, FixtureMatch | None]:
    """The record of this motion in ``folders`` (by key, else within the fixtures'
    tolerance, else shifted in time: :func:`matching_fixture`) and where it was found, if it
    was run for this case on the mesh and solver settings asked (else None, None: it is to
    be run)."""
    match = matching_fixture(key, motion, [Path(f) for f in folders if Path(f).is_dir()])
    if match is None:
        return None, None
    record = read_record(match.path)
    if input_mismatches(record, model.plate, model.fluid, model.stream,
                        folder_setup(match.path)) or _other_set_up(
                            record, mesh, solver, n_cycles, retries_from_start):
        return None, None
    return record, match


def run_backtest_case(motion: DiscreteMotion, label: str, name: str, *,
                      work_dir: str | Path, n_cycles: float = 3.0,
                      mesh: str | AnyMeshSpec = "coarse", solver: SolverSettings | None = None,
                      plate=None, fluid=None, stream=None,
                      progress: Callable[[str], None] | None = None,
                      parameters: dict | None = None,
                      retries_from_start: bool = False, n_procs: int = 1) -> CfdRecord:
    """Run the back-test CFD of ``motion``, the record ``name``: the periodic spline through
    its cycle (:func:`cfd_motion`) after a start-up ramp of half a period, for ``n_cycles``
    periods, written every quarter of the run (a killed run resumes from there). Its case
    is ``work_dir/name``, with ``_<n>cycles`` after it for other than 3 periods (so that a
    work folder holds both). The record's parameters say so, with ``parameters`` added.
    ``retries_from_start``: a retry reruns the case from t = 0 s, so that the record ran one
    set-up throughout (:func:`~mfflap.cfd.openfoam.run_motion.run_motion`). ``n_procs`` > 1
    runs it decomposed on that many processes under mpirun; its provenance says so.

    Raises
    ------
    MfflapError
        The run failed (:func:`~mfflap.cfd.openfoam.run_motion.run_motion`).
    """
    spline = cfd_motion(motion)
    period = spline.period
    params = {"kind": "periodic_spline", "label": label, "period": period,
              "n_steps": motion.n_steps, "ramp_time": 0.5 * period, "n_cycles": n_cycles,
              "motion_key": motion_key(motion), **(parameters or {})}
    settings = None if solver is None else replace(solver,
                                                   write_interval=n_cycles * period / 4)
    case = name if n_cycles == 3 else f"{name}_{n_cycles:g}cycles"
    return run_motion(Path(work_dir) / case, spline, name, params, n_cycles * period,
                      mesh=mesh, ramp_time=0.5 * period, plate=plate, fluid=fluid,
                      stream=stream, solver=settings, progress=progress,
                      retries_from_start=retries_from_start, n_procs=n_procs)


def _folders_said(folders: Sequence[str | Path]) -> str:
    """The fixture folders looked in, for a message: all of them when few, else their
    count and the first.

    Examples
    --------
    >>> _folders_said(["a/x", "a/y"])
    'a/x, a/y'
    >>> _folders_said([f"f{i}" for i in range(10)])
    'the 10 fixture folders (f0, f1, ...)'
    """
    if not folders:
        return "no fixture folder"
    if len(folders) <= 3:
        return ", ".join(str(f) for f in folders)
    return f"the {len(folders)} fixture folders ({folders[0]}, {folders[1]}, ...)"


def backtest_motion(motion: DiscreteMotion, label: str, model, max_power: float, *,
                    fixture_folders: Sequence[str | Path] = (), live: bool = False,
                    work_dir: str | Path | None = None, n_cycles: float = 3.0,
                    mesh: str = "coarse", plate=None, fluid=None, stream=None,
                    save_to: str | Path | None = None,
                    solver: SolverSettings | None = None,
                    progress: Callable[[str], None] | None = None,
                    done_folders: Sequence[str | Path] = (),
                    average_cycles: int = 1,
                    retries_from_start: bool = False, n_procs: int = 1) -> BacktestOutcome:
    """Back-test one periodic motion: run or find its CFD, compare the last cycle.

    Parameters
    ----------
    live
        Run OpenFOAM (requires it installed and ``work_dir``).
    n_cycles
        Periods a live run simulates (:func:`run_backtest_case`). A record of this motion
        run for fewer periods is not taken for a live run.
    retries_from_start
        A live run's retries rerun it from t = 0 s, so that it runs one set-up throughout
        (:func:`~mfflap.cfd.openfoam.run_motion.run_motion`); a record of this motion retried
        part-way is then not taken for it.
    n_procs
        Processes a live run is decomposed on (1: serial). A record run on another count
        is taken: the layout changes round-off, not the set-up.
    average_cycles
        The CFD and model means are those over the last ``average_cycles`` whole cycles
        (:func:`~mfflap.backtest.compare.compare_last_cycle`); a record with fewer after its
        start-up is not back-tested, with the reason.
    mesh, solver
        Mesh and solver settings of a live run (default: the coarse mesh at the default
        settings; a named set-up of setups.toml gives both); they are in the record's
        provenance.
    save_to
        Folder where a live run's record is written as ``backtest_<key>.h5`` (a fixture).
    progress
        Told every minute how far a live run's solver has got.
    done_folders
        Live, records of this motion run before on the same plate, fluid, stream, mesh and
        solver settings (``backtest_<key>.h5``) are taken instead of a new run (the rounds of
        :mod:`mfflap.rounds` back-test a motion repeated from an earlier round once).
    """
    key = motion_key(motion)
    period = cfd_motion(motion).period
    folders = [Path(f) for f in fixture_folders if Path(f).is_dir()]
    record, before = (_done_before(motion, key, done_folders, model, mesh, solver, n_cycles,
                                   retries_from_start) if live else (None, None))
    source = "" if before is None else "live OpenFOAM, run before ({})".format(
        ", ".join(filter(None, (str(before.path), before.shift_note()))))
    if live and record is None:
        if not openfoam_available():
            source = "OpenFOAM is not installed"
        elif work_dir is None:
            source = "no work folder for the live run"
        else:
            name = f"backtest_{key}"
            try:
                record = run_backtest_case(motion, label, name, work_dir=work_dir,
                                           n_cycles=n_cycles, mesh=mesh, solver=solver,
                                           plate=plate, fluid=fluid, stream=stream,
                                           progress=progress,
                                           retries_from_start=retries_from_start,
                                           n_procs=n_procs)
                source = "live OpenFOAM"
                if save_to is not None:  # go on with the record as saved (single precision),
                    # as a resumed or repeated run that finds it there will: the rounds'
                    # later optima are then the same motions, and so are their cases
                    saved = Path(save_to) / f"{name}.h5"
                    write_record(saved, record, single_precision=True)
                    record = read_record(saved)
            except CaseBusyError as exc:  # busy, not failed: nothing to record
                source = f"live OpenFOAM run not started: {str(exc).splitlines()[0]}"
            except MfflapError as exc:
                source = f"live OpenFOAM run failed: {str(exc).splitlines()[0]}"
                if save_to is not None:  # a failure is a result too: the report says why
                    Path(save_to).mkdir(parents=True, exist_ok=True)
                    (Path(save_to) / f"{name}.failed.toml").write_text(dumps(
                        {"motion_key": key, "label": label, "error": str(exc)[:4000]}))
    if record is None:
        match = matching_fixture(key, motion, folders)
        path = None if match is None else match.path
        failed = [f / f"backtest_{key}.failed.toml" for f in folders
                  if (f / f"backtest_{key}.failed.toml").exists()]
        found = None if path is None else read_record(path)
        mismatches = [] if found is None else input_mismatches(
            found, model.plate, model.fluid, model.stream, folder_setup(path))
        other_setup = (None if found is None or not live
                       else _other_set_up(found, mesh, solver, n_cycles, retries_from_start))
        if mismatches:  # the same motion, but not this case's CFD: its plate, fluid, stream
            m = mismatches[0]
            source = ((f"{source}; " if source else "")
                      + f"fixture {path.name} matches the motion but ran for {m.key} = "
                      f"{m.record_value:g} ({m.where}), the case has {m.case_value:g}")
        elif other_setup is not None:  # not the CFD the live run asked for would have been
            source += f"; fixture {path.name} was run {other_setup}"
        elif found is not None:
            record = found
            # a live run asked for and not had is said, not replaced by the fixture's name
            source = match.describe() + (f" instead of a live run: {source}" if source
                                         else "")
        elif failed and not source:
            error = str(read_toml(failed[0]).get("error", "")).splitlines()[0]
            source = f"the CFD run of this motion failed ({failed[0].name}): {error}"
        elif not source:
            source = (f"no CFD fixture for motion key {key} in {_folders_said(folders)} "
                      "and no live run")
        else:
            source += f"; no CFD fixture for motion key {key}"
    if record is None:
        return BacktestOutcome(label, key, "not back-tested", source)
    try:
        comparison = compare_last_cycle(record, model, period, max_power,
                                        average_cycles=average_cycles)
    except MfflapError as exc:  # the CFD run lost its numerics: no verdict on the model
        return BacktestOutcome(label, key, "not back-tested", f"{source}; {exc}")
    return BacktestOutcome(label, key, "back-tested", source, record, comparison)
