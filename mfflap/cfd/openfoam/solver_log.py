"""What a pimpleFoam log says about a finished run: OpenFOAM build, CPU and clock time,
time steps, and how often the turbulence fields had to be clipped."""

from __future__ import annotations

import math
import os
import re
import signal
from pathlib import Path
from typing import Any

_BUILD = re.compile(r"^Build\s*:\s*(.+)$", re.M)
_NUMBER = r"([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)"
_BOUNDING = re.compile(rf"^bounding (\w+), min: {_NUMBER} max: {_NUMBER}", re.M)
# the time line alone: tabulatedAccelerationSource also starts lines with "Time = "
_TIME_STEP = re.compile(rf"^Time = {_NUMBER}\s*$", re.M)
_EXEC = re.compile(rf"ExecutionTime = {_NUMBER} s\s+ClockTime = {_NUMBER} s")
# the lines that give a step's size, its time and the CPU time after it, in log order
_STEP_LINES = re.compile(rf"^deltaT = {_NUMBER}\s*$|^Time = {_NUMBER}\s*$|"
                         rf"ExecutionTime = {_NUMBER} s", re.M)


def read_tail(path: Path, n_bytes: int = 20_000, start: int = 0) -> str:
    """The last ``n_bytes`` of a file, none of them before byte ``start``: what a watcher
    reads of a solver log that may be tens of MB, or what tells whether an output file was
    written whole (:func:`mfflap.cfd.openfoam.time_folders.written_whole`)."""
    with open(path, "rb") as fh:
        fh.seek(0, os.SEEK_END)
        size = fh.tell()
        fh.seek(max(size - n_bytes, start, 0))
        return fh.read().decode(errors="replace")


def solver_provenance(case_dir: str | Path) -> dict[str, Any]:
    """OpenFOAM build, CPU and clock time, time steps and turbulence clipping, from the
    case's pimpleFoam log.

    A restarted run appends to the same log; CPU times and time steps of the segments are
    summed. A restart resumes from the last written time, so the steps a segment took past
    it are taken again: ``n_time_steps_redone`` and ``cpu_time_redone_s`` are that repeated
    work (:func:`redone_work`), which a cost per simulated second leaves out.
    ``n_steps_bounding_<field>`` counts the solves after which OpenFOAM clipped negative
    values of k or epsilon ("bounding epsilon, min: ..."), and ``worst_bounding_<field>`` is
    the most negative value relative to that step's maximum: a health figure of the
    turbulence solution (see ``SolverSettings.turbulence_convection``).

    Parameters
    ----------
    case_dir
        An OpenFOAM case folder; a missing ``log.pimpleFoam`` gives zeros.

    Returns
    -------
    dict
        ``solver``, ``openfoam_build``, ``cpu_time_s``, ``clock_time_s``, ``n_time_steps``,
        ``n_time_steps_redone``, ``cpu_time_redone_s``, ``n_steps_bounding_k``,
        ``n_steps_bounding_epsilon``, ``worst_bounding_k``, ``worst_bounding_epsilon``.
    """
    log = Path(case_dir) / "log.pimpleFoam"
    text = log.read_text(errors="replace") if log.exists() else ""
    build = _BUILD.search(text)
    cpu = clock = 0.0
    for segment in text.split("Create time")[1:]:
        times = _EXEC.findall(segment)
        if times:
            cpu += float(times[-1][0])
            clock += float(times[-1][1])
    n_redone, cpu_redone = redone_work(text)
    return {
        "solver": "OpenFOAM pimpleFoam",
        "openfoam_build": build.group(1).strip() if build else "unknown",
        "cpu_time_s": cpu,
        "clock_time_s": clock,
        # one "Time = " line per time step (the Courant line also precedes the loop)
        "n_time_steps": len(_TIME_STEP.findall(text)),
        "n_time_steps_redone": n_redone,
        "cpu_time_redone_s": cpu_redone,
        **bounding_summary(text),
    }


def _segment_steps(segment: str) -> tuple[list[float], list[float | None], float | None]:
    """Each step's time and the CPU time after it (None where the log stops before it is
    printed) in one run's part of a log, and the time that run started from."""
    times: list[float] = []
    cpus: list[float | None] = []
    step = start = None
    for match in _STEP_LINES.finditer(segment):
        delta_t, time_s, cpu_s = match.groups()
        if delta_t is not None:
            step = float(delta_t)
        elif time_s is not None:
            if not times:
                start = float(time_s) - (step or 0.0)
            times.append(float(time_s))
            cpus.append(None)
        elif cpus:
            cpus[-1] = float(cpu_s)
    return times, cpus, start


