"""Mesh and time-step convergence: the same motion on several meshes and Courant limits.

Every run is an OpenFOAM case under one folder, resumed if stopped and kept as a record
(``<mesh>_co<Co>.h5``) once finished, so the study resumes where it stopped. The reference is
the finest mesh at the first Courant limit; the time-step study repeats the first mesh at each
further limit. NRMSE is computed on the reference's time base after the start-up ramp, like
the paper's mesh study (0.26 % between its chosen and finest meshes); each run's numerical
bursts (:mod:`mfflap.records.bursts`) are listed beside it, not bridged: a study compares runs
as they are, so a burst counts against the run that has it. With three meshes or
more, the finest three also give the grid convergence index (:mod:`mfflap.cfd.gci`) of the
cycle's mean thrust and input power, peak normal force and RMS moment. For a periodic motion
whose runs hold two or more whole periods after the start, the same pairs are also compared by
their mean cycles (:mod:`mfflap.cfd.phase_average`), beside each run's cycle-to-cycle scatter.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from mfflap.cfd.case_inputs import kept_differences, kept_wall_treatment, solver_keys
from mfflap.cfd.gci import GridConvergence, grid_convergence
from mfflap.cfd.imposed_motion import check_end_time, check_ramp_time, imposed_state
from mfflap.cfd.openfoam.run_motion import run_motion
from mfflap.cfd.openfoam.setups import CfdSetup
from mfflap.cfd.openfoam.writer import SolverSettings, resolve_mesh
from mfflap.cfd.openfoam.yplus import (
    YPlusHistory,
    read_y_plus,
    wall_function_note,
    y_plus_summary,
)
from mfflap.cfd.phase_average import phase_average, whole_periods
from mfflap.errors import ConfigError
from mfflap.hydro.loads import LOAD_COMPONENTS
from mfflap.kinematics.continuous import Motion
from mfflap.metrics import nrmse, time_mean
from mfflap.parameters import Fluid, FreeStream, Plate
from mfflap.performance import thrust_and_power
from mfflap.records.bursts import find_load_bursts
from mfflap.records.inputs import input_mismatches
from mfflap.records.record import CfdRecord, read_record, write_record

COMPONENTS = LOAD_COMPONENTS


@dataclass
class ConvergenceRun:
    """One run of the study."""

    label: str
    mesh: str
    max_courant: float
    record: CfdRecord
    y_plus: YPlusHistory | None = None


@dataclass
class ConvergenceStudy:
    """All runs, the reference, the NRMSE of each against it and the grid convergence index.

    ``gci`` maps each quantity of :func:`integral_quantities` to its
    :class:`~mfflap.cfd.gci.GridConvergence` over the three finest meshes at the first Courant
    limit (empty with fewer than three meshes); ``gci_meshes`` names those runs.

    ``phase_nrmse`` holds, for the same pairs as ``nrmse``, the NRMSE between the two runs'
    mean cycles over ``phase_cycles`` whole periods, and ``cycle_scatter`` each run's
    cycle-to-cycle scatter (:attr:`~mfflap.cfd.phase_average.PhaseAverage.scatter`) per
    component; both empty unless the motion is periodic and every run holds two or more
    whole periods after the start of the comparison.
    """

    runs: list[ConvergenceRun]
    reference: str
    nrmse: dict[str, dict[str, float]] = field(default_factory=dict)
    pairs: dict[str, tuple[str, str]] = field(default_factory=dict)
    gci: dict[str, GridConvergence] = field(default_factory=dict)
    gci_meshes: tuple[str, ...] = ()
    phase_nrmse: dict[str, dict[str, float]] = field(default_factory=dict)
    phase_cycles: int = 0
    cycle_scatter: dict[str, dict[str, float]] = field(default_factory=dict)

    def as_dict(self) -> dict:
        """JSON-friendly summary."""
        return {"reference": self.reference, "nrmse": self.nrmse,
                "pairs": {k: list(v) for k, v in self.pairs.items()},
                "gci_meshes": list(self.gci_meshes),
                "gci": {k: v.as_dict() for k, v in self.gci.items()},
                "phase_cycles": self.phase_cycles, "phase_nrmse": self.phase_nrmse,
                "cycle_scatter": self.cycle_scatter,
                "runs": {r.label: {"mesh": r.mesh, "max_courant": r.max_courant,
                                   "n_cells": r.record.provenance.get("n_cells"),
                                   "cpu_time_s": r.record.provenance.get("cpu_time_s"),
                                   "epsilon_clipped_step_fraction": _clipped_fraction(r.record),
                                   "numerical_bursts": [b.describe() for b in
                                                        find_load_bursts(r.record.loads)],
                                   **_y_plus_keys(r)}
                         for r in self.runs}}


def _y_plus_keys(run: ConvergenceRun) -> dict[str, float | str | None]:
    """A run's mean and largest y+ on the plate and what they mean for its wall treatment
    (all None for a run without y+ output)."""
    if run.y_plus is None:
        return {"y_plus_mean": None, "y_plus_max": None, "wall_function_note": None}
    summary = y_plus_summary(run.y_plus)
    return {"y_plus_mean": summary["y_plus_mean"], "y_plus_max": summary["y_plus_max"],
            "wall_function_note": wall_function_note(
                summary, kept_wall_treatment(run.record.provenance) or "log_law")}


def _clipped_fraction(record: CfdRecord) -> float | None:
    """Fraction of time steps after which OpenFOAM clipped negative epsilon (None for
    records written before the count was kept)."""
    clipped = record.provenance.get("n_steps_bounding_epsilon")
    steps = record.provenance.get("n_time_steps")
    return None if clipped is None or not steps else float(clipped) / float(steps)


def compare(a: CfdRecord, b: CfdRecord, start: float) -> dict[str, float]:
    """NRMSE of ``a`` against ``b`` per load component on b's time base after ``start``."""
    t = b.time[(b.time >= start) & (b.time <= min(a.time[-1], b.time[-1]))]
    out = {}
    for k in COMPONENTS:
        ref = np.interp(t, b.time, getattr(b.loads, k))
        val = np.interp(t, a.time, getattr(a.loads, k))
        out[k] = float(nrmse(val, ref))
    return out


