"""How far a running pimpleFoam has got, in words: what ``mfflap cfd run`` prints while it
waits (simulated time against the end time, the time step, and the time left at the rate
seen so far)."""

from __future__ import annotations

import time
from collections.abc import Callable
from pathlib import Path

from mfflap.cfd.openfoam.control_dict import end_time
from mfflap.cfd.openfoam.solver_log import solver_progress


def _duration(seconds: float) -> str:
    seconds = round(seconds)
    if seconds < 60:
        return f"{seconds} s"
    if seconds < 3600:
        return f"{seconds // 60} min {seconds % 60:02d} s"
    return f"{seconds // 3600} h {seconds % 3600 // 60:02d} min"


def describe_progress(time_s: float, delta_t_s: float, end_s: float | None,
                      elapsed_s: float, rate: float | None) -> str:
    """One progress line.

    Parameters
    ----------
    time_s, delta_t_s
        The simulated time reached and the last time step, s.
    end_s
        The run's end time, s (None: not known).
    elapsed_s
        Wall-clock time since the solver started, s.
    rate
        Simulated seconds per wall-clock second so far (None: not known yet).
    """
    text = f"t = {time_s:.6g} s"
    if end_s:
        text += f" of {end_s:g} s ({100 * min(time_s / end_s, 1.0):.1f} %)"
    text += f", time step {delta_t_s:.3g} s, {_duration(elapsed_s)} elapsed"
    if end_s and rate and rate > 0:
        text += f", about {_duration(max(end_s - time_s, 0.0) / rate)} left"
    return text


class RunProgress:
    """A callable that reports, each time it is called, how far the case's solver has got.

    Parameters
    ----------
    case_dir
        The case whose log (``log.pimpleFoam``) is read; only its tail.
    report
        Where each line goes (e.g. ``click.echo(..., err=True)``).
    clock
        Wall-clock seconds (a test may pass its own).
    """

    def __init__(self, case_dir: str | Path, report: Callable[[str], None],
                 clock: Callable[[], float] = time.monotonic):
        self.case_dir = Path(case_dir)
        self.report = report
        self.clock = clock
        self.end_s = end_time(case_dir)
        self._started = clock()
        self._first: tuple[float, float] | None = None  # (wall clock, simulated time)

    def __call__(self) -> None:
        reached = solver_progress(self.case_dir)
        if reached is None:
            return
        now = self.clock()
        time_s, delta_t_s = reached
        if self._first is None:
            self._first = (now, time_s)
        wall, simulated = now - self._first[0], time_s - self._first[1]
        rate = simulated / wall if wall > 0 and simulated > 0 else None
        self.report(describe_progress(time_s, delta_t_s, self.end_s, now - self._started,
                                      rate))
