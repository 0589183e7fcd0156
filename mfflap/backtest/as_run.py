"""Whether two CFD runs ran alike: the settings each held over its last stretch.

A run whose time step collapses, or whose forces leave what the motion can drive, is
retried by :func:`~mfflap.campaign.openfoam_run.run_motion` with the inletOutlet far field,
half the Courant limit or upwind k and epsilon; the record keeps what it ran with last
(``as_run_*`` provenance, else the ``solver_*`` it was written with). Two back-tests
compared, as a trust-region step compares its centre's CFD with its trial's, measure the
motion's change only if they ran alike: at the trust series' beta = 0.5 optimum, max Co 2
instead of 4 moves the settled mean thrust by 7 % (README, "How long a back-test runs").
"""

from __future__ import annotations

from mfflap.campaign.records import CfdRecord

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


__all__ = ["COMPARED", "as_run_differences"]
