"""A CFD run's forces against the Morison model of the case file it was written from: what
``mfflap cfd parse`` prints.

The run is an OpenFOAM case folder written by mfflap or a Fluent report file (.out). Its
forces become F_n, F_t and M about the moving pivot, and thrust and input power, with
the motion, ramp and plate the case was written for (:mod:`mfflap.cfd.case_inputs` refuses
a case file that describes another run). Numerical bursts after the discarded start are
bridged before the comparison and listed (:mod:`mfflap.records.bursts`), stretches whose forces
the motion cannot have driven are listed (:mod:`mfflap.records.force_envelope`), and means are
time averages over the solver's steps. :func:`write_model_comparison` stores both time
series, the summary and the inputs in HDF5; :func:`mfflap.plots.model_comparison_figure`
draws them.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from mfflap.cfd.case_inputs import check_case_inputs
from mfflap.cfd.fluent.solver import FLUENT_COLUMNS, Fluent
from mfflap.cfd.force_history import to_loads
from mfflap.cfd.imposed_motion import imposed_state
from mfflap.cfd.linear_theory import compare_with_theory
from mfflap.cfd.openfoam.solver import OpenFoam
from mfflap.config import load_case
from mfflap.errors import ConfigError
from mfflap.hydro.loads import Loads
from mfflap.kinematics.table_file import read_motion_table
from mfflap.metrics import nrmse, pearson, time_mean
from mfflap.performance import thrust_and_power
from mfflap.records.bursts import bridge_load_bursts
from mfflap.records.force_envelope import find_envelope_breaches
from mfflap.results import ResultsFile


@dataclass
class ModelComparison:
    """A CFD run's forces beside the model's over the same imposed motion.

    Attributes
    ----------
    summary
        What :func:`compare_with_model` returns (means, NRMSE, Pearson, bursts, ...).
    cfd_loads, model_loads
        F_n, F_t and M at the run's samples (the CFD's with its bursts bridged).
    cfd_thrust_n, cfd_power_w, model_thrust_n, model_power_w
        Thrust (N) and input power (W) at the same samples.
    compared
        The samples after the discarded start, which the NRMSE, Pearson and means are of.
    """

    summary: dict[str, Any]
    cfd_loads: Loads
    model_loads: Loads
    cfd_thrust_n: np.ndarray
    cfd_power_w: np.ndarray
    model_thrust_n: np.ndarray
    model_power_w: np.ndarray
    compared: np.ndarray


def compare_with_model(source: str | Path, case_file: str | Path, *, discard_s: float = 0.0,
                       ramp_time_s: float | None = None, motion_table: str | Path | None = None,
                       fluent_columns: tuple[str, str, str] = FLUENT_COLUMNS,
                       depth_m: float | None = None, thin_aerofoil: bool = False
                       ) -> dict[str, Any]:
    """Parse a run's forces and compare them with the case file's model: the summary of
    :func:`model_comparison` (same parameters)."""
    return model_comparison(source, case_file, discard_s=discard_s, ramp_time_s=ramp_time_s,
                            motion_table=motion_table, fluent_columns=fluent_columns,
                            depth_m=depth_m, thin_aerofoil=thin_aerofoil).summary


def model_comparison(source: str | Path, case_file: str | Path, *, discard_s: float = 0.0,
                     ramp_time_s: float | None = None, motion_table: str | Path | None = None,
                     fluent_columns: tuple[str, str, str] = FLUENT_COLUMNS,
                     depth_m: float | None = None, thin_aerofoil: bool = False
                     ) -> ModelComparison:
    """Parse a run's forces and compare them with the case file's model.

    Parameters
    ----------
    source
        An OpenFOAM case folder, or a Fluent report file. A case mfflap did not write is read
        as :func:`read_foreign_case` says: its motion from ``motion_table`` or from its
        dynamicMeshDict, its depth from its mesh, its loads from its forces function object,
        the moments about its CofR; there is nothing to check the case file against.
    discard_s
        Start-up transient left out of the comparison, s.
    ramp_time_s
        The start-up ramp, s. Default: the one the case was written with (an OpenFOAM case's
        mfflap_case.toml, the mfflap_fluent.toml beside a Fluent report), else 0.
    motion_table
        The CSV table a Fluent UDF was written from, for a report without a
        mfflap_fluent.toml beside it (a case that keeps its table uses that one).
    fluent_columns
        A Fluent report's force and moment columns.
    depth_m
        The depth the forces are for, m: a Fluent report's (default 1 m, Fluent 2D), or an
        OpenFOAM case's that mfflap did not write (default the z extent of its mesh); an
        OpenFOAM case that mfflap wrote keeps its own.
    thin_aerofoil
        Also compare with linear unsteady thin-aerofoil theory
        (:func:`mfflap.cfd.linear_theory.compare_with_theory`).

    Returns
    -------
    ModelComparison
        The time series, and as ``summary``: the solver dialect, sample count, means of
        thrust and power of the CFD and the model, the bursts and the stretches beyond the
        force envelope, the NRMSE and Pearson of F_n, F_t and M (model against CFD), and
        ``inputs_checked_against``: the file of what the run was written for that the case
        file was checked against, or None for a Fluent report with no mfflap_fluent.toml
        beside it, whose motion, ramp, plate and stream are then taken on trust;
        ``written_end_time``, the end time the run was written for, and
        ``forces_reach_end_time``, whether its forces get there (:func:`reaches_end_time`;
        False for a run still going or stopped early, whose numbers cover only what it ran);
        both None where nothing says what it was written for.

    Raises
    ------
    ConfigError
        For a ramp or motion table other than the kept ones, a case file that describes
        another run, or a discard that leaves fewer than two samples.
    """
    source = Path(source)
    case = load_case(case_file)
    solver = OpenFoam() if source.is_dir() else Fluent(columns=fluent_columns)
    run = solver.read_forces(source, depth_m=depth_m, motion_table=motion_table)
    history, depth_m, frame, label = run.history, run.depth_m, run.frame, run.label
    kept, meta, pivot_m = run.kept, run.written_for, run.pivot_m
    if run.motion is not None:
        ramp_time_s = 0.0 if ramp_time_s is None else ramp_time_s
    if meta is not None:  # what the case was written for: its table, its ramp
        if "motion_table" in meta:
            if motion_table is not None:
                raise ConfigError(f"{kept.parent} keeps its own motion table "
                                  f"({meta['motion_table']}); leave out --motion-table",
                                  key="motion_table")
            motion_table = kept.parent / str(meta["motion_table"])
        kept_ramp_time = float(meta.get("ramp_time", 0.0))
        if ramp_time_s is not None and not math.isclose(ramp_time_s, kept_ramp_time,
                                                        rel_tol=1e-9, abs_tol=1e-12):
            raise ConfigError(f"--ramp-time {ramp_time_s:g} s, but the case was written with "
                              f"a ramp of {kept_ramp_time:g} s ({kept}); leave out "
                              "--ramp-time", key="ramp_time")
        ramp_time_s = kept_ramp_time
    ramp_time_s = 0.0 if ramp_time_s is None else ramp_time_s
    if run.motion is not None:
        motion = run.motion
    else:
        motion = (case.motion.build() if motion_table is None
                  else read_motion_table(motion_table, case.plate.chord))
    if meta is not None:  # the case file must describe what the case was written for
        check_case_inputs(kept, meta, case_file, motion, case.plate, case.fluid, case.flow)
    state = imposed_state(motion, history.time, ramp_time_s)
    cfd_loads = to_loads(history, state, case.plate.span, depth_m, source=label, frame=frame,
                         pivot_m=pivot_m)
    model_loads = case.morison_model().loads(state)
    keep = history.time >= discard_s
    if keep.sum() < 2:
        raise ConfigError(f"--discard {discard_s} s leaves fewer than two samples of "
                          f"{source} (it ends at t = {history.time[-1]:g} s)", key="discard")
    t = history.time[keep]
    cfd_loads, bursts = bridge_load_bursts(cfd_loads, keep)
    breaches = find_envelope_breaches(state, cfd_loads, case.plate, case.fluid, case.flow,
                                      window=keep)
    series = (*thrust_and_power(cfd_loads, state), *thrust_and_power(model_loads, state))
    thrust, power, m_thrust, m_power = (np.asarray(a)[keep] for a in series)
    out: dict[str, Any] = {
        "source": str(source), "dialect": history.dialect,
        "n_samples": len(history.time), "end_time": float(history.time[-1]),
        "cfd_mean_thrust": time_mean(t, thrust), "model_mean_thrust": time_mean(t, m_thrust),
        "cfd_mean_power": time_mean(t, power), "model_mean_power": time_mean(t, m_power),
        "written_end_time": None if meta is None else float(meta["end_time"]),
        "forces_reach_end_time": None if meta is None else reaches_end_time(
            history.time, float(meta["end_time"])),
        "numerical_bursts": [b.describe() for b in bursts],
        "forces_beyond_what_the_motion_can_drive": [b.describe() for b in breaches],
        "inputs_checked_against": None if meta is None else str(kept),
        "depth_m": depth_m, "pivot_m": list(pivot_m),
        "motion_from": run.motion_from}
    for name in ("normal_force", "tangential_force", "moment"):
        a, b = getattr(model_loads, name)[keep], getattr(cfd_loads, name)[keep]
        out[f"nrmse_{name}"] = float(nrmse(a, b))
        out[f"pearson_{name}"] = float(pearson(a, b))
    if thin_aerofoil:
        out["thin_aerofoil"], _ = compare_with_theory(motion, ramp_time_s, state, cfd_loads,
                                                      keep, case.plate, case.fluid, case.flow)
    return ModelComparison(out, cfd_loads, model_loads,
                           *(np.asarray(a, dtype=float) for a in series), compared=keep)


def reaches_end_time(time_s: np.ndarray, end_time_s: float) -> bool:
    """Whether a force history gets to the end time its run was written for: its last
    sample within one and a half of its last time steps of it (a solver stops once it is
    within half a step; the last step may have been shortened to land on it).

    Parameters
    ----------
    time_s
        The history's times, s, increasing.
    end_time_s
        The run's end time, s.
    """
    time_s = np.asarray(time_s, dtype=float)
    if time_s.size == 0:
        return False
    last_step = float(np.diff(time_s[-3:]).max()) if time_s.size > 1 else 0.0
    return bool(time_s[-1] >= end_time_s - 1.5 * last_step - 1e-9 * abs(end_time_s))


_SERIES_UNITS = {"time": "s", "cfd_thrust_n": "N", "cfd_power_w": "W", "model_thrust_n": "N",
                 "model_power_w": "W", "compared": "1"}


def write_model_comparison(path: str | Path, comparison: ModelComparison,
                           case_file: str | Path) -> Path:
    """Store a comparison in HDF5 with its inputs beside it.

    The case file's text is the file's input configuration; the summary (as JSON) and the
    kept file of what the run was written for (its text, if there was one) are attributes
    of the ``summary`` group; F_n, F_t and M of both are ``cfd_loads`` and ``model_loads``,
    thrust and power ``performance``.
    """
    summary = comparison.summary
    kept = summary.get("inputs_checked_against")
    attrs = {"summary_json": json.dumps(summary, default=lambda o: np.asarray(o).tolist()),
             "source": str(summary["source"])}
    if kept:
        attrs["kept_inputs_toml"] = Path(kept).read_text()
    with ResultsFile(path, "w", kind="cfd_model_comparison",
                     config_toml=Path(case_file).read_text()) as out:
        out.write_loads("cfd_loads", comparison.cfd_loads)
        out.write_loads("model_loads", comparison.model_loads)
        out.write_group("performance", {
            "time": comparison.cfd_loads.time, "cfd_thrust_n": comparison.cfd_thrust_n,
            "cfd_power_w": comparison.cfd_power_w, "model_thrust_n": comparison.model_thrust_n,
            "model_power_w": comparison.model_power_w, "compared": comparison.compared},
            _SERIES_UNITS)
        out.write_group("summary", {}, {}, attrs)
    return Path(path)


def read_model_comparison(path: str | Path) -> ModelComparison:
    """A comparison stored by :func:`write_model_comparison`."""
    with ResultsFile(path, kinds=("cfd_model_comparison",)) as stored:
        series, _ = stored.read_group("performance")
        _, attrs = stored.read_group("summary")
        return ModelComparison(json.loads(attrs["summary_json"]), stored.read_loads("cfd_loads"),
                               stored.read_loads("model_loads"), series["cfd_thrust_n"],
                               series["cfd_power_w"], series["model_thrust_n"],
                               series["model_power_w"], series["compared"].astype(bool))
