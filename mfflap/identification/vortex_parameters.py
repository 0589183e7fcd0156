"""The discrete-vortex model's free parameters identified from CFD records.

The model (:mod:`mfflap.hydro.discrete_vortex`) has two parameters no theory fixes: the
critical leading-edge suction parameter above which the leading edge sheds, and the core
radius of its vortices. Both enter non-linearly (shedding switches on and off), so they are
not fitted by least squares like Morison's coefficients: every pair of a grid is run
through every record's motion from rest, and the pair whose F_n follows CFD's best (the
root mean square over the records of each one's NRMSE over its last periods, so that every
record weighs alike, as Morison's per-case scaling does) is the identified one. The whole
grid is kept, so the flatness of the optimum is seen, not assumed.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace

import numpy as np

from mfflap.errors import ConfigError
from mfflap.hydro.discrete_vortex import VortexModelSettings, simulate_vortex_model
from mfflap.metrics import nrmse
from mfflap.parameters import Fluid, FreeStream, Plate

#: the critical leading-edge suction parameters tried by default (inf: never shedding)
CRITICAL_LESP_GRID = (0.1, 0.15, 0.2, 0.3, float("inf"))
#: the core radii tried by default, in chords
CORE_RADIUS_GRID = (0.01, 0.02, 0.05)
#: an NRMSE above this is a run that blew up, scored as such (the model's F_n is unbounded)
BLOWN_UP_NRMSE = 1.0


@dataclass(frozen=True)
class VortexParameterFit:
    """The grid searched and the pair identified.

    Attributes
    ----------
    critical_lesp, core_radius_chords : float
        The identified pair (lowest ``score``).
    grid : list of (critical LESP, core radius in chords, score, blown-up records)
        Every pair tried; score: RMS over the records of each record's F_n NRMSE.
    record_nrmse : dict
        Each record's F_n NRMSE at the identified pair.
    """

    critical_lesp: float
    core_radius_chords: float
    grid: list[tuple[float, float, float, int]]
    record_nrmse: dict[str, float]

    @property
    def score(self) -> float:
        """The identified pair's RMS NRMSE of F_n."""
        return min(row[2] for row in self.grid)

    def settings(self, base: VortexModelSettings | None = None) -> VortexModelSettings:
        """``base`` (the defaults if omitted) with the identified pair."""
        return replace(base or VortexModelSettings(), critical_lesp=self.critical_lesp,
                       core_radius_chords=self.core_radius_chords)


def record_nrmse(record, settings: VortexModelSettings, plate: Plate | None = None,
                 fluid: Fluid | None = None, stream: FreeStream | None = None,
                 steps_per_period: int = 200, periods: float = 2.0) -> float:
    """The vortex model's F_n NRMSE against one CFD record over its last ``periods``
    periods, the model run through the record's motion from rest at ``steps_per_period``
    uniform steps; :data:`BLOWN_UP_NRMSE` or above for a run that blew up.

    Raises
    ------
    MfflapError
        A record that names neither its period nor its frequency, or is shorter than the
        periods compared (:meth:`~mfflap.records.record.CfdRecord.last_periods`).
    """
    period, start = record.last_periods(periods)
    t = np.asarray(record.state.time, dtype=float)
    state = record.state.on_uniform_time(period / steps_per_period, start=0.0)
    loads = simulate_vortex_model(state, plate, fluid, stream, settings).loads
    window = t >= start
    model = np.interp(t[window], loads.time, loads.normal_force)
    if not np.all(np.isfinite(model)):
        return float("inf")
    return float(nrmse(model, record.loads.normal_force[window]))


def identify_vortex_parameters(records: Sequence, plate: Plate | None = None,
                               fluid: Fluid | None = None, stream: FreeStream | None = None,
                               critical_lesp: Sequence[float] = CRITICAL_LESP_GRID,
                               core_radius_chords: Sequence[float] = CORE_RADIUS_GRID,
                               base: VortexModelSettings | None = None,
                               steps_per_period: int = 200,
                               progress: Callable[[str], None] | None = None
                               ) -> VortexParameterFit:
    """Search the grid of critical LESP x core radius for the pair whose F_n follows the
    records' best (:func:`record_nrmse`, root mean square over the records).

    Raises
    ------
    ConfigError
        No records, or an empty or non-positive grid (key ``critical_lesp`` or
        ``core_radius_chords``).

    Examples
    --------
    >>> from mfflap.records.record import fixture_dir, read_records
    >>> runs = read_records(fixture_dir("backtest_main_job"))[:1]
    >>> fit = identify_vortex_parameters(runs, critical_lesp=(0.2, float("inf")),
    ...                                  core_radius_chords=(0.02,))
    >>> len(fit.grid), fit.score < 0.5
    (2, True)
    """
    if not records:
        raise ConfigError("no CFD records to identify the vortex model's parameters from",
                          key="records")
    for key, values in (("critical_lesp", critical_lesp),
                        ("core_radius_chords", core_radius_chords)):
        if not len(values) or any(not v > 0 for v in values):
            raise ConfigError(f"{key} grid {list(values)}: give one value or more, each > 0",
                              key=key)
    base = base or VortexModelSettings()
    grid, per_pair = [], {}
    for lesp in critical_lesp:
        for core in core_radius_chords:
            settings = replace(base, critical_lesp=float(lesp), core_radius_chords=float(core))
            errors = {r.name: record_nrmse(r, settings, plate, fluid, stream,
                                           steps_per_period) for r in records}
            values = np.minimum(np.array(list(errors.values())), 10 * BLOWN_UP_NRMSE)
            blown = int(np.sum(values >= BLOWN_UP_NRMSE))
            score = float(np.sqrt(np.mean(values**2)))
            grid.append((float(lesp), float(core), score, blown))
            per_pair[(float(lesp), float(core))] = errors
            if progress is not None:
                progress(f"critical LESP {lesp:g}, core {core:g} c: RMS NRMSE of F_n "
                         f"{score:.1%}" + (f", {blown} blown up" if blown else ""))
    best = min(grid, key=lambda row: row[2])
    return VortexParameterFit(best[0], best[1], grid, per_pair[(best[0], best[1])])


__all__ = ["BLOWN_UP_NRMSE", "CORE_RADIUS_GRID", "CRITICAL_LESP_GRID", "VortexParameterFit",
           "identify_vortex_parameters", "record_nrmse"]
