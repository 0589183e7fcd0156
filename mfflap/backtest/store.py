"""Back-test outcomes in HDF5 (``/backtest/<label>``)."""

from __future__ import annotations

import json

from mfflap.backtest.compare import BacktestComparison
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


def read_backtests(rf: ResultsFile, group: str = "backtest") -> dict[str, BacktestOutcome]:
    """Read back :func:`write_backtests`: every motion's outcome by its label, each
    comparison rebuilt from its stored histories and metrics. The CFD record itself is not
    in a results file (its provenance is, as the group's ``cfd_provenance``), so
    ``record`` is None."""
    if group not in rf.h5:
        return {}
    outcomes = {}
    for name in rf.h5[group]:
        g = rf.h5[f"{group}/{name}"]
        comparison = None
        if "metrics" in g.attrs:
            arrays, _ = rf.read_group(f"{group}/{name}")
            comparison = _comparison(arrays, json.loads(g.attrs["metrics"]))
        label = str(g.attrs["label"])
        outcomes[label] = BacktestOutcome(label=label, key=str(g.attrs["motion_key"]),
                                          status=str(g.attrs["status"]),
                                          source=str(g.attrs["source"]),
                                          comparison=comparison)
    return outcomes


def _comparison(arrays: dict, metrics: dict) -> BacktestComparison:
    """A comparison from its histories and :meth:`BacktestComparison.as_dict`."""

    def number(key: str, default: float = float("nan")) -> float:
        value = metrics.get(key)
        return default if value is None else float(value)

    return BacktestComparison(
        time=arrays["time"], cfd_thrust=arrays["cfd_thrust"],
        model_thrust=arrays["model_thrust"], cfd_power=arrays["cfd_power"],
        model_power=arrays["model_power"], nrmse=metrics["nrmse"], pearson=metrics["pearson"],
        cfd_mean_thrust=number("cfd_mean_thrust"), model_mean_thrust=number("model_mean_thrust"),
        cfd_mean_power=number("cfd_mean_power"), model_mean_power=number("model_mean_power"),
        cfd_max_power=number("cfd_max_power"), max_power_ok=bool(metrics["max_power_ok"]),
        cycle_to_cycle_thrust_change=number("cycle_to_cycle_thrust_change"),
        numerical_bursts=list(metrics.get("numerical_bursts", [])),
        cycles_averaged=int(metrics.get("cycles_averaged", 1)),
        cfd_thrust_standard_error=number("cfd_thrust_standard_error"),
        cfd_power_standard_error=number("cfd_power_standard_error"),
        compared_from_s=number("compared_from_s"),
        cfd_settings_since_s=number("cfd_settings_since_s", 0.0),
        cfd_repeat_nrmse={k: float("nan") if v is None else float(v)
                          for k, v in metrics.get("cfd_repeat_nrmse", {}).items()})
