"""SIGTERM and SIGUSR1 stop an mfflap command as Ctrl-C does.

A batch system ends a job with a signal, not a Ctrl-C: SLURM's ``--signal=USR1@120`` sends
SIGUSR1 to the job's processes two minutes before its time limit, ``scancel`` and
``kill`` send SIGTERM. Python would die at once on either, and the solver it started would
then be stopped by its death signal (:func:`mfflap.cfd.openfoam.runner.dies_with_caller`)
without writing. While a command runs, both raise :class:`StopRequested` in its main thread
instead, a KeyboardInterrupt, so every command stops as on Ctrl-C: the solver writes the
time step it reached and stops (:func:`mfflap.cfd.openfoam.runner.run_application`), and
the command says where the next run resumes.
"""

from __future__ import annotations

import signal
import threading
from collections.abc import Iterator
from contextlib import contextmanager

#: the signals that stop a command as Ctrl-C does
STOP_SIGNALS = (signal.SIGTERM, signal.SIGUSR1)


class StopRequested(KeyboardInterrupt):
    """A stop asked for by a signal (its name is the message)."""


def _raise_stop(signum: int, frame: object) -> None:
    raise StopRequested(signal.Signals(signum).name)


@contextmanager
def stop_signals_as_interrupt() -> Iterator[None]:
    """Within the block, :data:`STOP_SIGNALS` raise :class:`StopRequested` in the main
    thread; the handlers before are restored after it. Outside the main thread (where
    Python cannot set handlers) the block runs unchanged."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = {number: signal.signal(number, _raise_stop) for number in STOP_SIGNALS}
    try:
        yield
    finally:
        for number, handler in previous.items():
            signal.signal(number, handler)
