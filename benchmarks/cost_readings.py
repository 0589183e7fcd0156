"""The cost target under every reading measured, from the studies of cfd_cost.py.

Each study that ``benchmarks/cfd_cost.py --output F.h5`` wrote measures every run against
one yardstick on one motion, and is named ``cost_accuracy_pitch<P>[<suffix>].h5`` after the
motion's pitch amplitude (deg). The yardstick it names sorts it into one of four kinds:
mfflap's O-grid medium mesh at one time step (``reference[-coX]``), the mean of that mesh's
runs at several time steps (``mean of max Co ...``), openfoam.md's H-type medium mesh or its
fine one (``openfoam_md@openfoam_md_medium[-coX]``, ``..._fine[-coX]``). A study whose runs
all had the all_y_plus wall treatment (``cfd_cost.py --wall-treatment all_y_plus``) goes to
that kind's all_y_plus twin. Where several studies of one motion measure against one mesh
at different time steps, the smallest max Co counts; two studies of one motion against the
same yardstick are refused. For each study and each time window it holds (cycle 1, and the
first stroke where ``--window`` gave it), this prints the set-up within the cost that
comes nearest the yardstick and whether that meets the target: F_n and M within 2 % NRMSE
with both pressure solvers where the study reran the set-up with the other one (a pass
that turns on round-off is not a pass). "Within the cost" is the set-up's CPU per cycle as
a ratio to openfoam.md's set-up on the same motion and machine, at most 90 s / 4.4 min =
0.34. --figure draws the same as a grid, yardstick against pitch, one panel per window.

    python benchmarks/cost_readings.py [--studies docs/figures] [--figure F.png]
"""

from __future__ import annotations

import argparse
import math
import re
import textwrap
from dataclasses import dataclass
from pathlib import Path

STUDIES = Path(__file__).resolve().parents[1] / "docs" / "figures"
#: the kinds of yardstick, in the order drawn
YARDSTICKS = {"o_grid_time_step": "mfflap's O-grid medium mesh at its smallest time step run",
              "o_grid_mean": "mfflap's O-grid medium mesh, the mean of its time steps",
              "h_medium": "openfoam.md's H-type medium mesh at its smallest time step run",
              "h_fine": "openfoam.md's H-type fine mesh at its smallest time step run"}
#: the wall treatments a yardstick may run with: log_law (the shipped set-ups', named in the
#: kinds above) and all_y_plus (cfd_cost.py --wall-treatment all_y_plus), kinds of their own
YARDSTICKS.update({f"{kind}_all_y_plus": f"{said}, all_y_plus wall treatment"
                   for kind, said in list(YARDSTICKS.items())})
#: how cfd_cost.py's settings stamp names a wall treatment asked for every run
_WALL_TREATMENT = re.compile(r"; wall treatment (?P<name>\w+)")
_STUDY_FILE = re.compile(r"^cost_accuracy_pitch(?P<pitch>\d+(?:\.\d+)?)(?:_[\w.]+)?\.h5$")
#: a run's label: a set-up, maybe on a named mesh, maybe at another max Co
_RUN_LABEL = re.compile(r"^(?P<run>[^-\s]+?)(?:-co(?P<courant>\d+(?:\.\d+)?))?$")
#: the runs that are each kind of yardstick (at any max Co), and the set-up they run
_SINGLE_RUNS = {"reference": ("o_grid_time_step", "reference"),
                "openfoam_md@openfoam_md_medium": ("h_medium", "openfoam_md"),
                "openfoam_md@openfoam_md_fine": ("h_fine", "openfoam_md")}


def yardstick_kind(label: str) -> str:
    """The kind of yardstick (a key of YARDSTICKS) a study's ``yardstick`` label names: the
    O-grid medium mesh (``reference``), openfoam.md's H-type medium or fine mesh, each at
    its own max Co or another (``-coX``), or the mean of the O-grid's runs at several.

    Raises
    ------
    ValueError
        If the label is none of them.
    """
    if label.startswith("mean of max Co"):
        return "o_grid_mean"
    found = _RUN_LABEL.match(label)
    if found is None or found["run"] not in _SINGLE_RUNS:
        raise ValueError(f"yardstick {label!r} is none of: mean of max Co ..., "
                         f"{', '.join(_SINGLE_RUNS)} (each maybe -coX)")
    return _SINGLE_RUNS[found["run"]][0]


def study_wall_treatment(settings: str) -> str:
    """The wall treatment every run of a study had, from the settings cfd_cost.py stamps it
    with: the one ``--wall-treatment`` asked for, else the set-ups' own (log_law, the
    treatment of every set-up a yardstick runs)."""
    found = _WALL_TREATMENT.search(settings)
    return "log_law" if found is None else found["name"]


def _max_courant(label: str) -> float:
    """The max Co of a single-run yardstick (its set-up's own in setups.toml unless it ends
    in -coX); nan for a mean of several."""
    from mfflap.cfd.openfoam.setups import setup

    found = _RUN_LABEL.match(label)
    if found is None or found["run"] not in _SINGLE_RUNS:
        return math.nan
    if found["courant"]:
        return float(found["courant"])
    return setup(_SINGLE_RUNS[found["run"]][1]).solver.max_courant


