"""What a pimpleFoam log says about a finished run: OpenFOAM build, CPU and clock time,
time steps, and how often the turbulence fields had to be clipped."""

from __future__ import annotations

import math
import re
from pathlib import Path
from typing import Any

_BUILD = re.compile(r"^Build\s*:\s*(.+)$", re.M)
_NUMBER = r"([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)"
_BOUNDING = re.compile(rf"^bounding (\w+), min: {_NUMBER} max: {_NUMBER}", re.M)
# the time line alone: tabulatedAccelerationSource also starts lines with "Time = "
_TIME_STEP = re.compile(rf"^Time = {_NUMBER}\s*$", re.M)
_EXEC = re.compile(rf"ExecutionTime = {_NUMBER} s\s+ClockTime = {_NUMBER} s")


def solver_provenance(case_dir: str | Path) -> dict[str, Any]:
    """OpenFOAM build, CPU and clock time, time steps and turbulence clipping, from the
    case's pimpleFoam log.

    A restarted run appends to the same log; CPU times of the segments are summed.
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
        ``n_steps_bounding_k``, ``n_steps_bounding_epsilon``, ``worst_bounding_k``,
        ``worst_bounding_epsilon``.
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
    return {
        "solver": "OpenFOAM pimpleFoam",
        "openfoam_build": build.group(1).strip() if build else "unknown",
        "cpu_time_s": cpu,
        "clock_time_s": clock,
        # one "Time = " line per time step (the Courant line also precedes the loop)
        "n_time_steps": len(_TIME_STEP.findall(text)),
        **bounding_summary(text),
    }


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