def integral_quantities(record: CfdRecord, start: float,
                        end: float | None = None) -> dict[str, float]:
    """Scalars of a run over ``[start, end]`` that a mesh study extrapolates.

    Returns
    -------
    dict
        ``mean_thrust_N`` and ``mean_input_power_W`` (time means), ``peak_normal_force_N``
        (max |F_n|) and ``rms_moment_Nm``.
    """
    t = record.time
    end = t[-1] if end is None else end
    keep = (t >= start) & (t <= end)
    if np.count_nonzero(keep) < 2:
        raise ConfigError(f"{record.name}: fewer than two samples in [{start}, {end}] s",
                          key="compare_from")
    thrust, power = thrust_and_power(record.loads, record.state)
    tk = t[keep]
    return {"mean_thrust_N": time_mean(tk, thrust[keep]),
            "mean_input_power_W": time_mean(tk, power[keep]),
            "peak_normal_force_N": float(np.max(np.abs(record.loads.normal_force[keep]))),
            "rms_moment_Nm": float(np.sqrt(time_mean(tk, record.loads.moment[keep] ** 2)))}


def mesh_gci(records: Sequence[CfdRecord], start: float,
             end: float | None = None) -> dict[str, GridConvergence]:
    """Grid convergence index of each :func:`integral_quantities` over three meshes' runs.

    The window ends at ``end`` or where the shortest run ends; cell counts are read from each
    record's provenance (``n_cells``).
    """
    if len(records) != 3:
        raise ConfigError(f"a grid convergence index needs three meshes, got {len(records)}",
                          key="meshes")
    end = min(r.time[-1] for r in records) if end is None else end
    cells = [int(r.provenance["n_cells"]) for r in records]
    scalars = [integral_quantities(r, start, end) for r in records]
    return {k: grid_convergence([s[k] for s in scalars], cells) for k in scalars[0]}


