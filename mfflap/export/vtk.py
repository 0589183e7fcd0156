"""The plate's motion as a VTK time series for ParaView (pyvista writes the .vtp files).

One PolyData surface (chord x span quad, split in strips) per time step with point data
(pitch angle, heave, thrust, input power), and a ``.pvd`` collection that ParaView opens as
a time series. Coordinates are the CFD case frame (x along the stream, y heave, z span),
not the model's (X0 heave, Y0 stream), so that a motion opens on top of a CFD result; each
file names its frame in its field data (``frame``, :data:`FRAME`).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pyvista as pv

from mfflap.cfd.frames import case_displacement
from mfflap.kinematics.discrete import DiscreteMotion
from mfflap.performance import evaluate_discrete

#: the frame of the exported coordinates, as each file's field data names it
FRAME = "CFD case: x along the stream, y heave, z span (m)"


def plate_surface(chord: float, span: float, pitch_angle: float, heave: float,
                  n_strips: int = 10, pivot_m: float = 0.0) -> pv.PolyData:
    """The plate at one instant: its pivot (``pivot_m`` behind the leading edge) at
    (0, heave), rotated about it by the pitch angle."""
    xs = np.linspace(-pivot_m, chord - pivot_m, n_strips + 1)
    zs = np.array([-span / 2, span / 2])
    x, z = np.meshgrid(xs, zs, indexing="ij")
    c, s = np.cos(pitch_angle), np.sin(pitch_angle)
    # rotation about z (anticlockwise positive, as tabulated6DoFMotion's rz)
    disp = case_displacement(np.array([heave]))[0]
    px = c * x + disp[0]
    py = s * x + disp[1]
    points = np.column_stack([px.ravel(), py.ravel(), z.ravel()])
    faces = []
    for i in range(n_strips):
        a, b = 2 * i, 2 * (i + 1)
        faces += [4, a, b, b + 1, a + 1]
    return pv.PolyData(points, np.array(faces))


def export_motion(folder: str | Path, motion: DiscreteMotion, model, scheme: str = "paper",
                  name: str = "plate", n_frames: int | None = None) -> Path:
    """Write ``<folder>/<name>_NNNN.vtp`` over one full cycle and ``<name>.pvd``."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    t, pitch, heave = motion.full_cycle_positions()
    ev = evaluate_discrete(model, motion, scheme)  # type: ignore[arg-type]
    thrust = np.concatenate([ev.thrust, ev.thrust])
    power = np.concatenate([ev.input_power, ev.input_power])
    idx = np.arange(len(t)) if n_frames is None else np.unique(
        np.linspace(0, len(t) - 1, n_frames).round().astype(int))
    entries = []
    for k, i in enumerate(idx):
        surf = plate_surface(model.plate.chord, model.plate.span, float(pitch[i]),
                             float(heave[i]), pivot_m=model.plate.pivot_m)
        for key, value in (("pitch_angle_rad", pitch[i]), ("heave_m", heave[i]),
                           ("thrust_N", thrust[i]), ("input_power_W", power[i])):
            surf.point_data[key] = np.full(surf.n_points, float(np.real(value)))
        surf.field_data["frame"] = [FRAME]
        fname = f"{name}_{k:04d}.vtp"
        surf.save(folder / fname)
        entries.append(f'    <DataSet timestep="{float(t[i]):.9g}" file="{fname}"/>')
    pvd = folder / f"{name}.pvd"
    pvd.write_text('<?xml version="1.0"?>\n<VTKFile type="Collection" version="0.1">\n'
                   "  <Collection>\n" + "\n".join(entries) + "\n  </Collection>\n</VTKFile>\n")
    return pvd
