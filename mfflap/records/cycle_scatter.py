"""A CFD record's own statistical uncertainty: the scatter of its cycle means.

Each whole period of a record after its start-up ramp gives a mean thrust, a mean input
power and an RMS normal force; the spread of these over the periods is the part of the
record's uncertainty that one run shows by itself (the wake each cycle meets, the solver's
iterations), beside the mesh and time-step parts that need other runs
(:mod:`mfflap.cfd.gci`). For a motion that repeats (``kind = "harmonic"``) the spread is
that uncertainty; for the Table 1 grid's pitch ramp (``kind = "ramp_harmonic"``) the
cycles differ by the ramp as well, so the spread is an upper bound and says so
(``repeats = False``).

Stored in every campaign record as the attributes of its ``/cycle_scatter`` group (written
when the campaign finishes the record; ``mfflap campaign scatter FOLDER`` adds it to older
records and lists it).
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from pathlib import Path

import h5py
import numpy as np

from mfflap.errors import MfflapError
from mfflap.performance import thrust_and_power
from mfflap.records.record import CfdRecord, read_record, record_paths
from mfflap.results import edited_results

#: the group of a record that holds its cycle scatter
GROUP = "cycle_scatter"
#: samples per period on which each period's means are taken (CFD's time steps vary)
SAMPLES_PER_PERIOD = 200


@dataclass(frozen=True)
class CycleScatter:
    """The means of a record's whole periods after its start-up, and their scatter.

    Attributes
    ----------
    n_cycles : int
        The whole periods used, counted back from the record's end: those after the
        start-up ramp, less the first of them when at least two others remain (it still
        carries the start-up's wake: on the shipped back-tests its RMS F_n is up to 1.7x
        the later periods', as the back-tests leave it out too).
    repeats : bool
        Whether the motion repeats from period to period (false for a pitch ramp, whose
        scatter includes the ramp's change).
    mean_thrust_n, mean_power_w, rms_normal_force_n : float
        The means over those periods of each period's mean thrust (N), mean input power (W)
        and RMS F_n (N).
    thrust_scatter_n, power_scatter_w, rms_normal_force_scatter_n : float
        Their sample standard deviations over the periods (NaN with a single period).
    """

    n_cycles: int
    repeats: bool
    mean_thrust_n: float
    mean_power_w: float
    rms_normal_force_n: float
    thrust_scatter_n: float
    power_scatter_w: float
    rms_normal_force_scatter_n: float

    def relative(self, name: str) -> float:
        """The scatter of ``name`` ("thrust", "power" or "rms_normal_force") as a fraction of
        its mean's magnitude.

        Examples
        --------
        >>> s = CycleScatter(3, True, 2.0, -4.0, 10.0, 0.1, 0.4, 0.5)
        >>> s.relative("power"), s.relative("rms_normal_force")
        (0.1, 0.05)
        """
        fields = {"thrust": ("mean_thrust_n", "thrust_scatter_n"),
                  "power": ("mean_power_w", "power_scatter_w"),
                  "rms_normal_force": ("rms_normal_force_n", "rms_normal_force_scatter_n")}
        if name not in fields:
            raise KeyError(f"no cycle scatter of {name!r}: one of {sorted(fields)}")
        mean, scatter = (getattr(self, f) for f in fields[name])
        return float(abs(scatter / mean)) if mean != 0 else float("nan")


def cycle_scatter(record: CfdRecord) -> CycleScatter | None:
    """The scatter of ``record``'s cycle means, or None when it has no period (its
    parameters' ``period`` s or ``frequency`` Hz) or no whole period after its start-up ramp
    (``parameters["ramp_time"]``).

    Examples
    --------
    >>> from mfflap.hydro.loads import Loads
    >>> from mfflap.kinematics.continuous import HarmonicMotion
    >>> t = np.linspace(0.0, 4.0, 801)
    >>> state = HarmonicMotion(1.0, 0.1, 0.3).sample(t)
    >>> fn = np.sin(2 * np.pi * t) * (1 + 0.05 * np.floor(t))  # each period 5 % larger
    >>> record = CfdRecord("c", state, Loads(t, fn, 0 * t, 0 * t),
    ...                    {"kind": "harmonic", "frequency": 1.0, "ramp_time": 0.25})
    >>> s = cycle_scatter(record)
    >>> s.n_cycles, s.repeats, round(s.relative("rms_normal_force"), 3)
    (2, True, 0.031)
    """
    period = record.period
    if not (np.isfinite(period) and period > 0):
        return None
    t = np.asarray(record.time, dtype=float)
    start = max(float(record.parameters.get("ramp_time", 0.0)), float(t[0]))
    n_cycles = int(np.floor((t[-1] - start) / period + 1e-9))
    if n_cycles < 1:
        return None
    if n_cycles >= 3:  # the first period after the ramp still carries the start-up's wake
        n_cycles -= 1
    thrust, power = thrust_and_power(record.loads, record.state)
    first = t[-1] - n_cycles * period
    phase = (np.arange(SAMPLES_PER_PERIOD) + 0.5) * period / SAMPLES_PER_PERIOD
    per_cycle = np.empty((3, n_cycles))
    for k in range(n_cycles):
        at = first + k * period + phase
        per_cycle[0, k] = np.interp(at, t, thrust).mean()
        per_cycle[1, k] = np.interp(at, t, power).mean()
        per_cycle[2, k] = np.sqrt(np.mean(np.interp(at, t, record.loads.normal_force) ** 2))
    means = per_cycle.mean(axis=1)
    scatter = per_cycle.std(axis=1, ddof=1) if n_cycles > 1 else np.full(3, np.nan)
    return CycleScatter(n_cycles, record.parameters.get("kind") != "ramp_harmonic",
                        *(float(v) for v in means), *(float(v) for v in scatter))


def write_cycle_scatter(h5: h5py.File, scatter: CycleScatter | None) -> None:
    """Store ``scatter`` as the attributes of the record's :data:`GROUP` (replaced if there);
    nothing for None."""
    if GROUP in h5:
        del h5[GROUP]
    if scatter is not None:
        group = h5.create_group(GROUP)
        group.attrs.update(asdict(scatter))
        group.attrs["units"] = "N, W, N (thrust, input power, RMS normal force)"


def read_cycle_scatter(path: str | Path) -> CycleScatter | None:
    """The cycle scatter stored in the record at ``path``, or None if it has none."""
    with h5py.File(path, "r") as h5:
        if GROUP not in h5:
            return None
        attrs = h5[GROUP].attrs
        fields = CycleScatter.__dataclass_fields__
        return CycleScatter(**{k: (bool(attrs[k]) if k == "repeats" else
                                   int(attrs[k]) if k == "n_cycles" else float(attrs[k]))
                               for k in fields})


def add_cycle_scatter(path: str | Path, record: CfdRecord | None = None
                      ) -> CycleScatter | None:
    """Compute the record's cycle scatter and store it in the record (``record``: the
    record the file holds, if the caller has it, so that it is not read again). The record
    is rewritten whole (:func:`mfflap.results.edited_results`): a kill during the write
    leaves it as it was.

    Raises
    ------
    MfflapError
        If ``path`` is not a readable record (named in the message).
    """
    path = Path(path)
    scatter = cycle_scatter(read_record(path) if record is None else record)
    try:
        with edited_results(path) as h5:
            write_cycle_scatter(h5, scatter)
    except MfflapError as exc:
        raise MfflapError(f"{path}: cannot add the cycle scatter ({exc})") from exc
    return scatter


def folder_cycle_scatter(folder: str | Path) -> list[tuple[str, CycleScatter | None]]:
    """Every record of a campaign folder with its cycle scatter, added to the records that
    lack it (older records): (record name, scatter or None)."""
    out = []
    for path in record_paths(folder):
        scatter = read_cycle_scatter(path)
        if scatter is None:
            scatter = add_cycle_scatter(path)
        out.append((path.stem, scatter))
    return out


__all__ = ["GROUP", "CycleScatter", "add_cycle_scatter", "cycle_scatter",
           "folder_cycle_scatter", "read_cycle_scatter", "write_cycle_scatter"]
