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


def motion_mismatch(case_dir: str | Path, state) -> str | None:
    """How the motion an mfflap OpenFOAM case was written for differs from a record's, or
    None if they agree (or the case keeps no motion samples: not written by mfflap).

    The case keeps samples of its imposed heave and pitch (mfflap_case.toml,
    :mod:`mfflap.cfd.case_inputs`); those within the record's time span are compared with
    the record's kinematics, to 1 % of their amplitude. A flow field of another run would
    show the vorticity of a motion the record never had.

    Parameters
    ----------
    case_dir
        The OpenFOAM case folder.
    state
        The record's :class:`~mfflap.kinematics.state.KinematicState`.
    """
    from mfflap.toml_io import read_toml

    kept_path = Path(case_dir) / "mfflap_case.toml"
    kept = read_toml(kept_path) if kept_path.is_file() else {}
    if "motion_sample_time_s" not in kept:
        return None
    times = np.asarray(kept["motion_sample_time_s"], dtype=float)
    inside = (times >= state.time[0]) & (times <= state.time[-1])
    if not inside.any():
        return (f"it was written for t = {times[0]:g}-{times[-1]:g} s, outside the record's "
                f"{state.time[0]:g}-{state.time[-1]:g} s")
    for key, name, unit, recorded in (
            ("motion_sample_heave_m", "heave", "m", state.heave_position),
            ("motion_sample_pitch_rad", "pitch", "rad", state.pitch_angle)):
        case_values = np.asarray(kept[key], dtype=float)[inside]
        record_values = np.interp(times[inside], state.time, recorded)
        scale = max(float(np.max(np.abs(record_values))), float(np.max(np.abs(case_values))))
        worst = int(np.argmax(np.abs(case_values - record_values)))
        if abs(case_values[worst] - record_values[worst]) > 0.01 * scale + 1e-9:
            return (f"it was written for another motion: its {name} at t = "
                    f"{times[inside][worst]:.4g} s is {case_values[worst]:.4g} {unit}, the "
                    f"record's {record_values[worst]:.4g} {unit}")
    return None


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
