"""Range-checked fields for frozen dataclasses, and building them from TOML mappings.

A field declared with :func:`bounded` carries its unit, its allowed range and a short
description. :func:`check_fields` validates an instance (called from ``__post_init__``) and
:func:`from_mapping` builds an instance from a mapping, naming the file, the key, the value and
the allowed range in every error.
"""

from __future__ import annotations

import dataclasses
import difflib
import math
import re
from collections.abc import Mapping
from typing import Any, TypeVar

from mfflap.errors import ConfigError, shown

T = TypeVar("T")


def bounded(
    default: Any = dataclasses.MISSING,
    *,
    low: float | None = None,
    high: float | None = None,
    low_open: bool = False,
    high_open: bool = False,
    unit: str = "",
    doc: str = "",
    choices: tuple[Any, ...] | None = None,
    unique: bool = False,
    period: float | None = None,
) -> Any:
    """Declare a dataclass field with a unit and an allowed range.

    Parameters
    ----------
    default
        Default value; omit for a required field.
    low, high
        Bounds of the allowed range (``None``: unbounded).
    low_open, high_open
        Whether the bound itself is excluded.
    unit
        SI unit of the value, for messages and HDF5 attributes.
    doc
        One-line description.
    choices
        For string settings: the allowed values.
    unique
        For lists: each value at most once (a grid axis, a list of cases to run).
    period
        For unique lists of angles: values a whole number of ``period`` apart are the same
        value (phases 90 and -270 deg are one motion).
    """
    meta = {
        "low": low,
        "high": high,
        "low_open": low_open,
        "high_open": high_open,
        "unit": unit,
        "doc": doc,
        "choices": choices,
        "unique": unique,
        "period": period,
    }
    return dataclasses.field(default=default, metadata=meta)


def describe_range(meta: Mapping[str, Any]) -> str:
    """Human-readable allowed range of a field, e.g. ``(0, inf) m``."""
    if meta.get("choices") == (True, False):
        return "true or false"
    if meta.get("choices"):
        return "one of " + ", ".join(repr(c) for c in meta["choices"])
    low, high = meta.get("low"), meta.get("high")
    left = "(" if meta.get("low_open") or low is None else "["
    right = ")" if meta.get("high_open") or high is None else "]"
    lo = "-inf" if low is None else f"{low:g}"
    hi = "inf" if high is None else f"{high:g}"
    unit = f" {meta['unit']}" if meta.get("unit") else ""
    return f"{left}{lo}, {hi}{right}{unit}"


#: control characters a case file's text may not hold (all of C0 and DEL but tab, newline
#: and carriage return): HDF5 attributes, OpenFOAM dictionaries and C sources cannot carry
#: them whole
_CONTROL = re.compile(r"[\x00-\x08\x0b\x0c\x0e-\x1f\x7f]")


def _check_printable(name: str, value: Any, where: str | None) -> None:
    """Refuse a text (or a list's text) that holds a control character (:data:`_CONTROL`)."""
    for i, item in enumerate(value if isinstance(value, list | tuple) else [value]):
        if isinstance(item, str) and (bad := _CONTROL.search(item)):
            key = f"{name}[{i}]" if isinstance(value, list | tuple) else name
            raise ConfigError(f"holds the control character {bad.group()!r} at position "
                              f"{bad.start()}; text in a case file must be printable",
                              source=where, key=key)


def _check_value(name: str, value: Any, meta: Mapping[str, Any], where: str | None) -> None:
    if value is None:  # an optional setting left out (TOML has no null to give it)
        return
    if meta.get("choices") is not None:
        if value not in meta["choices"]:
            raise ConfigError(
                f"value {shown(value)} is not allowed; allowed: {describe_range(meta)}",
                source=where,
                key=name,
            )
        return
    if meta.get("low") is None and meta.get("high") is None:
        return
    if isinstance(value, list | tuple):
        if not value:
            raise ConfigError("empty list; give at least one value", source=where, key=name)
        for i, item in enumerate(value):
            _check_value(f"{name}[{i}]", item, meta, where)
            if meta.get("unique") and item in value[:i]:
                raise ConfigError(
                    f"value {shown(item)} is given twice ({name}[{list(value).index(item)}] and "
                    f"[{i}]); give each value once",
                    source=where,
                    key=f"{name}[{i}]",
                )
            period = meta.get("period") if meta.get("unique") else None
            same = next((j for j, earlier in enumerate(value[:i]) if period and math.isclose(
                math.remainder(float(item) - float(earlier), period), 0.0, abs_tol=1e-9)), None)
            if same is not None:
                raise ConfigError(
                    f"value {shown(item)} is the same as {shown(value[same])} "
                    f"({name}[{same}]): they lie "
                    f"{abs(float(item) - float(value[same])):g} {meta.get('unit', '')} apart, a "
                    f"whole number of periods ({period:g}); give each value once",
                    source=where,
                    key=f"{name}[{i}]",
                )
        return
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise ConfigError(
            f"value {shown(value)} is not a number; allowed: {describe_range(meta)}",
            source=where,
            key=name,
        )
    v = float(value)
    low, high = meta.get("low"), meta.get("high")
    # +inf only where the range says so: a closed high bound of inf
    bad = not math.isfinite(v) and not (v == math.inf and high == math.inf
                                        and not meta.get("high_open"))
    if low is not None:
        bad |= v <= low if meta.get("low_open") else v < low
    if high is not None:
        bad |= v >= high if meta.get("high_open") else v > high
    if bad:
        raise ConfigError(
            f"value {shown(value)} is out of range; allowed: {describe_range(meta)}",
            source=where,
            key=name,
        )


