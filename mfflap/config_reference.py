"""The case-file reference, written from the dataclasses that read case files.

Every key of every table with its default, unit, allowed range and description, as
:func:`mfflap.config.load_case` checks them: the documentation's case-file page is this
text, so it cannot drift from the code.
"""

from __future__ import annotations

import dataclasses
import re
from typing import Any

from mfflap.config import _SECTIONS, MOTION_KEYS, CaseConfig
from mfflap.parameters import MorisonCoefficients
from mfflap.toml_io import _value
from mfflap.validation import describe_range


def _default(f: dataclasses.Field) -> str:
    if f.default is not dataclasses.MISSING:
        value: Any = f.default
    elif f.default_factory is not dataclasses.MISSING:  # type: ignore[misc]
        value = f.default_factory()  # type: ignore[misc]
    else:
        return "(required)"
    if value is None:
        return "(none)"
    if isinstance(value, tuple):
        return "[" + ", ".join(f"{v:g}" if isinstance(v, float) else repr(v)
                               for v in value) + "]"
    if isinstance(value, str):
        return f'"{value}"'
    return f"{value:g}" if isinstance(value, float) else str(value)


def _table(title: str, cls: type) -> list[str]:
    doc = (cls.__doc__ or "").strip().splitlines()[0]
    # a Sphinx role (:class:`~mfflap.x.Name`) reads as the name in Markdown
    doc = re.sub(r":\w+:`~?(?:[\w.]+\.)?(\w+)`", r"`\1`", doc)
    lines = [f"## [{title}]", "", doc, "", "| key | default | unit | allowed | meaning |",
             "|---|---|---|---|---|"]
    for f in dataclasses.fields(cls):
        meta = f.metadata
        allowed = describe_range(meta) if meta else "text"
        if meta.get("unit"):
            allowed = allowed.removesuffix(" " + meta["unit"])
        unit = meta.get("unit", "") if meta else ""
        meaning = (meta.get("doc", "") if meta else "").replace("|", "\\|")
        lines.append(f"| `{f.name}` | `{_default(f)}` | {unit} | {allowed} | {meaning} |")
    return [*lines, ""]


def case_file_reference_markdown() -> str:
    """Markdown tables of every case-file key, one table per TOML table.

    Returns
    -------
    str
        The text of the documentation's case-file reference.

    Examples
    --------
    >>> text = case_file_reference_markdown()
    >>> "| `heave_amplitude` |" in text and "## [model.coefficients]" in text
    True
    """
    out = ["A case file is TOML. Every key is optional and takes the default below; a "
           "value outside its range, a key no table has and a table that does not exist "
           "are refused, naming the file and the key.", ""]
    for name, cls in _SECTIONS.items():
        out += _table(name, cls)
        if name == "model":
            out += _table("model.coefficients", MorisonCoefficients)
    return "\n".join(out)


def _tables(config: CaseConfig) -> list[tuple[str, type, Any]]:
    """(TOML table name, dataclass, the config's instance) in case-file order."""
    out = []
    for name, cls in _SECTIONS.items():
        out.append((name, cls, getattr(config, "flow" if name == "flow" else name)))
        if name == "model":
            out.append(("model.coefficients", MorisonCoefficients, config.coefficients))
    return out


def _given(data: dict[str, Any], table: str) -> dict[str, Any]:
    node: Any = data
    for part in table.split("."):
        node = node.get(part, {}) if isinstance(node, dict) else {}
    return node if isinstance(node, dict) else {}


def commented_case_toml(config: CaseConfig | None = None,
                        given: dict[str, Any] | None = None) -> str:
    """A case file with every key, its value and a comment giving its unit, allowed range
    and meaning: what ``mfflap init`` writes and ``mfflap case show`` prints.

    Parameters
    ----------
    config
        The case to write (default: the defaults, the paper's study).
    given
        The parsed TOML the case was read from: keys it does not hold are marked
        ``(default)``. None marks nothing.

    Examples
    --------
    >>> from mfflap.config import loads_case
    >>> text = commented_case_toml()
    >>> loads_case(text) == CaseConfig()
    True
    >>> "chord = 0.16" in text
    True
    """
    config = config or CaseConfig()
    lines = ["# An mfflap case file: every key, its value and, after #, its unit, the",
             "# values allowed and what it means. Keys left out take their defaults.", ""]
    for table, cls, instance in _tables(config):
        lines.append(f"[{table}]")
        held = _given(given, table) if given is not None else None
        for f in dataclasses.fields(cls):
            meta = f.metadata
            value = getattr(instance, f.name)
            note = [describe_range(meta), meta.get("doc", "")] if meta else []
            note = [n for n in note if n]
            if held is not None and f.name not in held:
                note.insert(0, "(default)")
            comment = f"  # {'; '.join(note)}" if note else ""
            unread = (table == "motion" and f.name != "kind"
                      and f.name not in MOTION_KEYS[instance.kind])
            if value is None:
                lines.append(f"# {f.name} = (not set){comment}")
            elif unread:  # the other kind's key: shown, not set
                lines.append(f"# {f.name} = {_value(value)}{comment}; not read by a "
                             f"{instance.kind} motion")
            else:
                lines.append(f"{f.name} = {_value(value)}{comment}")
        lines.append("")
    return "\n".join(lines)
