"""The results a study returns, each able to draw itself and to write itself to HDF5, and
:func:`open_results`, which reads any results file mfflap writes back into them.

Each class here is the type the rest of mfflap computes (an
:class:`~mfflap.performance.Evaluation`, an
:class:`~mfflap.identification.fit.IdentificationResult`, ...) with ``plot()`` (the
figure the reports show of it, with units) and ``to_hdf5(path)`` (a results file of its
kind, the case file beside it when the result knows its case).

Examples
--------
>>> import mfflap
>>> study = mfflap.Study.from_toml("cases/paper2026.toml")       # doctest: +SKIP
>>> optimum = study.optimise(beta=0.0)                           # doctest: +SKIP
>>> optimum.to_hdf5("optimum.h5")                                # doctest: +SKIP
>>> mfflap.open_results("optimum.h5").optima[0.0].summary.mean_thrust  # doctest: +SKIP
"""

from __future__ import annotations

import dataclasses
import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from matplotlib.figure import Figure

from mfflap.backtest.run import BacktestOutcome
from mfflap.backtest.store import read_backtests, write_backtests
from mfflap.config import CaseConfig, stored_case
from mfflap.errors import MfflapError
from mfflap.gap.diagnose import Diagnosis
from mfflap.gap.store import read_diagnosis, write_diagnosis
from mfflap.identification.fit import IdentificationResult
from mfflap.identification.store import read_identification, strategies_in, write_identification
from mfflap.optimisation.optimise import OptimisationResult
from mfflap.optimisation.store import beta_key, beta_label, read_result, read_sweep, write_result
from mfflap.performance import Evaluation
from mfflap.plots import cycle_figure
from mfflap.records.record import CfdRecord, read_record
from mfflap.reports.gap import candidate_figure
from mfflap.reports.identification import coefficient_figure
from mfflap.reports.optimisation import motion_figure, pareto_figure
from mfflap.reports.run import backtest_figure
from mfflap.results import ResultsFile
from mfflap.sweep import SweepResult

#: the kinds of results file :func:`open_results` reads
KINDS = ("run", "optimisation", "identification", "backtest", "gap_diagnosis", "rounds",
         "evaluation", "cfd_record")


def _toml(config: CaseConfig | None) -> str | None:
    return None if config is None else config.to_toml()


def _num(value: Any) -> str:
    """A number as a short plain figure (4 significant digits), whatever its numpy type."""
    return f"{float(np.real(value)):.4g}"


def as_result(base: Any, cls: type, **extra: Any) -> Any:
    """``base`` (a result the rest of mfflap computes) as an instance of its subclass
    ``cls`` here, with ``extra`` fields (its case, its model).

    Examples
    --------
    >>> from mfflap.backtest.run import BacktestOutcome
    >>> outcome = BacktestOutcome("motion", "k", "not back-tested", "no record")
    >>> as_result(outcome, BacktestResult).status
    'not back-tested'
    """
    values = {f.name: getattr(base, f.name) for f in dataclasses.fields(base) if f.init}
    return cls(**values, **extra)


@dataclass(frozen=True)
class CycleEvaluation(Evaluation):
    """The model's loads, thrust and power over one cycle of a motion.

    Examples
    --------
    >>> from mfflap.kinematics import HarmonicMotion, to_discrete
    >>> from mfflap.config import loads_case
    >>> from mfflap.performance import evaluate_discrete
    >>> case = loads_case('[study]\\nname = "demo"\\n')
    >>> motion = to_discrete(HarmonicMotion(1.0, 0.3, 0.35, 1.57), 1.0, 20)
    >>> ev = CycleEvaluation.of(evaluate_discrete(case.morison_model(), motion), 1.0)
    >>> ev.plot().axes[0].get_ylabel()
    'thrust [N]'
    """

    period_s: float = 1.0
    half_cycle: bool = True
    scheme: str = "paper"
    config: CaseConfig | None = field(default=None, repr=False, compare=False)

    @classmethod
    def of(cls, evaluation: Evaluation, period_s: float, half_cycle: bool = True,
           scheme: str = "paper", config: CaseConfig | None = None) -> CycleEvaluation:
        """``evaluation`` with what drawing and storing it need."""
        return as_result(evaluation, cls, period_s=period_s, half_cycle=half_cycle,
                       scheme=scheme, config=config)

    def plot(self) -> Figure:
        """Thrust [N], input power [W], F_n, F_t [N] and M [N m] over the cycle."""
        return cycle_figure(self, self.period_s, self.half_cycle)

    def __repr__(self) -> str:
        m = self.summary
        return (f"CycleEvaluation({_num(m.mean_thrust)} N mean thrust, {_num(m.mean_power)} W "
                f"mean power, {_num(m.max_power)} W peak, period {_num(self.period_s)} s, "
                f"scheme {self.scheme!r})")

    def to_hdf5(self, path: str | Path) -> Path:
        """Write state, loads, thrust, power and the cycle means (kind "evaluation")."""
        with ResultsFile(path, "w", kind="evaluation", config_toml=_toml(self.config)) as rf:
            rf.write_state("state", self.state)
            rf.write_loads("loads", self.loads)
            rf.write_group("performance", {"thrust": self.thrust,
                                           "input_power": self.input_power,
                                           "time": self.state.time},
                           {"thrust": "N", "input_power": "W", "time": "s"},
                           {"scheme": self.scheme, "period_s": self.period_s,
                            "half_cycle": self.half_cycle})
            rf.write_summary("summary", self.summary)
        return Path(path)


