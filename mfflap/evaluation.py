"""Evaluate a case file's motion with its Morison model (what ``mfflap evaluate`` does)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from mfflap.config import CaseConfig, load_case
from mfflap.errors import ConfigError
from mfflap.kinematics.convert import to_discrete
from mfflap.performance import CycleSummary, Evaluation, evaluate_discrete, evaluate_states
from mfflap.plots import cycle_figure
from mfflap.results import ResultsFile


@dataclass
class CaseEvaluation:
    """One evaluated case: the evaluation, its figure and the case it came from."""

    case: CaseConfig
    evaluation: Evaluation
    scheme: str
    description: str
    figure: Figure

    def summary_dict(self) -> dict:
        """Cycle means as plain floats."""
        return self.evaluation.summary.as_dict()

    def summary_with_units(self) -> dict[str, tuple[float, str]]:
        """Cycle means with their units."""
        d = self.summary_dict()
        return {k: (d[k], CycleSummary.UNITS[k]) for k in CycleSummary.UNITS}

    def save(self, path: str | Path) -> None:
        """Write state, loads, thrust, power and summary to HDF5 with the case beside them."""
        ev = self.evaluation
        with ResultsFile(path, "w", kind="evaluation", config_toml=self.case.to_toml()) as rf:
            rf.write_state("state", ev.state)
            rf.write_loads("loads", ev.loads)
            rf.write_group("performance", {"thrust": ev.thrust, "input_power": ev.input_power,
                                           "time": ev.state.time},
                           {"thrust": "N", "input_power": "W", "time": "s"},
                           {"scheme": self.scheme})
            rf.write_summary("summary", ev.summary)


def evaluate_case(path: str | Path, scheme: str | None = None) -> CaseEvaluation:
    """Evaluate the [motion] of a case file.

    Harmonic motions use the discrete scheme with the case's N (the paper's model); ramp
    motions are sampled continuously over the time a campaign case at this frequency runs
    (``identification.n_cycles`` carrier periods capped at ``max_duration``).

    Raises
    ------
    ConfigError
        If a ramp motion pitches the plate to 90 deg or past it in that time, or ``scheme``
        is given for it (a discrete scheme is for a harmonic motion).
    """
    case = load_case(path)
    model = case.morison_model()
    spec = case.motion
    if scheme is not None and spec.kind != "harmonic":
        raise ConfigError(f"scheme {scheme!r} is a discrete scheme of the harmonic motion; "
                          f"the {spec.kind} motion of [motion] is evaluated continuously",
                          source=case.source, key="scheme")
    scheme = scheme or case.model.scheme
    motion = spec.build()
    period = 1.0 / spec.frequency
    if spec.kind == "harmonic":
        d = to_discrete(motion, period, case.discretisation.n_steps)
        ev = evaluate_discrete(model, d, scheme)  # type: ignore[arg-type]
        half = True
        desc = (f"harmonic f={spec.frequency} Hz, h={spec.heave_amplitude} m, "
                f"theta={spec.pitch_amplitude_deg} deg, phi={spec.phase_deg} deg, "
                f"N={case.discretisation.n_steps}")
        plot_period = period
    else:
        duration = case.identification.case_duration(spec.frequency)
        n_cycles = duration / period
        spec.check_upright(duration, "identification.n_cycles periods capped at max_duration",
                           source=case.source)
        n = int(np.ceil(200 * n_cycles))
        t = np.arange(n) * (duration / n)
        ev = evaluate_states(model, motion.sample(t), spec.frequency)
        half = False
        scheme = "continuous"
        desc = (f"ramp harmonic f={spec.frequency} Hz, h={spec.heave_amplitude} m, "
                f"theta_kamp={spec.pitch_ramp_rate_deg} deg/s, phi={spec.phase_deg} deg, "
                f"{n_cycles:g} cycles")
        plot_period = n_cycles * period
    fig = cycle_figure(ev, plot_period, half_cycle=half, title=f"{case.study.name}: {desc}")
    return CaseEvaluation(case, ev, scheme, desc, fig)
