"""CPU per flapping cycle of CFD set-ups, and the NRMSE of their forces against the medium mesh.

f = 1 Hz, h_amp = 0.3 m, theta = 20 deg (--pitch-deg), phi = 90 deg, U = 0.3 m/s, with a
0.25 s smooth start-up ramp, two cycles. Every set-up runs in this process's pool (two at a
time, two cores; --workers); CPU times are each run's own (blockMesh + pimpleFoam), printed per
simulated cycle and as a ratio to the medium mesh. Progress goes to stderr: each run as it
finishes, and every minute the simulated time of the runs still going.

The reference is the "reference" set-up of setups.toml (the medium mesh, GAMG). It runs a
second time with PCG instead of GAMG (both converged to 1e-7): the NRMSE between those two is
the floor under any comparison with the medium mesh, since they differ only by round-off in
the linear solves. It runs a third time at max Co 3 instead of 4: the NRMSE between those is
the medium mesh's own time-step uncertainty, the scale against which a 2 % target has to be
read (--no-time-step-floor skips that run; at max Co 5 the medium mesh's time step collapses
in the second cycle). Every set-up named on the command line runs a second time too, with the
other pressure solver (PCG for GAMG, GAMG for PCG) at its own tolerances: the NRMSE between
those two is that set-up's solver floor, how far its forces move when only the round-off of
its linear solves changes (--no-solver-floor skips those runs, but reads those that finished
in --work-dir before). A set-up whose floor is close to its distance from the reference
cannot be said to be nearer the reference than that floor.
With --plate-frame the reference and every named set-up also run in the plate's frame (a
static mesh; SolverSettings.frame = "plate", which needs the inletOutlet far field): their CPU
and their distance from the same set-up with the moving mesh are printed, which is what the
formulation alone changes when --far-field inletOutlet is given too. Forces are compared on
the first cycle after the ramp (0.25-1 s) and on the second cycle
(1-2 s), de-spiked. CPU is pimpleFoam's own (the last ExecutionTime of its log). A run that
fails is reported with the reason; the others are still compared. A run stopped part-way
(this process killed) resumes from its last time folder written whole when the same command
runs again in the same --work-dir; the steps it then takes again are left out of its CPU
(solver_log.redone_work), though its forces carry the restart's round-off.

CPU seconds depend on the machine (the reference took 318-340 s per cycle on earlier machines
of this kind and 155 s on a later one). The cost target's 90 s per cycle was set against a
reference OpenFOAM set-up, which needed about 4.4 min per cycle on its own machine. That
set-up (the "openfoam_md" set-up: its H-type mesh, PIMPLE 2x1, PCG, max Co 2) runs here too, as
the baseline, and every CPU per cycle is printed two more ways: as a ratio to the baseline's on
the same motion and machine (the target as a ratio: 90 s / 4.4 min = 0.34), and at the speed of
openfoam.md's machine, scaled by the baseline's CPU per cell and time step against that file's
(5.63 µs: 4.4 min, 16,442 cells, about 2,850 steps). The two differ where the baseline takes
another number of steps per cycle here than that file's 2,850: the file does not give its
motion's pitch, and the H-type mesh's time step is set by how fast it turns (--no-baseline
skips it). The output ends with a verdict for each named set-up: whether its first-cycle F_n
and M are within 2 % NRMSE of the medium mesh, whether its run with the other pressure solver
is too (a pass that turns on round-off is not a robust one), and which of those three readings
of the 90 s it meets. --yardstick-courant X also runs the reference at max Co X and measures
every NRMSE against that run instead (the medium mesh at max Co 4 is not converged in time on
every motion). --yardstick-courant 4,1,2 (several max Co, 4 being the reference's own) measures
every NRMSE against the mean of the medium mesh's runs at those max Co, and prints each of
those runs' distance from that mean: the medium mesh's own time-step band. The verdict then
also says whether a set-up is inside that band (no further from the mean than the furthest of
the medium mesh's runs), the reading of a validation standard such as ASME V&V 20, where a
difference below the yardstick's own numerical uncertainty cannot be told apart from none.
--yardstick SETUP[@MESH][-coX] measures every NRMSE against that run instead of the medium
mesh: openfoam_md@openfoam_md_medium is the medium H-type mesh of openfoam.md's cost table
(32,452 cells there), which the cost target's "the medium mesh" may mean as well as mfflap's O-grid.
--yardstick-floor also reruns each of the yardstick's runs other than the reference with the
other pressure solver and prints how far it moves: the yardstick's own round-off floor (the
reference's, reference-PCG, always runs). --window 0.25:0.55 also compares every run over
that time window (s), in the tables, the verdict and the HDF5 file: over the first stroke,
before the shed vortex passes the plate, is the reading of openfoam.md's "early-cycle forces
agreed within 1-2 % between coarse and medium".

Run: python benchmarks/cfd_cost.py [setup ...] [--meshes coarse,lean] [--cycles 2]
                                   [--work-dir DIR] [--figure F.png] [--output F.h5]
     (default: the "affordable" set-up; SETUP@MESH: that set-up's solver settings on a
     named mesh, as `mfflap cfd write --setup SETUP --mesh MESH`; either with -coX: at max
     Co X; --meshes adds named meshes at the reference settings; --figure draws every run's
     cost against its accuracy, --histories their F_n and M over time, --output keeps the
     numbers in HDF5 with the command line;
     with --work-dir, runs that finished there before are read, not rerun, runs stopped
     part-way are resumed, and a folder
     whose runs had another motion, cycle count, far field, k-epsilon convection
     (--turbulence-convection) or wall treatment (--wall-treatment) is refused; the mesh study
     of docs/findings/known_limits.md: affordable --meshes fine --far-field inletOutlet
     --cycles 1; the plate's frame: affordable --plate-frame --far-field inletOutlet --cycles 1)
"""

from __future__ import annotations

import argparse
import re
import shutil
import sys
import tempfile
from concurrent.futures import Future, ProcessPoolExecutor, wait
from dataclasses import dataclass, field, replace
from functools import partial
from pathlib import Path

import numpy as np

from mfflap.cfd.force_history import to_loads
from mfflap.cfd.imposed_motion import imposed_state
from mfflap.cfd.openfoam.forces import read_forces
from mfflap.cfd.openfoam.runner import ran_to_end, run_case
from mfflap.cfd.openfoam.setups import mesh_and_solver, setup
from mfflap.cfd.openfoam.solver_log import solver_progress, solver_provenance
from mfflap.cfd.openfoam.writer import (
    WALL_TREATMENTS,
    AnyMeshSpec,
    SolverSettings,
    mesh_specs,
    write_case,
)
from mfflap.errors import MfflapError
from mfflap.identification.data import despike
from mfflap.kinematics import HarmonicMotion
from mfflap.metrics import nrmse

