"""Evaluate a case file's motion with its Morison model or with the discrete-vortex model
(what ``mfflap evaluate`` does)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from mfflap.config import CaseConfig, load_case
from mfflap.errors import ConfigError
from mfflap.hydro.loads import Loads
from mfflap.kinematics.convert import to_discrete
from mfflap.kinematics.state import KINEMATIC_UNITS, KinematicState
from mfflap.parameters import FreeStream, Plate
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


#: the models of ``mfflap evaluate``
MODELS = ("morison", "vortex")
#: the discrete-vortex model's time steps per period of the motion
VORTEX_STEPS_PER_PERIOD = 200
#: how far the stream travels, in chords, before the period the discrete-vortex model's
#: means are taken over (the harmonic motion starts from rest; its start-up wake is then
#: this far downstream)
VORTEX_SETTLING_CHORDS = 5.0


@dataclass(frozen=True)
class _ComputedLoads:
    """Loads computed beforehand, with what :func:`evaluate_states` asks of a model."""

    computed: Loads
    plate: Plate
    stream: FreeStream

    def loads(self, state: KinematicState) -> Loads:
        return self.computed


def _evaluate_with_vortex_model(case: CaseConfig, motion, frequency: float,
                                duration: float | None) -> tuple[Evaluation, float, str]:
    """The discrete-vortex model on the case's motion from rest; a harmonic motion's last
    period after the stream travelled VORTEX_SETTLING_CHORDS chords, a ramp motion's
    whole duration. Returns the evaluation, the time it spans and a description."""
    from mfflap.hydro.discrete_vortex import simulate_vortex_model

    period = 1.0 / frequency
    if duration is None:
        travel = case.flow.velocity * period / case.plate.chord  # chords per period
        periods = max(3, int(np.ceil(VORTEX_SETTLING_CHORDS / max(travel, 1e-12))) + 1)
    else:
        periods = duration / period
    n = int(np.ceil(VORTEX_STEPS_PER_PERIOD * periods))
    state = motion.sample(np.arange(n) * (periods * period / n))
    loads = simulate_vortex_model(state, case.plate, case.fluid, case.flow, case.vortex).loads
    keep = slice(n - VORTEX_STEPS_PER_PERIOD, None) if duration is None else slice(None)
    kept = KinematicState(state.time[keep],
                          **{k: getattr(state, k)[keep] for k in KINEMATIC_UNITS})
    kept_loads = Loads(kept.time, loads.normal_force[keep], loads.tangential_force[keep],
                       loads.moment[keep], source=loads.source)
    ev = evaluate_states(_ComputedLoads(kept_loads, case.plate, case.flow), kept, frequency)
    span = period if duration is None else duration
    where = (f"period {periods} of {periods} from rest" if duration is None
             else f"{periods:g} cycles from rest")
    return ev, span, f"discrete-vortex model, {where}"


#: samples a second of a motion table's span, at least
TABLE_SAMPLES_PER_SECOND = 200
#: samples between two rows of a motion table, at least, for the Morison model (cheap: the
#: spline between the rows is followed closely); the vortex model, whose cost grows as the
#: square of its steps, takes one a row
MORISON_SAMPLES_PER_ROW = 10
#: the most samples a motion table's evaluation takes (about 20 MB of state and loads)
MAX_TABLE_SAMPLES = 200_000


def table_states(table, end_time: float, per_row: int = MORISON_SAMPLES_PER_ROW
                 ) -> KinematicState:
    """Uniform samples of a motion table over [0, end_time]: the denser of
    TABLE_SAMPLES_PER_SECOND and ``per_row`` a table row, at most MAX_TABLE_SAMPLES.

    Raises
    ------
    ConfigError
        If the span needs more than MAX_TABLE_SAMPLES samples.
    """
    rows = int(np.size(table.table_time))
    n = max(int(np.ceil(TABLE_SAMPLES_PER_SECOND * end_time)), per_row * (rows - 1), 2)
    if n > MAX_TABLE_SAMPLES:
        raise ConfigError(f"the motion table's {end_time:g} s at "
                          f"{TABLE_SAMPLES_PER_SECOND} samples a second and {per_row} a row "
                          f"need {n:,} samples; at most {MAX_TABLE_SAMPLES:,} are taken",
                          key="motion_table")
    return table.sample(np.arange(n) * (end_time / n))


def table_evaluation(force_model, table, per_row: int = MORISON_SAMPLES_PER_ROW
                     ) -> tuple[Evaluation, float]:
    """``force_model``'s evaluation of a motion table over its span, first row to last,
    taken as one cycle (:func:`table_states`), and that span, s."""
    end_time = float(table.table_time[-1])
    state = table_states(table, end_time, per_row)
    return evaluate_states(force_model, state, 1.0 / end_time), end_time


def evaluate_table(case: CaseConfig, table_path: str | Path,
                   model: str = "morison") -> CaseEvaluation:
    """Evaluate a motion table (a CSV file, :mod:`mfflap.kinematics.table_file`) with the
    case's plate, fluid, stream and model, over the table's whole span: the means are those
    of the span from its first row to its last, taken as one cycle.

    Raises
    ------
    ParseError
        For a table that cannot be read (naming the file and the line).
    ConfigError
        If ``model`` is not one of MODELS, or the span needs more than MAX_TABLE_SAMPLES.
    """
    from mfflap.kinematics.table_file import read_motion_table

    if model not in MODELS:
        raise ConfigError(f"model must be one of {list(MODELS)}, got {model!r}", key="model")
    table = read_motion_table(table_path, case.plate.chord)
    if model == "vortex":
        from mfflap.hydro.discrete_vortex import simulate_vortex_model

        end_time = float(table.table_time[-1])
        state = table_states(table, end_time, per_row=1)
        loads = simulate_vortex_model(state, case.plate, case.fluid, case.flow,
                                      case.vortex).loads
        ev = evaluate_states(_ComputedLoads(loads, case.plate, case.flow), state,
                             1.0 / end_time)
        scheme = "discrete-vortex"
    else:
        ev, end_time = table_evaluation(case.morison_model(), table)
        scheme = "continuous"
    desc = f"motion table {Path(table_path).name}, {end_time:g} s"
    fig = cycle_figure(ev, end_time, half_cycle=False, title=f"{case.study.name}: {desc}")
    return CaseEvaluation(case, ev, scheme, desc, fig)


def evaluate_case(path: str | Path, scheme: str | None = None,
                  model: str = "morison") -> CaseEvaluation:
    """Evaluate the [motion] of a case file.

    With the Morison model, harmonic motions use the discrete scheme with the case's N (the
    paper's model); ramp motions are sampled continuously over the time a campaign case at
    this frequency runs (``identification.n_cycles`` carrier periods capped at
    ``max_duration``). The discrete-vortex model (``model="vortex"``) runs the motion from
    rest at VORTEX_STEPS_PER_PERIOD steps a period: a harmonic motion's means are those of
    its last period, once the stream has carried the start-up wake VORTEX_SETTLING_CHORDS
    chords away; a ramp motion's those of its whole duration.

    Raises
    ------
    ConfigError
        If a ramp motion pitches the plate to 90 deg or past it in that time, if ``scheme``
        is given for a ramp motion or for the vortex model (a discrete scheme is the
        Morison model's, for a harmonic motion), or if ``model`` is not one of MODELS.

    Examples
    --------
    >>> from pathlib import Path
    >>> case = Path(__file__).parents[1] / "cases" / "paper2026.toml"
    >>> result = evaluate_case(case, model="vortex")
    >>> result.scheme
    'discrete-vortex'
    """
    if model not in MODELS:
        raise ConfigError(f"model must be one of {list(MODELS)}, got {model!r}", key="model")
    case = load_case(path)
    spec = case.motion
    if scheme is not None and (spec.kind != "harmonic" or model == "vortex"):
        what = ("the discrete-vortex model runs in continuous time" if model == "vortex"
                else f"the {spec.kind} motion of [motion] is evaluated continuously")
        raise ConfigError(f"scheme {scheme!r} is a discrete scheme of the Morison model's "
                          f"harmonic motion; {what}", source=case.source, key="scheme")
    if model == "vortex":
        duration = None
        if spec.kind != "harmonic":
            duration = case.identification.case_duration(spec.frequency)
            spec.check_upright(duration, "identification.n_cycles periods capped at "
                               "max_duration", source=case.source)
        ev, span, where = _evaluate_with_vortex_model(case, spec.build(), spec.frequency,
                                                      duration)
        desc = f"{spec.kind} f={spec.frequency} Hz, h={spec.heave_amplitude} m, {where}"
        fig = cycle_figure(ev, span, half_cycle=False, title=f"{case.study.name}: {desc}")
        return CaseEvaluation(case, ev, "discrete-vortex", desc, fig)
    model = case.morison_model()
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