@dataclass
class IdentifiedCoefficients(IdentificationResult):
    """The coefficients identified from CFD with one frequency weighting, their bootstrap
    spread and the fit's errors per case.

    Examples
    --------
    >>> import mfflap
    >>> fit = mfflap.Study.from_toml("cases/paper2026.toml").identify()  # doctest: +SKIP
    >>> fit.plot().axes[0].get_ylabel()                                   # doctest: +SKIP
    'coefficient [-]'
    """

    config: CaseConfig | None = field(default=None, repr=False, compare=False)

    def plot(self) -> Figure:
        """The coefficients with their bootstrap 95 % intervals."""
        return coefficient_figure({self.strategy: self})

    def __repr__(self) -> str:
        said = ", ".join(f"{k}={_num(v)} ± {_num(self.standard_error.get(k, 0.0))}"
                         for k, v in self.coefficients.items())
        return (f"IdentifiedCoefficients({said}; {self.strategy} weighting, "
                f"{len(self.case_names)} cases)")

    def to_hdf5(self, path: str | Path) -> Path:
        """Write the fit (kind "identification", read by ``mfflap report identification``)."""
        with ResultsFile(path, "w", kind="identification",
                         config_toml=_toml(self.config)) as rf:
            write_identification(rf, self)
        return Path(path)


@dataclass
class OptimisedMotion(OptimisationResult):
    """An optimised motion of one β with its cycle means, the optimiser's history and the
    model it was optimised with.

    Examples
    --------
    >>> import mfflap
    >>> optimum = mfflap.Study.from_toml("cases/paper2026.toml").optimise(0.0)  # doctest: +SKIP
    >>> optimum.plot()                                                         # doctest: +SKIP
    <Figure size 1100x600 with 4 Axes>
    """

    model: Any = field(default=None, repr=False, compare=False)
    config: CaseConfig | None = field(default=None, repr=False, compare=False)

    def plot(self) -> Figure:
        """Pitch [deg], heave [m], thrust [N] and input power [W] over the cycle, the power
        limit drawn (Fig. 4c-e)."""
        model = self.model if self.model is not None else (
            self.config.morison_model() if self.config is not None else None)
        if model is None:
            raise MfflapError("this optimum knows neither its model nor its case; draw it "
                              "with mfflap.reports.optimisation.motion_figure(model, ...)")
        scheme = self.config.optimisation.scheme if self.config is not None else "paper"
        max_power = self.config.optimisation.max_power if self.config is not None else None
        return motion_figure(model, {beta_label(self.beta): self.motion}, scheme, max_power)

    def __repr__(self) -> str:
        m = self.summary
        state = "converged" if self.converged else "not converged"
        return (f"OptimisedMotion(β = {_num(self.beta)}: {_num(m.mean_thrust)} N mean thrust, "
                f"{_num(m.mean_power)} W mean power, {_num(self.resampled_max_power)} W peak, "
                f"period {_num(self.motion.period)} s, {state})")

    def to_hdf5(self, path: str | Path) -> Path:
        """Write the optimum (kind "optimisation", as ``mfflap optimise`` writes each β),
        with the coefficients it was optimised with, so that ``mfflap backtest`` takes it."""
        with ResultsFile(path, "w", kind="optimisation", config_toml=_toml(self.config)) as rf:
            write_result(rf, f"optimisation/sqp/{beta_key(self.beta)}", self)
            if self.model is not None:
                rf.h5["optimisation"].attrs["model_coefficients"] = json.dumps(
                    {k: float(v) for k, v in self.model.coefficients.items()})
        return Path(path)


