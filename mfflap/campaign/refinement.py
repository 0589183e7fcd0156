"""The mesh and time-step uncertainty of campaign records, from refined runs of their motions.

A refinement campaign reruns some motions of a coarse campaign on a finer mesh or at a
smaller Courant limit, otherwise on the same set-up. :func:`refinement_change` sets one
refined run against its coarse record (the F_n histories over their common whole periods,
and the three means with Roache's two-level index); :func:`add_refinement` stores that in
every coarse record that has a refined counterpart (:mod:`mfflap.records.refinement`), so
each record states its own numerical uncertainty wherever it has been measured.
"""

from __future__ import annotations

import hashlib
from pathlib import Path

import numpy as np

from mfflap.cfd.gci import two_level_index
from mfflap.errors import ConfigError, MfflapError
from mfflap.metrics import nrmse, pearson
from mfflap.performance import thrust_and_power
from mfflap.records.cycle_scatter import SAMPLES_PER_PERIOD
from mfflap.records.record import CfdRecord, read_record, record_paths
from mfflap.records.refinement import KINDS, RefinementChange, write_refinement
from mfflap.results import edited_results

#: the provenance key that says each kind of refinement was made
_REFINED_KEY = {"mesh": "n_cells", "time_step": "solver_max_courant"}


def refinement_ratio(coarse: CfdRecord, refined: CfdRecord, kind: str) -> float:
    """r = h_coarse / h_fine of a pair: sqrt of the cell-count ratio (the meshes are 2-D,
    one cell deep) for ``"mesh"``, the ratio of the Courant limits for ``"time_step"``.

    Raises
    ------
    MfflapError
        Naming both records: their provenance lacks the key, or the refined run is not
        finer.
    """
    key = _REFINED_KEY[kind]
    try:
        a, b = float(coarse.provenance[key]), float(refined.provenance[key])
    except KeyError as err:
        raise MfflapError(f"records {coarse.name} and {refined.name}: no {key} in their "
                          "provenance to measure the refinement by") from err
    ratio = (b / a) ** 0.5 if kind == "mesh" else a / b
    if not ratio > 1:
        raise MfflapError(f"record {refined.name} is not a {kind} refinement of "
                          f"{coarse.name}: {key} {b:g} against {a:g}")
    return float(ratio)


def refinement_kind(coarse: CfdRecord, refined: CfdRecord) -> str:
    """What ``refined`` refines of ``coarse``: ``"mesh"`` when their meshes differ,
    ``"time_step"`` when their Courant limits do (their provenance's ``mesh`` and
    ``solver_max_courant``).

    Raises
    ------
    MfflapError
        Naming both records, when both differ (two refinements at once give neither's part)
        or neither does.
    """
    mesh = coarse.provenance.get("mesh") != refined.provenance.get("mesh")
    step = coarse.provenance.get("solver_max_courant") != \
        refined.provenance.get("solver_max_courant")
    if mesh and step:
        raise MfflapError(f"records {coarse.name} and {refined.name} differ in both the mesh "
                          "and the Courant limit: a refinement varies one of them")
    if not (mesh or step):
        raise MfflapError(f"records {coarse.name} and {refined.name} have the same mesh "
                          "and Courant limit: nothing was refined")
    return "mesh" if mesh else "time_step"


