"""What mfflap asks of a CFD solver, whichever it is: write a case that imposes a motion,
and read a run's forces with what says how to turn them into the plate's loads.

OpenFOAM (:class:`mfflap.cfd.openfoam.solver.OpenFoam`) and Fluent
(:class:`mfflap.cfd.fluent.solver.Fluent`) each implement :class:`CfdSolver`; the comparison
with the model (:mod:`mfflap.cfd.model_comparison`) reads either through it.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any, Protocol

from mfflap.cfd.force_history import ForceHistory
from mfflap.kinematics.continuous import Motion
from mfflap.parameters import Fluid, FreeStream, Plate


@dataclass(frozen=True)
class RunForces:
    """A run's forces and what turns them into the plate's loads.

    Attributes
    ----------
    history : ForceHistory
        Total force and moment in the case's axes, per the depth below.
    depth_m : float
        The depth the forces are for, m.
    frame : str
        "inertial" (the mesh moves with the plate) or "plate" (a static mesh in its frame).
    label : str
        ``<solver>:<source>``, the loads' source.
    kept : Path or None
        The file keeping what the run was written for (mfflap_case.toml,
        mfflap_fluent.toml), None where there is none.
    written_for : dict or None
        Its contents.
    motion : Motion or None
        The motion the run imposed, where the run says it without a case file (a case mfflap
        did not write); else None, and the case file's or the kept table's is used.
    motion_from : str or None
        Where that motion was read from.
    pivot_m : tuple of float
        The pivot at rest in the case's axes, m.
    """

    history: ForceHistory
    depth_m: float
    frame: str
    label: str
    kept: Path | None = None
    written_for: dict[str, Any] | None = None
    motion: Motion | None = None
    motion_from: str | None = None
    pivot_m: tuple[float, float] = (0.0, 0.0)


class CfdSolver(Protocol):
    """A CFD solver as mfflap uses it.

    Examples
    --------
    >>> from mfflap.cfd.openfoam.solver import OpenFoam
    >>> from mfflap.cfd.fluent.solver import Fluent
    >>> [s.name for s in (OpenFoam(), Fluent())]
    ['openfoam', 'fluent']
    """

    name: str

    def write_case(self, folder: str | Path, motion: Motion, end_time_s: float, *,
                   plate: Plate, fluid: Fluid, stream: FreeStream,
                   ramp_time_s: float = 0.0) -> Path:
        """Write what the solver needs to run ``motion`` to ``end_time_s`` into ``folder``."""
        ...

    def read_forces(self, source: str | Path, *, depth_m: float | None = None,
                    motion_table: str | Path | None = None) -> RunForces:
        """A run's forces (``depth_m``, ``motion_table``: what the run does not say)."""
        ...


__all__ = ["CfdSolver", "RunForces"]
