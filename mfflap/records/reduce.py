"""Compact copies of CFD records: window means on a uniform time base, single precision.

A solver writes its forces at every (adaptive) time step: 4,000-6,000 samples a period on
the campaigns' set-up. Identification, back-tests and the gap diagnosis compare the model
with CFD at about a hundred points a period, so a record kept for comparisons needs no
more. :func:`reduced_record` takes the mean of every history (kinematics and loads alike)
over consecutive windows of one hundredth of a period, the exact mean of the piecewise
linear signal the samples describe. A window mean is a linear filter, so it keeps the
relations between the kinematic histories (the mean of a rate is the change of its
position over the window) and attenuates a harmonic k of the motion by
``sinc(k / samples_per_period)`` (0.2 % at k = 10), while the solver's step-to-step noise
averages out rather than aliasing as point samples would. The raw case-frame forces are
left out: the full record keeps them.

:func:`reduce_folder` writes such a copy of every record of a folder, keeping each one's
parameters, provenance, inputs, cycle scatter and refinement groups.
"""

from __future__ import annotations

from pathlib import Path

import h5py
import numpy as np

from mfflap.errors import MfflapError
from mfflap.hydro.loads import Loads
from mfflap.kinematics.state import KINEMATIC_UNITS, KinematicState
from mfflap.records.record import CfdRecord, read_record, record_paths, write_record
from mfflap.results import edited_results

#: window means per period of a reduced record
SAMPLES_PER_PERIOD = 100
#: groups of a record copied unchanged into its reduced copy (its parameters, provenance,
#: inputs and refinement are part of the record, which
#: :func:`~mfflap.records.record.write_record` writes)
_KEPT_GROUPS = ("cycle_scatter",)


def window_means(time: np.ndarray, values: np.ndarray, edges: np.ndarray) -> np.ndarray:
    """The mean of the piecewise-linear signal ``values(time)`` over each window between
    consecutive ``edges`` (s), exactly.

    Examples
    --------
    >>> t = np.array([0.0, 1.0, 2.0])
    >>> window_means(t, np.array([0.0, 2.0, 0.0]), np.array([0.0, 1.0, 2.0]))
    array([1., 1.])
    """
    time = np.asarray(time, dtype=float)
    values = np.asarray(values, dtype=float)
    integral = np.concatenate([[0.0], np.cumsum(0.5 * (values[1:] + values[:-1])
                                                * np.diff(time))])
    # the integral up to each edge: whole steps, then the part of the step it falls in
    i = np.clip(np.searchsorted(time, edges, side="right") - 1, 0, len(time) - 2)
    dt = time[i + 1] - time[i]
    s = np.clip(edges - time[i], 0.0, dt)
    slope = (values[i + 1] - values[i]) / dt
    at_edges = integral[i] + s * (values[i] + 0.5 * slope * s)
    return np.diff(at_edges) / np.diff(edges)


def reduced_record(record: CfdRecord, samples_per_period: int = SAMPLES_PER_PERIOD
                   ) -> CfdRecord:
    """``record`` as window means over ``1 / samples_per_period`` of its period (whole
    windows from its first sample to its last, each mean at its window's centre), without
    its raw case-frame forces.

    Raises
    ------
    MfflapError
        Naming the record, if it gives no period, or already has fewer samples than the
        reduced copy would.

    Examples
    --------
    >>> t = np.linspace(0.0, 2.0, 4001)
    >>> zero = np.zeros_like(t)
    >>> state = KinematicState(t, np.sin(2 * np.pi * t), *(zero for _ in range(5)))
    >>> run = CfdRecord("run", state, Loads(t, np.cos(2 * np.pi * t), zero, zero),
    ...                 {"frequency": 1.0})
    >>> small = reduced_record(run)
    >>> len(small.time), round(float(small.time[0]), 6)
    (200, 0.005)
    >>> bool(np.allclose(small.loads.normal_force, np.cos(2 * np.pi * small.time), atol=2e-4))
    True
    """
    period = record.period
    if not (np.isfinite(period) and period > 0):
        raise MfflapError(f"record {record.name}: no period nor frequency to reduce it by "
                          f"(its parameters are {sorted(record.parameters)})")
    t = np.asarray(record.time, dtype=float)
    n = max(1, round((t[-1] - t[0]) * samples_per_period / period))
    if n >= len(t):
        raise MfflapError(f"record {record.name}: {len(t)} samples, no more than the {n} of "
                          f"its reduced copy")
    edges = np.linspace(t[0], t[-1], n + 1)
    centres = 0.5 * (edges[1:] + edges[:-1])
    state = record.state
    kinematics = {k: window_means(t, getattr(state, k), edges) for k in KINEMATIC_UNITS}
    loads = record.loads
    forces = [window_means(t, getattr(loads, k), edges)
              for k in ("normal_force", "tangential_force", "moment")]
    provenance = {**record.provenance, "reduced_from_samples": len(t),
                  "reduced_to_samples_per_period": samples_per_period}
    return CfdRecord(record.name, KinematicState(centres, **kinematics),
                     Loads(centres, *forces, source=loads.source), dict(record.parameters),
                     provenance, refinement=dict(record.refinement))


def reduce_folder(source: str | Path, destination: str | Path,
                  samples_per_period: int = SAMPLES_PER_PERIOD) -> list[Path]:
    """Write the reduced copy (:func:`reduced_record`, single precision) of every record of
    ``source`` into ``destination`` under the same name, with its cycle scatter and
    refinement groups; return the paths written. The campaign's ``campaign.toml`` is copied
    too, so the copy says what was run.

    Raises
    ------
    MfflapError
        If ``source`` holds no record, or naming a record that cannot be reduced.
    """
    source, destination = Path(source), Path(destination)
    paths = record_paths(source)
    if not paths:
        raise MfflapError(f"{source}: no CFD record to reduce")
    destination.mkdir(parents=True, exist_ok=True)
    written = []
    for path in paths:
        out = destination / path.name
        write_record(out, reduced_record(read_record(path), samples_per_period),
                     single_precision=True)
        with h5py.File(path, "r") as full, edited_results(out) as small:
            for group in _KEPT_GROUPS:
                if group in full:
                    full.copy(full[group], small, name=group)
        written.append(out)
    campaign_file = source / "campaign.toml"
    if campaign_file.is_file():
        (destination / "campaign.toml").write_text(campaign_file.read_text())
    return written
