"""OpenFOAM as a :class:`~mfflap.cfd.solver.CfdSolver`: a case folder written by mfflap
(:func:`~mfflap.cfd.openfoam.writer.write_case`), and the forces of any case, mfflap's or
not (:mod:`~mfflap.cfd.openfoam.foreign_case`)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from mfflap.cfd.openfoam.forces import read_forces
from mfflap.cfd.openfoam.foreign_case import read_foreign_case
from mfflap.cfd.openfoam.writer import SolverSettings, write_case
from mfflap.cfd.solver import RunForces
from mfflap.errors import ConfigError
from mfflap.kinematics.continuous import Motion
from mfflap.parameters import Fluid, FreeStream, Plate
from mfflap.toml_io import read_toml

#: what a case mfflap wrote keeps of what it was written for
KEPT_FILE = "mfflap_case.toml"


@dataclass(frozen=True)
class OpenFoam:
    """OpenFOAM: cases on ``mesh`` with ``solver``'s settings (the defaults when None).

    Examples
    --------
    >>> OpenFoam().name
    'openfoam'
    """

    mesh: str = "coarse"
    solver: SolverSettings | None = None
    name: str = "openfoam"

    def write_case(self, folder: str | Path, motion: Motion, end_time_s: float, *,
                   plate: Plate, fluid: Fluid, stream: FreeStream,
                   ramp_time_s: float = 0.0) -> Path:
        """An OpenFOAM case folder of ``motion``
        (:func:`~mfflap.cfd.openfoam.writer.write_case`)."""
        return write_case(folder, motion, end_time_s, mesh=self.mesh, plate=plate, fluid=fluid,
                          stream=stream, solver=self.solver, ramp_time=ramp_time_s)

    def read_forces(self, source: str | Path, *, depth_m: float | None = None,
                    motion_table: str | Path | None = None) -> RunForces:
        """The forces of a case folder: one mfflap wrote keeps its depth, frame and what it
        was written for; another is read from its own files (its motion from
        ``motion_table`` or its dynamicMeshDict, its depth from its mesh unless given)."""
        source = Path(source)
        kept = source / KEPT_FILE
        label = f"openfoam:{source}"
        if not kept.is_file():
            case = read_foreign_case(source, motion_table, depth_m)
            return RunForces(case.history, case.depth_m, "inertial", label, motion=case.motion,
                             motion_from=case.motion_from, pivot_m=case.pivot_m)
        if depth_m is not None:
            raise ConfigError(f"{source} keeps its depth ({KEPT_FILE}); leave out the depth",
                              key="depth")
        meta = read_toml(kept)
        return RunForces(read_forces(source), float(meta["depth"]),
                         str(meta.get("frame", "inertial")), label, kept, meta)


__all__ = ["KEPT_FILE", "OpenFoam"]