@dataclass
class BacktestResult(BacktestOutcome):
    """One motion against CFD: the model's and CFD's thrust and power over the compared
    cycles, their means, and whether the power limit held in CFD.

    Examples
    --------
    >>> import mfflap
    >>> study = mfflap.Study.from_toml("cases/paper2026.toml")         # doctest: +SKIP
    >>> result = study.backtest(study.optimise(0.0))                   # doctest: +SKIP
    >>> result.status                                                  # doctest: +SKIP
    'back-tested'
    """

    config: CaseConfig | None = field(default=None, repr=False, compare=False)

    def plot(self) -> Figure:
        """Thrust [N] and input power [W] over the last compared cycle, model and CFD, the
        power limit drawn."""
        max_power = self.config.optimisation.max_power if self.config is not None else np.nan
        return backtest_figure({self.label: self}, max_power)

    def __repr__(self) -> str:
        c = self.comparison
        if c is None:
            return f"BacktestResult({self.label}: {self.status}, {self.source})"
        return (f"BacktestResult({self.label}: CFD {_num(c.cfd_mean_thrust)} N, "
                f"{_num(c.cfd_mean_power)} W mean, {_num(c.cfd_max_power)} W peak; model "
                f"{_num(c.model_mean_thrust)} N, {_num(c.model_mean_power)} W)")

    def to_hdf5(self, path: str | Path) -> Path:
        """Write the comparison (kind "backtest"): histories, metrics, status and source."""
        with ResultsFile(path, "w", kind="backtest", config_toml=_toml(self.config)) as rf:
            write_backtests(rf, {self.label: self})
        return Path(path)


@dataclass
class GapDiagnosis(Diagnosis):
    """Where the model departs from CFD and which candidate effect explains it.

    Examples
    --------
    >>> import mfflap
    >>> verdict = mfflap.Study.from_toml("cases/paper2026.toml").diagnose()  # doctest: +SKIP
    >>> verdict.verdict                                                     # doctest: +SKIP
    'within noise: ...'
    """

    #: where the residual lies (:func:`mfflap.gap.where.decompose`)
    where: dict = field(default_factory=dict, repr=False)
    config: CaseConfig | None = field(default=None, repr=False, compare=False)

    def plot(self) -> Figure:
        """Each candidate's held-out error reduction [%], the significant ones in green."""
        return candidate_figure(self)

    def __repr__(self) -> str:
        headline = self.headline()
        return f"GapDiagnosis({headline if len(headline) <= 160 else headline[:157] + '...'})"

    def to_hdf5(self, path: str | Path) -> Path:
        """Write the diagnosis (kind "gap_diagnosis", as ``mfflap gap diagnose`` does)."""
        with ResultsFile(path, "w", kind="gap_diagnosis",
                         config_toml=_toml(self.config)) as rf:
            write_diagnosis(rf, self, self.where)
        return Path(path)


@dataclass(frozen=True)
class StoredRound:
    """One round of CFD in the loop: per back-tested motion the model's, the corrected
    prediction's and CFD's mean thrust [N] and power [W], and the round's summary."""

    index: int
    labels: list[str]
    values: dict[str, np.ndarray]
    summary: dict


@dataclass
class Results:
    """A results file read back (:func:`open_results`): what it holds, each as the type a
    study returns. Attributes a file of its kind does not hold are empty or None.

    Attributes
    ----------
    path, kind
        The file and what it holds (``run``, ``optimisation``, ...).
    config
        The case file stored beside the results (None for a CFD record).
    evaluation
        A model evaluation (``mfflap evaluate --output``).
    identification
        Identified coefficients by weighting.
    sweep, best_sinusoid
        The sinusoid sweep and the index of its best feasible motion.
    optima
        Optimised motions by β.
    backtests
        Back-tests by motion label.
    gap
        The gap diagnosis.
    rounds
        The rounds of CFD in the loop.
    record
        A CFD record (a campaign's or a back-test's run).
    """

    path: Path
    kind: str
    config: CaseConfig | None = None
    evaluation: CycleEvaluation | None = None
    identification: dict[str, IdentifiedCoefficients] = field(default_factory=dict)
    sweep: SweepResult | None = None
    best_sinusoid: int | None = None
    optima: dict[float, OptimisedMotion] = field(default_factory=dict)
    backtests: dict[str, BacktestResult] = field(default_factory=dict)
    gap: GapDiagnosis | None = None
    rounds: list[StoredRound] = field(default_factory=list)
    record: CfdRecord | None = None

    def plot(self) -> Figure:
        """The file's main figure: the thrust-power plane of the sweep and the optima
        (Fig. 4a,b) for a run or optimisation, else the figure of what it holds."""
        if self.sweep is not None:
            return pareto_figure(self.sweep, int(self.best_sinusoid or 0), self.optima)
        for held in (self.evaluation, *self.identification.values(), *self.optima.values(),
                     *self.backtests.values(), self.gap):
            if held is not None:
                return held.plot()
        raise MfflapError(f"{self.path}: holds nothing mfflap draws ({self.kind!r} results)")


