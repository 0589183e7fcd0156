"""Exceptions raised by mfflap. Every message names what was wrong and where."""

from __future__ import annotations

from typing import Any

#: the most characters of a value an error message repeats
SHOWN_CHARS = 60


def shown(value: Any) -> str:
    """``repr(value)``, cut to :data:`SHOWN_CHARS` characters with ``...`` so that an error
    about a huge value stays one readable line.

    Examples
    --------
    >>> shown(1.5)
    '1.5'
    >>> len(shown("x" * 100_000)) <= SHOWN_CHARS + 3
    True
    """
    text = repr(value)
    return text if len(text) <= SHOWN_CHARS else text[:SHOWN_CHARS] + "..."


class MfflapError(Exception):
    """Base class of every error mfflap raises on purpose.

    Errors pickle with their keyword arguments (case, key, path, line...), so one raised in
    a worker process or on a dask worker arrives whole in the process that waits for it.
    """

    def _keep(self, message: str, **kwargs: Any) -> None:
        self._message = message
        self._kwargs = kwargs

    @property
    def detail(self) -> str:
        """The message without the file, key or line it names (for a caller that names the
        place its own way, such as a command-line option)."""
        return getattr(self, "_message", self.args[0] if self.args else "")

    def __reduce__(self) -> tuple[Any, ...]:
        message = getattr(self, "_message", self.args[0] if self.args else "")
        return (_rebuild, (type(self), message, getattr(self, "_kwargs", {})))


def _rebuild(cls: type[MfflapError], message: str, kwargs: dict[str, Any]) -> MfflapError:
    return cls(message, **kwargs)


class ConfigError(MfflapError, ValueError):
    """An impossible or malformed configuration (case file, parameter, setting).

    Parameters
    ----------
    message
        What is wrong and what is allowed.
    source
        The file (or other source) the setting came from, if any.
    key
        Dotted key of the offending setting, if any.
    """

    def __init__(self, message: str, *, source: str | None = None, key: str | None = None):
        self._keep(message, source=source, key=key)
        self.source = source
        self.key = key
        where = ": ".join(p for p in (source, key) if p)
        super().__init__(f"{where}: {message}" if where else message)


class MotionError(MfflapError, ValueError):
    """A motion that cannot be evaluated (NaN samples, non-increasing times, bad period)."""


class ParseError(MfflapError, ValueError):
    """A solver output file that cannot be read as what it claims to be.

    Parameters
    ----------
    message
        What is wrong.
    path
        The file being parsed.
    line
        1-based line number of the offending line, if known.
    """

    def __init__(self, message: str, *, path: str | None = None, line: int | None = None):
        self._keep(message, path=path, line=line)
        self.path = path
        self.line = line
        where = str(path) if path else "<text>"
        if line is not None:
            where += f", line {line}"
        super().__init__(f"{where}: {message}")


class CfdRunError(MfflapError, RuntimeError):
    """A CFD run that crashed, diverged or timed out.

    Parameters
    ----------
    message
        What happened.
    case
        The case directory.
    log_tail
        The last lines of the solver log.
    """

    def __init__(self, message: str, *, case: str, log_tail: str = ""):
        self._keep(message, case=case, log_tail=log_tail)
        self.case = case
        self.log_tail = log_tail
        text = f"case {case}: {message}"
        if log_tail:
            text += "\n--- last log lines ---\n" + log_tail
        super().__init__(text)


class UnreadableRecordError(MfflapError, OSError):
    """A results or record file whose bytes cannot be read back (cut short by a copy or a
    full disk, or a compressed chunk damaged on disk).

    Parameters
    ----------
    message
        What could not be read.
    path
        The file.
    dataset
        The HDF5 dataset or group whose read failed, if known.
    """

    def __init__(self, message: str, *, path: str, dataset: str | None = None):
        self._keep(message, path=path, dataset=dataset)
        self.path = path
        self.dataset = dataset
        where = f"{path}" + (f", {dataset}" if dataset else "")
        super().__init__(f"{where}: {message}")


class SolverDiverged(CfdRunError):
    """A CFD run whose numerics broke down: its time step collapsed below the runner's
    floor, or its Courant number exploded.

    Parameters
    ----------
    message, case, log_tail
        As :class:`CfdRunError`.
    kind
        :data:`TIME_STEP_COLLAPSED` or :data:`COURANT_EXPLODED`.
    time_s
        The flow time at which it happened, s.
    """

    def __init__(self, message: str, *, case: str, log_tail: str = "", kind: str,
                 time_s: float):
        super().__init__(message, case=case, log_tail=log_tail)
        self._keep(message, case=case, log_tail=log_tail, kind=kind, time_s=time_s)
        self.kind = kind
        self.time_s = time_s


#: :attr:`SolverDiverged.kind` of a time step that fell below the floor
TIME_STEP_COLLAPSED = "time step collapsed"
#: :attr:`SolverDiverged.kind` of a Courant number beyond the abort limit
COURANT_EXPLODED = "Courant number exploded"


class RunStoppedByWatch(CfdRunError):
    """A CFD run stopped while running by a check of its output (a run's ``watch``).

    Parameters
    ----------
    message, case, log_tail
        As :class:`CfdRunError`.
    reason
        What the check found, as it gave it (for the force bound, an
        :class:`~mfflap.records.force_envelope.EnvelopeBreach`).
    """

    def __init__(self, message: str, *, case: str, log_tail: str = "", reason: Any = None):
        super().__init__(message, case=case, log_tail=log_tail)
        self._keep(message, case=case, log_tail=log_tail, reason=reason)
        self.reason = reason


class RepeatedTimes(ParseError):
    """A force log whose times stop increasing (the time step fell below the precision the
    times are written with).

    Parameters
    ----------
    message, path, line
        As :class:`ParseError`.
    time_s
        The last time before they repeat, s.
    """

    def __init__(self, message: str, *, path: str | None = None, line: int | None = None,
                 time_s: float):
        super().__init__(message, path=path, line=line)
        self._keep(message, path=path, line=line, time_s=time_s)
        self.time_s = time_s


class OutputExistsError(MfflapError, FileExistsError):
    """An output folder that already holds another run's outputs, which a new run would
    overwrite or mix with its own.

    Parameters
    ----------
    message
        What the folder holds and how to go on.
    path
        The folder.
    held
        The names of the run outputs found in it.
    """

    def __init__(self, message: str, *, path: str, held: tuple[str, ...] = ()):
        self._keep(message, path=path, held=held)
        self.path = path
        self.held = tuple(held)
        super().__init__(f"{path}: {message}")
