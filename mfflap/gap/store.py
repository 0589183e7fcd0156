"""A gap diagnosis in a results file: the candidates' scores, the residual's decomposition,
the gap before and after, the verdict, the check on the held-out motions and the vortex
level."""

from __future__ import annotations

import json
from typing import TYPE_CHECKING

import numpy as np

from mfflap.gap.diagnose import CFD_OWN, CandidateScore, Diagnosis
from mfflap.gap.transfer import BASE, TransferCheck
from mfflap.identification.error_growth import growth_from_json, growth_to_json
from mfflap.results import ResultsFile

if TYPE_CHECKING:
    from mfflap.gap.levels import LevelComparison


def write_diagnosis(rf: ResultsFile, diag: Diagnosis, where: dict, group: str = "gap") -> None:
    """Store the scores, the decomposition, the gap before/after and the verdict."""
    n_cases = len(diag.base_sse)
    rf.write_group(f"{group}/scores", {
        "heldout_gain": np.array([s.gain for s in diag.scores]),
        "p_value": np.array([s.p_value for s in diag.scores]),
        "significant": np.array([s.significant for s in diag.scores]),
        "base_heldout_sse": diag.base_sse,
        "heldout_sse": np.array([s.heldout_sse for s in diag.scores]).reshape(
            len(diag.scores), n_cases)},
        {"heldout_gain": "1", "p_value": "1", "significant": "1", "base_heldout_sse": "1",
         "heldout_sse": "1"},
        {"labels": json.dumps([s.label for s in diag.scores]),
         "names": json.dumps([list(s.names) for s in diag.scores]),
         "coefficients": json.dumps([s.coefficients for s in diag.scores]),
         "coefficient_spread": json.dumps([s.coefficient_spread for s in diag.scores]),
         "plausible": json.dumps([s.plausible for s in diag.scores]),
         "held_coefficients": json.dumps([s.held_coefficients for s in diag.scores]),
         "variance_inflation": json.dumps([s.variance_inflation for s in diag.scores]),
         "confounded_with": json.dumps([s.confounded_with for s in diag.scores])})
    for phase, metrics in diag.gap.items():
        arrays, units = {}, {}
        for sig, val in metrics.items():
            if isinstance(val, dict):
                for m, arr in val.items():
                    arrays[f"{m}_{sig}"] = arr
                    units[f"{m}_{sig}"] = "1"
            else:
                arrays[sig] = val
                units[sig] = "1"
        rf.write_group(f"{group}/gap_{phase}", arrays, units)
    rf.write_group(f"{group}/where", {
        "phase_bin_centres": where["by_phase"]["bin_centres_deg"],
        "phase_squared_share": where["by_phase"]["squared_share"],
        "phase_lag": where["phase_lag_deg"], "case_sse": where["case_sse"]},
        {"phase_bin_centres": "deg", "phase_squared_share": "1", "phase_lag": "deg",
         "case_sse": "1"},
        {"ranking": json.dumps(where["ranking"]),
         "by_component": json.dumps(where["by_component"]),
         "by_state": json.dumps(where["by_state"]), "by_regime": json.dumps(where["by_regime"]),
         "by_harmonic": json.dumps(where["by_harmonic"])})
    g = rf.h5[group]
    g.attrs["base_names"] = json.dumps(list(diag.base_names))
    g.attrs["verdict"] = diag.verdict
    g.attrs["chosen"] = diag.chosen.label if diag.chosen else ""
    g.attrs["case_names"] = json.dumps(diag.case_names)
    g.attrs["validation"] = json.dumps(diag.validation)
    g.attrs["validation_skipped"] = json.dumps(diag.validation_skipped)
    g.attrs["not_claimed"] = json.dumps(diag.not_claimed)
    g.attrs["residual_scaling"] = diag.residual_scaling
    g.attrs["error_growth"] = growth_to_json(diag.error_growth)
    g.attrs["residual_scaling_asked"] = diag.scaling_asked
    g.attrs["descriptions"] = json.dumps(diag.descriptions)
    g.attrs["whiteness"] = json.dumps(diag.whiteness)
    g.attrs["indistinguishable"] = json.dumps(diag.indistinguishable)
    g.attrs["whiteness_after"] = json.dumps(diag.whiteness_after)
    g.attrs["family"] = json.dumps(diag.family)
    if diag.transfer is not None:
        write_transfer(rf, diag.transfer, f"{group}/transfer")
    if diag.levels is not None:
        write_levels(rf, diag.levels, f"{group}/levels")


