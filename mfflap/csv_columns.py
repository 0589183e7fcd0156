"""Numeric CSV files with a header line naming the columns: what users hand to mfflap
(motion tables, external force histories).

Lines that are empty or start with ``#`` are skipped; the first other line is the header,
unless it is a row of numbers: then the last comment line before it is the header, as
``numpy.savetxt(..., header="t,h,theta")`` writes it (``# t,h,theta``). Values are separated
by commas, or by semicolons or tabs when the header is (as spreadsheets in many locales save
CSV); the decimal mark is ``.``. Spaces alone do not separate values (a header such as
``time [s]`` holds them). A UTF-8 byte-order mark (Excel's "CSV
UTF-8") is skipped. Numbers are plain ASCII decimals (``-1.5``, ``2e-3``): Python's
``float`` would also take ``1_000`` and digits of other scripts, which no solver writes and
which are more likely a mistake than a value. Every error names the file and the line.
"""

from __future__ import annotations

import io
import re
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from mfflap.errors import ParseError

#: the separators a file may use, as its header shows them
SEPARATORS = (",", ";", "\t")
#: the separators as an error message names them
SEPARATORS_SAID = "',', ';' or a tab (the header's decides)"

#: a plain ASCII decimal number, with an optional sign, fraction and exponent
_PLAIN_NUMBER = re.compile(r"[+-]?(?:[0-9]+(?:\.[0-9]*)?|\.[0-9]+)(?:[eE][+-]?[0-9]+)?",
                           re.ASCII)


#: one field of a row: a plain number, or nan / inf (refused later as not finite)
_FIELD = (r"\s*(?:[+-]?(?:[0-9]+(?:\.[0-9]*)?|\.[0-9]+)(?:[eE][+-]?[0-9]+)?"
          r"|[+-]?(?:nan|inf|infinity))\s*")


def _row_pattern(separator: str, n_columns: int) -> re.Pattern:
    """A whole row of ``n_columns`` plain numbers separated by ``separator``."""
    return re.compile(_FIELD + f"(?:{re.escape(separator)}{_FIELD}){{{n_columns - 1}}}",
                      re.ASCII | re.IGNORECASE)


def _number(text: str) -> float:
    """``text`` as a float when it is a plain ASCII decimal (``nan`` and ``inf`` too, which
    the caller refuses as not finite), else ValueError."""
    value = text.strip()
    if _PLAIN_NUMBER.fullmatch(value) or value.lower().lstrip("+-") in ("nan", "inf",
                                                                        "infinity"):
        return float(value)
    shown = value if len(value) <= 40 else value[:40] + "..."
    raise ValueError(f"{shown!r} is not a plain decimal number")


def _commented_header(numbered: list[tuple[int, str]], first_line: int,
                      first_text: str) -> tuple[int, str] | None:
    """The last comment line before ``first_line`` as (line, header text without its
    ``#``), when the first non-comment line is a row of numbers and the comment splits into
    as many names as that row has values; else None."""
    separator = next((s for s in SEPARATORS if s in first_text), ",")
    values = first_text.split(separator)
    if not _row_pattern(separator, len(values)).fullmatch(first_text):
        return None
    before = [(i, line) for i, line in numbered[:first_line - 1] if line.strip()]
    if not before or not before[-1][1].lstrip().startswith("#"):
        return None
    i, line = before[-1]
    text = line.lstrip()[1:].strip()
    names = [n.strip() for n in text.split(separator)]
    if len(names) != len(values) or not all(names) or _row_pattern(
            separator, len(names)).fullmatch(text):
        return None
    return i, text


@dataclass(frozen=True)
class CsvColumns:
    """The columns of a CSV file by header name, and the file's line number of each row."""

    columns: dict[str, np.ndarray]
    line_numbers: np.ndarray
    #: the file's line number of the header
    header_line: int = 1

    def __getitem__(self, name: str) -> np.ndarray:
        return self.columns[name]

    def __contains__(self, name: object) -> bool:
        return name in self.columns