def redone_work(log_text: str) -> tuple[int, float]:
    """Time steps and CPU time (s) that later runs in the same log took again.

    A run that resumes from time t repeats what the runs before it simulated past t (a run
    killed between writes resumes from its last write; a retried run may be rewound
    further). Those earlier steps are redone work: the run's history holds the later ones.

    Parameters
    ----------
    log_text
        A pimpleFoam log that restarted runs appended to (one ``Create time`` each).

    Returns
    -------
    tuple
        The number of redone steps and the CPU time they took, s.
    """
    n_redone, cpu_redone = 0, 0.0
    resumed_from = math.inf  # the earliest start of the runs after this one
    for segment in reversed(log_text.split("Create time")[1:]):
        times, cpus, start = _segment_steps(segment)
        kept = [i for i, t in enumerate(times) if t <= resumed_from]
        if len(kept) < len(times):
            ran = [c for c in cpus if c is not None]
            before = [cpus[i] for i in kept if cpus[i] is not None]
            n_redone += len(times) - len(kept)
            redone_s = (ran[-1] if ran else 0.0) - (before[-1] if before else 0.0)
            cpu_redone += redone_s if math.isfinite(redone_s) and redone_s > 0 else 0.0
        if start is not None:  # half a step of slack: the log prints times to 8 digits
            resumed_from = min(resumed_from, start + 0.5 * (times[0] - start))
    return n_redone, cpu_redone


def bounding_summary(log_text: str) -> dict[str, int | float]:
    """Number of k and epsilon solves clipped by OpenFOAM's ``bound()`` and the most
    negative clipped value relative to that solve's maximum (0 when none were clipped).

    Parameters
    ----------
    log_text
        Text of a pimpleFoam log; lines that do not parse are ignored.

    Returns
    -------
    dict
        ``n_steps_bounding_<field>`` (int) and ``worst_bounding_<field>`` (a ratio <= 0) for
        k and epsilon.
    """
    counts = {"k": 0, "epsilon": 0}
    worst = {"k": 0.0, "epsilon": 0.0}
    for field, low, high in _BOUNDING.findall(log_text):
        if field not in counts:
            continue
        counts[field] += 1
        ratio = float(low) / abs(float(high)) if float(high) != 0 else 0.0
        if math.isfinite(ratio):
            worst[field] = min(worst[field], ratio)
    return {**{f"n_steps_bounding_{f}": n for f, n in counts.items()},
            **{f"worst_bounding_{f}": w for f, w in worst.items()}}


# an OpenFOAM fatal error: its heading, then what went wrong up to where it was raised
_FATAL = re.compile(r"FOAM FATAL (IO )?ERROR:?[^\n]*\n(.*?)(?=\n\s*From function|\nFOAM "
                    r"exiting|\nFOAM aborting|\Z)", re.S)
# the sigFpe handler's stack trace (not the banner's "Floating point exception trapping
# enabled"), and NaN residuals
_FLOATING_POINT = re.compile(r"sigFpe::sigHandler|Floating point exception \(core", re.I)
_NAN = re.compile(r"(?<![A-Za-z])-?nan(?![A-Za-z])", re.I)
#: crash and divergence signatures in a log: NaN, a floating point exception, a fatal error
DIVERGED = re.compile(rf"({_NAN.pattern}|{_FLOATING_POINT.pattern}|FOAM FATAL)", re.I)
#: the longest fatal-error text a failure's one-line reason quotes, characters
FATAL_TEXT_CHARS = 400


def failure_reason(log_text: str, returncode: int | None) -> str:
    """Why an OpenFOAM application failed, in a line: the text of its last fatal error
    (what was wrong and in which file and line), a floating point exception or NaN (the
    solution diverged), the signal that killed it, or else its exit code.

    Parameters
    ----------
    log_text
        The application's own log (its last part will do).
    returncode
        Its exit status (negative: killed by that signal), or None if unknown.
    """
    fatal = list(_FATAL.finditer(log_text))
    if fatal:
        kind = "FOAM FATAL IO ERROR" if fatal[-1].group(1) else "FOAM FATAL ERROR"
        text = " ".join(fatal[-1].group(2).split())
        if len(text) > FATAL_TEXT_CHARS:
            text = text[:FATAL_TEXT_CHARS - 3] + "..."
        return f"{kind}: {text}" if text else kind
    if _FLOATING_POINT.search(log_text):
        return "a floating point exception: the solution diverged"
    if _NAN.search(log_text):
        return "NaN in the solution: it diverged"
    if returncode is not None and returncode < 0:
        try:
            name = signal.Signals(-returncode).name
        except ValueError:
            name = f"signal {-returncode}"
        return f"killed by {name}" + (" (the out-of-memory killer?)" if name == "SIGKILL"
                                      else "")
    return f"exit code {returncode}"


#: a solver log's line of a time step's size, s
DELTA_T_LINE = re.compile(r"^deltaT = ([0-9.eE+-]+)\s*$", re.M)
#: a solver log's line of a time step's time, s
TIME_LINE = re.compile(r"^Time = ([0-9.eE+-]+)\s*$", re.M)


def solver_progress(case_dir: str | Path, log_name: str = "log.pimpleFoam"
                    ) -> tuple[float, float] | None:
    """(time, deltaT) of the last time step the solver's log reports, in s; None if the
    case has no such log or it has no time step yet. Reads only the log's tail."""
    path = Path(case_dir) / log_name
    if not path.is_file():
        return None
    text = read_tail(path)
    times, steps = TIME_LINE.findall(text), DELTA_T_LINE.findall(text)
    if not times:
        return None
    return float(times[-1]), float(steps[-1]) if steps else float("nan")