#: the per-record figures of the vortex level in the results file
LEVEL_FIGURES = ("morison_nrmse", "vortex_nrmse", "explained_share", "cfd_repeat_nrmse")


def write_levels(rf: ResultsFile, levels: LevelComparison, group: str = "gap/levels") -> None:
    """Per record the F_n NRMSE of each level and CFD's own, and the share of Morison's
    residual the vortex model removes (fractions); the records, their groups and the
    records left out as attributes."""
    rows = levels.rows
    rf.write_group(group, {key: np.array([getattr(r, key) for r in rows], dtype=float)
                           for key in LEVEL_FIGURES}, dict.fromkeys(LEVEL_FIGURES, "1"),
                   {"records": json.dumps([r.record for r in rows]),
                    "groups": json.dumps([r.group for r in rows]),
                    "excluded": json.dumps(levels.excluded)})


def read_levels(rf: ResultsFile, group: str = "gap/levels") -> LevelComparison | None:
    """Read back :func:`write_levels`; None where the file has no levels."""
    from mfflap.gap.levels import LevelComparison, LevelResidual  # the vortex kernel's module

    if group not in rf.h5:
        return None
    arrays, attrs = rf.read_group(group)
    names, groups = json.loads(attrs["records"]), json.loads(attrs["groups"])
    rows = [LevelResidual(name, *(float(arrays[key][i]) for key in LEVEL_FIGURES), groups[i])
            for i, name in enumerate(names)]
    return LevelComparison(rows, json.loads(attrs["excluded"]))


