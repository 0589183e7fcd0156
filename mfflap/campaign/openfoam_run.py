"""Run one motion in OpenFOAM and turn the finished case into a :class:`CfdRecord`."""

from __future__ import annotations

import re
import shutil
import time
from dataclasses import asdict
from pathlib import Path
from typing import Any

from mfflap.campaign.records import CfdRecord
from mfflap.cfd.openfoam.forces import read_forces
from mfflap.cfd.openfoam.loads import imposed_state, to_loads
from mfflap.cfd.openfoam.runner import is_time_folder, run_case
from mfflap.cfd.openfoam.solver_log import solver_provenance
from mfflap.cfd.openfoam.writer import MeshSpec, SolverSettings, write_case
from mfflap.errors import CfdRunError
from mfflap.kinematics.continuous import Motion
from mfflap.parameters import Fluid, FreeStream, Plate
from mfflap.toml_io import read_toml

_MAX_CO = re.compile(r"^(maxCo\s+)([0-9.eE+-]+)(;)", re.M)


def lower_courant_limit(case_dir: str | Path, factor: float = 0.5) -> float:
    """Halve ``maxCo`` in the case's controlDict; return the new limit."""
    path = Path(case_dir) / "system" / "controlDict"
    text = path.read_text()
    match = _MAX_CO.search(text)
    if match is None:
        raise CfdRunError("no maxCo entry in system/controlDict", case=str(case_dir))
    value = float(match.group(2)) * factor
    path.write_text(_MAX_CO.sub(lambda m: f"{m.group(1)}{value:g}{m.group(3)}", text, count=1))
    return value


_TURBULENCE_DIV = re.compile(r"^(\s*div\(phi,(?:k|epsilon)\)\s+)Gauss [^;]+;", re.M)


def use_upwind_turbulence(case_dir: str | Path) -> bool:
    """Switch k and epsilon convection to bounded first-order upwind (the most robust choice
    for a k-epsilon blow-up); True if the schemes changed."""
    path = Path(case_dir) / "system" / "fvSchemes"
    text = path.read_text()
    new = _TURBULENCE_DIV.sub(lambda m: f"{m.group(1)}Gauss upwind;", text)
    if new == text:
        return False
    path.write_text(new)
    return True


_FREESTREAM_U = re.compile(
    rb"type\s+freestreamVelocity;\s*freestreamValue(\s+uniform\s+\([^)]*\));")
_FREESTREAM_P = re.compile(rb"type\s+freestreamPressure;\s*freestreamValue\s+uniform\s+[^;]+;")


def use_inlet_outlet_far_field(case_dir: str | Path) -> bool:
    """Switch the far field from freestreamVelocity/freestreamPressure to inletOutlet
    velocity and a fixed pressure, in 0/ and in every written time folder, those of a
    decomposed case's processor folders too (ASCII or binary fields: only the dictionary text
    of the patch changes); True if anything changed.

    Where the whole mesh heaves several times faster than the stream (h = 0.5 m at
    f = 0.5 Hz, U = 0.3 m/s) the freestream pair let the velocity grow without bound in the
    outer cells along the heave path; restarted from the same fields with this far field
    the run went on with a normal time step.
    """
    changed = False
    case = Path(case_dir)
    for field, pattern, repl in (("U", _FREESTREAM_U, rb"type inletOutlet;\n        inletValue\1;"),
                                 ("p", _FREESTREAM_P, rb"type fixedValue;")):
        for path in [*case.glob(f"*/{field}"), *case.glob(f"processor*/*/{field}")]:
            if not is_time_folder(path.parent.name):
                continue
            data = path.read_bytes()
            new = pattern.sub(repl, data)
            if new != data:
                path.write_bytes(new)
                changed = True
    return changed


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
    for key, value in meta.items():
        if key.startswith("solver_"):
            prov[key] = value
    if plate is not None:
        prov["chord_m"] = plate.chord
    return CfdRecord(name, state, loads, parameters, prov, history.force, history.moment)


#: every retry of a case, one line each, across the calls that ran it
RETRY_LOG = "mfflap_retries.txt"


def run_motion(case_dir: str | Path, motion: Motion, name: str, parameters: dict[str, Any],
               end_time: float, *, mesh: str | MeshSpec = "coarse", ramp_time: float = 0.0,
               solver: SolverSettings | None = None, plate: Plate | None = None,
               fluid: Fluid | None = None, stream: FreeStream | None = None,
               timeout_s: float = 6 * 3600.0, y_plus: bool = False,
               n_procs: int = 1, max_retries: int = 3,
               min_time_step: float = 1e-7) -> CfdRecord:
    """Write (unless already written), run or resume, and parse one OpenFOAM case.

    Fields are written four times per run so that a killed run resumes from its last
    written time instead of from zero. A run whose time step collapses (an instability held
    at the Courant limit) is resumed from its last written time, up to ``max_retries``
    times: first with the inletOutlet far field (:func:`use_inlet_outlet_far_field`) if it
    had the freestream one, then with half the Courant limit, the last time also with
    first-order upwind convection of k and epsilon. The retries are recorded in the case
    (:data:`RETRY_LOG`) and in the record's provenance, those of earlier calls that resumed
    the same case included: the case's settings changed there, not in mfflap_case.toml.
    """
    case_dir = Path(case_dir)
    solver = solver or SolverSettings(write_interval=end_time / 4)
    if not (case_dir / "mfflap_case.toml").exists():
        tmp = case_dir.with_name(case_dir.name + ".writing")
        shutil.rmtree(tmp, ignore_errors=True)
        write_case(tmp, motion, end_time, mesh=mesh, plate=plate, fluid=fluid, stream=stream,
                   solver=solver, ramp_time=ramp_time, y_plus=y_plus)
        with open(tmp / "mfflap_case.toml", "a") as fh:
            for key, value in asdict(solver).items():
                fh.write(f"solver_{key} = {value!r}\n")
        shutil.rmtree(case_dir, ignore_errors=True)
        tmp.rename(case_dir)
    started = time.perf_counter()
    retries = []
    while True:
        try:
            run_case(case_dir, timeout_s=timeout_s, n_procs=n_procs,
                     min_time_step=min_time_step)
            break
        except CfdRunError as exc:
            if "time step collapsed" not in str(exc) or len(retries) >= max_retries:
                raise
            if not retries and use_inlet_outlet_far_field(case_dir):
                note = "the inletOutlet far field"
            else:
                note = f"maxCo {lower_courant_limit(case_dir):g}"
                if len(retries) == max_retries - 1 and use_upwind_turbulence(case_dir):
                    note += " and first-order upwind k and epsilon"
            retries.append(note)
            # kept in the case, so that a run resumed by a later call still records them
            with open(case_dir / RETRY_LOG, "a") as fh:
                fh.write(f"time step collapsed; resumed from the last written time with "
                         f"{note}\n")
    record = record_from_case(case_dir, motion, name, parameters, plate)
    if (case_dir / RETRY_LOG).is_file():
        record.provenance["retries"] = "; ".join(
            (case_dir / RETRY_LOG).read_text().splitlines())
    if record.time[-1] < 0.98 * end_time:
        raise CfdRunError(f"the run stopped at t = {record.time[-1]:.4g} s before endTime "
                          f"{end_time:.4g} s", case=str(case_dir))
    record.provenance["wall_time_this_session_s"] = time.perf_counter() - started
    return record
