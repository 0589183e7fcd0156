"""Back-test outcomes in HDF5 (``/backtest/<label>``)."""

from __future__ import annotations

import json

from mfflap.backtest.run import BacktestOutcome
from mfflap.results import ResultsFile


def safe_label(label: str) -> str:
    """A motion's label as an HDF5 group name ("β = 0" -> "beta__0")."""
    return label.replace(" ", "_").replace("β", "beta").replace("=", "")


def write_backtests(rf: ResultsFile, outcomes: dict[str, BacktestOutcome]) -> None:
    """Store status, source, metrics and last-cycle histories of every back-test."""
    for label, o in outcomes.items():
        group = f"backtest/{safe_label(label)}"
        if o.comparison is not None:
            c = o.comparison
            rf.write_group(group, {"time": c.time, "cfd_thrust": c.cfd_thrust,
                                   "model_thrust": c.model_thrust, "cfd_power": c.cfd_power,
                                   "model_power": c.model_power},
                           {"time": "s", "cfd_thrust": "N", "model_thrust": "N",
                            "cfd_power": "W", "model_power": "W"})
            rf.h5[group].attrs["metrics"] = json.dumps(c.as_dict())
        else:
            rf.h5.require_group(group)
        g = rf.h5[group]
        g.attrs.update({"label": label, "status": o.status, "source": o.source,
                        "motion_key": o.key})
        if o.record is not None:
            g.attrs["cfd_provenance"] = json.dumps(o.record.provenance, default=str)
            g.attrs["cfd_n_cycles"] = float(o.record.parameters.get("n_cycles", float("nan")))
