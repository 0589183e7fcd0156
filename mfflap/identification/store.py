"""Identification results in HDF5 (``/identification/<strategy>``), and back."""

from __future__ import annotations

import json

import numpy as np

from mfflap.identification.error_growth import growth_from_json, growth_to_json
from mfflap.identification.fit import IdentificationResult
from mfflap.results import ResultsFile


def write_identification(rf: ResultsFile, result: IdentificationResult,
                         group: str | None = None) -> str:
    """Store one strategy's result; return the group name."""
    group = group or f"identification/{result.strategy}"
    names = list(result.coefficients)
    arrays = {
        "coefficients": np.array([result.coefficients[n] for n in names]),
        "standard_error": np.array([result.standard_error[n] for n in names]),
        "interval": np.array([result.interval[n] for n in names]),
        "bootstrap": result.bootstrap,
        "weight_frequencies": np.array(list(result.weights)),
        "weights": np.array(list(result.weights.values())),
        # rows: cases (case_names), columns: fitted_terms
        "leave_one_out": np.asarray(result.leave_one_out, dtype=float),
    }
    units = {"coefficients": "1", "standard_error": "1", "interval": "1", "bootstrap": "1",
             "weight_frequencies": "Hz", "weights": "1", "leave_one_out": "1"}
    for signal, values in result.metrics.items():
        for metric, arr in values.items():
            arrays[f"{metric}_{signal}"] = arr
            units[f"{metric}_{signal}"] = "1"
    attrs = {"terms": json.dumps(names), "fitted_terms": json.dumps(result.fitted_terms),
             "strategy": result.strategy, "components": json.dumps(result.components),
             "case_names": json.dumps(result.case_names),
             "case_parameters": json.dumps(result.case_parameters),
             "excluded": json.dumps(result.excluded), "notes": json.dumps(result.notes),
             "residual_scaling": result.residual_scaling,
             "residual_scaling_asked": result.scaling_asked,
             "error_growth": growth_to_json(result.error_growth)}
    rf.write_group(group, arrays, units, attrs)
    return group


def read_identification(rf: ResultsFile, group: str) -> IdentificationResult:
    """Read back a result written by :func:`write_identification`."""
    a, attrs = rf.read_group(group)
    names = json.loads(attrs["terms"])
    metrics: dict[str, dict[str, np.ndarray]] = {}
    for key, arr in a.items():
        for metric in ("nrmse", "pearson"):
            if key.startswith(metric + "_"):
                metrics.setdefault(key[len(metric) + 1:], {})[metric] = arr
    return IdentificationResult(
        coefficients=dict(zip(names, a["coefficients"].tolist(), strict=True)),
        standard_error=dict(zip(names, a["standard_error"].tolist(), strict=True)),
        interval={n: tuple(v) for n, v in zip(names, a["interval"].tolist(), strict=True)},
        bootstrap=a["bootstrap"], fitted_terms=tuple(json.loads(attrs["fitted_terms"])),
        strategy=str(attrs["strategy"]),
        weights=dict(zip(a["weight_frequencies"].tolist(), a["weights"].tolist(), strict=True)),
        components=tuple(json.loads(attrs["components"])),
        case_names=json.loads(attrs["case_names"]),
        case_parameters=json.loads(attrs["case_parameters"]), metrics=metrics,
        excluded=json.loads(attrs["excluded"]), notes=json.loads(attrs.get("notes", "{}")),
        # a file written before the refits without each case were kept has none
        leave_one_out=a.get("leave_one_out", np.empty((0, 0))),
        # files written before the choice was offered were fitted on the grid's scales
        residual_scaling=str(attrs.get("residual_scaling", "grid")),
        # likewise before the error's growth with the loads was measured
        error_growth=growth_from_json(attrs.get("error_growth", "{}")),
        # and before "auto" was offered, the scaling used was the one asked for
        scaling_asked=str(attrs.get("residual_scaling_asked",
                                    attrs.get("residual_scaling", "grid"))),
    )


def strategies_in(rf: ResultsFile) -> list[str]:
    """Strategy names stored in a file."""
    return sorted(rf.h5["identification"]) if "identification" in rf.h5 else []
