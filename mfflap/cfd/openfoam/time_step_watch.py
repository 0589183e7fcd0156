"""Watch a growing solver log for a collapsed time step, every line of it once.

pimpleFoam with an adjustable time step holds the Courant number at its limit while an
instability grows: the time step goes to zero instead, and the run may never end. The
collapse can also be brief. On the coarse mesh a back-test's time step fell below 1e-7 s for
33 of its steps around t = 4.32 s (to 1.5e-8 s) and recovered within a second of wall time,
with forces near 1e9 N there; a watch that read only the last time step of the log every
2 s did not see it, and the run went on to its end. :class:`TimeStepWatch` reads every line
the run writes, as the log grows, so no step escapes it, however short the collapse. It
keeps the largest Courant number of the run too (an explosion of the Courant number, with
a fixed or a lagging time step, is the other way a run diverges).
"""

from __future__ import annotations

import math
import re
from pathlib import Path

# a step's Courant number, time step and time lines, each alone on its line
# (tabulatedAccelerationSource also starts lines with "Time = "), in log order: pimpleFoam
# prints a step's Courant numbers and deltaT, then the time it reaches
_STEP_OR_TIME = re.compile(rb"^(?:(deltaT|Time) = |Courant Number mean: \S+ max: )"
                           rb"([-+0-9.eE]+)[ \t\r]*$", re.M)


class TimeStepWatch:
    """The time steps and Courant numbers of one run of a solver, read from its log as the
    log grows.

    Parameters
    ----------
    log_path
        The solver's log (it need not exist yet).
    min_time_step_s
        A time step below this, s, is a collapse.
    start_byte
        Where this run's lines begin in the log (a restart appends to its run's log, and an
        earlier run's collapse above them is not this run's).

    Attributes
    ----------
    collapse
        (time step s, flow time s) of the first step below ``min_time_step_s``, the time
        being the one that step reached (the time before it while that line is not yet
        written; nan if the log has no time line yet); None while there is none.
    smallest_time_step_s
        The smallest time step read so far, s (inf before the first).
    largest_courant
        (largest maximum Courant number read so far, the flow time its step began at); (0,
        nan) before the first.
    """

    def __init__(self, log_path: str | Path, min_time_step_s: float, start_byte: int = 0):
        self.log_path = Path(log_path)
        self.min_time_step_s = min_time_step_s
        self.collapse: tuple[float, float] | None = None
        self.smallest_time_step_s = math.inf
        self.largest_courant = (0.0, math.nan)
        self._next_byte = start_byte
        self._last_time_s = math.nan
        self._awaiting_time = False  # the collapse's step has no time line yet

    def read(self, *, to_end: bool = False) -> tuple[float, float] | None:
        """Read the lines the log gained since the last call; return :attr:`collapse`.

        Parameters
        ----------
        to_end
            Read a last line that has no newline yet too (the solver has exited). Without
            it such a line waits for the next call, so that a number is never read half
            written.
        """
        if not self.log_path.is_file():
            return self.collapse
        with open(self.log_path, "rb") as fh:
            fh.seek(self._next_byte)
            gained = fh.read()
        if not to_end:
            gained = gained[:gained.rfind(b"\n") + 1]  # whole lines only
        self._next_byte += len(gained)
        for found in _STEP_OR_TIME.finditer(gained):
            try:
                value = float(found[2])
            except ValueError:  # a garbled number: no step to judge
                continue
            if found[1] is None:  # a Courant number line
                if value > self.largest_courant[0]:
                    self.largest_courant = (value, self._last_time_s)
                continue
            if found[1] == b"Time":
                self._last_time_s = value
                if self._awaiting_time:
                    self.collapse = (self.collapse[0], value)
                    self._awaiting_time = False
                continue
            self.smallest_time_step_s = min(self.smallest_time_step_s, value)
            if self.collapse is None and value < self.min_time_step_s:
                self.collapse = (value, self._last_time_s)
                self._awaiting_time = True
        return self.collapse
