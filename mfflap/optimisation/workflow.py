"""Run and store the optimisation study of a case."""

from __future__ import annotations

import json
from collections.abc import Mapping
from dataclasses import asdict

import numpy as np

from mfflap.config import CaseConfig
from mfflap.optimisation.store import beta_key, problem_settings, write_result, write_sweep
from mfflap.optimisation.study import BetaStudy, problem_for
from mfflap.results import ResultsFile

GAIN_UNITS = {"gain": "1", "thrust": "N", "strouhal_number": "1", "flagged": "1",
              "n_steps": "1", "smoothing_factors": "1", "baseline_thrust": "N"}


def _or_nan(value: float | None) -> float:
    """An HDF5 attribute for a number that may not have been computed."""
    return np.nan if value is None else value


def write_study(rf: ResultsFile, config: CaseConfig, study: BetaStudy,
                gain: Mapping[str, np.ndarray] | None = None, model=None,
                prefix: str = "optimisation") -> None:
    """Store the sweep, every beta's SQP optimum (and all starts), IPOPT results, the gain,
    and the coefficients of the model they were optimised with."""
    write_sweep(rf, f"{prefix}/sweep", study.sweep, study.best_sinusoid)
    o = config.optimisation
    # the coefficients the motions were optimised with (the case file's, or identified ones)
    rf.h5[prefix].attrs["model_coefficients"] = json.dumps(
        {k: float(v) for k, v in (model or config.morison_model()).coefficients.items()})
    for beta, r in study.sqp.items():
        settings = {**problem_settings(problem_for(config, beta, model)), "n_steps": o.n_steps,
                    "min_period": o.min_period, "max_period": o.max_period, "phase": o.phase}
        if beta in study.corrections:  # the problem solved: the case's, outputs corrected
            corr = study.corrections[beta]
            settings.update({"output_thrust_scale": corr.thrust_scale,
                             "output_power_scale": corr.power_scale,
                             "output_correction": json.dumps(corr.as_dict())})
            if corr.slopes is not None:  # first order: the affine term of J, its value here
                settings.update({"output_objective_shift": corr.shift(r.motion),
                                 "output_objective_slope": corr.slopes.objective,
                                 "output_slope_centre": corr.slopes.centre})
        if beta in study.trust_regions:  # kept in a box about an earlier optimum
            region = study.trust_regions[beta]
            settings.update({"trust_region_radius": region.radius,
                             "trust_region_centre": region.source,
                             "trust_region_step_fraction": region.step_fraction(r.motion)})
        write_result(rf, f"{prefix}/sqp/{beta_key(beta)}", r, settings)
        for k, other in enumerate(study.sqp_all.get(beta, [])):
            write_result(rf, f"{prefix}/sqp_starts/{beta_key(beta)}/start_{k}", other, settings)
        if beta in study.ipopt:
            write_result(rf, f"{prefix}/ipopt/{beta_key(beta)}", study.ipopt[beta], settings)
    rf.h5[prefix].attrs["thrust_gain_beta0"] = _or_nan(study.thrust_gain)
    rf.h5[prefix].attrs["interrupted_beta"] = _or_nan(study.interrupted_beta)  # NaN: ran to the end
    rf.h5[prefix].attrs["betas_not_optimised"] = np.asarray(study.betas_not_optimised, float)
    if study.no_thrust_gain_reason is not None:
        rf.h5[prefix].attrs["thrust_gain_beta0_missing"] = study.no_thrust_gain_reason
    if study.thrust_gain_caveat is not None:
        rf.h5[prefix].attrs["thrust_gain_beta0_caveat"] = study.thrust_gain_caveat
    if study.refined is not None:

        r = study.refined
        rf.write_group(f"{prefix}/refined_sinusoid",
                       {k: v for k, v in asdict(r).items() if isinstance(v, float)},
                       {"frequency": "Hz", "heave_amplitude": "m", "pitch_amplitude": "rad",
                        "phase": "rad", "mean_thrust": "N", "max_power": "W",
                        "grid_thrust": "N"}, {"success": r.success, "message": r.message})
        rf.h5[prefix].attrs["thrust_gain_beta0_refined"] = _or_nan(study.thrust_gain_refined)
    if gain is not None:
        rf.write_group(f"{prefix}/gain_table", gain, GAIN_UNITS)
