"""The plate, fluid and stream a CFD record was run for, and the check that a case file
describes the same ones.

Identification, gap diagnosis and back-tests put a record's forces beside the Morison
model of a case file. Forces of another plate (chord, span), fluid or stream read with the
case file's would fit wrong coefficients, or judge the model wrongly, without any sign of
it. A record says what it was run for in its provenance (``chord_m`` and ``span_m`` since
the first records; the plate's thickness, the fluid and the stream with the keys of
mfflap_case.toml, :data:`PHYSICAL_KEYS`, in newer records) and in
the ``campaign.toml`` of the folder it was run into; what neither says cannot be checked
and is not refused, but for the pivot: a run that does not give it pitched about the leading
edge (:data:`IMPLIED_KEYS`).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from mfflap.errors import ConfigError
from mfflap.parameters import Fluid, FreeStream, Plate
from mfflap.records.record import CfdRecord
from mfflap.toml_io import read_toml

#: mfflap_case.toml key -> (case-file key, where the value lives)
PHYSICAL_KEYS = {
    "span": ("plate.span", lambda p, f, s: p.span),
    "plate_chord_m": ("plate.chord", lambda p, f, s: p.chord),
    "plate_thickness_m": ("plate.thickness", lambda p, f, s: p.thickness),
    "plate_pivot_chord_fraction": ("plate.pivot_chord_fraction",
                                   lambda p, f, s: p.pivot_chord_fraction),
    "fluid_density_kg_per_m3": ("fluid.density", lambda p, f, s: f.density),
    "fluid_kinematic_viscosity_m2_per_s": ("fluid.kinematic_viscosity",
                                           lambda p, f, s: f.kinematic_viscosity),
    "flow_velocity_m_per_s": ("flow.velocity", lambda p, f, s: s.velocity),
}
#: mfflap_case.toml keys a run that does not give them was run for, at these values (the
#: pivot was the leading edge before it could be placed elsewhere)
IMPLIED_KEYS = {"plate_pivot_chord_fraction": 0.0}
#: relative tolerance of the comparisons (the kept values are exact float reprs)
RELATIVE_TOLERANCE = 1e-6
#: provenance keys a record had before it kept mfflap_case.toml's (the case-file key's)
_EARLIER_KEYS = {"plate.chord": ("chord_m",), "plate.span": ("span_m",)}
#: case-file key -> (provenance keys of a record, in order of preference; the value in a
#: case's plate, fluid and stream)
CHECKED_KEYS: dict[str, tuple[tuple[str, ...], Callable[[Plate, Fluid, FreeStream], float]]] = {
    case_key: (((kept,) if kept != "span" else ()) + _EARLIER_KEYS.get(case_key, ()), getter)
    for kept, (case_key, getter) in PHYSICAL_KEYS.items()}
def _differ(a: float, b: float) -> bool:
    """Whether two kept values differ by more than the tolerance of kept inputs
    (:data:`RELATIVE_TOLERANCE` of the larger)."""
    return abs(a - b) > RELATIVE_TOLERANCE * max(abs(a), abs(b))


@dataclass(frozen=True)
class InputMismatch:
    """One value a record was run for that differs from the case file's."""

    record: str
    key: str  #: case-file key, e.g. ``plate.chord``
    record_value: float
    case_value: float
    #: where the record's value was read: ``provenance`` or the folder's campaign.toml
    where: str


def run_for(record: CfdRecord, folder_setup: dict[str, Any] | None = None
            ) -> dict[str, tuple[float, str]]:
    """What a record was run for: case-file key -> (value, where it was read), for the keys
    the record's provenance or its folder's ``campaign.toml`` ``[setup]`` give."""
    found: dict[str, tuple[float, str]] = {}
    for key, (names, _) in CHECKED_KEYS.items():
        name = next((n for n in names if n in record.provenance), None)
        if name is not None:
            found[key] = (float(record.provenance[name]), f"its provenance {name}")
            continue
        section, field = key.split(".")
        value = (folder_setup or {}).get("stream" if section == "flow" else section,
                                         {}).get(field)
        if isinstance(value, (int, float)):
            found[key] = (float(value), "the folder's campaign.toml")
            continue
        implied = next((IMPLIED_KEYS[n] for n in names if n in IMPLIED_KEYS), None)
        if implied is not None:
            found[key] = (implied, "the value every run that does not say it was run for")
    return found


def folder_setup(path: Path) -> dict[str, Any] | None:
    """The ``[setup]`` of the campaign.toml beside a record file or in a record folder."""
    manifest = (path if path.is_dir() else path.parent) / "campaign.toml"
    if not manifest.is_file():
        return None
    setup = read_toml(manifest).get("setup")
    return setup if isinstance(setup, dict) else None


def input_mismatches(record: CfdRecord, plate: Plate, fluid: Fluid, stream: FreeStream,
                     folder_setup: dict[str, Any] | None = None) -> list[InputMismatch]:
    """The values a record was run for that differ from ``plate``, ``fluid`` and
    ``stream`` (those it does not give are not compared)."""
    out = []
    for key, (value, where) in run_for(record, folder_setup).items():
        wanted = float(CHECKED_KEYS[key][1](plate, fluid, stream))
        if _differ(value, wanted):
            out.append(InputMismatch(record.name, key, value, wanted, where))
    return out


def run_for_differences(a: dict[str, tuple[float, str]], b: dict[str, tuple[float, str]]
                        ) -> list[tuple[str, float, float]]:
    """(case-file key, value in ``a``, value in ``b``) for each key both :func:`run_for`
    results give that differs."""
    return [(key, a[key][0], b[key][0]) for key in CHECKED_KEYS
            if key in a and key in b and _differ(a[key][0], b[key][0])]


def check_records_inputs(records: Sequence[tuple[CfdRecord, Path]], plate: Plate,
                         fluid: Fluid, stream: FreeStream, *, case_source: str | None,
                         use: str) -> None:
    """Refuse records run for another plate, fluid or stream than a case file's.

    Parameters
    ----------
    records
        Each record with the file or folder it was read from (whose campaign.toml is read).
    case_source
        The case file, for the message.
    use
        What the records were read for, for the message (e.g. "identification").

    Raises
    ------
    ConfigError
        Naming, for each folder and key that differs (the first four), the records' value,
        where it was read, how many records and the case file's value, keyed by the first
        case-file key that differs.
    """
    setups: dict[Path, dict[str, Any] | None] = {}
    groups: dict[tuple[Path, str, float, float, str], list[str]] = {}
    for record, path in records:
        if path not in setups:
            setups[path] = folder_setup(path)
        for m in input_mismatches(record, plate, fluid, stream, setups[path]):
            groups.setdefault((path, m.key, m.record_value, m.case_value, m.where),
                              []).append(m.record)
    if not groups:
        return
    lines = []
    for (path, key, had, wanted, where), names in list(groups.items())[:4]:
        which = f"record {names[0]}" if len(names) == 1 else f"{len(names)} records"
        lines.append(f"{which} in {path} ran for {key} = {had:g} ({where}), the case file "
                     f"has {wanted:g}")
    more = "; ..." if len(groups) > 4 else ""
    raise ConfigError(
        f"CFD records of another plate, fluid or stream than the case file's: "
        f"{'; '.join(lines)}{more}. Their forces would be read as this case's in the "
        f"{use} and give wrong numbers: give the case file the records' values, or records "
        f"run for this case (`mfflap campaign run`, `--fixtures`)",
        source=case_source, key=next(iter(groups))[1])
