"""Two campaigns of the same motions, case by case: how far one set-up's forces are from
another's.

For each case both campaigns finished, the loads of campaign A are compared with those of
campaign B (the reference) on B's time base after the start-up: NRMSE and Pearson of F_n,
F_t and M, and the relative difference of mean thrust and mean input power. Numerical bursts
(:mod:`mfflap.records.bursts`) are bridged in both before comparing, as identification does, and
counted, so a comparison of, say, the fixtures at max Co 2 against max Co 4 separates the
bursts from the time-step error; so are stretches whose forces the motion cannot have driven
(:mod:`mfflap.records.force_envelope`), timed, and the summary leaves out the cases with them.
The CPU time of each run is kept beside.
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from mfflap.campaign.execute import _bound_setup, manifest_setup, setting_differences
from mfflap.errors import ConfigError, MfflapError
from mfflap.hydro.loads import LOAD_COMPONENTS, Loads
from mfflap.metrics import nrmse, pearson, time_mean
from mfflap.parameters import Fluid, FreeStream, Plate
from mfflap.performance import thrust_and_power
from mfflap.plots import save_figure
from mfflap.records.bursts import bridge_bursts, bridge_load_bursts
from mfflap.records.force_envelope import find_envelope_breaches
from mfflap.records.inputs import folder_setup, run_for, run_for_differences
from mfflap.records.record import CfdRecord, read_record, read_records
from mfflap.results import ResultsFile
from mfflap.toml_io import read_toml

COMPONENTS = LOAD_COMPONENTS
#: parameters that describe how a record is kept, not the motion
_NOT_MOTION = frozenset({"storage"})


@dataclass(frozen=True)
class CaseComparison:
    """One case run by both campaigns: A against B (B the reference)."""

    case_id: str
    start_s: float
    end_s: float
    nrmse_normal_force: float
    nrmse_tangential_force: float
    nrmse_moment: float
    pearson_normal_force: float
    pearson_tangential_force: float
    pearson_moment: float
    mean_thrust_a_n: float
    mean_thrust_b_n: float
    mean_power_a_w: float
    mean_power_b_w: float
    n_bursts_a: int
    n_bursts_b: int
    #: seconds after the start whose forces the motion cannot have driven (a run that lost
    #: its numerics, :mod:`mfflap.records.force_envelope`; bridged like bursts before comparing)
    lost_a_s: float
    lost_b_s: float
    cpu_time_a_s: float
    cpu_time_b_s: float

    @property
    def thrust_difference(self) -> float:
        """(A - B) / |B| of the mean thrust (nan if B's is zero)."""
        return _relative(self.mean_thrust_a_n, self.mean_thrust_b_n)

    @property
    def power_difference(self) -> float:
        """(A - B) / |B| of the mean input power (nan if B's is zero)."""
        return _relative(self.mean_power_a_w, self.mean_power_b_w)

    @property
    def cpu_ratio(self) -> float:
        """CPU time of A over B's (nan if B's is unknown or zero)."""
        return _ratio(self.cpu_time_a_s, self.cpu_time_b_s)


def _relative(a: float, b: float) -> float:
    return (a - b) / abs(b) if b != 0 else float("nan")


def _ratio(a: float, b: float) -> float:
    return a / b if b > 0 else float("nan")


@dataclass
class CampaignComparison:
    """Every common case, and the cases only one campaign has."""

    folder_a: str
    folder_b: str
    cases: list[CaseComparison]
    only_a: list[str]
    only_b: list[str]
    #: common cases with no stretch in the window asked for (--start / --end), with why
    outside_window: dict[str, str] = field(default_factory=dict)
    #: (setting, A's value, B's value) for each setting of the two folders' campaign.toml
    #: that differs (mesh, solver), what the comparison measures; None if either has none
    setup_differences: list[tuple[str, Any, Any]] | None = None

    def summary(self) -> dict[str, float]:
        """Median and largest NRMSE per component and the median thrust difference over the
        cases where neither run lost its numerics (all cases if every one did), their
        number, and the CPU ratio A / B over all cases."""
        out: dict[str, float] = {}
        kept = [c for c in self.cases if c.lost_a_s == 0 and c.lost_b_s == 0] or self.cases
        out["n_cases_compared"] = len(kept)
        for k in COMPONENTS:
            values = np.array([getattr(c, f"nrmse_{k}") for c in kept])
            out[f"median_nrmse_{k}"] = float(np.median(values))
            out[f"max_nrmse_{k}"] = float(np.max(values))
        out["median_abs_thrust_difference"] = float(np.nanmedian(
            [abs(c.thrust_difference) for c in kept]))
        out["cpu_ratio"] = _ratio(sum(c.cpu_time_a_s for c in self.cases),
                                  sum(c.cpu_time_b_s for c in self.cases))
        return out


class OutsideWindow(ConfigError):
    """Two records that share fewer than two samples in the window compared."""


def _motion_parameters(record: CfdRecord) -> dict:
    return {k: v for k, v in record.parameters.items() if k not in _NOT_MOTION}


def compare_records(a: CfdRecord, b: CfdRecord, start_s: float | None = None,
                    bound: tuple[Plate, Fluid, FreeStream] | None = None,
                    end_s: float | None = None) -> CaseComparison:
    """A against B for one motion, after ``start_s`` (default: the start-up ramp) and up to
    ``end_s`` (default: the shorter record's end), e.g. one period.

    Stretches whose forces the motion cannot have driven (``bound``: plate, fluid and stream
    of the force bound, by default the package's) are bridged like bursts and timed.

    Raises
    ------
    ConfigError
        If the two records are of different motions, naming the parameter, or if the
        window ends before it starts; :class:`OutsideWindow` if they share fewer than two
        samples in it.
    """
    pa, pb = _motion_parameters(a), _motion_parameters(b)
    for key in sorted(set(pa) | set(pb)):
        if pa.get(key) != pb.get(key):
            raise ConfigError(f"{a.name}: the two campaigns ran different motions "
                              f"({pa.get(key)!r} against {pb.get(key)!r})", key=key)
    start = float(pb.get("ramp_time", 0.0)) if start_s is None else float(start_s)
    end = min(a.time[-1], b.time[-1])
    if end_s is not None:
        if float(end_s) <= start:
            raise ConfigError(f"{a.name}: the comparison ends (t = {end_s:g} s) before it "
                              f"starts (t = {start:g} s)", key="end_s")
        end = min(end, float(end_s))
    keep = (b.time >= start) & (b.time <= end)
    if np.count_nonzero(keep) < 2:
        raise OutsideWindow(f"{a.name}: fewer than two common samples from t = {start:g} s "
                            f"to {end:g} s (the records end at {a.time[-1]:g} and "
                            f"{b.time[-1]:g} s)")
    t = b.time[keep]
    loads_a, bursts_a = bridge_load_bursts(a.loads, (a.time >= start) & (a.time <= end))
    loads_b, bursts_b = bridge_load_bursts(b.loads, (b.time >= start) & (b.time <= end))
    lost = {}
    for label, record in (("a", a), ("b", b)):
        loads = loads_a if label == "a" else loads_b
        breaches = find_envelope_breaches(record.state, loads,
                                          *(bound or (Plate(), Fluid(), FreeStream())),
                                          window=(record.time >= start)
                                          & (record.time <= end))
        lost[f"lost_{label}_s"] = float(sum(x.duration_s for x in breaches))
        if breaches:
            loads = Loads(loads.time, *(bridge_bursts(loads.time, getattr(loads, k), breaches)
                                        for k in COMPONENTS), source=loads.source)
            if label == "a":
                loads_a = loads
            else:
                loads_b = loads
    metrics = {}
    for k in COMPONENTS:
        ref = getattr(loads_b, k)[keep]
        val = np.interp(t, a.time, getattr(loads_a, k))
        metrics[f"nrmse_{k}"] = float(nrmse(val, ref))
        metrics[f"pearson_{k}"] = float(pearson(val, ref))
    means = {}
    for label, record, loads in (("a", a, loads_a), ("b", b, loads_b)):
        thrust, power = thrust_and_power(loads, record.state)
        window = (record.time >= start) & (record.time <= end)
        means[f"mean_thrust_{label}_n"] = time_mean(record.time[window], thrust[window])
        means[f"mean_power_{label}_w"] = time_mean(record.time[window], power[window])
    return CaseComparison(a.name, start, float(end), **metrics, **means,
                          n_bursts_a=len(bursts_a), n_bursts_b=len(bursts_b), **lost,
                          cpu_time_a_s=float(a.provenance.get("cpu_time_s", np.nan)),
                          cpu_time_b_s=float(b.provenance.get("cpu_time_s", np.nan)))


def compare_campaigns(folder_a: str | Path, folder_b: str | Path,
                      start_s: float | None = None,
                      end_s: float | None = None) -> CampaignComparison:
    """Every case both campaign folders finished, A against B.

    A case whose records share no stretch of two samples or more in the window asked for
    (a short case of a grid that runs each frequency for its own time, with a ``start_s``
    past its end) is left out and listed in ``outside_window``, with why.

    Raises
    ------
    MfflapError
        If the folders have no finished case in common, or none in the window.
    ConfigError
        If ``end_s`` is not after ``start_s``, or two records of a case are of different
        motions, or were run for another plate, fluid or stream
        (:mod:`mfflap.records.inputs`).
    """
    if start_s is not None and end_s is not None and float(end_s) <= float(start_s):
        raise ConfigError(f"the comparison ends (t = {end_s:g} s) before it starts "
                          f"(t = {start_s:g} s)", key="end_s")
    records_a = {r.name: r for r in read_records(folder_a)}
    records_b = {r.name: r for r in read_records(folder_b)}
    common = sorted(set(records_a) & set(records_b))
    if not common:
        raise MfflapError(f"{folder_a} and {folder_b} have no finished case in common "
                          f"({len(records_a)} and {len(records_b)} records)")
    setups = folder_setup(Path(folder_a)), folder_setup(Path(folder_b))
    for name in common:  # set-ups compared on one flow, not two flows
        differ = run_for_differences(run_for(records_a[name], setups[0]),
                                     run_for(records_b[name], setups[1]))
        if differ:
            key, in_a, in_b = differ[0]
            raise ConfigError(f"case {name} ran for {key} = {in_a:g} in {folder_a} and "
                              f"{in_b:g} in {folder_b}: a comparison of two set-ups needs the "
                              "same plate, fluid and stream", key=key)
    manifest = Path(folder_b) / "campaign.toml"
    bound = _bound_setup(read_toml(manifest)) if manifest.is_file() else None
    cases, outside = [], {}
    for name in common:
        try:
            cases.append(compare_records(records_a[name], records_b[name], start_s, bound,
                                         end_s))
        except OutsideWindow as exc:
            outside[name] = str(exc)
    if not cases:
        raise MfflapError(f"no case of the {len(common)} in common has two samples or more "
                          f"in the window asked for: {next(iter(outside.values()))}")
    manifests = manifest_setup(folder_a), manifest_setup(folder_b)
    return CampaignComparison(str(folder_a), str(folder_b), cases,
                              sorted(set(records_a) - set(records_b)),
                              sorted(set(records_b) - set(records_a)), outside,
                              None if None in manifests else setting_differences(*manifests))


def write_comparison(path: str | Path, comparison: CampaignComparison) -> Path:
    """The comparison as an HDF5 results file (``kind="campaign_comparison"``), with both
    campaigns' manifests (campaign.toml) stored beside it."""
    manifests = []
    for label, folder in (("A", comparison.folder_a), ("B", comparison.folder_b)):
        manifest = Path(folder) / "campaign.toml"
        text = manifest.read_text() if manifest.is_file() else "# no campaign.toml\n"
        manifests.append(f"# campaign {label}: {folder}\n{text}")
    rows = [asdict(c) for c in comparison.cases]
    units = {k: ("N" if k.endswith("_n") else "W" if k.endswith("_w") else
                 "s" if k.endswith("_s") else "1")
             for k in rows[0] if k != "case_id"}
    arrays = {k: np.array([r[k] for r in rows]) for k in units}
    with ResultsFile(path, "w", kind="campaign_comparison",
                     config_toml="\n".join(manifests)) as rf:
        rf.write_group("cases", arrays, units,
                       attrs={"case_ids": [c.case_id for c in comparison.cases],
                              "folder_a": comparison.folder_a,
                              "folder_b": comparison.folder_b,
                              "only_a": comparison.only_a, "only_b": comparison.only_b,
                              "outside_window": json.dumps(comparison.outside_window),
                              "setup_differences": json.dumps(comparison.setup_differences)})
    return Path(path)


def plot_comparison(path: str | Path, comparison: CampaignComparison,
                    labels: Sequence[str] = ("A", "B")) -> Path:
    """NRMSE of F_n and M per case against frequency, one marker per heave amplitude, and
    the relative mean-thrust difference."""
    # matplotlib takes about a second to load: only figures need it
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    folder_b = Path(comparison.folder_b)
    params = {c.case_id: read_record(folder_b / f"{c.case_id}.h5").parameters
              for c in comparison.cases}
    fig, axes = plt.subplots(1, 3, figsize=(13, 3.6))
    groups = sorted({params[c.case_id].get("heave_amplitude") for c in comparison.cases},
                    key=lambda v: (v is None, v))
    for g_index, amplitude in enumerate(groups):
        chosen = [c for c in comparison.cases
                  if params[c.case_id].get("heave_amplitude") == amplitude]
        f = [params[c.case_id].get("frequency", np.nan) for c in chosen]
        style = dict(marker="osD^v<>"[g_index % 7], ls="none",
                     label=f"h = {amplitude} m" if amplitude is not None else "cases")
        axes[0].plot(f, [100 * c.nrmse_normal_force for c in chosen], **style)
        axes[1].plot(f, [100 * c.nrmse_moment for c in chosen], **style)
        axes[2].plot(f, [100 * c.thrust_difference for c in chosen], **style)
    frequencies = sorted({params[c.case_id].get("frequency", np.nan)
                          for c in comparison.cases})
    for ax, title in zip(axes, ("F_n NRMSE [%]", "M NRMSE [%]",
                                "mean thrust, (A - B) / |B| [%]"), strict=True):
        ax.set_xscale("log")
        ax.set_xticks(frequencies, [f"{f:g}" for f in frequencies])
        ax.minorticks_off()
        ax.set_xlabel("frequency [Hz]")
        ax.set_title(title, fontsize=9)
        ax.grid(alpha=0.3)
    axes[2].axhline(0, color="0.5", lw=0.8)
    axes[0].legend(fontsize=7)
    fig.suptitle(f"{labels[0]} against {labels[1]}", fontsize=9)
    fig.tight_layout()
    save_figure(fig, path, dpi=110)
    plt.close(fig)
    return Path(path)
