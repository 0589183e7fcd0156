"""Fluent report files (``*.out``): parse by column names, flow-time aware.

Layout: line 1 a quoted title; line 2 starts with ``"Time Step"`` (transient) or
``"Iteration"`` (steady); line 3 the column names as quoted tokens in parentheses; then
whitespace-separated numeric rows. Columns are found by name (their order varies) and the
time is the ``flow-time`` column, never step x dt (the step may change during a run).
Restarted runs that append rows again from an earlier time keep the later rows. A restart
is told by the file's own marker: the ``Time Step`` column goes back with the flow time, to
the step the earlier rows put at that time. A flow time that goes back without it (a value
written wrong, or rows from another run pasted in) is an error naming the line, never a
reason to drop the rows before it. Fluent ends
every row with a newline: a last line without one is a row cut short by a killed run and is
dropped, even when it holds a value for every column (its last number may be cut).
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from mfflap.cfd.force_history import ForceHistory
from mfflap.errors import ParseError

_TOKEN = re.compile(r'"([^"]*)"')


@dataclass
class FluentReport:
    """Columns of one report file."""

    path: str
    title: str
    kind: str  # "transient" | "steady"
    columns: dict[str, np.ndarray]

    @property
    def time(self) -> np.ndarray:
        """Flow time, s (transient reports only)."""
        if "flow-time" not in self.columns:
            raise ParseError(f"no 'flow-time' column; columns: {list(self.columns)}",
                             path=self.path, line=3)
        return self.columns["flow-time"]


def parse_report(text: str, path: str = "<text>") -> FluentReport:
    """Parse the text of a report file.

    Raises
    ------
    ParseError
        For a missing or malformed header, a row with a wrong number of values, an
        unreadable number, NaN/inf, or flow time that is not increasing after restarts are
        resolved; naming the file and line. A last line without a newline (cut short by a
        killed run) is dropped, not parsed.
    """
    lines = text.splitlines()
    if len(lines) < 3:
        raise ParseError("a report file needs a title, a type and a column-name line",
                         path=path, line=len(lines) or 1)
    title = _TOKEN.findall(lines[0])
    if not title:
        raise ParseError("line 1 is not a quoted report title", path=path, line=1)
    second = lines[1].strip()
    if second.startswith('"Time Step"'):
        kind = "transient"
    elif second.startswith('"Iteration"'):
        kind = "steady"
    else:
        raise ParseError('line 2 must start with "Time Step" or "Iteration" (is this a Fluent '
                         "report file?)", path=path, line=2)
    header = lines[2].strip()
    if not (header.startswith("(") and header.endswith(")")):
        raise ParseError("line 3 must list the column names in parentheses", path=path, line=3)
    names = _TOKEN.findall(header)
    if not names or len(set(names)) != len(names):
        raise ParseError(f"line 3 has no or repeated column names: {names}", path=path, line=3)
    rows, row_lines = [], []
    cut_last = len(lines) if not text.endswith(("\n", "\r")) else None
    body = [(i, ln) for i, ln in enumerate(lines[3:], start=4) if ln.strip() and i != cut_last]
    for lineno, line in body:
        parts = line.split()
        if len(parts) != len(names):
            raise ParseError(f"{len(parts)} values for {len(names)} columns {names}",
                             path=path, line=lineno)
        try:
            values = [float(p) for p in parts]
        except ValueError as exc:
            raise ParseError(f"unreadable number in {line.strip()!r}", path=path,
                             line=lineno) from exc
        if not all(np.isfinite(values)):
            raise ParseError("NaN or infinite value: the run diverged here", path=path,
                             line=lineno)
        rows.append(values)
        row_lines.append(lineno)
    if not rows:
        raise ParseError("no data rows", path=path, line=4)
    data = np.array(rows)
    if kind == "transient" and "flow-time" in names:
        data, row_lines = _resolve_restarts(data, names, row_lines, path)
    return FluentReport(path, title[0], kind, {n: data[:, j] for j, n in enumerate(names)})


def _time_at_step_matches(steps: np.ndarray, times: np.ndarray, step: float,
                          time: float) -> bool:
    """Whether the earlier rows (``steps``, ``times``) put ``step`` at ``time``: within a
    tenth of the time step there (they may not have written that very step)."""
    order = np.argsort(steps, kind="stable")
    steps, times = steps[order], times[order]
    if not steps[0] <= step <= steps[-1]:
        return False
    k = min(max(int(np.searchsorted(steps, step)), 1), len(steps) - 1)
    per_step = (times[k] - times[k - 1]) / max(steps[k] - steps[k - 1], 1.0)
    return abs(float(np.interp(step, steps, times)) - time) <= 0.1 * abs(per_step)


def _resolve_restarts(data: np.ndarray, names: list[str], row_lines: list[int],
                      path: str) -> tuple[np.ndarray, list[int]]:
    """The rows of a transient report after its restarts: for each time, the last row
    written (module notes for how a restart is told from a wrong value).

    Raises
    ------
    ParseError
        Naming the line where the flow time goes back without a restart.
    """
    t = data[:, names.index("flow-time")]
    step = data[:, names.index("Time Step")] if "Time Step" in names else None
    for i in np.flatnonzero(np.diff(t) <= 0) + 1:
        restart = step is not None and step[i] < step[i - 1] and _time_at_step_matches(
            step[:i], t[:i], step[i], t[i])
        if not restart:
            said = ("the Time Step column does not go back with it" if step is not None
                    else "and the report has no Time Step column to show a restart")
            raise ParseError(f"flow-time goes back from {t[i - 1]:.9g} s to {t[i]:.9g} s, "
                             f"but this is no restart: {said} to the step of that time "
                             "(a wrong value, or rows of another run?)", path=path,
                             line=int(row_lines[i]))
    # a restart appends from an earlier time: keep, for each time, the last row written
    # (what is kept increases in time by construction)
    keep = np.ones(len(t), dtype=bool)
    latest = np.inf
    for i in range(len(t) - 1, -1, -1):
        if t[i] >= latest:
            keep[i] = False
        else:
            latest = t[i]
    return data[keep], list(np.array(row_lines)[keep])


def read_report(path: str | Path) -> FluentReport:
    """Parse a report file from disk."""
    path = Path(path)
    if not path.exists():
        raise ParseError("no such report file", path=str(path))
    return parse_report(path.read_text(errors="replace"), str(path))


def report_forces(path: str | Path, force_x: str = "fx-plate", force_y: str = "fy-plate",
                  moment_z: str | None = "mz-plate") -> ForceHistory:
    """The case-frame force (and moment about the CofR) of a report file as a
    :class:`~mfflap.cfd.openfoam.forces.ForceHistory`, the object the OpenFOAM side produces,
    so :func:`~mfflap.cfd.force_history.to_loads` turns both into the same loads."""
    rep = read_report(path)
    wanted = [c for c in (force_x, force_y, moment_z) if c]
    missing = [c for c in wanted if c not in rep.columns]
    if missing:
        raise ParseError(f"missing column(s) {missing}; the file has {list(rep.columns)}",
                         path=str(path), line=3)
    t = rep.time
    zeros = np.zeros_like(t)
    force = np.column_stack([rep.columns[force_x], rep.columns[force_y], zeros])
    moment = None
    if moment_z:
        moment = np.column_stack([zeros, zeros, rep.columns[moment_z]])
    return ForceHistory(t, force, moment, dialect="fluent-report")