def check_fields(instance: Any, where: str | None = None, prefix: str = "") -> None:
    """Validate every :func:`bounded` field of a dataclass instance.

    Raises
    ------
    ConfigError
        Naming the key, the value and the allowed range.
    """
    for f in dataclasses.fields(instance):
        if "unit" in f.metadata:
            _check_value(prefix + f.name, getattr(instance, f.name), f.metadata, where)


def _check_shape(name: str, value: Any, f: dataclasses.Field, where: str | None) -> None:
    """Refuse one value for a list setting, and a list for a one-value setting."""
    wants_list = str(f.type).startswith("tuple")
    if wants_list and not isinstance(value, list | tuple):
        raise ConfigError(f"value {shown(value)} must be a list, e.g. [{shown(value)}]",
                          source=where, key=name)
    if not wants_list and isinstance(value, list | tuple):
        raise ConfigError(f"value {shown(value)} is a list; give one value", source=where,
                          key=name)



#: tables with more keys than this name the nearest ones, not all, when a key is unknown
_LISTED_KEYS = 12


def _unknown_keys_hint(unknown: list[str], allowed: list[str]) -> str:
    """The unknown keys and what is allowed, in one line of bounded length: at most three
    unknown keys named, and a table's allowed keys listed only when they are few (else the
    nearest to the first unknown key, and where to see them all).

    Examples
    --------
    >>> _unknown_keys_hint(["lift"], ["drag", "mass"])
    'lift; allowed: drag, mass'
    >>> _unknown_keys_hint(["a", "b", "c", "d"], [f"key{i}" for i in range(20)] + ["ab"])
    'a, b, c (+1 more); did you mean ab? 21 keys allowed (`mfflap case show` prints them)'
    """
    named = ", ".join(unknown[:3]) + (f" (+{len(unknown) - 3} more)" if len(unknown) > 3
                                       else "")
    if len(allowed) <= _LISTED_KEYS:
        return f"{named}; allowed: {', '.join(allowed)}"
    near = difflib.get_close_matches(unknown[0], allowed, n=3)
    guess = f"did you mean {', '.join(near)}? " if near else ""
    return f"{named}; {guess}{len(allowed)} keys allowed (`mfflap case show` prints them)"

def from_mapping(cls: type[T], mapping: Mapping[str, Any], *, source: str | None = None,
                 prefix: str = "") -> T:
    """Build a dataclass from a mapping, refusing unknown keys and out-of-range values.

    Parameters
    ----------
    cls
        The dataclass to build.
    mapping
        Keys are field names.
    source
        File the mapping came from (for messages).
    prefix
        Dotted key of the mapping in its file, e.g. ``"plate."``.
    """
    if not isinstance(mapping, Mapping):
        raise ConfigError(
            f"expected a table of settings, got {type(mapping).__name__}",
            source=source,
            key=prefix.rstrip(".") or None,
        )
    fields = {f.name: f for f in dataclasses.fields(cls)}  # type: ignore[arg-type]
    unknown = sorted(set(mapping) - set(fields))
    if unknown:
        raise ConfigError(f"unknown key(s) {_unknown_keys_hint(unknown, sorted(fields))}",
                          source=source, key=prefix + unknown[0])
    for name, value in mapping.items():
        _check_printable(prefix + name, value, source)
        _check_shape(prefix + name, value, fields[name], source)
    for name, f in fields.items():
        if name in mapping and "unit" in f.metadata:
            _check_value(prefix + name, mapping[name], f.metadata, source)
    missing = [
        n for n, f in fields.items()
        if n not in mapping and f.default is dataclasses.MISSING
        and f.default_factory is dataclasses.MISSING
    ]
    if missing:
        raise ConfigError(f"required key(s) missing: {', '.join(missing)}", source=source,
                          key=prefix + missing[0])
    values = {}
    for k, v in mapping.items():
        f = fields[k]
        if f.type in ("int", int) and (isinstance(v, bool) or not isinstance(v, int)):
            raise ConfigError(f"value {shown(v)} must be a whole number; allowed: "
                              f"{describe_range(f.metadata)}", source=source, key=prefix + k)
        if f.type in ("bool", bool) and not isinstance(v, bool):
            raise ConfigError(f"value {shown(v)} must be true or false", source=source,
                              key=prefix + k)
        if f.type in ("str", str) and not isinstance(v, str):
            allowed = (describe_range(f.metadata) if f.metadata.get("choices")
                       else "any text in quotes")
            raise ConfigError(f"value {shown(v)} must be a string; allowed: {allowed}",
                              source=source, key=prefix + k)
        if isinstance(v, list):
            v = tuple(v)
        elif f.type in ("float", float) and isinstance(v, int):
            v = float(v)
        values[k] = v
    return cls(**values)


def as_dict(instance: Any) -> dict[str, Any]:
    """Plain-dict form of a (nested) dataclass, for TOML/HDF5 attributes."""
    return dataclasses.asdict(instance)


def unit_of(cls: Any, name: str) -> str:
    """Unit declared for field ``name`` of dataclass ``cls``."""
    for f in dataclasses.fields(cls):
        if f.name == name:
            return str(f.metadata.get("unit", ""))
    raise KeyError(name)