def _check_resumed(path: Path, record: CfdRecord, settings: SolverSettings,
                   end_time: float, motion: Motion, ramp_time: float, plate: Plate | None,
                   fluid: Fluid | None, stream: FreeStream | None) -> None:
    """Refuse a finished run of an earlier study that this one would compare as its own:
    another duration, solver setting, plate, fluid, stream or motion."""
    if abs(record.time[-1] - end_time) > 0.02 * end_time:
        raise ConfigError(f"this run ends at {record.time[-1]:.4g} s, the study at "
                          f"{end_time:.4g} s (another --cycles?); use another output folder, "
                          f"or delete the record to rerun it", source=str(path), key="cycles")
    asked = solver_keys(settings, leave_out=("write_interval",))
    for key, stored, value in kept_differences(record.provenance, asked)[:1]:
        key = key.removeprefix("solver_")
        raise ConfigError(f"this run was made with {key} = {stored!r}, the study asks for "
                          f"{value!r}; use another output folder, or delete the record to "
                          "rerun it", source=str(path), key=key)
    mismatches = input_mismatches(record, plate or Plate(), fluid or Fluid(),
                                  stream or FreeStream())
    if mismatches:
        m = mismatches[0]
        raise ConfigError(f"this run was made for {m.key} = {m.record_value:g}, the study asks "
                          f"for {m.case_value:g}; use another output folder, or delete the "
                          "record to rerun it", source=str(path), key=m.key)
    asked = imposed_state(motion, record.time, ramp_time)
    for name, unit, made, wanted in (
            ("heave", "m", record.state.heave_position, asked.heave_position),
            ("pitch", "rad", record.state.pitch_angle, asked.pitch_angle)):
        scale = max(float(np.max(np.abs(wanted))), float(np.max(np.abs(made))), 1e-12)
        bad = np.flatnonzero(np.abs(made - wanted) > 1e-6 * scale)
        if bad.size:
            i = int(bad[0])
            raise ConfigError(f"this run imposed another motion (another --motion-table, "
                              f"pitch, heave, frequency or --ramp-time?): at t = "
                              f"{record.time[i]:.6g} s its {name} is {made[i]:.6g} {unit}, the "
                              f"study's {wanted[i]:.6g} {unit}; use another output folder, or "
                              "delete the record to rerun it", source=str(path), key="motion")