#: pitch amplitude of the benchmark motion, deg (openfoam.md does not give its own)
PITCH_DEG = 20.0


def benchmark_motion(pitch_deg: float = PITCH_DEG) -> HarmonicMotion:
    """f = 1 Hz, h_amp = 0.3 m, phi = 90 deg, the given pitch amplitude."""
    return HarmonicMotion(1.0, 0.3, np.deg2rad(pitch_deg), np.pi / 2)
RAMP_S = 0.25
COMPONENTS = ("normal_force", "moment", "tangential_force")
#: CPU per cycle of the set-up in shared/design/openfoam.md on that file's machine, s
OPENFOAM_MD_CPU_PER_CYCLE_S = 4.4 * 60
#: its time steps per cycle at f = 1 Hz, h = 0.3 m (max Co 2), "about" in that file
OPENFOAM_MD_STEPS_PER_CYCLE = 2_850
#: its CPU per cell and time step there (16,442 cells), µs: the baseline's here, against this,
#: is the speed of this machine against that one
OPENFOAM_MD_US_PER_CELL_STEP = OPENFOAM_MD_CPU_PER_CYCLE_S / (16_442 * 2_850) * 1e6
#: the cost target: CPU per cycle, s, and as a ratio to the set-up of openfoam.md
TARGET_CPU_PER_CYCLE_S = 90.0
TARGET_RATIO = TARGET_CPU_PER_CYCLE_S / OPENFOAM_MD_CPU_PER_CYCLE_S
#: and its accuracy: F_n and M NRMSE against the medium mesh in the first cycle, %
TARGET_NRMSE_PERCENT = 2.0
#: the label of the baseline run (the "openfoam_md" set-up of setups.toml)
BASELINE = "openfoam_md"


def windows(cycles: float, extra: tuple[float, float] | None = None
            ) -> dict[str, tuple[float, float]]:
    """Comparison windows: each simulated cycle (1 s at f = 1 Hz) after the ramp, and the
    ``extra`` window (start and end, s; --window) after them, named by its times."""
    named = {f"cycle {k}": (max(RAMP_S, k - 1.0), min(float(k), cycles))
             for k in range(1, int(np.ceil(cycles)) + 1) if min(k, cycles) > max(RAMP_S, k - 1)}
    if extra is not None:
        named[window_name(extra)] = extra
    return named


def window_name(window: tuple[float, float]) -> str:
    """The name of a --window in tables and in the study file, ``"t = 0.25-0.55 s"``."""
    return f"t = {window[0]:g}-{window[1]:g} s"


def time_window(text: str) -> tuple[float, float]:
    """The start and end of --window, s, from ``"0.25:0.55"``.

    Raises
    ------
    argparse.ArgumentTypeError
        If it is not two numbers with 0 <= start < end.
    """
    try:
        start, end = (float(v) for v in text.split(":"))
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"{text!r} is not a time window START:END in seconds") from None
    if not (np.isfinite(start) and np.isfinite(end) and 0.0 <= start < end):
        raise argparse.ArgumentTypeError(
            f"the window {text!r} must have 0 <= START < END, s")
    return start, end


@dataclass(frozen=True)
class SetupRun:
    """What one set-up's run gave: its CPU and forces, or why it failed."""

    label: str
    #: pimpleFoam's CPU per simulated cycle, s (None: the run failed)
    cpu_per_cycle_s: float | None
    #: the first line of the error of a failed run
    failure: str = ""
    time_s: np.ndarray = field(default_factory=lambda: np.empty(0))
    #: de-spiked F_n, M and F_t (COMPONENTS) at time_s, N and N m
    loads: dict[str, np.ndarray] = field(default_factory=dict)
    cpu_per_cell_step_us: float = float("nan")
    steps_per_cycle: float = float("nan")

    @property
    def ok(self) -> bool:
        """Whether the run finished."""
        return self.cpu_per_cycle_s is not None


@dataclass(frozen=True)
class Job:
    """One set-up to run: its label (the name of its case folder), mesh and solver settings."""

    label: str
    mesh: AnyMeshSpec
    solver: SolverSettings

    def with_solver(self, **changes) -> Job:
        """The same job with some solver settings changed."""
        return replace(self, solver=replace(self.solver, **changes))

    def variant(self, suffix: str, **changes) -> Job:
        """This job with some solver settings changed, labelled ``<label>-<suffix>``."""
        return replace(self.with_solver(**changes), label=f"{self.label}-{suffix}")


def run_setup(job: Job, cycles: float, root: str, pitch_deg: float) -> SetupRun:
    """Run (or, when it finished before in the work folder, read) one set-up."""
    label, mesh, solver = job.label, job.mesh, job.solver
    motion = benchmark_motion(pitch_deg)
    case = Path(root) / label
    if not ran_to_end(case):  # a run stopped early (written and stopped) ends in End too
        solver = replace(solver, write_interval=0.5)
        if not (case / "mfflap_case.toml").is_file():  # never written whole: start afresh
            shutil.rmtree(case, ignore_errors=True)
            case = write_case(case, motion, end_time=cycles, mesh=mesh, ramp_time=RAMP_S,
                              solver=solver)
        try:
            run_case(case, timeout_s=4 * 3600)
        except MfflapError as err:
            return SetupRun(label, None, failure=str(err).splitlines()[0])
    try:
        history = read_forces(case)
    except MfflapError as err:  # a finished run whose force log cannot be read
        return SetupRun(label, None, failure=str(err).splitlines()[0])
    loads = to_loads(history, imposed_state(motion, history.time, RAMP_S), 0.18, 0.18,
                     source=f"openfoam:{label}", frame=solver.frame)
    series = {k: despike(np.asarray(getattr(loads, k)))[0] for k in COMPONENTS}
    provenance = solver_provenance(case)
    cpu_s = provenance["cpu_time_s"] - provenance["cpu_time_redone_s"]
    n_steps = provenance["n_time_steps"] - provenance["n_time_steps_redone"]
    per_cell_step_us = cpu_s / (mesh.n_cells * max(n_steps, 1)) * 1e6
    return SetupRun(label, cpu_s / cycles, time_s=np.asarray(history.time), loads=series,
                    cpu_per_cell_step_us=per_cell_step_us, steps_per_cycle=n_steps / cycles)