#: the windows drawn, by their names in the studies
WINDOWS = {"cycle 1": "cycle 1", "t = 0.25-0.55 s": "first stroke, t = 0.25-0.55 s"}


@dataclass(frozen=True)
class Reading:
    """The nearest set-up within the cost under one reading of the target."""

    pitch_deg: float
    #: the kind of yardstick the study measures against, a key of YARDSTICKS
    yardstick: str
    #: the yardstick run's (or runs') label in the study
    yardstick_label: str
    window: str
    #: the nearest set-up within the cost, None if no named set-up is within it
    setup: str | None
    #: the larger of its F_n and M NRMSE, %, the worse of its runs (both pressure solvers)
    nrmse_percent: float
    #: its cost as a ratio to openfoam.md's set-up
    cost_ratio: float
    #: whether it ran with both pressure solvers
    both_solvers: bool
    #: openfoam.md's set-up's larger F_n and M NRMSE, %, for scale (nan if not run)
    baseline_nrmse_percent: float
    target_nrmse_percent: float

    @property
    def met(self) -> bool:
        """Within the cost and within the NRMSE target (with both solvers where run)."""
        return self.setup is not None and self.nrmse_percent <= self.target_nrmse_percent


def _worst_error(group, window: int) -> float:
    """The larger of a run's F_n and M NRMSE in a window, %."""
    return float(max(group["nrmse_percent"][window][:2]))


def study_readings(path: str | Path) -> list[Reading]:
    """The nearest set-up within the cost in each window of one study file.

    Parameters
    ----------
    path
        A ``cost_accuracy_pitch<P>[<suffix>].h5`` written by cfd_cost.py --output.

    Returns
    -------
    list of Reading
        One per window of the study that WINDOWS names, in the study's order.
    """
    import h5py

    path = Path(path)
    name = _STUDY_FILE.match(path.name)
    if name is None:
        raise ValueError(f"{path}: not a cost study file (cost_accuracy_pitch<P>"
                         "[<suffix>].h5)")
    readings = []
    with h5py.File(path, "r") as h5:
        attrs = dict(h5.attrs)
        for key in ("target_ratio", "target_nrmse_percent", "yardstick", "windows"):
            if key not in attrs:
                raise ValueError(f"{path}: the study has no attribute {key!r}")
        target_ratio = float(attrs["target_ratio"])
        try:
            kind = yardstick_kind(str(attrs["yardstick"]))
        except ValueError as error:
            raise ValueError(f"{path}: {error}") from None
        wall = study_wall_treatment(str(attrs.get("settings", "")))
        if wall != "log_law":
            kind = f"{kind}_{wall}"
            if kind not in YARDSTICKS:
                raise ValueError(f"{path}: wall treatment {wall!r} is none of log_law, "
                                 "all_y_plus")
        named = [label for label in h5 if h5[label].attrs.get("named", False)
                 and "cost_ratio" in h5[label].attrs]
        for index, window in enumerate(str(w) for w in attrs["windows"]):
            if window not in WINDOWS:
                continue
            best: tuple[float, str, float, bool] | None = None
            for label in named:
                group = h5[label]
                cost = float(group.attrs["cost_ratio"])
                if not cost <= target_ratio:
                    continue
                twin = group.attrs.get("other_pressure_solver_run")
                # a twin that failed (no NRMSE) leaves the set-up judged by one solver
                runs = [group] + ([h5[twin]] if twin is not None and twin in h5
                                  and "nrmse_percent" in h5[twin] else [])
                error = max(_worst_error(run, index) for run in runs)
                if best is None or error < best[0]:
                    best = (error, label, cost, len(runs) == 2)
            baseline = (_worst_error(h5["openfoam_md"], index)
                        if "nrmse_percent" in h5.get("openfoam_md", {}) else math.nan)
            error, setup, cost, both = best or (math.nan, None, math.nan, False)
            readings.append(Reading(float(name["pitch"]), kind,
                                    str(attrs["yardstick"]), window, setup, error, cost,
                                    both, baseline, float(attrs["target_nrmse_percent"])))
    return readings


def all_readings(studies: str | Path = STUDIES) -> list[Reading]:
    """Every reading of every cost study in a folder, by yardstick, then pitch, then window.

    Raises
    ------
    FileNotFoundError
        If there is no such folder, or it holds no cost study.
    ValueError
        If a study is malformed, or two measure one motion against the same yardstick
        (other than one mesh at two time steps).
    """
    if not Path(studies).is_dir():
        raise FileNotFoundError(f"{studies}: no such folder")
    paths = sorted(p for p in Path(studies).iterdir() if _STUDY_FILE.match(p.name))
    if not paths:
        raise FileNotFoundError(f"{studies}: no cost study (cost_accuracy_pitch<P>*.h5)")
    readings = {}
    for path in paths:
        for r in study_readings(path):
            key = (r.yardstick, r.pitch_deg, r.window)
            before = readings.get(key)
            if before is None:
                readings[key] = r
                continue
            courant = _max_courant(r.yardstick_label)
            courant_before = _max_courant(before.yardstick_label)
            if math.isnan(courant) or math.isnan(courant_before) or courant == courant_before:
                raise ValueError(f"{path}: a second study of {r.pitch_deg:g} deg against "
                                 f"{YARDSTICKS[r.yardstick]} (one is {before.yardstick_label})")
            # one mesh at two time steps: the smaller one counts
            readings[key] = r if courant < courant_before else before
    order = list(YARDSTICKS)
    return sorted(readings.values(), key=lambda r: (order.index(r.yardstick), r.pitch_deg,
                                                    list(WINDOWS).index(r.window)))