def run_convergence(out_dir: str | Path, motion: Motion, end_time: float, *,
                    meshes: Sequence[str] = ("coarse", "medium", "fine"),
                    courants: Sequence[float] = (4.0, 2.0), ramp_time: float = 0.0,
                    compare_from: float | None = None, plate=None, fluid=None, stream=None,
                    timeout_s: float = 6 * 3600.0, n_procs: int = 1,
                    solver: SolverSettings | None = None, floor: bool = False,
                    setups: Sequence[CfdSetup] = (), time_step_mesh: str | None = None,
                    period: float | None = None, phase_from: float | None = None,
                    progress: Callable[[str], None] | None = None) -> ConvergenceStudy:
    """Run (or resume) every mesh at ``courants[0]`` and one mesh at the other limits.

    Parameters
    ----------
    solver
        Base solver settings (pressure solver, correctors, far field, k and epsilon
        convection, wall treatment); the Courant limit is the study's.
    floor
        Also rerun the reference with the other pressure solver (PCG <-> GAMG, both converged
        to the same tolerance): the NRMSE between the two is the floor under every mesh
        comparison, since they differ only by round-off in the linear solves. A flow whose
        later cycles are sensitive to round-off shows it here. Each set-up is rerun with its
        other pressure solver too, at its own tolerances (``setup_<name>_<solver>``): a
        set-up's distance from the reference means little where its own floor is as large
        (PISO with LUST convection amplifies round-off to up to about 2 % NRMSE within one
        cycle of the paper's motion).
    time_step_mesh
        The mesh of ``meshes`` repeated at the further Courant limits (default the first,
        the cheapest; the finest tells whether the reference itself is time-step converged).
    setups
        Named set-ups (setups.toml) run as well, each with its own mesh and solver settings
        but the study's far field, k and epsilon convection and wall treatment
        (``setup_<name>``), and
        compared with the reference.
    period
        The motion's period, s, if it is periodic (not for a pitch ramp): with two or more
        whole periods after the start of the comparison in every run, the pairs are also
        compared by their mean cycles (:func:`compare_mean_cycles`).
    phase_from
        Start of the first cycle averaged, s (default: the first multiple of the period after
        the first cycle and the start of the comparison, so that the start-up cycle is left
        out; a three-period run then gives two cycles).
    """
    base = solver or SolverSettings()
    out = Path(out_dir)
    dt_mesh = meshes[0] if time_step_mesh is None else time_step_mesh
    if dt_mesh not in meshes:
        raise ConfigError(f"the time-step mesh {dt_mesh!r} is not one of the study's meshes "
                          f"({', '.join(meshes)})", key="time_step_mesh")
    if period is not None and not period > 0:
        raise ConfigError(f"the period must be > 0 s, got {period!r}", key="period")
    check_ramp_time(ramp_time, check_end_time(end_time))  # before any run starts
    if phase_from is not None and not 0 <= phase_from < end_time:
        raise ConfigError(f"the mean cycles would start at {phase_from!r} s, outside the run "
                          f"(0-{end_time:.6g} s)", key="phase_from")
    reference = f"{meshes[-1]}_co{courants[0]:g}"
    # (label, mesh, solver settings without the time-step limit, Courant limit)
    plan = [(f"{m}_co{courants[0]:g}", m, base, courants[0]) for m in meshes] + [
        (f"{dt_mesh}_co{c:g}", dt_mesh, base, c) for c in courants[1:]]
    floor_of: dict[str, str] = {}  # round-off floor run -> the run it repeats

    def add_floor(label: str, mesh: str, settings: SolverSettings, co: float) -> None:
        other = "GAMG" if settings.pressure_solver == "PCG" else "PCG"
        floor_of[f"{label}_{other}"] = label
        plan.append((f"{label}_{other}", mesh, replace(settings, pressure_solver=other), co))

    if floor:
        add_floor(reference, meshes[-1], base, courants[0])
    for s in setups:  # each with its own mesh and solver, in the study's far field,
        # turbulence convection and wall treatment
        if s.solver.frame == "plate" and base.far_field != "inletOutlet":
            raise ConfigError(f"set-up {s.name!r} runs in the plate's frame, which needs the "
                              f"inletOutlet far field; the study's is {base.far_field} "
                              "(cfd.far_field = \"inletOutlet\")", key="far_field")
        settings = replace(s.solver, far_field=base.far_field,
                           turbulence_convection=base.turbulence_convection,
                           wall_treatment=base.wall_treatment)
        plan.append((f"setup_{s.name}", s.mesh, settings, s.solver.max_courant))
        if floor:
            add_floor(f"setup_{s.name}", s.mesh, settings, s.solver.max_courant)
    labels = [label for label, *_ in plan]
    twice = sorted({label for label in labels if labels.count(label) > 1})
    if twice:
        raise ConfigError(f"the study would run {', '.join(twice)} twice: name each mesh and "
                          "Courant limit once", key="meshes/courants")
    # every mesh and setting checked before the first run starts: none is lost to a typo
    plan = [(label, mesh, replace(settings, max_courant=co, write_interval=end_time / 4), co)
            for label, mesh, settings, co in plan]
    mesh_names = {label: resolve_mesh(mesh).name for label, mesh, _, _ in plan}
    runs = []
    for label, mesh, settings, co in plan:
        path = out / f"{label}.h5"
        case_dir = out / "cases" / label
        mesh_name = mesh_names[label]
        if path.exists():
            record = read_record(path)
            _check_resumed(path, record, settings, end_time, motion, ramp_time, plate, fluid,
                           stream)
            if progress:
                progress(f"{label}: already finished")
        else:
            if progress:
                progress(f"{label}: running OpenFOAM")
            run_progress = None if progress is None else (
                lambda message, label=label: progress(f"{label}: {message}"))
            record = run_motion(case_dir, motion, label, {"mesh": mesh_name, "max_courant": co,
                                                          "pressure_solver":
                                                              settings.pressure_solver},
                                end_time, mesh=mesh, ramp_time=ramp_time, solver=settings,
                                plate=plate, fluid=fluid, stream=stream, timeout_s=timeout_s,
                                y_plus=True, n_procs=n_procs, progress=run_progress)
            write_record(path, record)
            if progress:
                progress(f"{label}: {record.provenance.get('cpu_time_s', 0):.0f} s CPU")
        y_plus = read_y_plus(case_dir) if (case_dir / "postProcessing" / "yPlus").is_dir() \
            else None
        runs.append(ConvergenceRun(label, mesh_name, co, record, y_plus))
    by_label = {r.label: r for r in runs}
    start = compare_from if compare_from is not None else max(ramp_time, 0.1 * end_time)
    study = ConvergenceStudy(runs, reference)
    for r in runs:
        if r.label in floor_of:
            repeated = floor_of[r.label]
            key = f"{r.label} vs {repeated} (round-off floor)"
            study.nrmse[key] = compare(r.record, by_label[repeated].record, start)
            study.pairs[key] = (r.label, repeated)
        elif r.label != reference:
            study.nrmse[f"{r.label} vs {reference}"] = compare(r.record,
                                                               by_label[reference].record,
                                                               start)
            study.pairs[f"{r.label} vs {reference}"] = (r.label, reference)
    first = f"{dt_mesh}_co{courants[0]:g}"
    for co in courants[1:]:
        fine_dt = f"{dt_mesh}_co{co:g}"
        study.nrmse[f"{first} vs {fine_dt}"] = compare(by_label[first].record,
                                                       by_label[fine_dt].record, start)
        study.pairs[f"{first} vs {fine_dt}"] = (first, fine_dt)
    if period is not None:
        if phase_from is None:
            phase_from = period * max(1, int(np.ceil(start / period - 1e-9)))
        compare_mean_cycles(study, period, phase_from)
    if len(meshes) >= 3:
        finest = [f"{m}_co{courants[0]:g}" for m in meshes[-3:]]
        study.gci = mesh_gci([by_label[k].record for k in finest], start)
        study.gci_meshes = tuple(finest)
    return study


