"""A Ctrl-C during an IPOPT solve stops the caller, as it does everywhere else.

CasADi runs Python's signal handlers while IPOPT iterates. The KeyboardInterrupt that a
Ctrl-C raises there (or the :class:`~mfflap.cli.stop_signals.StopRequested` of a SIGTERM or
SIGUSR1 in a command) is caught in CasADi's C++ layer: it logs a warning, IPOPT returns
``NonIpopt_Exception_Thrown`` and the caller would go on with a half-solved motion, stored
as a result, as if nothing had been asked. :func:`interrupts_kept` notes what the handlers
raised and raises it again once the solver has returned.
"""

from __future__ import annotations

import signal
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from types import FrameType

#: the signals whose Python handlers are watched (those that are Python functions)
WATCHED_SIGNALS = (signal.SIGINT, signal.SIGTERM, signal.SIGUSR1)


@contextmanager
def interrupts_kept() -> Iterator[None]:
    """Raise, after the block, what a signal handler raised inside it and something there
    caught (CasADi's IPOPT interface does).

    Only handlers that are Python functions are watched (Python's own Ctrl-C handler, and
    mfflap's command handlers); a signal left to the system, or ignored, is left alone.
    Outside the main thread (where Python cannot set handlers) the block runs unchanged.
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    raised: list[BaseException] = []
    previous = {number: signal.getsignal(number) for number in WATCHED_SIGNALS}

    def noted(number: int, frame: FrameType | None) -> None:
        try:
            previous[number](number, frame)  # type: ignore[operator]
        except BaseException as exc:
            raised.append(exc)
            raise

    watched = {number for number, handler in previous.items() if callable(handler)}
    for number in watched:
        signal.signal(number, noted)
    try:
        yield
    finally:
        for number in watched:
            signal.signal(number, previous[number])
    if raised:
        raise raised[0]