def read_diagnosis(rf: ResultsFile, group: str = "gap") -> tuple[Diagnosis, dict]:
    """Read back :func:`write_diagnosis`: the diagnosis and where its residual lies.

    The check on held-out motions (``<group>/transfer``) stays in the file: its motions'
    errors are arrays there, and the diagnosis read back has ``transfer = None``.

    Raises
    ------
    MfflapError
        Naming the file, for a file without the group.
    """
    arrays, attrs = rf.read_group(f"{group}/scores")
    labels = json.loads(attrs["labels"])
    names = json.loads(attrs.get("names", json.dumps([lbl.split(" + ") for lbl in labels])))
    n = len(labels)

    def listed(key: str) -> list[dict]:
        return json.loads(attrs.get(key, json.dumps([{}] * n)))

    sse = arrays.get("heldout_sse", np.full((n, 0), np.nan))
    scores = [CandidateScore(
        names=tuple(names[i]), heldout_sse=np.asarray(sse[i]),
        gain=float(arrays["heldout_gain"][i]), p_value=float(arrays["p_value"][i]),
        significant=bool(arrays["significant"][i]), coefficients=listed("coefficients")[i],
        coefficient_spread=listed("coefficient_spread")[i], plausible=listed("plausible")[i],
        held_coefficients=listed("held_coefficients")[i],
        variance_inflation=listed("variance_inflation")[i],
        confounded_with={k: tuple(v) for k, v in listed("confounded_with")[i].items()})
        for i in range(n)]
    g = rf.h5[group]
    chosen_label = str(g.attrs.get("chosen", ""))
    gap: dict[str, dict] = {}
    for phase in ("before", "after", *CFD_OWN):
        if f"{group}/gap_{phase}" not in rf.h5:
            continue
        flat, _ = rf.read_group(f"{group}/gap_{phase}")
        metrics: dict = {}
        for key, value in flat.items():
            metric, _, signal = key.partition("_")
            if metric in ("nrmse", "pearson") and signal:
                metrics.setdefault(signal, {})[metric] = value
            else:
                metrics[key] = value
        gap[phase] = metrics
    where_arrays, where_attrs = rf.read_group(f"{group}/where")
    where = {"by_phase": {"bin_centres_deg": where_arrays["phase_bin_centres"],
                          "squared_share": where_arrays["phase_squared_share"]},
             "phase_lag_deg": where_arrays["phase_lag"], "case_sse": where_arrays["case_sse"],
             **{key: json.loads(where_attrs[key]) for key in
                ("ranking", "by_component", "by_state", "by_regime", "by_harmonic")}}
    diagnosis = Diagnosis(
        base_names=json.loads(g.attrs.get("base_names", "[]")),
        base_sse=arrays["base_heldout_sse"], scores=scores,
        chosen=next((s for s in scores if s.label == chosen_label), None),
        verdict=str(g.attrs["verdict"]), gap=gap,
        validation=json.loads(g.attrs.get("validation", "{}")),
        validation_skipped=json.loads(g.attrs.get("validation_skipped", "{}")),
        not_claimed=json.loads(g.attrs.get("not_claimed", "{}")),
        case_names=json.loads(g.attrs.get("case_names", "[]")),
        residual_scaling=str(g.attrs.get("residual_scaling", "grid")),
        error_growth=growth_from_json(g.attrs.get("error_growth", "{}")),
        scaling_asked=str(g.attrs.get("residual_scaling_asked", "grid")),
        descriptions=json.loads(g.attrs.get("descriptions", "{}")),
        whiteness=json.loads(g.attrs.get("whiteness", "{}")),
        indistinguishable=json.loads(g.attrs.get("indistinguishable", "[]")),
        whiteness_after=json.loads(g.attrs.get("whiteness_after", "{}")),
        family=json.loads(g.attrs.get("family", "[]")),
        levels=read_levels(rf, f"{group}/levels"))
    return diagnosis, where


def write_transfer(rf: ResultsFile, check: TransferCheck, group: str = "gap/transfer") -> None:
    """Per held-out motion each set's error and the checked effect's NRMSE and means; the
    verdict, gains, coefficients and excluded runs as attributes."""
    ms = check.motions
    arrays: dict[str, np.ndarray] = {}
    units: dict[str, str] = {}
    for label in check.coefficients:
        arrays[f"error/{label}"] = np.array([m.error[label] for m in ms])
        units[f"error/{label}"] = "1"
    for which, label in (("base", BASE), ("effect", check.label)):
        for comp in (ms[0].nrmse[BASE] if ms else ()):
            arrays[f"nrmse_{comp}_{which}"] = np.array([m.nrmse[label][comp] for m in ms])
            units[f"nrmse_{comp}_{which}"] = "1"
    for comp in (ms[0].cfd_repeat_nrmse if ms else ()):
        arrays[f"cfd_repeat_nrmse_{comp}"] = np.array([m.cfd_repeat_nrmse[comp] for m in ms])
        units[f"cfd_repeat_nrmse_{comp}"] = "1"
    for key, unit in (("mean_thrust", "N"), ("mean_power", "W")):
        for which, label in (("cfd", "cfd"), ("base", BASE), ("effect", check.label)):
            arrays[f"{key}_{which}"] = np.array([getattr(m, key)[label] for m in ms])
            units[f"{key}_{which}"] = unit
    rf.write_group(group, arrays, units, {
        "verdict": check.verdict, "effect": json.dumps(list(check.effect)),
        "claimed": check.claimed, "carries_over": check.carries_over,
        "residual_scaling": check.residual_scaling, "gains": json.dumps(check.gains),
        "n_better": json.dumps(check.n_better),
        "coefficients": json.dumps(check.coefficients),
        "excluded": json.dumps(check.excluded),
        "motion_names": json.dumps([m.name for m in ms]),
        "motion_labels": json.dumps([m.label for m in ms])})