def compare_mean_cycles(study: ConvergenceStudy, period: float, start: float) -> None:
    """Fill ``study.phase_nrmse``, ``phase_cycles`` and ``cycle_scatter`` when every run holds
    two or more whole periods from ``start`` (the same number from each run); else leave them
    empty."""
    n = min(whole_periods(start, r.record.time[-1], period) for r in study.runs)
    if n < 2:
        return
    means = {}
    for r in study.runs:
        averages = {k: phase_average(r.record.time, getattr(r.record.loads, k), period, start,
                                     n_cycles=n) for k in COMPONENTS}
        means[r.label] = {k: a.mean for k, a in averages.items()}
        study.cycle_scatter[r.label] = {k: a.scatter for k, a in averages.items()}
    study.phase_cycles = n
    for key, (a, b) in study.pairs.items():
        study.phase_nrmse[key] = {k: float(nrmse(means[a][k], means[b][k]))
                                  for k in COMPONENTS}


def convergence_figure(study: ConvergenceStudy):
    """F_n over time per run, and y+ (min, mean, max) over time like the paper's Fig. 2c."""
    # matplotlib takes about a second to load: only figures need it
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (a, b) = plt.subplots(1, 2, figsize=(11, 3.8))
    for r in study.runs:
        a.plot(r.record.time, r.record.loads.normal_force, lw=1, label=r.label)
        if r.y_plus is not None:
            line = b.plot(r.y_plus.time, r.y_plus.average, lw=1.2, label=f"{r.label} mean")[0]
            b.fill_between(r.y_plus.time, r.y_plus.minimum, r.y_plus.maximum, alpha=0.15,
                           color=line.get_color())
    a.set_xlabel("t [s]")
    a.set_ylabel("F_n [N]")
    a.legend(fontsize=7)
    b.set_xlabel("t [s]")
    b.set_ylabel("y+ on the plate (band: min-max)")
    b.legend(fontsize=7)
    fig.tight_layout()
    return fig