def _sha256(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def refinement_change(coarse: CfdRecord, refined: CfdRecord, kind: str, *,
                      refined_path: str | Path = "", periods: int | None = None
                      ) -> RefinementChange:
    """How ``coarse``'s answer moves in ``refined``, the same motion on a finer mesh
    (``kind = "mesh"``) or at a smaller time step (``"time_step"``).

    Both are compared over their last ``periods`` whole periods (by default all after the
    start-up ramp but the first, as the cycle scatter counts them), on
    :data:`~mfflap.records.cycle_scatter.SAMPLES_PER_PERIOD` samples a period.

    Examples
    --------
    >>> from mfflap.hydro.loads import Loads
    >>> from mfflap.kinematics.continuous import HarmonicMotion
    >>> t = np.linspace(0.0, 4.0, 801)
    >>> state = HarmonicMotion(1.0, 0.1, 0.3).sample(t)
    >>> def run(scale, cells):
    ...     fn = scale * np.sin(2 * np.pi * t)
    ...     return CfdRecord("c", state, Loads(t, fn, 0 * t, 0 * t),
    ...                      {"kind": "harmonic", "frequency": 1.0, "ramp_time": 0.25},
    ...                      {"n_cells": cells})
    >>> change = refinement_change(run(1.0, 10_000), run(1.1, 40_000), "mesh")
    >>> change.refinement_ratio, change.n_cycles, round(change.normal_force_nrmse, 4)
    (2.0, 2, 0.0354)
    >>> round(change.relative_change("rms_normal_force"), 6)
    0.1

    Raises
    ------
    ConfigError
        For a ``kind`` not in :data:`~mfflap.records.refinement.KINDS`.
    MfflapError
        Naming the records: different motions, no period, no whole period in common, or a
        refined run that is not finer.
    """
    if kind not in KINDS:
        raise ConfigError(f"no refinement {kind!r}: one of {list(KINDS)}", key="kind")
    if coarse.parameters != refined.parameters:
        differ = sorted(k for k in set(coarse.parameters) | set(refined.parameters)
                        if coarse.parameters.get(k) != refined.parameters.get(k))
        raise MfflapError(f"records {coarse.name} and {refined.name} are different motions "
                          f"(they differ in {', '.join(differ)})")
    ratio = refinement_ratio(coarse, refined, kind)
    period = coarse.period
    if not (np.isfinite(period) and period > 0):
        raise MfflapError(f"record {coarse.name} names no period nor frequency")
    end = min(float(coarse.time[-1]), float(refined.time[-1]))
    start = max(float(coarse.parameters.get("ramp_time", 0.0)), float(coarse.time[0]),
                float(refined.time[0]))
    available = int(np.floor((end - start) / period + 1e-9))
    if periods is None:
        periods = available - 1 if available >= 3 else available
    if periods < 1 or periods > available:
        raise MfflapError(f"records {coarse.name} and {refined.name}: {available} whole "
                          f"period(s) in common after the start-up, {periods} asked for")
    at = end - periods * period + (np.arange(periods * SAMPLES_PER_PERIOD) + 0.5) * (
        period / SAMPLES_PER_PERIOD)

    def means(record: CfdRecord) -> tuple[np.ndarray, np.ndarray]:
        thrust, power = thrust_and_power(record.loads, record.state)
        fn = np.interp(at, record.time, record.loads.normal_force)
        return fn, np.array([np.interp(at, record.time, thrust).mean(),
                             np.interp(at, record.time, power).mean(),
                             np.sqrt(np.mean(fn**2))])

    fn_coarse, coarse_means = means(coarse)
    fn_refined, refined_means = means(refined)
    gci = [two_level_index(float(a), float(b), ratio).gci_coarse
           for a, b in zip(coarse_means, refined_means, strict=True)]
    pairs = [(float(a), float(b)) for a, b in zip(coarse_means, refined_means, strict=True)]
    path = Path(refined_path) if refined_path else None
    return RefinementChange(
        kind=kind, refined_record=path.name if path else refined.name,
        refined_folder=str(path.parent) if path else "",
        refined_sha256=_sha256(path) if path else "", refinement_ratio=ratio,
        n_cycles=int(periods),
        normal_force_nrmse=_nrmse_against_coarse(fn_coarse, fn_refined),
        normal_force_pearson=float(pearson(fn_coarse, fn_refined)),
        mean_thrust_n=pairs[0], mean_power_w=pairs[1], rms_normal_force_n=pairs[2],
        gci_mean_thrust=float(gci[0]), gci_mean_power=float(gci[1]),
        gci_rms_normal_force=float(gci[2]))


def _nrmse_against_coarse(fn_coarse: np.ndarray, fn_refined: np.ndarray) -> float:
    """RMS of the difference normalised by the coarse record's range: the record a model is
    scored against is the coarse one, so its range is the yardstick."""
    return float(nrmse(fn_refined, fn_coarse))


def add_refinement(coarse_folder: str | Path, refined_folder: str | Path
                   ) -> list[tuple[str, RefinementChange]]:
    """Store in each record of ``coarse_folder`` that has a counterpart of the same name in
    ``refined_folder`` how it moves there (its kind, mesh or time step, from what differs
    between the two: :func:`refinement_kind`; a change of that kind stored before is
    replaced); return (record name, change) for each.

    Raises
    ------
    MfflapError
        Naming the folder: ``refined_folder`` holds no record, or one of its records has no
        counterpart in ``coarse_folder``, is another motion, refines both or neither of mesh
        and time step, or is not finer.
    """
    coarse_folder, refined_folder = Path(coarse_folder), Path(refined_folder)
    refined_paths = record_paths(refined_folder)
    if not refined_paths:
        raise MfflapError(f"{refined_folder}: no finished record to set against "
                          f"{coarse_folder}")
    out = []
    for path in refined_paths:
        coarse_path = coarse_folder / path.name
        if not coarse_path.exists():
            raise MfflapError(f"{path}: no record {path.name} in {coarse_folder} to set "
                              "it against")
        coarse, refined = read_record(coarse_path), read_record(path)
        kind = refinement_kind(coarse, refined)
        change = refinement_change(coarse, refined, kind, refined_path=path)
        try:  # rewritten whole: a kill during the write leaves the record as it was
            with edited_results(coarse_path) as h5:
                write_refinement(h5, change)
        except MfflapError as exc:
            raise MfflapError(f"{coarse_path}: cannot add the {kind} refinement "
                              f"({exc})") from exc
        out.append((coarse_path.stem, change))
    return out


__all__ = ["add_refinement", "refinement_change", "refinement_kind", "refinement_ratio"]
