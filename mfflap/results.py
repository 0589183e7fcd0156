"""Results in HDF5: a schema version, SI units on every dataset, inputs stored beside them.

Layout of a results file::

    /                       attrs: mfflap_schema_version, mfflap_version, created_utc, kind,
                            mfflap_checksum_sha256 (everything else the file holds)
    /inputs                 attrs: config_toml (the full input configuration as TOML text)
    /<group>/<dataset>      attrs: units, description; arrays carry HDF5's Fletcher-32

A file is written beside its place and renamed into it when complete
(:mod:`mfflap.atomic_write`); its checksum is checked whenever it is opened for reading, so
a flipped bit is an error naming the file, never a wrong number.

:func:`write_group` / :func:`read_group` store flat dicts of arrays; the typed helpers below
store the package's objects and read them back into the same objects.
"""

from __future__ import annotations

import datetime as _dt
import hashlib
from collections.abc import Iterator, Mapping
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import h5py
import numpy as np

from mfflap.atomic_write import commit, edited_copy, temporary_beside
from mfflap.errors import MfflapError, UnreadableRecordError
from mfflap.hydro.loads import LOAD_UNITS, Loads
from mfflap.kinematics.discrete import DiscreteMotion
from mfflap.kinematics.state import KINEMATIC_UNITS, KinematicState
from mfflap.performance import CycleSummary
from mfflap.version import __version__

SCHEMA_VERSION = 1
#: the root attribute that holds the checksum of everything else a results file holds
CHECKSUM_ATTR = "mfflap_checksum_sha256"


def _value_bytes(value: Any) -> bytes:
    """An attribute's or a small dataset's value as bytes, the same for the same value."""
    if isinstance(value, bytes):
        return value
    if isinstance(value, str):
        return value.encode("utf-8", "surrogatepass")
    arr = np.asarray(value)
    if arr.dtype.kind in "OSU":
        return repr(arr.tolist()).encode("utf-8", "surrogatepass")
    return arr.dtype.str.encode() + np.ascontiguousarray(arr).tobytes()


def content_checksum(h5: h5py.File) -> str:
    """SHA-256 over every attribute of the file (its own checksum left out), every dataset's
    name, type and shape, and the data of the datasets HDF5's Fletcher-32 does not guard
    (scalars, and datasets written without it): with Fletcher-32 on the rest, a flipped
    bit anywhere in what mfflap wrote is found."""
    digest = hashlib.sha256()
    objects: list[tuple[str, Any]] = []
    h5.visititems(lambda name, obj: objects.append((name, obj)))
    for name, obj in [("/", h5), *sorted(objects, key=lambda item: item[0])]:
        for key in sorted(obj.attrs):
            if name == "/" and key == CHECKSUM_ATTR:
                continue
            digest.update(f"{name}@{key}=".encode("utf-8", "surrogatepass"))
            digest.update(_value_bytes(obj.attrs[key]))
        if isinstance(obj, h5py.Dataset):
            digest.update(f"{name}:{obj.dtype.str}{obj.shape}".encode())
            if not obj.fletcher32:
                digest.update(_value_bytes(obj[()]))
    return digest.hexdigest()


def seal(h5: h5py.File) -> None:
    """Store :func:`content_checksum` in the file (done by :class:`ResultsFile` on a clean
    close, and by :func:`edited_results` at the end of an edit)."""
    h5.attrs[CHECKSUM_ATTR] = content_checksum(h5)


@contextmanager
def edited_results(path: str | Path) -> Iterator[h5py.File]:
    """A results file or record opened for an edit outside :class:`ResultsFile` (derived
    groups added to a finished record): a copy that is sealed (:func:`seal`) and takes the
    file's place whole when the block ends without an error
    (:func:`mfflap.atomic_write.edited_copy`).

    Raises
    ------
    MfflapError
        Naming the file, if it cannot be copied, opened or written.
    """
    with edited_copy(path) as h5:
        yield h5
        seal(h5)


def check_seal(h5: h5py.File, path: str | Path) -> None:
    """Refuse a file whose stored checksum does not match what it holds (a file written
    before files carried one is taken as it is).

    Raises
    ------
    UnreadableRecordError
        Naming the file.
    """
    stored = h5.attrs.get(CHECKSUM_ATTR)
    if stored is None:
        return
    try:
        held = content_checksum(h5)
    except (OSError, RuntimeError, KeyError, ValueError, TypeError) as err:  # h5py's forms
        # of a damaged object header, link or chunk
        raise UnreadableRecordError(f"its data cannot be read ({err})", path=str(path)) from err
    if str(stored) != held:
        raise UnreadableRecordError("what it holds does not match its checksum: damaged on "
                                    "disk, or edited outside mfflap", path=str(path))


