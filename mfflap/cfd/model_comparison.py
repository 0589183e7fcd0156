"""A CFD run's forces against the Morison model of the case file it was written from: what
``mfflap cfd parse`` prints.

The run is an OpenFOAM case folder written by mfflap or a Fluent report file (.out). Its
forces become F_n, F_t and M about the moving leading edge, and thrust and input power, with
the motion, ramp and plate the case was written for (:mod:`mfflap.cfd.case_inputs` refuses
a case file that describes another run). Numerical bursts after the discarded start are
bridged before the comparison and listed (:mod:`mfflap.cfd.bursts`), stretches whose forces
the motion cannot have driven are listed (:mod:`mfflap.cfd.force_envelope`), and means are
time averages over the solver's steps.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

from mfflap.cfd.bursts import bridge_load_bursts
from mfflap.cfd.case_inputs import check_case_inputs
from mfflap.cfd.fluent.report import report_forces
from mfflap.cfd.fluent.udf import FLUENT_KEPT_FILE
from mfflap.cfd.force_envelope import find_envelope_breaches
from mfflap.cfd.openfoam.forces import read_forces
from mfflap.cfd.openfoam.loads import imposed_state, to_loads
from mfflap.config import load_case
from mfflap.errors import ConfigError
from mfflap.kinematics.table_file import read_motion_table
from mfflap.metrics import nrmse, pearson, time_mean
from mfflap.performance import thrust_and_power
from mfflap.toml_io import read_toml

#: Fluent report columns of the x force, the y force and the z moment about the origin
FLUENT_COLUMNS = ("fx-plate", "fy-plate", "mz-plate")


def compare_with_model(source: str | Path, case_file: str | Path, *, discard_s: float = 0.0,
                       ramp_time_s: float | None = None, motion_table: str | Path | None = None,
                       fluent_columns: tuple[str, str, str] = FLUENT_COLUMNS,
                       fluent_depth_m: float = 1.0, thin_aerofoil: bool = False
                       ) -> dict[str, Any]:
    """Parse a run's forces and compare them with the case file's model.

    Parameters
    ----------
    source
        An OpenFOAM case folder written by mfflap, or a Fluent report file.
    discard_s
        Start-up transient left out of the comparison, s.
    ramp_time_s
        The start-up ramp, s. Default: the one the case was written with (an OpenFOAM case's
        mfflap_case.toml, the mfflap_fluent.toml beside a Fluent report), else 0.
    motion_table
        The CSV table a Fluent UDF was written from, for a report without a
        mfflap_fluent.toml beside it (a case that keeps its table uses that one).
    fluent_columns, fluent_depth_m
        A Fluent report's force and moment columns, and the depth its 2D forces are for.
    thin_aerofoil
        Also compare with linear unsteady thin-aerofoil theory
        (:func:`mfflap.cfd.linear_check.compare_with_theory`).

    Returns
    -------
    dict
        The solver dialect, sample count, means of thrust and power of the CFD and the model,
        the bursts and the stretches beyond the force envelope, the NRMSE and Pearson of
        F_n, F_t and M (model against CFD), and ``inputs_checked_against``: the file of what
        the run was written for that the case file was checked against, or None for a Fluent
        report with no mfflap_fluent.toml beside it, whose motion, ramp, plate and stream
        are then taken on trust.

    Raises
    ------
    ConfigError
        For a ramp or motion table other than the kept ones, a case file that describes
        another run, or a discard that leaves fewer than two samples.
    """
    source = Path(source)
    case = load_case(case_file)
    if source.is_dir():
        kept = source / "mfflap_case.toml"
        meta: dict[str, Any] | None = read_toml(kept)
        history = read_forces(source)
        depth_m = float(meta["depth"])
        frame = str(meta.get("frame", "inertial"))
        label = f"openfoam:{source}"
    else:
        history = report_forces(source, *fluent_columns)
        depth_m, frame, label = fluent_depth_m, "inertial", f"fluent:{source}"
        kept = source.parent / FLUENT_KEPT_FILE
        meta = read_toml(kept) if kept.is_file() else None
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
    motion = case.motion.build() if motion_table is None else read_motion_table(motion_table)
    if meta is not None:  # the case file must describe what the case was written for
        check_case_inputs(kept, meta, case_file, motion, case.plate, case.fluid, case.flow)
    state = imposed_state(motion, history.time, ramp_time_s)
    cfd_loads = to_loads(history, state, case.plate.span, depth_m, source=label, frame=frame)
    model_loads = case.morison_model().loads(state)
    keep = history.time >= discard_s
    if keep.sum() < 2:
        raise ConfigError(f"--discard {discard_s} s leaves fewer than two samples of "
                          f"{source} (it ends at t = {history.time[-1]:g} s)", key="discard")
    t = history.time[keep]
    cfd_loads, bursts = bridge_load_bursts(cfd_loads, keep)
    breaches = find_envelope_breaches(state, cfd_loads, case.plate, case.fluid, case.flow,
                                      window=keep)
    thrust, power = thrust_and_power(cfd_loads, state)
    m_thrust, m_power = thrust_and_power(model_loads, state)
    thrust, power, m_thrust, m_power = (a[keep] for a in (thrust, power, m_thrust, m_power))
    out: dict[str, Any] = {
        "source": str(source), "dialect": history.dialect,
        "n_samples": len(history.time), "end_time": float(history.time[-1]),
        "cfd_mean_thrust": time_mean(t, thrust), "model_mean_thrust": time_mean(t, m_thrust),
        "cfd_mean_power": time_mean(t, power), "model_mean_power": time_mean(t, m_power),
        "numerical_bursts": [b.describe() for b in bursts],
        "forces_beyond_what_the_motion_can_drive": [b.describe() for b in breaches],
        "inputs_checked_against": None if meta is None else str(kept)}
    for name in ("normal_force", "tangential_force", "moment"):
        a, b = getattr(model_loads, name)[keep], getattr(cfd_loads, name)[keep]
        out[f"nrmse_{name}"] = float(nrmse(a, b))
        out[f"pearson_{name}"] = float(pearson(a, b))
    if thin_aerofoil:
        from mfflap.cfd.linear_check import compare_with_theory

        out["thin_aerofoil"], _ = compare_with_theory(motion, ramp_time_s, state, cfd_loads,
                                                      keep, case.plate, case.fluid, case.flow)
    return out
