"""The flow at the instants where the model misses most: vorticity from OpenFOAM fields,
read with pyvista's OpenFOAM reader, drawn with matplotlib (no render window needed)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pyvista as pv

from mfflap.errors import MfflapError


def _reader(case_dir: Path) -> pv.POpenFOAMReader:
    foam = case_dir / "case.foam"
    if not foam.exists():
        foam.write_text("")
    return pv.POpenFOAMReader(str(foam))


def written_times(case_dir: str | Path) -> list[float]:
    """Times at which fields were written (excluding 0)."""
    reader = _reader(Path(case_dir))
    return [t for t in reader.time_values if t > 0]


def vorticity_field(case_dir: str | Path, time: float) -> tuple[np.ndarray, np.ndarray, float]:
    """Cell centres (n, 2) and z-vorticity (n,) at the written time nearest ``time``.

    Raises
    ------
    MfflapError
        If the case has no written fields after t = 0.
    """
    case_dir = Path(case_dir)
    reader = _reader(case_dir)
    times = [t for t in reader.time_values if t > 0]
    if not times:
        raise MfflapError(f"{case_dir}: no fields written after t = 0 (set a write interval)")
    chosen = min(times, key=lambda t: abs(t - time))
    reader.set_active_time_value(chosen)
    reader.cell_to_point_creation = False
    mesh = reader.read()["internalMesh"]
    if "U" not in mesh.cell_data:
        raise MfflapError(f"{case_dir}: no velocity field U at t = {chosen}")
    grad = mesh.compute_derivative(scalars="U", vorticity=True, preference="cell")
    omega_z = np.asarray(grad.cell_data["vorticity"])[:, 2]
    centres = np.asarray(mesh.cell_centers().points)[:, :2]
    return centres, omega_z, float(chosen)


def vorticity_figure(case_dir: str | Path, time: float, chord: float, window_chords: float = 1.2,
                     title: str = ""):
    """z-vorticity around the plate at the written time nearest ``time``."""
    # matplotlib takes about a second to load: only figures need it
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.tri import Triangulation

    xy, w, chosen = vorticity_field(case_dir, time)
    near = np.max(np.abs(xy - np.median(xy[np.argsort(np.abs(w))[-50:]], axis=0)), axis=1)
    keep = near < window_chords * chord
    tri = Triangulation(xy[keep, 0], xy[keep, 1])
    lim = np.percentile(np.abs(w[keep]), 98) or 1.0
    fig, ax = plt.subplots(figsize=(6, 4))
    pc = ax.tripcolor(tri, w[keep], cmap="RdBu_r", vmin=-lim, vmax=lim, shading="gouraud")
    ax.set_aspect("equal")
    ax.set_xlabel("x [m] (stream)")
    ax.set_ylabel("y [m] (heave)")
    ax.set_title(title or f"z-vorticity at t = {chosen:.4g} s")
    fig.colorbar(pc, ax=ax, label="ω_z [1/s]")
    fig.tight_layout()
    return fig, chosen