def check_overwrite(path: str | Path, kind: str) -> None:
    """Refuse to write ``kind`` results over a file that holds something else.

    Writing over results of the same kind is a rerun and is allowed; writing over another
    kind of results (an ``--output`` that names the optimisation file), over an HDF5 file
    mfflap did not write, or over a file that is not HDF5 at all would lose it.

    Raises
    ------
    MfflapError
        Naming the file and what it holds.
    """
    path = Path(path)
    if not path.exists():
        return
    if path.is_dir():
        raise MfflapError(f"{path}: is a folder; name a results file (.h5)")
    lose = "writing results over it would lose it: choose another file, or delete it first"
    try:
        with h5py.File(path, "r") as h5:
            attrs = dict(h5.attrs)
    except OSError:
        raise MfflapError(f"{path}: exists and is not an HDF5 file (or one cut short); "
                          f"{lose}") from None
    if "mfflap_schema_version" not in attrs:
        raise MfflapError(f"{path}: is an HDF5 file mfflap did not write; {lose}")
    held = attrs.get("kind")
    if held != kind:
        raise MfflapError(f"{path}: holds {held!r} results; writing {kind!r} results over them "
                          "would lose them: choose another file, or delete it first")


class ResultsFile:
    """An HDF5 results file opened for writing or reading.

    Parameters
    ----------
    path
        File path.
    mode
        ``"w"`` (create/overwrite: written beside ``path`` and put in its place when the
        file is closed cleanly, so that an error or Ctrl-C while writing keeps what ``path``
        held), ``"a"`` (append) or ``"r"``.
    kind
        What the file holds (e.g. ``"evaluation"``, ``"optimisation"``), written at creation.
    config_toml
        Full input configuration as TOML text, stored at creation in ``/inputs``.
    kinds
        Reading: the kinds of file the reader understands (e.g. ``("optimisation",
        "run")``); another kind is refused by name, not read as if it were one of them.
    """

    def __init__(self, path: str | Path, mode: str = "r", *, kind: str = "results",
                 config_toml: str | None = None, kinds: tuple[str, ...] | None = None):

        self.path = Path(path)
        if mode == "r" and not self.path.exists():
            raise MfflapError(f"{self.path}: no such results file")
        if mode == "w":
            check_overwrite(self.path, kind)
        if mode != "r":  # a file asked for in a new folder: made, not failed after the work
            self.path.parent.mkdir(parents=True, exist_ok=True)
        # "w" writes beside the file (mfflap.atomic_write) and takes its place on a clean
        # close: a run stopped or failed while writing leaves the results written before whole
        self._writing = temporary_beside(self.path) if mode == "w" else None
        try:
            self._h5 = h5py.File(self._writing or self.path, mode)
        except (OSError, RuntimeError) as err:  # not HDF5, cut short, or locked by a writer
            if self._writing is not None:
                self._writing.unlink(missing_ok=True)
            raise MfflapError(f"{self.path}: cannot be opened as an HDF5 file ({err})") from err
        if mode == "r":
            try:
                check_seal(self._h5, self.path)
            except UnreadableRecordError:
                self._h5.close()
                raise
            version = self._h5.attrs.get("mfflap_schema_version")
            if version is None:
                self._h5.close()
                raise MfflapError(f"{self.path}: not an mfflap results file (no schema version)")
            if int(version) > SCHEMA_VERSION:
                self._h5.close()
                raise MfflapError(
                    f"{self.path}: schema version {int(version)} is newer than this mfflap "
                    f"reads ({SCHEMA_VERSION}); upgrade mfflap"
                )
            held = self._h5.attrs.get("kind")
            if kinds is not None and held not in kinds:
                self._h5.close()
                raise MfflapError(f"{self.path}: holds {held!r} results, not "
                                  f"{' or '.join(repr(k) for k in kinds)}")
        elif "mfflap_schema_version" not in self._h5.attrs:
            self._h5.attrs["mfflap_schema_version"] = SCHEMA_VERSION
            self._h5.attrs["mfflap_version"] = __version__
            self._h5.attrs["created_utc"] = _dt.datetime.now(_dt.UTC).isoformat()
            self._h5.attrs["kind"] = kind
            grp = self._h5.require_group("inputs")
            grp.attrs["config_toml"] = config_toml or ""

    @property
    def h5(self) -> h5py.File:
        """The underlying h5py file."""
        return self._h5

    @property
    def config_toml(self) -> str:
        """The input configuration stored at creation."""
        return str(self._h5["inputs"].attrs.get("config_toml", ""))

    def close(self) -> None:
        """Close the file; one opened with ``"w"`` then takes the place of ``path``
        (:func:`mfflap.atomic_write.commit`: an error naming ``path`` if its new content was
        removed meanwhile or the disk refused it)."""
        if self._h5.id.valid and self._h5.mode != "r":
            seal(self._h5)
        self._h5.close()
        if self._writing is not None:
            commit(self._writing, self.path)

    def discard(self) -> None:
        """Close a file opened with ``"w"`` without writing it: ``path`` keeps what it held."""
        self._h5.close()
        if self._writing is not None:
            self._writing.unlink(missing_ok=True)

    def __enter__(self) -> ResultsFile:
        return self

    def __exit__(self, exc_type, *exc) -> None:
        if exc_type is not None and self._writing is not None:
            self.discard()  # an error or Ctrl-C while writing: the file before is kept
        else:
            self.close()

    # -- generic -----------------------------------------------------------------------------
    def write_group(self, name: str, arrays: Mapping[str, Any], units: Mapping[str, str],
                    attrs: Mapping[str, Any] | None = None) -> h5py.Group:
        """Write a flat dict of arrays; every array must have a unit.

        Raises
        ------
        MfflapError
            If an array has no unit.
        """
        if name in self._h5:
            del self._h5[name]
        grp = self._h5.create_group(name)
        for key, value in arrays.items():
            if key not in units:
                raise MfflapError(f"{self.path}:{name}/{key}: no unit given")
            arr = np.asarray(value)
            if np.iscomplexobj(arr):
                arr = np.real(arr)
            big = arr.size >= 256 and arr.dtype.kind in "fiu"
            guarded = arr.ndim > 0 and arr.size > 0 and arr.dtype.kind in "fiub"
            ds = grp.create_dataset(key, data=arr, compression="gzip" if big else None,
                                    shuffle=big, fletcher32=guarded)
            ds.attrs["units"] = units[key]
        for k, v in (attrs or {}).items():
            grp.attrs[k] = v
        return grp

    def read_group(self, name: str) -> tuple[dict[str, np.ndarray], dict[str, Any]]:
        """Arrays and attributes of a group written by :meth:`write_group`."""
        if name not in self._h5:
            raise MfflapError(f"{self.path}: no group {name!r}; has {sorted(self._h5)}")
        grp = self._h5[name]
        try:
            arrays = {k: grp[k][()] for k in grp if isinstance(grp[k], h5py.Dataset)}
        except (OSError, RuntimeError) as err:  # a damaged chunk, a failed checksum
            raise UnreadableRecordError(f"its data cannot be read ({err})", path=str(self.path),
                                        dataset=name) from err
        return arrays, dict(grp.attrs)

    def units(self, name: str) -> dict[str, str]:
        """Units of every dataset of a group."""
        grp = self._h5[name]
        return {k: str(grp[k].attrs["units"]) for k in grp if isinstance(grp[k], h5py.Dataset)}

    # -- typed -------------------------------------------------------------------------------
    def write_state(self, name: str, state: KinematicState) -> None:
        """Store a kinematic state."""
        arrays = {k: getattr(state, k) for k in KINEMATIC_UNITS}
        arrays["time"] = state.time
        self.write_group(name, arrays, {**KINEMATIC_UNITS, "time": "s"})

    def read_state(self, name: str) -> KinematicState:
        """Read back a kinematic state."""
        arrays, _ = self.read_group(name)
        return KinematicState(**arrays)

    def write_loads(self, name: str, loads: Loads) -> None:
        """Store loads with their source."""
        arrays = {k: getattr(loads, k) for k in LOAD_UNITS}
        arrays["time"] = loads.time
        self.write_group(name, arrays, {**LOAD_UNITS, "time": "s"}, {"source": loads.source})

    def read_loads(self, name: str) -> Loads:
        """Read back loads."""
        arrays, attrs = self.read_group(name)
        return Loads(source=str(attrs.get("source", "unknown")), **arrays)

    def write_discrete_motion(self, name: str, motion: DiscreteMotion) -> None:
        """Store the controls and the time step of a discrete motion."""
        self.write_group(
            name,
            {"pitch_acceleration": motion.pitch_acceleration,
             "heave_acceleration": motion.heave_acceleration,
             "time_step": motion.time_step},
            {"pitch_acceleration": "rad/s^2", "heave_acceleration": "m/s^2", "time_step": "s"},
        )

    def read_discrete_motion(self, name: str) -> DiscreteMotion:
        """Read back a discrete motion."""
        a, _ = self.read_group(name)
        dt = a["time_step"]
        return DiscreteMotion(a["pitch_acceleration"], a["heave_acceleration"],
                              float(dt) if np.ndim(dt) == 0 else dt)

    def write_summary(self, name: str, summary) -> None:
        """Store a :class:`~mfflap.performance.CycleSummary`."""
        self.write_group(name, {k: getattr(summary, k) for k in CycleSummary.UNITS},
                         CycleSummary.UNITS)

    def read_summary(self, name: str):
        """Read back a :class:`~mfflap.performance.CycleSummary`."""
        arrays, _ = self.read_group(name)
        return CycleSummary(**{k: arrays[k] for k in CycleSummary.UNITS})
