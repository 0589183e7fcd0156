"""The rounds' numbers written out: ``rounds.h5``, the case file beside them (the report
beside it: :mod:`mfflap.reports.rounds`)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from mfflap.config import CaseConfig
from mfflap.results import ResultsFile
from mfflap.rounds.summary import LoopResult


def write_rounds_results(result: LoopResult, config: CaseConfig, out_dir: Path) -> None:
    """``out_dir/rounds.h5``: every round's numbers, the case file beside them."""
    with ResultsFile(out_dir / "rounds.h5", "w", kind="rounds",
                     config_toml=config.to_toml()) as rf:
        rf.h5.attrs["tolerance"] = result.tolerance
        rf.h5.attrs["converged"] = result.converged
        rf.h5.attrs["stopped_because"] = result.stopped_because
        rf.h5.attrs["correct_outputs"] = result.correct_outputs
        rf.h5.attrs["correction_gain"] = result.correction_gain
        rf.h5.attrs["refit"] = result.refit
        rf.h5.attrs["trust_radius"] = np.nan if result.trust_radius is None else \
            result.trust_radius
        rf.h5.attrs["first_order"] = result.first_order
        rf.h5.attrs["cfd_repeatability"] = np.nan if result.cfd_repeatability is None else \
            result.cfd_repeatability
        for r in result.rounds:
            labels = list(r.checks)
            arrays = {name: np.array([getattr(r.checks[lbl], name) for lbl in labels])
                      for name in ("cfd_mean_thrust", "model_mean_thrust", "predicted_thrust",
                                   "cfd_mean_power", "model_mean_power", "predicted_power",
                                   "thrust_scale", "power_scale", "optimised_mean_thrust",
                                   "optimised_mean_power")}
            units = {name: "1" if "scale" in name else "N" if "thrust" in name else "W"
                     for name in arrays}
            rf.write_group(f"rounds/round_{r.index}", arrays, units, {
                "labels": json.dumps(labels), "summary": json.dumps(r.as_dict())})
