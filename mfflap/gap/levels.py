"""The discrete-vortex model as a level of the gap diagnosis: what its residual against
CFD leaves of Morison's.

Both models run through each record's motion (the vortex model from rest, at uniform
steps); over the record's last periods, each one's F_n residual against CFD is
summed, and the share of Morison's residual the vortex model removes,
1 - SSE_vortex / SSE_morison, is what the vortex level explains that Morison cannot (negative
where it does worse). The residual Morison leaves, the diagnosis's candidates work on; the
share says how much of it a model with a wake and leading-edge shedding accounts for, record
by record.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace

import numpy as np

from mfflap.errors import MfflapError
from mfflap.hydro.discrete_vortex import VortexModelSettings, simulate_vortex_model
from mfflap.hydro.morison import MorisonModel
from mfflap.metrics import nrmse

#: periods at the end of each record that are compared (the start-up transient left out)
COMPARED_PERIODS = 2.0
#: vortex-model steps a period
STEPS_PER_PERIOD = 200


@dataclass(frozen=True)
class LevelResidual:
    """One record's F_n residual at both levels, over its last :data:`COMPARED_PERIODS`.

    Attributes
    ----------
    record : str
    morison_nrmse, vortex_nrmse : float
        F_n NRMSE against CFD (fraction of CFD's range).
    explained_share : float
        1 - SSE_vortex / SSE_morison: the share of Morison's residual (sum of squares) the
        vortex model removes; negative where it does worse; NaN where Morison's is zero.
    """

    record: str
    morison_nrmse: float
    vortex_nrmse: float
    explained_share: float
    #: CFD's own F_n NRMSE: its last period against the period before (normalised by the
    #: last period's range), the closest a model that repeats each cycle can come
    cfd_repeat_nrmse: float = float("nan")
    #: "diagnosed" for a case the diagnosis fitted, "held out" for a run it never saw
    group: str = "diagnosed"


def level_residuals(records: Sequence, morison: MorisonModel,
                    settings: VortexModelSettings | None = None,
                    progress: Callable[[str], None] | None = None) -> list[LevelResidual]:
    """Each record's F_n residual against Morison (as configured) and the vortex model.

    Examples
    --------
    >>> from mfflap.records.record import fixture_dir, read_records
    >>> (row,) = level_residuals(read_records(fixture_dir("backtest_main_job"))[:1],
    ...                          MorisonModel())
    >>> row.vortex_nrmse < row.morison_nrmse
    True

    Raises
    ------
    MfflapError
        A record that names no period, or is shorter than the periods compared.
    """
    settings = settings or VortexModelSettings()
    out = []
    for record in records:
        period, start = record.last_periods(COMPARED_PERIODS)
        t = np.asarray(record.state.time, dtype=float)
        window = t >= start
        cfd = np.asarray(record.loads.normal_force, dtype=float)[window]
        uniform = record.state.on_uniform_time(period / STEPS_PER_PERIOD, start=0.0)
        vortex = simulate_vortex_model(uniform, morison.plate, morison.fluid, morison.stream,
                                       settings).loads
        v = np.interp(t[window], vortex.time, vortex.normal_force)
        m = np.asarray(morison.loads(record.state).normal_force, dtype=float)[window]
        sse_m, sse_v = float(np.sum((m - cfd) ** 2)), float(np.sum((v - cfd) ** 2))
        row = LevelResidual(record.name, float(nrmse(m, cfd)), float(nrmse(v, cfd)),
                            1.0 - sse_v / sse_m if sse_m > 0 else float("nan"),
                            record.repeat_nrmse())
        out.append(row)
        if progress is not None:
            progress(f"{row.record}: F_n NRMSE Morison {row.morison_nrmse:.1%}, vortex "
                     f"{row.vortex_nrmse:.1%}, explained {row.explained_share:+.0%}")
    return out


@dataclass
class LevelComparison:
    """The vortex level over a diagnosis's records: a row per record it could compare.

    Attributes
    ----------
    rows : list of LevelResidual
    excluded : dict of str to str
        Records it could not compare (no period, shorter than :data:`COMPARED_PERIODS`),
        with why.
    """

    rows: list[LevelResidual]
    excluded: dict[str, str]

    def summary(self, group: str | None = None) -> dict[str, float | int]:
        """Medians over the rows (of ``group`` only, if given): each level's F_n NRMSE and
        CFD's own, the share of Morison's residual the vortex model removes, and on how many
        records it removes some (NaN medians with no rows).

        Examples
        --------
        >>> rows = [LevelResidual("a", 0.2, 0.1, 0.75, 0.05),
        ...         LevelResidual("b", 0.1, 0.12, -0.44, 0.04, "held out")]
        >>> LevelComparison(rows, {}).summary("diagnosed")["median_explained_share"]
        0.75
        """
        rows = [r for r in self.rows if group is None or r.group == group]

        def median(key: str) -> float:
            values = np.array([getattr(r, key) for r in rows], dtype=float)
            values = values[np.isfinite(values)]
            return float(np.median(values)) if values.size else float("nan")

        shares = np.array([r.explained_share for r in rows], dtype=float)
        return {"n_records": len(rows), "median_morison_nrmse": median("morison_nrmse"),
                "median_vortex_nrmse": median("vortex_nrmse"),
                "median_cfd_repeat_nrmse": median("cfd_repeat_nrmse"),
                "median_explained_share": median("explained_share"),
                "records_explained": int(np.sum(shares > 0))}


def compare_levels(records: Sequence, morison: MorisonModel,
                   settings: VortexModelSettings | None = None, *,
                   held_out: Sequence = (),
                   progress: Callable[[str], None] | None = None) -> LevelComparison:
    """:func:`level_residuals` of ``records`` (the diagnosed cases') and of ``held_out``
    (runs the diagnosis never saw), each record that cannot be compared left out with why
    rather than ending the comparison.

    Examples
    --------
    >>> from mfflap.records.record import fixture_dir, read_records
    >>> runs = read_records(fixture_dir("backtest_main_job"))
    >>> levels = compare_levels(runs[:1], MorisonModel(), held_out=runs[1:2])
    >>> [row.group for row in levels.rows], levels.excluded
    (['diagnosed', 'held out'], {})
    """
    rows, excluded = [], {}
    for group, group_records in (("diagnosed", records), ("held out", held_out)):
        for record in group_records:
            try:
                (row,) = level_residuals([record], morison, settings, progress)
            except MfflapError as exc:
                excluded[record.name] = str(exc)
                continue
            rows.append(replace(row, group=group))
    return LevelComparison(rows, excluded)


__all__ = ["COMPARED_PERIODS", "STEPS_PER_PERIOD", "LevelComparison", "LevelResidual",
           "compare_levels", "level_residuals"]