def describe(reading: Reading) -> str:
    """One line: the reading, the nearest set-up within the cost and the verdict."""
    where = (f"{reading.pitch_deg:g} deg, {YARDSTICKS[reading.yardstick]} "
             f"({reading.yardstick_label}), {reading.window}")
    if reading.setup is None:
        return f"{where}: no set-up within the cost"
    solvers = "both pressure solvers" if reading.both_solvers else "one pressure solver"
    return (f"{where}: {reading.setup} ({reading.cost_ratio:.2f} of openfoam.md's set-up) "
            f"{reading.nrmse_percent:.1f} % ({solvers}; openfoam.md's set-up "
            f"{reading.baseline_nrmse_percent:.1f} %): "
            f"{'met' if reading.met else 'not met'}")


def readings_figure(readings: list[Reading], path: str | Path):
    """A grid per window: yardstick against pitch, each cell the nearest set-up within the
    cost and its NRMSE, green where the target is met, red where not, grey where not
    measured. Returns the Figure."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    pitches = sorted({r.pitch_deg for r in readings})
    rows = [y for y in YARDSTICKS if any(r.yardstick == y for r in readings)]
    windows = [w for w in WINDOWS if any(r.window == w for r in readings)]
    cell = {(r.window, r.yardstick, r.pitch_deg): r for r in readings}
    fig, axes = plt.subplots(1, len(windows), figsize=(6.8 * len(windows), 1.2 + 1.5 * len(rows)),
                             squeeze=False)
    for ax, window in zip(axes[0], windows, strict=True):
        for i, yardstick in enumerate(rows):
            for j, pitch in enumerate(pitches):
                r = cell.get((window, yardstick, pitch))
                if r is None:
                    colour, text = "0.85", "not measured"
                elif r.setup is None:
                    colour, text = "#f4a6a6", "nothing within the cost"
                else:
                    colour = "#9bd69b" if r.met else "#f4a6a6"
                    twin = "" if r.both_solvers else ", one solver"
                    courant = _max_courant(r.yardstick_label)
                    against = "" if math.isnan(courant) else f"its max Co {courant:g}:\n"
                    text = (f"{against}{r.setup.replace('@', chr(10) + '@')}\n"
                            f"{r.nrmse_percent:.1f} %{twin}\n"
                            f"(openfoam.md's set-up {r.baseline_nrmse_percent:.1f} %)")
                ax.add_patch(plt.Rectangle((j, i), 1, 1, facecolor=colour, edgecolor="white",
                                           linewidth=2))
                ax.text(j + 0.5, i + 0.5, text, ha="center", va="center", fontsize=7.5)
        ax.set_xlim(0, len(pitches))
        ax.set_ylim(len(rows), 0)
        ax.set_xticks([j + 0.5 for j in range(len(pitches))],
                      [f"pitch {p:g}°" for p in pitches])
        ax.set_yticks([i + 0.5 for i in range(len(rows))],
                      [textwrap.fill(YARDSTICKS[y], 24) for y in rows], fontsize=8)
        ax.tick_params(length=0, pad=8)
        ax.set_title(WINDOWS[window], fontsize=10)
    fig.suptitle("The cost target: the nearest set-up within the cost (≤ 0.34 of openfoam.md's "
                 "set-up) and its larger F_n / M NRMSE\nagainst each yardstick "
                 "(the worse of its two pressure solvers; green: within 2 %)", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return fig


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--studies", default=str(STUDIES),
                        help="folder of the cost studies (default: docs/figures)")
    parser.add_argument("--figure", default=None, help="draw the readings into this image")
    args = parser.parse_args()
    try:
        readings = all_readings(args.studies)
    except (FileNotFoundError, ValueError) as error:
        raise SystemExit(str(error)) from None
    for reading in readings:
        print(describe(reading))
    met = [r for r in readings if r.met]
    print(f"{len(met)} of {len(readings)} readings met"
          + (": " + "; ".join(f"{r.pitch_deg:g} deg against {r.yardstick_label}"
                              + (" with all_y_plus" if r.yardstick.endswith("_all_y_plus")
                                 else "") + f", {r.window}" for r in met) if met else ""))
    if args.figure:
        readings_figure(readings, args.figure)
        print(f"wrote {args.figure}")


if __name__ == "__main__":
    main()