def other_solver(job: Job) -> Job:
    """``job`` with the other pressure solver (PCG for GAMG, GAMG for PCG), labelled so.

    The two runs differ only by the round-off of their linear solves: their NRMSE is the
    job's round-off (solver) floor.
    """
    other = "PCG" if job.solver.pressure_solver == "GAMG" else "GAMG"
    return job.variant(other, pressure_solver=other)


def yardstick_jobs(reference: Job, courants: list[float] | None) -> list[Job]:
    """The runs of the medium mesh whose mean is the yardstick: the reference at each max Co
    of --yardstick-courant (labelled ``reference-coX``; the reference itself at its own max
    Co), or the reference alone."""
    own = reference.solver.max_courant
    return [reference if courant == own else reference.variant(f"co{courant:g}",
                                                                 max_courant=courant)
            for courant in courants or [own]]


_SETUP_LABEL = re.compile(r"^(?P<name>[^@\s-]+)(?:@(?P<mesh>[^@\s-]+))?"
                          r"(?:-co(?P<courant>[0-9.eE+]+))?$")


def setup_label(label: str) -> tuple[str, str, float | None]:
    """(set-up, mesh or "", max Co or None) of a set-up named on the command line:
    ``SETUP``, ``SETUP@MESH``, either with ``-coX`` (the set-up at max Co X, as
    ``--max-courant X`` labels it), so that one study holds set-ups at several max Co.

    Raises
    ------
    argparse.ArgumentTypeError
        If the label is not of that form or its max Co is not a positive number.
    """
    match = _SETUP_LABEL.match(label)
    courant = None
    if match is not None and match.group("courant") is not None:
        try:
            courant = float(match.group("courant"))
        except ValueError:
            courant = float("nan")
    if match is None or (courant is not None and not (np.isfinite(courant) and courant > 0)):
        raise argparse.ArgumentTypeError(
            f"{label!r}: a set-up is named SETUP, SETUP@MESH or either with -coX (X a "
            "positive max Courant number)")
    return match.group("name"), match.group("mesh") or "", courant


def courant_list(text: str) -> list[float]:
    """The max Co values of --yardstick-courant, ``"1"`` or ``"4,1,2"``.

    Raises
    ------
    argparse.ArgumentTypeError
        If a value is not a positive number or appears twice.
    """
    try:
        values = [float(v) for v in text.split(",")]
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"{text!r} is not a comma-separated list of max Courant numbers") from None
    bad = [v for v in values if not (np.isfinite(v) and v > 0)]
    if bad:
        raise argparse.ArgumentTypeError(f"max Courant numbers must be positive, not {bad[0]:g}")
    if len(set(values)) != len(values):
        raise argparse.ArgumentTypeError(f"{text!r} names a max Courant number twice")
    return values


def ensemble_mean(members: list[SetupRun], label: str, samples_per_s: int = 4000) -> SetupRun:
    """The mean of several runs' loads, on a uniform grid over the time they all cover.

    Its CPU per cycle is the members' sum: what the yardstick cost.
    """
    start = max(m.time_s[0] for m in members)
    end = min(m.time_s[-1] for m in members)
    time_s = np.linspace(start, end, max(2, round(float(end - start) * samples_per_s) + 1))
    loads = {k: np.mean([np.interp(time_s, m.time_s, m.loads[k]) for m in members], axis=0)
             for k in COMPONENTS}
    return SetupRun(label, sum(m.cpu_per_cycle_s for m in members), time_s=time_s,
                    loads=loads)


def time_step_band(members: list[SetupRun], mean: SetupRun, cycles: float) -> tuple[float, float]:
    """The furthest any member's first-cycle F_n and M are from their mean, NRMSE %."""
    first = [nrmse_percent(m, mean, cycles)["cycle 1"] for m in members]
    return max(e[0] for e in first), max(e[1] for e in first)


def collect(futures: dict[Future, str], root: str, cycles: float,
            every_s: float = 60.0) -> dict[str, SetupRun]:
    """The runs' results as they finish, with progress on stderr.

    Each finished run is reported at once (its CPU per cycle, or why it failed), and every
    ``every_s`` seconds the simulated time of the runs still going.
    """
    results: dict[str, SetupRun] = {}
    pending = set(futures)
    while pending:
        done, pending = wait(pending, timeout=every_s)
        for future in done:
            res = future.result()
            results[res.label] = res
            said = (f"{res.cpu_per_cycle_s:.1f} s CPU per cycle" if res.ok
                    else f"failed: {res.failure}")
            print(f"[{len(results)}/{len(futures)}] {res.label}: {said}", file=sys.stderr,
                  flush=True)
        # a queued run counts as running in a process pool: leave out those finished before
        going = [(futures[f], solver_progress(Path(root) / futures[f])) for f in pending
                 if f.running() and not ran_to_end(Path(root) / futures[f])]
        going = [f"{label} t = {at[0]:.3f} of {cycles:g} s" for label, at in going if at]
        if going:
            print(f"  running: {'; '.join(going)}", file=sys.stderr, flush=True)
    return results


def nrmse_percent(run: SetupRun, ref: SetupRun, cycles: float,
                  window: tuple[float, float] | None = None) -> dict[str, list[float]]:
    """F_n, M and F_t NRMSE of ``run`` against ``ref``, %, in each cycle's window and in
    ``window`` (start and end, s) if given."""
    out = {}
    for name, (a, b) in windows(cycles, window).items():
        t = np.linspace(a, b, 500)
        out[name] = [100 * nrmse(np.interp(t, run.time_s, run.loads[k]),
                                 np.interp(t, ref.time_s, ref.loads[k])) for k in COMPONENTS]
    return out


def compare(run: SetupRun, ref: SetupRun, cycles: float,
            window: tuple[float, float] | None = None) -> str:
    """F_n, M and F_t NRMSE of ``run`` against ``ref`` in each cycle's window (and in
    ``window``), as text."""
    return "   ".join(f"{name}: F_n {e[0]:5.2f} %  M {e[1]:5.2f} %  F_t {e[2]:5.1f} %"
                       for name, e in nrmse_percent(run, ref, cycles, window).items())