def read_csv_columns(path: str | Path, required: Sequence[str],
                     one_of: Sequence[Sequence[str]] = ()) -> CsvColumns:
    """The columns of a CSV file by header name, as finite float arrays.

    Parameters
    ----------
    path
        The file.
    required
        Column names that must be present.
    one_of
        Groups of alternative names (for example one column in radians or one in degrees):
        exactly one name of each group must be present.

    Returns
    -------
    CsvColumns
        Every column of the file by its header name (extra columns included) and the line
        number of each row.

    Raises
    ------
    ParseError
        Naming the file and line: no header, a missing or duplicated column, a row with the
        wrong number of values, an unreadable or non-finite number, no data rows.
    """
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8-sig")  # a byte-order mark is not a column name
    except UnicodeDecodeError as exc:
        raise ParseError(f"not a text file ({exc.reason})", path=str(path)) from exc
    numbered = list(enumerate(text.splitlines(), start=1))
    lines = [(i, line) for i, line in numbered
             if line.strip() and not line.lstrip().startswith("#")]
    if not lines:
        raise ParseError("no header line (an empty file)", path=str(path))
    header_line, header_text = lines[0]
    commented = _commented_header(numbered, header_line, header_text)
    if commented is not None:  # numpy.savetxt's "# " header over the first row of numbers
        header_line, header_text = commented
        lines = [(header_line, header_text), *lines]
    separator = next((s for s in SEPARATORS if s in header_text), ",")
    header = [h.strip() for h in header_text.split(separator)]
    if len(header) == 1 and len(header_text.split()) > 1:
        raise ParseError(f"the header {header_text.strip()[:80]!r} has no separator: values "
                         f"are separated by {SEPARATORS_SAID}, not by spaces alone",
                         path=str(path), line=header_line)
    if len(set(header)) != len(header):
        raise ParseError(f"a column is named twice in the header {header}", path=str(path),
                         line=header_line)
    missing = [c for c in required if c not in header]
    if missing:
        raise ParseError(f"missing column(s) {missing}; the header has {header}",
                         path=str(path), line=header_line)
    for group in one_of:
        present = [c for c in group if c in header]
        if len(present) != 1:
            raise ParseError(f"exactly one of the columns {list(group)} is needed, the header "
                             f"has {present or 'none'}", path=str(path), line=header_line)
    body = lines[1:]
    row = _row_pattern(separator, len(header))
    if body and all(row.fullmatch(line) for _, line in body):
        # every row is well formed: numpy's parser reads them at once (one check a row, not
        # one a value; the rows are checked value by value below only to name an error)
        data = np.loadtxt(io.StringIO("\n".join(line for _, line in body)),
                          delimiter=separator, dtype=float, ndmin=2)
        finite = np.isfinite(data)
        if not finite.all():
            r, c = (int(k[0]) for k in np.nonzero(~finite))
            raise ParseError(f"column {header[c]} is not finite", path=str(path),
                             line=body[r][0])
        return CsvColumns({h: data[:, j] for j, h in enumerate(header)},
                          np.array([i for i, _ in body]), header_line)
    rows, numbers = [], []
    for i, line in body:
        parts = line.split(separator)
        if len(parts) != len(header):
            raise ParseError(f"{len(parts)} values for {len(header)} columns "
                             f"(separated by {separator!r}, as the header is; a file may "
                             f"use {SEPARATORS_SAID})", path=str(path), line=i)
        try:
            values = [_number(p) for p in parts]
        except ValueError as exc:
            comma = " (the decimal mark is '.', not ',')" if any(
                "," in p for p in parts) else (
                f" (values are separated by {separator!r}, as the header is; a file may use "
                f"{SEPARATORS_SAID}, not spaces)" if any(
                    len(p.split()) > 1 for p in parts) else "")
            raise ParseError(f"unreadable number: {exc}{comma}", path=str(path),
                             line=i) from exc
        bad = [h for h, v in zip(header, values, strict=True) if not np.isfinite(v)]
        if bad:
            raise ParseError(f"column {bad[0]} is not finite", path=str(path), line=i)
        rows.append(values)
        numbers.append(i)
    if not rows:
        raise ParseError("a header but no data rows", path=str(path), line=header_line)
    data = np.array(rows, dtype=float)
    return CsvColumns({h: data[:, j] for j, h in enumerate(header)}, np.array(numbers),
                      header_line)
