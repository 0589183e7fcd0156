"""Fluent as a :class:`~mfflap.cfd.solver.CfdSolver`: a UDF and journal for any motion
(:func:`~mfflap.cfd.fluent.udf.write_fluent_case`), and the forces of a report file."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from mfflap.cfd.fluent.report import report_forces
from mfflap.cfd.fluent.udf import FLUENT_KEPT_FILE, write_fluent_case
from mfflap.cfd.solver import RunForces
from mfflap.kinematics.continuous import Motion
from mfflap.parameters import Fluid, FreeStream, Plate
from mfflap.toml_io import read_toml

#: the depth a Fluent 2D report's forces are for, m
FLUENT_DEPTH_M = 1.0
#: report columns of the x force, the y force and the z moment about the origin
FLUENT_COLUMNS = ("fx-plate", "fy-plate", "mz-plate")


@dataclass(frozen=True)
class Fluent:
    """Fluent: UDFs stepping ``time_step_s``, reports with ``columns``.

    Examples
    --------
    >>> Fluent().columns
    ('fx-plate', 'fy-plate', 'mz-plate')
    """

    time_step_s: float = 1e-3
    columns: tuple[str, str, str] = FLUENT_COLUMNS
    name: str = "fluent"

    def write_case(self, folder: str | Path, motion: Motion, end_time_s: float, *,
                   plate: Plate, fluid: Fluid, stream: FreeStream,
                   ramp_time_s: float = 0.0) -> Path:
        """The UDF, journal and kept inputs of ``motion`` in ``folder``."""
        return write_fluent_case(folder, motion, end_time_s, ramp_time=ramp_time_s,
                                 time_step=self.time_step_s, velocity=stream.velocity,
                                 plate=plate, fluid=fluid)

    def read_forces(self, source: str | Path, *, depth_m: float | None = None,
                    motion_table: str | Path | None = None) -> RunForces:
        """The forces of a report file (``depth_m``: default 1 m, Fluent 2D), with the
        mfflap_fluent.toml written beside it, if any; the motion is the case file's or
        ``motion_table``."""
        source = Path(source)
        kept = source.parent / FLUENT_KEPT_FILE
        meta = read_toml(kept) if kept.is_file() else None
        return RunForces(report_forces(source, *self.columns),
                         FLUENT_DEPTH_M if depth_m is None else depth_m, "inertial",
                         f"fluent:{source}", kept if kept.is_file() else None, meta,
                         pivot_m=(kept_pivot_m(meta), 0.0))


def kept_pivot_m(meta: dict | None) -> float:
    """The pivot's distance behind the leading edge a UDF was written for, m (0 where its
    mfflap_fluent.toml does not say, or there is none: the leading edge)."""
    if not meta:
        return 0.0
    fraction = float(meta.get("plate_pivot_chord_fraction", 0.0))
    return fraction * float(meta.get("plate_chord_m", 0.0))


__all__ = ["FLUENT_COLUMNS", "FLUENT_DEPTH_M", "Fluent"]
