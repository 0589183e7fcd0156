"""Campaign records whose identified window mixes two set-ups.

:func:`~mfflap.cfd.openfoam.run_motion.run_motion` retries a run whose time step collapses, or
whose forces leave what the motion can drive, from its last written time with the
inletOutlet far field or a lower Courant limit, unless asked to rerun it from t = 0 s
(``retries_from_start``). Resumed after the identification's start-up (the case file's
``[identification] discard_time``, or the case's ramp if later), the run's fitted window ran
two set-ups: the stretch before the retry with the settings before it. Identification fits
such a record as it is, with a note (:func:`mfflap.identification.data.prepare_case`);
``mfflap campaign status`` names it, and ``mfflap campaign run --rerun-mixed`` keeps it
aside (:data:`~mfflap.records.record.MIXED_SUFFIX`) and reruns its case as one set-up. On
the campaigns of ``campaigns/`` such reruns moved single runs by several per cent and the
identified coefficients by less than their bootstrap spread (campaigns/README.md).
"""

from __future__ import annotations

from mfflap.config import IdentificationGrid
from mfflap.records.as_run import as_run_since_s
from mfflap.records.record import CfdRecord

#: the identification's default start-up left out of the fit, s
DEFAULT_DISCARD_TIME_S = IdentificationGrid().discard_time


def fitted_from_s(record: CfdRecord, discard_time_s: float = DEFAULT_DISCARD_TIME_S) -> float:
    """Where identification's window of ``record`` begins, s: the later of
    ``discard_time_s`` and the case's start-up ramp."""
    return max(discard_time_s, float(record.parameters.get("ramp_time", 0.0)))


def mixed_since_s(record: CfdRecord,
                  discard_time_s: float = DEFAULT_DISCARD_TIME_S) -> float | None:
    """The flow time, s, from which a retry resumed ``record``'s run with other settings, if
    that lies within its identified window (:func:`fitted_from_s`); None when the window
    ran one set-up (no retry, a retry before the window, or every retry rerun from t = 0 s)."""
    since = as_run_since_s(record)
    return since if since > fitted_from_s(record, discard_time_s) else None


def describe_mixed(record: CfdRecord, discard_time_s: float = DEFAULT_DISCARD_TIME_S) -> str:
    """One line on why ``record``'s identified window mixes two set-ups and how to rerun it,
    '' if it does not."""
    since = mixed_since_s(record, discard_time_s)
    if since is None:
        return ""
    return (f"a retry resumed it from t = {since:.4g} s with other settings, within the "
            f"identified window from t = {fitted_from_s(record, discard_time_s):.4g} s "
            f"({record.provenance.get('retries')}); `campaign run --rerun-mixed` reruns it "
            "as one set-up")


__all__ = ["DEFAULT_DISCARD_TIME_S", "describe_mixed", "fitted_from_s", "mixed_since_s"]
