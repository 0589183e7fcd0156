"""Verification of a CFD set-up against linear unsteady thin-aerofoil theory.

Small harmonic heaves, pitches and both together (effective incidence of a few degrees,
reduced frequency k = omega c / 2U from 0.4 to 3.4) are run as a resumable campaign
(:func:`mfflap.campaign.execute.run_campaign`). Each record's F_n and M are compared with
:mod:`mfflap.hydro.thin_aerofoil`, which is exact for such motions of a thin plate in inviscid
attached flow, and with the strip model, which has no circulation. A set-up whose frames,
scaling or moment reference were wrong fails here by tens of percent; a sound one lies a few
percent from the theory (docs/findings/linear_theory.md).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

from mfflap.campaign.cases import HarmonicCase
from mfflap.cfd.imposed_motion import imposed_state
from mfflap.cfd.linear_theory import compare_with_theory
from mfflap.errors import MfflapError
from mfflap.hydro.base import ForceModel
from mfflap.hydro.thin_aerofoil import thin_aerofoil_loads_at
from mfflap.metrics import nrmse, time_mean
from mfflap.parameters import Fluid, FreeStream, Plate
from mfflap.performance import thrust_and_power
from mfflap.plots import save_figure
from mfflap.records.bursts import bridge_load_bursts
from mfflap.records.record import CfdRecord
from mfflap.results import ResultsFile

#: Start-up left out of the comparison, s (the motions ramp up over 0.25 s).
DISCARD_TIME_S = 0.5


def _case(frequency: float, heave_m: float, pitch_deg: float, phase_deg: float) -> HarmonicCase:
    """Two periods (at least 1.5 s) after a 0.25 s ramp."""
    return HarmonicCase(frequency, heave_m, pitch_deg, phase_deg,
                        duration=max(2.0 / frequency, 1.5), ramp_time=0.25)


#: The default motions: heave, pitch and heave leading pitch by 90 deg at f = 0.25-2 Hz, with
#: amplitudes that keep the effective incidence near 4-10 deg in the package's stream.
SMALL_MOTIONS: tuple[HarmonicCase, ...] = (
    _case(1.0, 0.005, 0.0, 0.0), _case(1.0, 0.0, 2.0, 90.0), _case(1.0, 0.004, 1.5, 90.0),
    _case(0.5, 0.01, 0.0, 0.0), _case(0.5, 0.0, 2.0, 90.0), _case(0.5, 0.008, 2.0, 90.0),
    _case(2.0, 0.0025, 0.0, 0.0), _case(2.0, 0.0, 1.0, 90.0), _case(2.0, 0.002, 0.75, 90.0),
    _case(0.25, 0.02, 0.0, 0.0), _case(0.25, 0.0, 3.0, 90.0),
)


@dataclass(frozen=True)
class LinearCheck:
    """One CFD record against linear theory and the strip model (after the start-up).

    Attributes
    ----------
    case_id : str
    reduced_frequency : k = omega c / (2 U)
    max_effective_incidence_deg : deg, max |atan(q / U)| of the theory's downwash q
    nrmse_normal_force, nrmse_moment : NRMSE of the theory against the CFD (CFD's range)
    pearson_normal_force, pearson_moment : Pearson r of the theory and the CFD
    strip_nrmse_normal_force, strip_nrmse_moment : the strip model's NRMSE against the CFD
    cfd_mean_power_w, theory_mean_power_w : W, time-mean input power
    n_numerical_bursts : bridged before the comparison (:mod:`mfflap.records.bursts`)
    """

    case_id: str
    reduced_frequency: float
    max_effective_incidence_deg: float
    nrmse_normal_force: float
    pearson_normal_force: float
    nrmse_moment: float
    pearson_moment: float
    strip_nrmse_normal_force: float
    strip_nrmse_moment: float
    cfd_mean_power_w: float
    theory_mean_power_w: float
    n_numerical_bursts: int


def case_of_record(record: CfdRecord) -> HarmonicCase:
    """The harmonic case a record was run for, from its parameters.

    Raises
    ------
    MfflapError
        If the record is not of a harmonic motion (names the record and what it is).
    """
    p = record.parameters
    if p.get("kind") != "harmonic":
        raise MfflapError(f"record {record.name}: a linear check needs a harmonic motion, "
                          f"got kind {p.get('kind')!r}")
    try:
        return HarmonicCase(**{k: float(p[k]) for k in (
            "frequency", "heave_amplitude", "pitch_amplitude_deg", "phase_deg", "duration",
            "ramp_time")})
    except KeyError as exc:
        raise MfflapError(f"record {record.name}: parameter {exc.args[0]!r} missing") from None


def check_record(record: CfdRecord, model: ForceModel, plate: Plate | None = None,
                 fluid: Fluid | None = None, stream: FreeStream | None = None,
                 discard_time: float = DISCARD_TIME_S) -> LinearCheck:
    """Compare one harmonic record with linear theory and with ``model`` after ``discard_time``."""
    plate, fluid, stream = plate or Plate(), fluid or Fluid(), stream or FreeStream()
    case = case_of_record(record)
    motion, t = case.motion(), record.time
    keep = t >= discard_time
    if keep.sum() < 8:
        raise MfflapError(f"record {record.name}: fewer than 8 samples after "
                          f"t = {discard_time} s")
    cfd, bursts = bridge_load_bursts(record.loads, keep)
    out, _ = compare_with_theory(motion, case.ramp_time, record.state, cfd, keep, plate, fluid,
                                 stream)
    strip = model.loads(record.state)
    for name in ("normal_force", "moment"):
        out[f"strip_nrmse_{name}"] = float(nrmse(getattr(strip, name)[keep],
                                                 getattr(cfd, name)[keep]))
    _, cfd_power = thrust_and_power(cfd, record.state)
    return LinearCheck(
        case_id=record.name,
        reduced_frequency=float(np.pi * case.frequency * plate.chord / stream.velocity),
        cfd_mean_power_w=time_mean(t[keep], cfd_power[keep]),
        theory_mean_power_w=out.pop("mean_power"),
        n_numerical_bursts=len(bursts), **out)


def summary_table(checks: Sequence[LinearCheck]) -> str:
    """Plain-text table of the checks, one line per case."""
    lines = [f"{'case':42s} {'k':>5s} {'inc':>5s} {'F_n NRMSE':>9s} {'r':>6s} "
             f"{'M NRMSE':>8s} {'r':>6s} {'P cfd/th':>8s} {'strip F_n':>9s}"]
    for c in checks:
        ratio = (c.cfd_mean_power_w / c.theory_mean_power_w if c.theory_mean_power_w
                 else float("nan"))
        lines.append(f"{c.case_id:42s} {c.reduced_frequency:5.2f} "
                     f"{c.max_effective_incidence_deg:5.1f} {100 * c.nrmse_normal_force:8.1f}% "
                     f"{c.pearson_normal_force:6.3f} {100 * c.nrmse_moment:7.1f}% "
                     f"{c.pearson_moment:6.3f} {ratio:8.2f} "
                     f"{100 * c.strip_nrmse_normal_force:8.1f}%")
    return "\n".join(lines)


def write_checks(path: str | Path, checks: Sequence[LinearCheck], config_toml: str) -> Path:
    """The checks as an HDF5 results file (``kind="linear_check"``), the set-up beside them."""
    rows = [asdict(c) for c in checks]
    units = {"reduced_frequency": "1", "max_effective_incidence_deg": "deg",
             "nrmse_normal_force": "1", "pearson_normal_force": "1", "nrmse_moment": "1",
             "pearson_moment": "1", "strip_nrmse_normal_force": "1",
             "strip_nrmse_moment": "1", "cfd_mean_power_w": "W", "theory_mean_power_w": "W",
             "n_numerical_bursts": "1"}
    arrays = {k: np.array([r[k] for r in rows]) for k in units}
    with ResultsFile(path, "w", kind="linear_check", config_toml=config_toml) as rf:
        rf.write_group("checks", arrays, units,
                       attrs={"case_ids": [c.case_id for c in checks],
                              "discard_time_s": DISCARD_TIME_S})
    return Path(path)


def plot_checks(path: str | Path, records: Sequence[CfdRecord], model: ForceModel,
                plate: Plate | None = None, fluid: Fluid | None = None,
                stream: FreeStream | None = None) -> Path:
    """F_n of each record: CFD, linear theory and the strip model, one panel per case."""
    # matplotlib takes about a second to load: only figures need it
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    n = len(records)
    cols = min(3, max(n, 1))
    rows = -(-n // cols)
    fig, axes = plt.subplots(rows, cols, figsize=(4.2 * cols, 2.6 * rows), squeeze=False)
    for ax, record in zip(axes.flat, records, strict=False):
        case = case_of_record(record)
        motion, t = case.motion(), record.time
        theory = thin_aerofoil_loads_at(lambda tt, m=motion, r=case.ramp_time:
                                        imposed_state(m, tt, r), t, plate, fluid, stream)
        ax.plot(t, record.loads.normal_force, "k", lw=1.2, label="CFD")
        ax.plot(t, theory.normal_force, "C0--", lw=1.0, label="linear theory")
        ax.plot(t, model.loads(record.state).normal_force, "C3:", lw=1.0, label="strip model")
        ax.axvline(DISCARD_TIME_S, color="0.7", lw=0.6)
        ax.set_title(record.name.removeprefix("harmonic_"), fontsize=8)
        ax.set_xlabel("t (s)", fontsize=8)
        ax.set_ylabel("F_n (N)", fontsize=8)
        ax.tick_params(labelsize=7)
    for ax in list(axes.flat)[n:]:
        ax.set_visible(False)
    axes.flat[0].legend(fontsize=7)
    fig.tight_layout()
    save_figure(fig, path, dpi=110)
    plt.close(fig)
    return Path(path)