def open_results(path: str | Path) -> Results:
    """Read a results file mfflap wrote (any of :data:`KINDS`) back into the objects a
    study returns.

    Raises
    ------
    MfflapError
        Naming the file: not an HDF5 file mfflap wrote, or a kind this reader does not know.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> from mfflap.config import loads_case
    >>> from mfflap.kinematics import HarmonicMotion, to_discrete
    >>> from mfflap.performance import evaluate_discrete
    >>> case = loads_case('[study]\\nname = "demo"\\n')
    >>> motion = to_discrete(HarmonicMotion(1.0, 0.3, 0.35, 1.57), 1.0, 20)
    >>> ev = CycleEvaluation.of(evaluate_discrete(case.morison_model(), motion), 1.0,
    ...                         config=case)
    >>> path = ev.to_hdf5(pathlib.Path(tempfile.mkdtemp()) / "cycle.h5")
    >>> back = open_results(path)
    >>> back.kind, back.config.study.name
    ('evaluation', 'demo')
    >>> bool(abs(back.evaluation.summary.mean_thrust - ev.summary.mean_thrust) < 1e-9)
    True
    """
    path = Path(path)
    with ResultsFile(path, "r") as rf:
        kind = str(rf.h5.attrs.get("kind", ""))
    if kind not in KINDS:
        raise MfflapError(f"{path}: holds {kind!r} results, which open_results does not "
                          f"read; it reads {', '.join(KINDS)}")
    if kind == "cfd_record":
        return Results(path, kind, record=read_record(path))
    with ResultsFile(path, "r") as rf:
        toml_text = rf.config_toml
        config = stored_case(toml_text, source=f"{path}:/inputs") if toml_text else None
        results = Results(path, kind, config)
        _read_into(results, rf)
    return results


def _read_into(results: Results, rf: ResultsFile) -> None:
    """Fill ``results`` with what ``rf`` holds."""
    config, h5 = results.config, rf.h5
    if "summary" in h5 and "state" in h5 and "loads" in h5:
        performance, attrs = rf.read_group("performance")
        results.evaluation = CycleEvaluation(
            state=rf.read_state("state"), loads=rf.read_loads("loads"),
            thrust=performance["thrust"], input_power=performance["input_power"],
            summary=rf.read_summary("summary"), period_s=float(attrs.get("period_s", np.nan)),
            half_cycle=bool(attrs.get("half_cycle", True)),
            scheme=str(attrs.get("scheme", "paper")), config=config)
    for strategy in strategies_in(rf):
        fit = read_identification(rf, f"identification/{strategy}")
        results.identification[strategy] = as_result(fit, IdentifiedCoefficients, config=config)
    if "optimisation" in h5:
        model = None
        stored = h5["optimisation"].attrs.get("model_coefficients")
        if config is not None:
            model = config.morison_model()
            if stored is not None:
                model = model.with_coefficients(json.loads(stored))
        if "optimisation/sweep" in h5:
            results.sweep, results.best_sinusoid = read_sweep(rf, "optimisation/sweep")
        for key in h5["optimisation/sqp"] if "optimisation/sqp" in h5 else ():
            optimum = read_result(rf, f"optimisation/sqp/{key}")
            results.optima[optimum.beta] = as_result(optimum, OptimisedMotion, model=model,
                                                   config=config)
    for label, outcome in read_backtests(rf).items():
        results.backtests[label] = as_result(outcome, BacktestResult, config=config)
    if "gap" in h5 and "gap/scores" in h5:
        diagnosis, where = read_diagnosis(rf)
        results.gap = as_result(diagnosis, GapDiagnosis, where=where, config=config)
    if "rounds" in h5:
        for name in sorted(h5["rounds"], key=lambda n: int(n.rsplit("_", 1)[1])):
            values, attrs = rf.read_group(f"rounds/{name}")
            results.rounds.append(StoredRound(int(name.rsplit("_", 1)[1]),
                                              json.loads(attrs["labels"]), values,
                                              json.loads(attrs["summary"])))


__all__ = [
    "KINDS",
    "BacktestResult",
    "CycleEvaluation",
    "GapDiagnosis",
    "IdentifiedCoefficients",
    "OptimisedMotion",
    "Results",
    "StoredRound",
    "as_result",
    "open_results",
]
