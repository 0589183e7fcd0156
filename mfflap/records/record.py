"""CFD records: one HDF5 file per finished CFD run (kinematics, loads, raw forces, provenance).

A record is self-contained: the imposed kinematics and the forces on the same time base,
so identification, back-tests and gap diagnosis need nothing else. Records are written to a
temporary name and renamed into place, so a run killed at any moment leaves either a whole
record or none.

Layout::

    /                 attrs: kind = "cfd_record", schema version, mfflap version
    /inputs           attrs: config_toml (the case parameters as TOML)
    /kinematics       imposed KinematicState (SI units)
    /loads            body-frame F_n, F_t, M about the moving pivot, whole span
    /raw              case-frame total force and moment about CofR, per mesh depth
    /parameters       attrs: the motion's parameters (e.g. frequency, heave_amplitude, ...)
    /provenance       attrs: solver, version, mesh, cells, solver settings, CPU time, ...
    /cycle_scatter    attrs: the scatter of its cycle means (mfflap.records.cycle_scatter)
    /refinement/mesh, /refinement/time_step
                      attrs: how its answer moves when refined (mfflap.records.refinement)
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from mfflap.errors import MfflapError, UnreadableRecordError
from mfflap.hydro.loads import Loads
from mfflap.kinematics.state import KINEMATIC_UNITS, KinematicState
from mfflap.metrics import nrmse
from mfflap.records.refinement import RefinementChange, read_refinement, write_refinement
from mfflap.results import ResultsFile
from mfflap.toml_io import dumps

RECORD_SUFFIX = ".h5"
#: a record whose run lost its numerics, kept aside when its case is rerun
#: (:func:`mfflap.campaign.execute.run_campaign`); not a record of the folder
LOST_SUFFIX = ".lost.h5"
#: a record that cannot be read (cut short by a copy, a full disk), kept aside when its case
#: is run again (:func:`mfflap.campaign.execute.run_campaign`); not a record of the folder
UNREADABLE_SUFFIX = ".unreadable.h5"
#: a record whose run a retry resumed part-way within the identified window (two set-ups
#: fitted as one), kept aside when its case is rerun as one set-up
#: (:mod:`mfflap.records.mixed_set_up`); not a record of the folder
MIXED_SUFFIX = ".mixed.h5"
_STATE_KEYS = tuple(KINEMATIC_UNITS)


@dataclass
class CfdRecord:
    """The result of one CFD run.

    Attributes
    ----------
    name : str
        Case identifier (file stem).
    state : KinematicState
        Imposed kinematics on the force time base.
    loads : Loads
        CFD loads (body frame, whole span, moment about the pivot).
    parameters : dict
        Parameters of the motion (``kind`` plus e.g. ``frequency`` Hz, ``heave_amplitude`` m,
        ``phase_deg``, ``pitch_ramp_rate_deg``, ``duration`` s, ``ramp_time`` s).
    provenance : dict
        Solver, version, mesh, number of cells, solver settings, CPU time s, ...
    raw_force, raw_moment : ndarray (n, 3) or None
        Case-frame total force N and moment N*m about CofR per mesh depth, as written.
    refinement : dict of str to RefinementChange
        How its answer moves when its mesh (``"mesh"``) or time step (``"time_step"``) is
        refined, where a refined run of its motion exists (:mod:`mfflap.records.refinement`).
    """

    name: str
    state: KinematicState
    loads: Loads
    parameters: dict[str, Any]
    provenance: dict[str, Any] = field(default_factory=dict)
    raw_force: np.ndarray | None = None
    raw_moment: np.ndarray | None = None
    refinement: dict[str, RefinementChange] = field(default_factory=dict)

    @property
    def time(self) -> np.ndarray:
        """Sample times, s."""
        return self.loads.time

    @property
    def period(self) -> float:
        """The motion's period, s: its ``period`` parameter, else 1 / ``frequency``; NaN
        when it gives neither."""
        if "period" in self.parameters:
            return float(self.parameters["period"])
        return 1.0 / float(self.parameters.get("frequency", float("nan")))

    def last_periods(self, periods: float) -> tuple[float, float]:
        """The motion's :attr:`period`, s, and the time its last ``periods`` periods start
        at, s.

        Raises
        ------
        MfflapError
            Naming the record: it gives neither a period nor a frequency, or it is shorter
            than ``periods`` periods.
        """
        period = self.period
        if not (np.isfinite(period) and period > 0):
            raise MfflapError(f"record {self.name} names no period nor frequency: its "
                              f"parameters are {sorted(self.parameters)}")
        start = float(self.time[-1]) - periods * period
        if start < 0:
            raise MfflapError(f"record {self.name} runs {self.time[-1]:.3g} s, shorter than "
                              f"the {periods:g} periods of {period:.3g} s compared")
        return period, start

    def repeat_nrmse(self) -> float:
        """CFD's own repeat of F_n: the NRMSE of its last :attr:`period` against the period
        before (over the last period's range), the closest a model that repeats each cycle
        can come to it.

        Examples
        --------
        >>> t = np.linspace(0.0, 2.0, 201)
        >>> state = KinematicState(t, *(np.zeros_like(t) for _ in range(6)))
        >>> f_n = np.sin(2 * np.pi * t)
        >>> run = CfdRecord("run", state, Loads(t, f_n, 0 * t, 0 * t), {"period": 1.0})
        >>> round(run.repeat_nrmse(), 12)
        0.0
        """
        t = np.asarray(self.time, dtype=float)
        period, f_n = self.period, self.loads.normal_force
        last = t >= t[-1] - period
        return float(nrmse(np.interp(t[last] - period, t, f_n), f_n[last]))

    def window(self, start_time: float) -> CfdRecord:
        """The record from ``start_time`` s on (drops a start-up transient)."""
        keep = self.time >= start_time
        if keep.sum() < 4:
            raise MfflapError(f"record {self.name}: fewer than 4 samples after t = "
                              f"{start_time} s (it ends at {self.time[-1]:.4g} s)")
        s = self.state
        state = KinematicState(**{k: getattr(s, k)[..., keep] for k in ("time", *_STATE_KEYS)})
        ld = self.loads
        loads = Loads(ld.time[keep], ld.normal_force[keep], ld.tangential_force[keep],
                      ld.moment[keep], source=ld.source)
        return CfdRecord(self.name, state, loads, dict(self.parameters), dict(self.provenance),
                         None if self.raw_force is None else self.raw_force[keep],
                         None if self.raw_moment is None else self.raw_moment[keep],
                         dict(self.refinement))


def _clean_attrs(mapping: Mapping[str, Any]) -> dict[str, Any]:
    out = {}
    for k, v in mapping.items():
        if v is None:
            continue
        out[k] = v if isinstance(v, (int, float, str, bool, np.number)) else str(v)
    return out


def _single(record: CfdRecord) -> CfdRecord:
    """The record with every array but time in float32 (compact fixtures)."""
    def f32(a):
        return None if a is None else np.asarray(a, dtype=np.float32)

    s, ld = record.state, record.loads
    state = KinematicState(time=s.time, **{k: f32(getattr(s, k)) for k in _STATE_KEYS})
    loads = Loads(ld.time, f32(ld.normal_force), f32(ld.tangential_force), f32(ld.moment),
                  source=ld.source)
    return CfdRecord(record.name, state, loads, record.parameters, record.provenance,
                     f32(record.raw_force), f32(record.raw_moment), record.refinement)


def write_record(path: str | Path, record: CfdRecord, single_precision: bool = False) -> Path:
    """Write ``record`` whole or not at all (:class:`~mfflap.results.ResultsFile` writes
    beside ``path`` and puts the file in its place when complete); return the path.

    ``single_precision`` stores everything but time as float32 (about half the size; the
    forces' own noise is far above float32 resolution), for the fixtures that ship.
    """
    path = Path(path)
    if single_precision:
        record = _single(record)
        record.provenance = {**record.provenance, "storage": "float32"}
    toml = dumps({"parameters": _clean_attrs(record.parameters)})
    with ResultsFile(path, "w", kind="cfd_record", config_toml=toml) as rf:
        rf.write_state("kinematics", record.state)
        rf.write_loads("loads", record.loads)
        if record.raw_force is not None:
            raw = {"force": record.raw_force}
            units = {"force": "N"}
            if record.raw_moment is not None:
                raw["moment"] = record.raw_moment
                units["moment"] = "N*m"
            rf.write_group("raw", raw, units,
                           {"frame": "case (x stream, y heave)", "per": "mesh depth"})
        rf.h5.create_group("parameters").attrs.update(_clean_attrs(record.parameters))
        rf.h5.create_group("provenance").attrs.update(_clean_attrs(record.provenance))
        for change in record.refinement.values():
            write_refinement(rf.h5, change)
        rf.h5.attrs["name"] = record.name
    return path


def _attr(v: Any) -> Any:
    if isinstance(v, bytes):
        return v.decode()
    if isinstance(v, np.generic):
        return v.item()
    return v


def read_record(path: str | Path) -> CfdRecord:
    """Read a record written by :func:`write_record`.

    Raises
    ------
    MfflapError
        If the file is not a CFD record, or its loads are not finite or not on the
        kinematics' time base (the message names the file).
    UnreadableRecordError
        If a dataset's bytes cannot be read (a damaged compressed chunk, a file cut short).
    """
    path = Path(path)
    with ResultsFile(path, "r", kinds=("cfd_record",)) as rf:
        try:
            return _read_record(rf, path)
        except (KeyError, TypeError) as err:  # a group, dataset or field missing
            raise MfflapError(f"{path}: not a complete CFD record ({err})") from err
        except (OSError, RuntimeError) as err:  # h5py opened the file, but a chunk will
            # not decompress or a link cannot be followed (a file damaged mid-write)
            raise UnreadableRecordError(f"its data cannot be read ({err})",
                                        path=str(path)) from err


def read_record_parameters(path: str | Path) -> dict[str, Any]:
    """The parameters of a record written by :func:`write_record` (its motion's, e.g.
    ``period``), without reading its histories: what a look-up over many records checks
    first.

    Raises
    ------
    MfflapError
        If the file is not a CFD record or has no parameters (the message names the file).
    """
    path = Path(path)
    with ResultsFile(path, "r", kinds=("cfd_record",)) as rf:
        try:
            if "parameters" not in rf.h5:
                raise MfflapError(f"{path}: not a complete CFD record (no parameters)")
            return {k: _attr(v) for k, v in rf.h5["parameters"].attrs.items()}
        except (OSError, RuntimeError) as err:
            raise UnreadableRecordError(f"its parameters cannot be read ({err})",
                                        path=str(path), dataset="parameters") from err


def _read_record(rf: ResultsFile, path: Path) -> CfdRecord:
    """The record in an open results file of kind ``cfd_record``."""
    state = rf.read_state("kinematics")
    state = KinematicState(**{k: np.asarray(getattr(state, k), dtype=float)
                              for k in ("time", *_STATE_KEYS)})
    loads = rf.read_loads("loads")
    loads = Loads(loads.time, *(np.asarray(getattr(loads, k), dtype=float) for k in
                                ("normal_force", "tangential_force", "moment")),
                  source=loads.source)
    raw_force = raw_moment = None
    if "raw" in rf.h5:
        raw_force = rf.h5["raw/force"][()]
        raw_moment = rf.h5["raw/moment"][()] if "moment" in rf.h5["raw"] else None
    params = {k: _attr(v) for k, v in rf.h5["parameters"].attrs.items()}
    prov = {k: _attr(v) for k, v in rf.h5["provenance"].attrs.items()}
    name = str(_attr(rf.h5.attrs.get("name", path.stem)))
    t = loads.time
    if t.shape != state.time.shape or not np.allclose(t, state.time):
        raise MfflapError(f"{path}: loads and kinematics are on different time bases")
    if np.any(np.diff(t) <= 0):
        i = int(np.argmin(np.diff(t)))
        raise MfflapError(f"{path}: time is not increasing at sample {i + 1} (t = {t[i + 1]})")
    for key in ("normal_force", "tangential_force", "moment"):
        bad = ~np.isfinite(getattr(loads, key))
        if bad.any():
            i = int(np.argmax(bad))
            raise MfflapError(f"{path}: loads/{key} is not finite at sample {i} (t = {t[i]})")
    return CfdRecord(name, state, loads, params, prov, raw_force, raw_moment,
                     read_refinement(rf.h5))


def read_records(folder: str | Path) -> list[CfdRecord]:
    """Every record in ``folder`` (sorted by name; hidden files and records kept aside as
    lost or unreadable left out); an unreadable one raises naming its file."""
    folder = Path(folder)
    if not folder.is_dir():
        raise MfflapError(f"{folder}: no such fixture folder")
    return [read_record(p) for p in record_paths(folder)]


def record_paths(folder: str | Path) -> list[Path]:
    """The record files of ``folder``, sorted by name (see :func:`read_records`)."""
    return [p for p in sorted(Path(folder).glob(f"*{RECORD_SUFFIX}"))
            if not p.name.startswith(".")
            and not p.name.endswith((LOST_SUFFIX, UNREADABLE_SUFFIX, MIXED_SUFFIX))]


def fixtures_root() -> Path:
    """The folder of the shipped record sets: the installed ``mfflap-data`` distribution's,
    else the one beside the package in a clone of the repository
    (``data/mfflap_data/fixtures``).

    Raises
    ------
    MfflapError
        If neither is there, saying how to install the records.
    """
    try:
        import mfflap_data  # the records' own distribution, a separate install

        return mfflap_data.fixtures_root()
    except ImportError:
        pass
    beside = Path(__file__).resolve().parents[2] / "data" / "mfflap_data" / "fixtures"
    if beside.is_dir():
        return beside
    raise MfflapError("the shipped CFD records are not installed: they are the mfflap-data "
                      "distribution (pip install ./data from a clone of mfflap)")


def fixture_dir(name: str) -> Path:
    """A shipped record set (``<fixtures_root>/<name>``, :func:`fixtures_root`)."""
    return fixtures_root() / name


#: The shipped record sets identification uses by default: the paper's whole Table 1 grid
#: (125 pitch-ramp motions, 3 periods each) and the harmonic set (36 motions pitching at up
#: to 16 rad/s, as optimised motions do), both on the ``table1`` CFD set-up, as window
#: means of 100 samples a period (:mod:`mfflap.records.reduce`; the full records are the
#: repository's ``campaigns/table1_full`` and ``campaigns/harmonic_set``).
IDENTIFICATION_FIXTURES = ("table1_grid", "harmonic_set")


def identification_fixture_dirs() -> tuple[Path, ...]:
    """The shipped record sets identification uses by default
    (:data:`IDENTIFICATION_FIXTURES`)."""
    return tuple(fixture_dir(name) for name in IDENTIFICATION_FIXTURES)


#: The shipped back-test fixture folders: the optimised motions of the main job as the
#: shipped case file runs it, and as it ran with the 43-case identification (main_job), of
#: the shipped case with its own coefficients (backtest), kept within the identification
#: data (within_data), of the later rounds of
#: CFD in the loop and of rounds with the output correction (filtered, with round 1's model
#: kept, in a trust region, in a trust region with slopes, the same with the phase fixed;
#: each record named by its motion's key).
BACKTEST_FIXTURES = ("backtest_main_job", "backtest_polish_bandwidth", "backtest",
                     "backtest_within_data", "backtest_rounds",
                     "backtest_corrected", "backtest_filtered", "backtest_fixed_model",
                     "backtest_trust_region", "backtest_first_order",
                     "backtest_first_order_fixed_phase")


def backtest_fixture_dirs() -> list[Path]:
    """The shipped back-test fixture folders (:data:`BACKTEST_FIXTURES`)."""
    return [fixture_dir(name) for name in BACKTEST_FIXTURES]


def compact_folder(folder: str | Path) -> list[Path]:
    """Rewrite every full-precision record of ``folder`` in single precision (fixtures)."""
    done = []
    for path in record_paths(folder):
        rec = read_record(path)
        if rec.provenance.get("storage") == "float32":
            continue
        write_record(path, rec, single_precision=True)
        done.append(path)
    return done
