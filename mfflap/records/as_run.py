"""Whether two CFD runs ran alike: the settings each held over its last stretch.

A run whose time step collapses, or whose forces leave what the motion can drive, is retried
by :func:`~mfflap.cfd.openfoam.run_motion.run_motion` with the inletOutlet far field, half the
Courant limit or upwind k and epsilon; the record keeps what it ran with last (``as_run_*``
provenance, else the ``solver_*`` it was written with). Two back-tests compared, as a
trust-region step compares its centre's CFD with its trial's, measure the motion's change
only if they ran alike: at the trust series' beta = 0.5 optimum, max Co 2 instead of 4 moves
the settled mean thrust by 7 % (docs/findings/optimised_motions.md, "How long a back-test runs").
"""

from __future__ import annotations

from mfflap.records.record import CfdRecord
from mfflap.records.retries import RERUN_REQUESTED, legacy_restart_s, retries_from_json

#: (what it is called, the as-run provenance key, the written one it falls back to)
COMPARED = (("mesh", "mesh", "mesh"),
            ("max Co", "as_run_max_courant", "solver_max_courant"),
            ("far field", "as_run_far_field", "solver_far_field"),
            ("k-epsilon convection", "as_run_turbulence_convection",
             "solver_turbulence_convection"),
            ("wall treatment", "as_run_wall_treatment", "solver_wall_treatment"))


def _setting(record: CfdRecord, as_run: str, written: str):
    value = record.provenance.get(as_run, record.provenance.get(written))
    return float(value) if isinstance(value, int | float) else value


def as_run_differences(first: CfdRecord, second: CfdRecord) -> list[str]:
    """How ``second`` ran otherwise than ``first`` (each ``"<setting> <first> against
    <second>"``); empty when they ran alike or a record does not say. A Courant limit
    within a millionth counts as alike (``mfflap backtest --repeat``'s copies)."""
    out = []
    for name, as_run, written in COMPARED:
        a, b = _setting(first, as_run, written), _setting(second, as_run, written)
        if a is None or b is None:
            continue
        if isinstance(a, float) and isinstance(b, float):
            if abs(a - b) <= 1e-5 * max(abs(a), abs(b)):
                continue
            out.append(f"{name} {a:g} against {b:g}")
        elif a != b:
            out.append(f"{name} {a} against {b}")
    return out


def as_run_since_s(record: CfdRecord) -> float:
    """The flow time since which ``record`` ran the settings it ran last with (its
    ``as_run_*`` provenance), s: 0 when it ran one set-up throughout (no retry, or every
    retry reran it from t = 0 s, as ``run_motion(..., retries_from_start=True)`` does), else
    the written time its last retry resumed from. Its cycles before then ran with the
    settings before that retry.

    The retries are read from the record's ``retry_log`` (:mod:`mfflap.records.retries`);
    a record written before that was kept is read from its text (``retries``)."""
    logged = record.provenance.get("retry_log")
    if logged is None:
        return legacy_restart_s(str(record.provenance.get("retries") or ""))
    retries = [r for r in retries_from_json(str(logged), f"{record.name}: retry_log")
               if r.cause != RERUN_REQUESTED]
    return float(retries[-1].resumed_from_s) if retries else 0.0


def describe_as_run(record: CfdRecord) -> str:
    """How ``record``'s run ran at its end, in one line: each setting of :data:`COMPARED`
    its provenance gives, and since when if a retry changed them part-way
    (:func:`as_run_since_s`); '' if it says none."""
    said = []
    for name, as_run, written in COMPARED:
        value = _setting(record, as_run, written)
        if value is not None:
            said.append(f"{name} {value:g}" if isinstance(value, float) else f"{name} {value}")
    since = as_run_since_s(record)
    if said and since > 0.0:
        said.append(f"since t = {since:.4g} s (a retry resumed it)")
    return ", ".join(said)


__all__ = ["COMPARED", "as_run_differences", "as_run_since_s", "describe_as_run"]
