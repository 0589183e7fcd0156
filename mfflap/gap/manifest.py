"""A whole external dataset in one input: a folder of CSV runs and the manifest that says
what each run is.

``manifest.toml`` in the folder gives the set-up every run shares and each run's motion::

    [setup]                      # checked against the case file
    velocity = 0.3               # m/s
    chord = 0.16                 # m
    span = 0.18                  # m
    density = 1000.0             # kg/m^3
    kinematic_viscosity = 1e-6   # m^2/s

    [[run]]
    file = "f1_h01.csv"          # the CSV of mfflap.gap.external, relative to the folder
    frequency = 1.0              # Hz
    heave_amplitude = 0.1        # m
    phase_deg = 90.0

The runs are read in the manifest's order; a CSV file of the folder that the manifest
does not list is refused, as is a listed one that is missing, so that nothing is left out
unseen. A run's own ``# key = value`` lines may repeat the manifest's values but not
contradict them.
"""

from __future__ import annotations

import tomllib
from pathlib import Path

import numpy as np

from mfflap.errors import ConfigError, ParseError
from mfflap.gap.external import MOTION_KEYS, SETUP_KEYS, check_setup, csv_parameters, read_csv_case
from mfflap.identification.data import CaseData

#: the manifest's file name in a dataset folder
MANIFEST_NAME = "manifest.toml"
#: the keys a ``[[run]]`` entry may give besides ``file``
RUN_KEYS = MOTION_KEYS


def has_manifest(folder: str | Path) -> bool:
    """Whether ``folder`` is a dataset folder (holds :data:`MANIFEST_NAME`)."""
    return (Path(folder) / MANIFEST_NAME).is_file()


def _number(value, key: str, source: str) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float) or not np.isfinite(value):
        raise ConfigError(f"{key} = {value!r} is not a finite number", source=source, key=key)
    return float(value)


def read_manifest(folder: str | Path) -> tuple[dict[str, float], list[tuple[Path, dict]]]:
    """The shared set-up and the (CSV path, parameters) of every run of a dataset folder.

    Raises
    ------
    ParseError
        For a manifest that is not TOML (naming its line) or that lists no run.
    ConfigError
        Naming the manifest and the key: an unknown table or key, a value that is not a
        finite number, a run without ``file`` or listed twice, a listed file that is
        missing, or a CSV file of the folder the manifest does not list.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> d = pathlib.Path(tempfile.mkdtemp())
    >>> _ = (d / "a.csv").write_text("time\\n0\\n")
    >>> _ = (d / "manifest.toml").write_text(
    ...     '[setup]\\nchord = 0.16\\n[[run]]\\nfile = "a.csv"\\nfrequency = 1.0\\n')
    >>> setup, runs = read_manifest(d)
    >>> setup, [(p.name, given) for p, given in runs]
    ({'chord': 0.16}, [('a.csv', {'frequency': 1.0})])
    """
    folder = Path(folder)
    path = folder / MANIFEST_NAME
    source = str(path)
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8"))
    except tomllib.TOMLDecodeError as err:
        raise ParseError(f"not TOML: {err}", path=source, line=getattr(err, "lineno", None)
                         ) from err
    unknown = sorted(set(data) - {"setup", "run"})
    if unknown:
        raise ConfigError(f"unknown table {unknown[0]!r}: a manifest has [setup] and [[run]]",
                          source=source, key=unknown[0])
    setup_table = data.get("setup", {})
    for key in setup_table:
        if key not in SETUP_KEYS:
            raise ConfigError(f"unknown [setup] key {key!r}: choose from "
                              f"{', '.join(SETUP_KEYS)}", source=source, key=f"setup.{key}")
    setup = {k: _number(v, f"setup.{k}", source) for k, v in setup_table.items()}
    runs_table = data.get("run", [])
    if not isinstance(runs_table, list) or not runs_table:
        raise ParseError("the manifest lists no [[run]]", path=source)
    runs: list[tuple[Path, dict]] = []
    seen: set[Path] = set()
    for number, entry in enumerate(runs_table, start=1):
        where = f"run[{number}]"
        if "file" not in entry or not isinstance(entry["file"], str):
            raise ConfigError(f"{where} has no file = \"NAME.csv\"", source=source,
                              key=f"{where}.file")
        for key in entry:
            if key != "file" and key not in RUN_KEYS:
                raise ConfigError(f"unknown {where} key {key!r}: choose from file, "
                                  f"{', '.join(RUN_KEYS)}", source=source, key=f"{where}.{key}")
        csv = (folder / entry["file"]).resolve()
        if csv in seen:
            raise ConfigError(f"{where}: {entry['file']} is listed twice", source=source,
                              key=f"{where}.file")
        if not csv.is_file():
            raise ConfigError(f"{where}: {entry['file']} does not exist in {folder}",
                              source=source, key=f"{where}.file")
        seen.add(csv)
        runs.append((csv, {k: _number(v, f"{where}.{k}", source) for k, v in entry.items()
                           if k != "file"}))
    unlisted = sorted(p.name for p in folder.glob("*.csv") if p.resolve() not in seen)
    if unlisted:
        raise ConfigError(f"{len(unlisted)} CSV file(s) of the folder are not in the manifest "
                          f"(e.g. {unlisted[0]}): list each run, or move the file out",
                          source=source, key="run")
    return setup, runs


def read_dataset(folder: str | Path, discard_s: float = 0.0, config=None) -> list[CaseData]:
    """Every run of a dataset folder as a case, with the manifest's parameters and set-up
    (checked against ``config``, a :class:`~mfflap.config.CaseConfig`, when given), its
    first ``discard_s`` seconds left out (:func:`mfflap.gap.external.read_csv_case`).

    Raises
    ------
    ConfigError
        For a manifest error (:func:`read_manifest`), a set-up that is not the case file's,
        or a run whose own ``# key = value`` line contradicts the manifest (naming both).

    Examples
    --------
    >>> import tempfile, pathlib
    >>> d = pathlib.Path(tempfile.mkdtemp())
    >>> t = np.linspace(0.0, 2.0, 41)
    >>> rows = "\\n".join(f"{x},{0.1*np.sin(x)},{0.05*np.cos(x)},0,0,0" for x in t)
    >>> _ = (d / "a.csv").write_text(
    ...     "time,pitch_angle,heave_position,normal_force,tangential_force,moment\\n" + rows)
    >>> _ = (d / "manifest.toml").write_text(
    ...     '[setup]\\nvelocity = 0.3\\n[[run]]\\nfile = "a.csv"\\nfrequency = 0.16\\n')
    >>> [(c.name, c.parameters["frequency"]) for c in read_dataset(d)]
    [('a', 0.16)]
    """
    setup, runs = read_manifest(folder)
    manifest = str(Path(folder) / MANIFEST_NAME)
    if config is not None:
        check_setup(setup, config, manifest)
    cases = []
    for csv, parameters in runs:
        own = csv_parameters(csv)
        for key, value in {**setup, **parameters}.items():
            if key in own and abs(own[key] - value) > 1e-9 * max(1.0, abs(value)):
                raise ConfigError(f"{csv.name} states {key} = {own[key]:g}; the manifest "
                                  f"gives {value:g}", source=str(csv), key=key)
        cases.append(read_csv_case(csv, {**setup, **parameters}, discard_s=discard_s,
                                   config=config))
    return cases


__all__ = ["MANIFEST_NAME", "RUN_KEYS", "has_manifest", "read_dataset", "read_manifest"]