def verdict(run: SetupRun, yardstick: SetupRun, baseline: SetupRun | None,
            speed_factor: float, cycles: float, band: tuple[float, float] | None = None,
            twin: SetupRun | None = None, window: tuple[float, float] | None = None) -> str:
    """Which readings of the cost target ``run`` meets, in its first cycle.

    The accuracy half: F_n and M within 2 % NRMSE of the yardstick in cycle 1, and, given the
    ``band`` (the F_n and M NRMSE % of the furthest of the runs the yardstick is the mean of),
    whether they are inside it. Given the ``twin`` (the same set-up with the other pressure
    solver), the same for it, and whether the two verdicts differ: a pass that turns on the
    round-off of the linear solves is not a robust one. The cost half three ways: CPU per
    cycle on this machine, as a ratio to openfoam.md's set-up on the same motion and
    machine, and at openfoam.md's speed (``speed_factor`` x CPU here). Given a ``window``
    (start and end, s; --window), also whether F_n and M are within 2 % in it: openfoam.md's
    "early-cycle forces" are one such reading.
    """
    errors = nrmse_percent(run, yardstick, cycles, window)
    first = errors["cycle 1"]
    accurate = max(first[:2]) <= TARGET_NRMSE_PERCENT
    with_twin = ""
    if twin is not None and twin.ok:
        other = nrmse_percent(twin, yardstick, cycles)["cycle 1"]
        twin_accurate = max(other[:2]) <= TARGET_NRMSE_PERCENT
        with_twin = (f"; with the other pressure solver "
                     f"{'within' if twin_accurate else 'not within'} "
                     f"(F_n {other[0]:.2f} %, M {other[1]:.2f} %)")
        if twin_accurate != accurate:
            with_twin += ": the verdict turns on round-off"
    cpu = run.cpu_per_cycle_s
    readings = {"this machine's seconds": cpu <= TARGET_CPU_PER_CYCLE_S}
    if baseline is not None and baseline.ok:
        readings["ratio to openfoam.md's set-up"] = cpu / baseline.cpu_per_cycle_s <= TARGET_RATIO
        readings["openfoam.md's speed"] = cpu * speed_factor <= TARGET_CPU_PER_CYCLE_S
    costs = ", ".join(f"{k}: {'yes' if ok else 'no'}" for k, ok in readings.items())
    inside = ""
    if band is not None:
        within_band = first[0] <= band[0] and first[1] <= band[1]
        inside = (f"; {'inside' if within_band else 'outside'} the medium mesh's time-step band "
                  f"(F_n {band[0]:.2f} %, M {band[1]:.2f} %)")
    in_window = ""
    if window is not None:
        e = errors[window_name(window)]
        in_window = (f"; over {window_name(window)} "
                     f"{'within' if max(e[:2]) <= TARGET_NRMSE_PERCENT else 'not within'} "
                     f"(F_n {e[0]:.2f} %, M {e[1]:.2f} %)")
    return (f"{'within' if accurate else 'not within'} {TARGET_NRMSE_PERCENT:g} % "
            f"(F_n {first[0]:.2f} %, M {first[1]:.2f} %){with_twin}{inside}{in_window}; "
            f"cost met by {costs}")


@dataclass(frozen=True)
class Study:
    """What one run of this benchmark measured, for its figure and its HDF5 file."""

    results: dict[str, SetupRun]
    yardstick: SetupRun
    cycles: float
    #: the named set-ups, and each one's rerun with the other pressure solver by label
    named: list[str]
    floors: dict[str, str]
    cells: dict[str, int]
    baseline: SetupRun | None = None
    #: the medium mesh's time-step band, F_n and M NRMSE %, when the yardstick is a mean
    band: tuple[float, float] | None = None
    #: the motion and settings every run shares (the work folder's stamp)
    settings: str = ""
    #: --window: a time window (start and end, s) compared besides each cycle
    window: tuple[float, float] | None = None

    def cost_ratio(self, run: SetupRun) -> float:
        """CPU per cycle as a ratio to openfoam.md's set-up (to the reference without it)."""
        base = self.baseline if self.baseline is not None and self.baseline.ok else \
            self.results["reference"]
        return run.cpu_per_cycle_s / base.cpu_per_cycle_s

    def first_cycle_error(self, run: SetupRun) -> float:
        """The larger of F_n and M NRMSE against the yardstick in cycle 1, %."""
        return max(nrmse_percent(run, self.yardstick, self.cycles)["cycle 1"][:2])


def write_study(study: Study, path: str | Path, argv: list[str]) -> None:
    """Every run's CPU and NRMSE against the yardstick in an HDF5 file, with the inputs
    beside them (the command line, the shared settings, the yardstick and the targets)."""
    import h5py

    names = list(windows(study.cycles, study.window))
    with h5py.File(path, "w") as h5:
        h5.attrs.update({"command": " ".join(argv), "settings": study.settings,
                         "yardstick": study.yardstick.label, "cycles": study.cycles,
                         "components": list(COMPONENTS), "windows": names,
                         "target_cpu_per_cycle_s": TARGET_CPU_PER_CYCLE_S,
                         "target_ratio": TARGET_RATIO,
                         "target_nrmse_percent": TARGET_NRMSE_PERCENT,
                         "cost_ratio_to": BASELINE if study.baseline is not None
                         and study.baseline.ok else "reference"})
        if study.band is not None:
            h5.attrs["time_step_band_percent"] = list(study.band)
        for label, run in study.results.items():
            group = h5.create_group(label)
            group.attrs["n_cells"] = study.cells[label]
            group.attrs["named"] = label in study.named
            if label in study.floors:
                group.attrs["other_pressure_solver_run"] = study.floors[label]
            if not run.ok:
                group.attrs["failure"] = run.failure
                continue
            group.attrs.update({"cpu_per_cycle_s": run.cpu_per_cycle_s,
                                "cost_ratio": study.cost_ratio(run),
                                "steps_per_cycle": run.steps_per_cycle,
                                "cpu_per_cell_step_us": run.cpu_per_cell_step_us})
            errors = nrmse_percent(run, study.yardstick, study.cycles, study.window)
            group["nrmse_percent"] = np.array([errors[n] for n in names])


def cost_accuracy_figure(study: Study, path: str | Path, title: str = ""
                         ) -> dict[str, tuple[float, float]]:
    """Cost against accuracy: every finished run's CPU per cycle (as a ratio to
    openfoam.md's set-up) against the larger of its F_n and M NRMSE from the yardstick in
    cycle 1, the cost target as a shaded box, the medium mesh's time-step band as a line,
    and each named set-up joined to its rerun with the other pressure solver (the length of
    that line is its round-off floor seen from the yardstick). Returns the points drawn,
    (cost ratio, NRMSE %) by label."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(8.0, 5.5))
    have_baseline = study.baseline is not None and study.baseline.ok
    shown = [run for label, run in study.results.items()
             if run.ok and label != study.yardstick.label]
    ratios = [study.cost_ratio(run) for run in shown] + [TARGET_RATIO]
    x_range = (min(ratios) / 1.3, max(ratios) * 1.3)
    if have_baseline:
        ax.fill_between([x_range[0], TARGET_RATIO], 0, TARGET_NRMSE_PERCENT, color="tab:green",
                        alpha=0.15, label=f"target: <= {TARGET_RATIO:.2f} of openfoam.md's "
                        f"set-up, <= {TARGET_NRMSE_PERCENT:g} %")
    if study.band is not None:
        ax.axhline(max(study.band), color="tab:grey", linestyle="--",
                   label="the medium mesh's time-step band")
    twins = set(study.floors.values())
    drawn: dict[str, tuple[float, float]] = {}
    y_top = max([study.first_cycle_error(run) for run in shown] + [TARGET_NRMSE_PERCENT])
    labels, unlabelled = [], []  # the points drawn without a label: the twins
    for label, run in study.results.items():
        if not run.ok or label == study.yardstick.label:
            continue
        x, y = drawn[label] = study.cost_ratio(run), study.first_cycle_error(run)
        if label in study.named:
            style = {"color": "tab:blue", "marker": "o"}
        elif label in twins:
            style = {"color": "tab:blue", "marker": "o", "markerfacecolor": "none"}
        else:  # the medium mesh's own runs and the baseline
            style = {"color": "tab:grey", "marker": "s"}
        ax.plot([x], [y], linestyle="none", markersize=6, **style)
        if label not in twins:  # a twin is the open marker joined to its set-up
            labels.append(ax.annotate(label, (x, y), textcoords="offset points",
                                      xytext=(5, -3), fontsize=7))
        else:
            unlabelled.append((x, y))
    for label, twin in study.floors.items():
        a, b = study.results[label], study.results[twin]
        if a.ok and b.ok:
            ax.plot([study.cost_ratio(a), study.cost_ratio(b)],
                    [study.first_cycle_error(a), study.first_cycle_error(b)],
                    color="tab:blue", linewidth=0.8)
    ax.plot([], [], "o", color="tab:blue", label="set-up (GAMG or its own pressure solver)")
    ax.plot([], [], "o-", color="tab:blue", markerfacecolor="none", linewidth=0.8,
            label="the same with the other pressure solver (its round-off)")
    ax.plot([], [], "s", color="tab:grey", label="the medium meshes, openfoam.md's set-up")
    ax.set_xscale("log")
    ax.set_xlim(*x_range)
    ticks = [t for t in (0.1, 0.15, 0.2, round(TARGET_RATIO, 2), 0.5, 1, 2, 5, 10, 20, 50)
             if x_range[0] <= t <= x_range[1]]
    ax.set_xticks(ticks, [f"{t:g}" for t in ticks])
    ax.minorticks_off()
    ax.set_xlabel("CPU per cycle / openfoam.md's set-up" if have_baseline
                  else "CPU per cycle / the reference")
    ax.set_ylabel(f"max(F_n, M) NRMSE, cycle 1 (%),\nagainst {study.yardstick.label}")
    ax.set_ylim(0, 1.4 * max(y_top, *(study.band or (0.0,))))  # room for the legend above
    ax.set_title(title or study.settings, fontsize=9)
    ax.legend(fontsize=7, loc="upper right")
    fig.tight_layout()
    unstack_labels(fig, labels, unlabelled)
    fig.savefig(path, dpi=130)
    plt.close(fig)
    return drawn


def unstack_labels(fig, labels: list, points: list[tuple[float, float]] = (),
                   line_pt: float = 9.0, most_lines: int = 4, marker_pt: float = 4.0) -> None:
    """Place each point label beside its point where its text overlaps neither the labels
    placed before it nor any point drawn: right of the point, else left of it, else a line
    (``line_pt`` points) higher or lower, right or left, up to ``most_lines`` lines away,
    inside the axes; where every place is taken, the one that overlaps least. Labels of
    runs close in cost and accuracy (a long label reaches the next run's point) stay
    legible. ``points`` are the points drawn without a label (data coordinates), each
    label's own point counts too, a marker being ``marker_pt`` points in radius. A label
    moved off its point's line gets a thin leader to it. Measured on the figure as drawn, so
    it is called after the layout."""
    from matplotlib.transforms import Bbox

    if not labels:
        return
    renderer = fig.canvas.get_renderer()
    ax = labels[0].axes
    radius = marker_pt * fig.dpi / 72.0
    every_point = np.asarray([t.xy for t in labels] + list(points), dtype=float)
    markers = [Bbox([[x - radius, y - radius], [x + radius, y + radius]])
               for x, y in ax.transData.transform(every_point)]
    places = [(dx, -3.0 + line_pt * lift, ha)
              for lift in sorted(range(-most_lines, most_lines + 1), key=lambda k: (abs(k), -k))
              for dx, ha in ((5.0, "left"), (-5.0, "right"))]
    placed: list = []
    inside = ax.get_window_extent(renderer)
    for text in labels:
        best, best_overlaps = places[0], None
        for dx, dy, ha in places:
            text.xyann = (dx, dy)
            text.set_horizontalalignment(ha)
            box = text.get_window_extent(renderer)
            overlaps = sum(box.overlaps(other) for other in placed + markers)
            overlaps += 10 * (not inside.contains(box.x0, box.y0)
                              or not inside.contains(box.x1, box.y1))
            if best_overlaps is None or overlaps < best_overlaps:
                best, best_overlaps = (dx, dy, ha), overlaps
            if overlaps == 0:
                break
        text.xyann = best[:2]
        text.set_horizontalalignment(best[2])
        placed.append(text.get_window_extent(renderer))
        if best[1] != places[0][1]:  # off its point's line: a leader from its near end
            ax.annotate("", text.xy, xytext=(best[0], best[1] + 2.5), textcoords="offset points",
                        arrowprops={"arrowstyle": "-", "color": "0.6", "linewidth": 0.5,
                                    "shrinkA": 0, "shrinkB": 3})


def force_histories_figure(study: Study, path: str | Path, title: str = "") -> list[str]:
    """F_n and M over the simulated time after the ramp: the yardstick (black), the medium
    mesh (the reference), openfoam.md's set-up and each named set-up, so that where and how
    far they part can be seen. A set-up's rerun with the other pressure solver is left out.
    Returns the labels drawn, in the order drawn."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    wanted = [study.yardstick.label, "reference", BASELINE, *study.named]
    runs = {study.yardstick.label: study.yardstick,
            **{label: study.results[label] for label in wanted[1:]
               if label in study.results and study.results[label].ok}}
    fig, axes = plt.subplots(2, 1, figsize=(9.0, 6.5), sharex=True)
    for ax, component, unit in zip(axes, COMPONENTS[:2], ("F_n (N)", "M (N m)"), strict=True):
        for label, run in runs.items():
            shown = run.time_s >= RAMP_S
            style = ({"color": "black", "linewidth": 2.0, "zorder": 3}
                     if label == study.yardstick.label else {"linewidth": 0.9})
            ax.plot(run.time_s[shown], run.loads[component][shown], label=label, **style)
        ax.set_ylabel(unit)
        ax.grid(alpha=0.3)
    axes[-1].set_xlabel("t (s)")
    axes[0].legend(fontsize=7, ncol=2)
    axes[0].set_title(title or study.settings, fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=130)
    plt.close(fig)
    return list(runs)


def _checked_label(label: str) -> str:
    setup_label(label)
    return label


def labelled_job(label: str, max_courant: float | None = None) -> Job:
    """The job of a set-up named on the command line (``SETUP``, ``SETUP@MESH``, either with
    ``-coX``); ``max_courant`` is --max-courant, which a ``-coX`` of the label overrides."""
    name, mesh_name, courant = setup_label(label)
    job = Job(f"{name}@{mesh_name}" if mesh_name else name,
              *mesh_and_solver(mesh_name or None, name))
    courant = courant if courant is not None else max_courant
    return job if courant is None else job.variant(f"co{courant:g}", max_courant=courant)


def argument_parser() -> argparse.ArgumentParser:
    """The command line of this benchmark."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("setups", nargs="*", default=["affordable"], type=_checked_label,
                        help="set-ups of setups.toml; SETUP@MESH runs a set-up's solver "
                        "settings on a named mesh of meshes.toml; -coX after either runs it "
                        "at max Co X")
    parser.add_argument("--meshes", default="", help="named meshes run at the reference "
                        "settings, comma separated")
    parser.add_argument("--cycles", type=float, default=2.0, help="cycles simulated")
    parser.add_argument("--no-time-step-floor", action="store_true",
                        help="skip the reference's rerun at max Co 3")
    parser.add_argument("--no-solver-floor", action="store_true",
                        help="skip the set-ups' reruns with the other pressure solver (those "
                        "that finished in --work-dir before are still read)")
    parser.add_argument("--far-field", choices=("freestream", "inletOutlet"), default=None,
                        help="far field of every run (default: each set-up's own); the fine "
                        "mesh runs only with inletOutlet")
    parser.add_argument("--turbulence-convection", choices=("limitedLinear", "upwind"),
                        default=None, help="convection of k and epsilon in every run "
                        "(default: each set-up's own; upwind needs no clipping of epsilon)")
    parser.add_argument("--wall-treatment", choices=tuple(WALL_TREATMENTS), default=None,
                        help="the plate's wall conditions in every run, the reference and "
                        "the baseline included (default: each set-up's own): log_law (k-"
                        "epsilon wall functions) or all_y_plus (Spalding's law, any y+)")
    parser.add_argument("--plate-frame", action="store_true",
                        help="also run the reference and every set-up in the plate's frame "
                        "(static mesh, inletOutlet far field)")
    parser.add_argument("--no-baseline", action="store_true",
                        help="skip the run of openfoam.md's set-up (the machine-speed "
                        "baseline)")
    parser.add_argument("--max-courant", type=float, default=None,
                        help="max Co of the named set-ups instead of their own (their labels "
                        "end in -coX); the reference and the baseline keep theirs")
    parser.add_argument("--pitch-deg", type=float, default=PITCH_DEG,
                        help="pitch amplitude of the motion, deg (the H-type baseline's time "
                        "step is set by how fast it turns)")
    parser.add_argument("--yardstick-courant", type=courant_list, default=None,
                        help="also run the reference at this max Co (label reference-coX) "
                        "and measure every NRMSE against it (the medium mesh at max Co 4 "
                        "is not converged in time on every motion); several, comma "
                        "separated (4: the reference itself): against the mean of those "
                        "runs, with their own distance from it (the time-step band)")
    parser.add_argument("--yardstick", type=_checked_label, default=None,
                        help="measure every NRMSE against this run (SETUP[@MESH][-coX]) "
                        "instead of the medium mesh, e.g. openfoam_md@openfoam_md_medium, "
                        "the medium H-type mesh of openfoam.md's cost table")
    parser.add_argument("--yardstick-floor", action="store_true",
                        help="also rerun each of the yardstick's runs other than the reference "
                        "with the other pressure solver and print how far it moves: the "
                        "yardstick's own round-off floor (the reference's is always run)")
    parser.add_argument("--window", type=time_window, default=None,
                        help="also compare the forces over this time window, START:END in s, "
                        "e.g. 0.25:0.55 (the first stroke, before the shed vortex passes the "
                        "plate: openfoam.md's \"early-cycle forces\")")
    parser.add_argument("--workers", type=int, default=2,
                        help="runs at a time (one core each; default 2, this machine's cores)")
    parser.add_argument("--figure", default=None,
                        help="draw cost against accuracy of every run into this image file")
    parser.add_argument("--histories", default=None,
                        help="draw F_n and M over time of the yardstick, the medium mesh, "
                        "openfoam.md's set-up and the named set-ups into this image file")
    parser.add_argument("--output", default=None,
                        help="write every run's CPU and NRMSE, with the command line and "
                        "settings, into this HDF5 file")
    parser.add_argument("--work-dir", default=None,
                        help="folder of the cases (default: a new temporary folder); runs "
                        "that finished there before are read, not rerun")
    return parser


def parsed_arguments(argv: list[str] | None = None) -> argparse.Namespace:
    """The command line, checked: an impossible combination exits with the reason."""
    parser = argument_parser()
    args = parser.parse_args(argv)
    if args.workers < 1:
        parser.error(f"--workers must be >= 1, got {args.workers}")
    if args.yardstick and args.yardstick_courant:
        parser.error("--yardstick and --yardstick-courant name two yardsticks: give one")
    if args.window is not None and args.window[1] > args.cycles:
        parser.error(f"--window ends at {args.window[1]:g} s, after the {args.cycles:g} s "
                     "simulated")
    return args


def settings_stamp(args: argparse.Namespace) -> str:
    """What every run of a work folder shares: the motion, the cycles simulated, the far
    field, the k-epsilon convection and, when asked, the wall treatment."""
    own = "each set-up's own"
    # said only when asked, so that the folders of earlier commands keep their stamps
    wall = "" if args.wall_treatment is None else f"; wall treatment {args.wall_treatment}"
    return (f"motion {benchmark_motion(args.pitch_deg)!r}; cycles {args.cycles!r}; far field "
            f"{args.far_field or own}; k-epsilon convection "
            f"{args.turbulence_convection or own}{wall}\n")


def claim_work_dir(root: str | Path, said: str) -> None:
    """Stamp the work folder with ``said`` (:func:`settings_stamp`), so that its finished runs
    are read instead of rerun only by a command of the same settings.

    Raises
    ------
    SystemExit
        When the folder holds runs of other settings; naming the stamp file and what it says.
    """
    Path(root).mkdir(parents=True, exist_ok=True)
    stamp = Path(root) / "benchmark_settings.txt"
    if stamp.is_file() and stamp.read_text() != said:
        raise SystemExit(f"{root} holds runs of other settings ({stamp}: "
                         f"{stamp.read_text().strip()}); use another --work-dir")
    stamp.write_text(said)


@dataclass
class RunPlan:
    """The runs one command asks for, and what each is for."""

    #: every run, the longest first
    jobs: list[Job]
    #: labels of the yardstick's runs (several: the yardstick is their mean)
    members: list[str]
    #: the named set-ups' labels, and each one's rerun with the other pressure solver
    named: list[str]
    floors: dict[str, str]
    #: each yardstick run's rerun with the other pressure solver (--yardstick-floor)
    yardstick_floors: dict[str, str]
    #: labels also run in the plate's frame (--plate-frame), as ``<label>-plate``
    moving: set[str]


def plan_runs(args: argparse.Namespace, root: str | Path | None = None) -> RunPlan:
    """The runs of a command: the reference and its reruns, the yardstick's runs, the
    baseline, the named set-ups with their reruns, the named meshes and the plate's-frame
    variants, each label once, the longest first.

    With --no-solver-floor a named set-up's rerun with the other pressure solver is left out
    unless it finished before in the work folder ``root``: then it costs nothing and is read,
    so that the set-up is still judged by both solvers.
    """
    ref = setup("reference")
    reference = Job("reference", ref.mesh, ref.solver)
    jobs = [reference, reference.variant("PCG", pressure_solver="PCG")]
    if not args.no_time_step_floor:
        jobs.append(reference.variant("co3", max_courant=3.0))
    members, yardstick_floors = [], {}
    chosen = [labelled_job(args.yardstick)] if args.yardstick else None
    for member in chosen or yardstick_jobs(reference, args.yardstick_courant):
        members.append(member.label)
        if member.label not in {j.label for j in jobs}:  # the reference or its max Co 3 run
            jobs.append(member)
        if args.yardstick_floor and member.label != reference.label:  # reference-PCG runs
            floor = other_solver(member)
            yardstick_floors[member.label] = floor.label
            jobs.append(floor)
    if not args.no_baseline:
        base_setup = setup(BASELINE)
        jobs.append(Job(BASELINE, base_setup.mesh, base_setup.solver))
    floors, named = {}, []
    for label in args.setups:
        job = labelled_job(label, args.max_courant)
        if job.label in {j.label for j in jobs}:  # the reference, its max Co 3 run or the yardstick
            continue
        named.append(job.label)
        jobs.append(job)
        floor = other_solver(job)
        if not args.no_solver_floor or (root is not None
                                        and ran_to_end(Path(root) / floor.label)):
            floors[job.label] = floor.label
            jobs.append(floor)
    specs = mesh_specs()
    jobs += [Job(f"{m}-mesh", specs[m], ref.solver)
             for m in (s.strip() for s in args.meshes.split(",")) if m]
    if args.far_field:
        jobs = [j.with_solver(far_field=args.far_field) for j in jobs]
    if args.turbulence_convection:
        jobs = [j.with_solver(turbulence_convection=args.turbulence_convection) for j in jobs]
    if args.wall_treatment:
        jobs = [j.with_solver(wall_treatment=args.wall_treatment) for j in jobs]
    moving = {"reference", *named} if args.plate_frame else set()
    jobs += [j.variant("plate", frame="plate", far_field="inletOutlet")
             for j in jobs if j.label in moving]
    # the longest runs first (cells times steps, which go as 1 / max Co), so that the workers
    # finish together
    jobs.sort(key=lambda j: -j.mesh.n_cells / j.solver.max_courant)
    return RunPlan(jobs, members, named, floors, yardstick_floors, moving)


def yardstick_of(results: dict[str, SetupRun], plan: RunPlan,
                 courants: list[float] | None, cycles: float
                 ) -> tuple[SetupRun, tuple[float, float] | None]:
    """The yardstick every run is measured against, and the time-step band when it is the
    mean of several runs of the medium mesh (--yardstick-courant with several max Co).

    Raises
    ------
    SystemExit
        When the reference or a run of the yardstick failed.
    """
    for needed in ("reference", *plan.members):
        if not results[needed].ok:
            raise SystemExit(f"the {needed} run failed: {results[needed].failure}")
    members = [results[m] for m in plan.members]
    if len(members) == 1:
        return members[0], None
    said = ", ".join(f"{c:g}" for c in courants)
    mean = ensemble_mean(members, f"mean of max Co {said}")
    return mean, time_step_band(members, mean, cycles)


def print_report(results: dict[str, SetupRun], plan: RunPlan, yardstick: SetupRun,
                 yardstick_is: str, band: tuple[float, float] | None, cells: dict[str, int],
                 cycles: float, window: tuple[float, float] | None) -> None:
    """Print every run's cost and distance from the yardstick, the floors, the time-step band,
    the plate's-frame comparisons, the machine's speed against openfoam.md's and the verdict
    on each named set-up."""
    members, named, floors = plan.members, plan.named, plan.floors
    yardstick_floors, moving = plan.yardstick_floors, plan.moving
    yardstick_label = yardstick.label
    base = results["reference"]
    baseline = results.get(BASELINE)
    have_baseline = baseline is not None and baseline.ok
    scale = (OPENFOAM_MD_US_PER_CELL_STEP / baseline.cpu_per_cell_step_us if have_baseline
             else float("nan"))
    width = max(len(label) for label in results)
    print(f"{'set-up':{width}s}  cells  CPU per cycle  / reference  / openfoam.md set-up  at "
          f"openfoam.md's speed   NRMSE against {yardstick_is}")
    for label, res in results.items():
        if not res.ok:
            print(f"{label:{width}s} {cells[label]:6d}   failed: {res.failure}")
            continue
        errors = compare(res, yardstick, cycles, window)
        cpu = res.cpu_per_cycle_s
        to_baseline = cpu / baseline.cpu_per_cycle_s if have_baseline else float("nan")
        print(f"{label:{width}s} {cells[label]:6d} {cpu:10.1f} s   "
              f"{cpu / base.cpu_per_cycle_s:7.3f}   {to_baseline:12.3f}   "
              f"{cpu * scale:14.1f} s   {errors}")
    for rerun, meaning in (("reference-PCG", "the floor: the same mesh, another linear "
                            "solver"),
                           ("reference-co3", "the medium mesh's own time-step uncertainty, "
                            "max Co 3 instead of 4")):
        if rerun in results and results[rerun].ok:
            print(f"{rerun} against reference ({meaning}): "
                  f"{compare(results[rerun], base, cycles, window)}")
    for member, rerun in yardstick_floors.items():
        if results[rerun].ok:
            print(f"round-off floor of the yardstick's {member} ({rerun} against {member}): "
                  f"{compare(results[rerun], results[member], cycles, window)}")
    if band is not None:
        print(f"the medium mesh's time-step band (each run against the {yardstick_label}):")
        for member in members:
            print(f"  {member}: {compare(results[member], yardstick, cycles, window)}")
    for name, rerun in floors.items():
        if not (results[name].ok and results[rerun].ok):
            continue
        print(f"solver floor of {name} ({rerun} against {name}): "
              f"{compare(results[rerun], results[name], cycles, window)}")
    for name in moving:
        plate = results.get(f"{name}-plate")
        if plate is None or not (plate.ok and results[name].ok):
            continue
        ratio = plate.cpu_per_cycle_s / results[name].cpu_per_cycle_s
        print(f"plate's frame of {name} ({name}-plate against {name}): CPU "
              f"{ratio:.3f}x, {compare(plate, results[name], cycles, window)}")
    if have_baseline:
        print(f"This machine: the set-up of shared/design/openfoam.md took "
              f"{baseline.cpu_per_cycle_s:.1f} s "
              f"per cycle ({baseline.steps_per_cycle:.0f} time steps; that file: "
              f"{OPENFOAM_MD_CPU_PER_CYCLE_S:.0f} s, about {OPENFOAM_MD_STEPS_PER_CYCLE}) and "
              f"{baseline.cpu_per_cell_step_us:.2f} µs CPU per cell and time step (that file: "
              f"{OPENFOAM_MD_US_PER_CELL_STEP:.2f} µs), so CPU at openfoam.md's speed is CPU "
              f"here x {scale:.2f}.")
    else:
        print("The set-up of shared/design/openfoam.md did not run (--no-baseline or failed): "
              "no ratio to it and no CPU at that file's speed.")
    print(f"Target: <= {TARGET_CPU_PER_CYCLE_S:.0f} s per cycle at openfoam.md's speed (<= "
          f"{TARGET_RATIO:.3f} of its set-up's CPU on the same motion and machine) with F_n "
          f"and M within {TARGET_NRMSE_PERCENT:g} % NRMSE of {yardstick_is} in the first "
          "cycle:")
    for name in named:
        if results[name].ok:
            twin = results.get(floors.get(name, ""))
            said_of = verdict(results[name], yardstick, baseline, scale, cycles, band, twin,
                              window)
            print(f"  {name}: {said_of}")


def main(argv: list[str] | None = None) -> None:
    """Run (or read) the runs of the command line, print the report and write what it asks
    for: the HDF5 study, the cost-accuracy figure, the force histories."""
    args = parsed_arguments(argv)
    cycles = args.cycles
    window = args.window
    root = args.work_dir or tempfile.mkdtemp(prefix="mfflap-cfd-cost-")
    pitch = args.pitch_deg
    said = settings_stamp(args)
    claim_work_dir(root, said)
    plan = plan_runs(args, root)
    jobs = plan.jobs
    run = partial(run_setup, cycles=cycles, root=root, pitch_deg=pitch)
    print(f"{len(jobs)} runs in {root}, {args.workers} at a time: "
          f"{', '.join(j.label for j in jobs)}", file=sys.stderr, flush=True)
    with ProcessPoolExecutor(args.workers) as pool:
        finished = collect({pool.submit(run, job): job.label for job in jobs}, root, cycles)
    results = {j.label: finished[j.label] for j in jobs}
    yardstick, band = yardstick_of(results, plan, args.yardstick_courant, cycles)
    # what the yardstick is: the medium mesh (one or several of its time steps) or --yardstick
    yardstick_is = (f"{yardstick.label}, the --yardstick" if args.yardstick
                    else f"{yardstick.label}, the medium mesh")
    print(f"f = 1 Hz, h = 0.3 m, theta = {pitch:g} deg, U = 0.3 m/s; {cycles:g} cycles; "
          f"cases in {root}")
    cells = {j.label: j.mesh.n_cells for j in jobs}
    print_report(results, plan, yardstick, yardstick_is, band, cells, cycles, window)
    baseline = results.get(BASELINE)
    study = Study(results, yardstick, cycles, plan.named, plan.floors, cells, baseline, band,
                  said.strip(), window)
    if args.output:
        # the command as typed; called with argv (a test, another script), that argv
        command = sys.argv if argv is None else ["benchmarks/cfd_cost.py", *argv]
        write_study(study, args.output, command)
        print(f"wrote {args.output}")
    if args.figure:
        cost_accuracy_figure(study, args.figure,
                             f"f = 1 Hz, h = 0.3 m, pitch {pitch:g} deg, {cycles:g} "
                             f"cycle{'' if cycles == 1 else 's'}")
        print(f"wrote {args.figure}")
    if args.histories:
        force_histories_figure(study, args.histories,
                               f"f = 1 Hz, h = 0.3 m, pitch {pitch:g} deg: F_n and M against "
                               f"{yardstick.label} (black)")
        print(f"wrote {args.histories}")


if __name__ == "__main__":
    main()
