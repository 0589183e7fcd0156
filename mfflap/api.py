"""The study facade: one case file's identify, optimise, back-test and diagnose steps, each
a method returning the typed result the rest of mfflap uses.

A :class:`Study` keeps the model it optimises with: the case file's coefficients until
:meth:`Study.identify` replaces them with those identified from CFD. Every step is also a
command (``mfflap identify``, ``optimise``, ``backtest``, ``gap diagnose``); the facade is
for notebooks and scripts.

Examples
--------
>>> import mfflap
>>> study = mfflap.Study.from_toml("cases/paper2026.toml")  # doctest: +SKIP
>>> fit = study.identify()                                  # doctest: +SKIP
>>> optimum = study.optimise(beta=0.0)                      # doctest: +SKIP
>>> outcome = study.backtest(optimum)                       # doctest: +SKIP
>>> verdict = study.diagnose([outcome])                     # doctest: +SKIP
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from mfflap.backtest.run import BacktestOutcome
from mfflap.backtest.workflow import backtest_all
from mfflap.config import CaseConfig, load_case
from mfflap.errors import ConfigError, shown
from mfflap.evaluation import table_evaluation
from mfflap.identification.fit import IdentificationResult
from mfflap.identification.workflow import identify_strategies, load_cases
from mfflap.kinematics import DiscreteMotion, TabulatedMotion, to_discrete
from mfflap.kinematics.table_file import read_motion_table
from mfflap.optimisation.optimise import OptimisationResult
from mfflap.optimisation.study import beta_study
from mfflap.optimisation.vortex_polish import PolishResult
from mfflap.performance import evaluate_discrete
from mfflap.pipeline import gap_diagnosis
from mfflap.records.record import backtest_fixture_dirs
from mfflap.study_results import (
    BacktestResult,
    CycleEvaluation,
    GapDiagnosis,
    IdentifiedCoefficients,
    OptimisedMotion,
    as_result,
    open_results,
)

#: the frequency weightings :meth:`Study.identify` takes
WEIGHTINGS = ("uniform", "low", "high")


@dataclass
class Study:
    """A study of one case file.

    Parameters
    ----------
    config
        The case (:func:`mfflap.config.load_case`).

    Attributes
    ----------
    model
        The Morison model the study optimises and back-tests with: the case file's
        coefficients, or those :meth:`identify` found.
    identification
        The last identification, or None.
    """

    config: CaseConfig
    model: Any = None
    identification: IdentificationResult | None = None
    _cases: list | None = field(default=None, repr=False)

    def __post_init__(self) -> None:
        if self.model is None:
            self.model = self.config.morison_model()

    @classmethod
    def from_toml(cls, path: str | Path) -> Study:
        """The study of a case file.

        Examples
        --------
        >>> Study.from_toml("cases/paper2026.toml").config.study.name
        'paper2026'
        """
        return cls(load_case(path))

    def evaluate(self, motion: DiscreteMotion | TabulatedMotion | str | Path | None = None
                 ) -> CycleEvaluation:
        """The model's loads, thrust and power over one cycle of ``motion``: a discrete
        motion, a motion table (a CSV file's path, or a :class:`TabulatedMotion`, taken as
        one cycle from its first row to its last) or, by default, the case file's [motion]
        with its N steps per half cycle.

        Examples
        --------
        >>> import numpy as np, tempfile
        >>> from pathlib import Path
        >>> from mfflap.api import Study
        >>> table = Path(tempfile.mkdtemp()) / "motion.csv"
        >>> t = np.linspace(0, 1, 41)
        >>> _ = table.write_text("t,h [m],theta [deg]\\n" + "".join(
        ...     f"{a},{0.2 * np.cos(2 * np.pi * a)},{20 * np.sin(2 * np.pi * a)}\\n" for a in t))
        >>> import mfflap
        >>> case = Path(mfflap.__file__).parents[1] / "cases" / "paper2026.toml"
        >>> study = Study.from_toml(case)
        >>> bool(study.evaluate(table).summary.mean_thrust > 0)  # heave leads pitch by 90 deg
        True
        """
        if isinstance(motion, str | Path | TabulatedMotion):
            return self._evaluate_table(motion)
        if motion is None:
            spec = self.config.motion
            motion = to_discrete(spec.build(), 1.0 / spec.frequency,
                                 self.config.discretisation.n_steps)
        scheme = self.config.optimisation.scheme
        return CycleEvaluation.of(evaluate_discrete(self.model, motion, scheme),
                                  float(motion.period), scheme=scheme, config=self.config)

    def _evaluate_table(self, table: TabulatedMotion | str | Path) -> CycleEvaluation:
        """A motion table over its span as one cycle, with the study's model."""
        if not isinstance(table, TabulatedMotion):
            table = read_motion_table(table, self.config.plate.chord)
        evaluation, end_time = table_evaluation(self.model, table)
        return CycleEvaluation.of(evaluation, end_time, half_cycle=False,
                                  scheme="continuous", config=self.config)

    def identify(self, records: str | Path | Sequence[str | Path] | None = None,
                 weighting: str = "uniform", bootstrap: int = 200) -> IdentifiedCoefficients:
        """Fit the coefficients to CFD records (default: the shipped Table 1 runs) with one
        of :data:`WEIGHTINGS`; the study then optimises with them.

        Raises
        ------
        ConfigError
            For a weighting that is not one of :data:`WEIGHTINGS`.
        """
        if weighting not in WEIGHTINGS:
            raise ConfigError(f"value {shown(weighting)}; allowed: {', '.join(WEIGHTINGS)}",
                              key="weighting")
        cases, excluded = load_cases(self.config, records)
        result = identify_strategies(self.config, cases, excluded, [weighting],
                                     n_bootstrap=bootstrap)[weighting]
        self._cases, self.identification = cases, result
        self.model = result.model(self.config.morison_model())
        return as_result(result, IdentifiedCoefficients, config=self.config)

    def optimise(self, beta: float, starts: int = 1) -> OptimisedMotion:
        """The optimised motion for the weight ``beta`` (0: most thrust, 1: least power),
        from the best sinusoid of a sweep and ``starts`` - 1 more starts, with the study's
        model."""
        study = beta_study(self.config, [beta], n_starts=starts, with_ipopt=False,
                           model=self.model, progress=lambda _: None)
        return as_result(study.sqp[beta], OptimisedMotion, model=self.model, config=self.config)

    def polish(self, optimum: OptimisationResult) -> PolishResult:
        """The optimum polished on the case's discrete-vortex model ([vortex]): Morison
        corrected sample by sample to the vortex model, in a trust region the vortex model
        judges (:func:`~mfflap.optimisation.vortex_polish.polish_on_vortex_model`).

        Examples
        --------
        >>> study = Study(load_case("cases/paper2026.toml",  # a short wake: a quick example
        ...                         ["vortex.wake_chords=0.5", "vortex.chord_points=16"]))
        >>> polished = study.polish(study.optimise(beta=0.0))
        >>> bool(polished.samples.peak_power < polished.start_samples.peak_power)
        True
        """
        from mfflap.optimisation.vortex_polish_study import polish_optima  # compiled kernel

        return polish_optima(self.config, {optimum.beta: optimum}, self.model)[optimum.beta]

    def backtest(self, optimum: OptimisationResult | DiscreteMotion, live: bool = False,
                 work_dir: str | Path | None = None) -> BacktestResult:
        """The optimum against CFD: a shipped record of the same motion, or with ``live`` a
        real OpenFOAM run (three periods after a start-up ramp). Without either, the
        outcome's status is "not back-tested" and its source says why."""
        motion = optimum.motion if isinstance(optimum, OptimisationResult) else optimum
        label = (f"β = {optimum.beta:g}" if isinstance(optimum, OptimisationResult)
                 else "motion")
        outcomes = backtest_all(self.config, {label: motion}, self.model,
                                fixture_folders=backtest_fixture_dirs(), live=live,
                                work_dir=work_dir)
        return as_result(outcomes[label], BacktestResult, config=self.config)

    def diagnose(self, backtests: Sequence[BacktestOutcome] = ()) -> GapDiagnosis:
        """Where the model departs from the identification CFD and which unmodelled
        effect explains it, checked on the back-tests' runs (which no fit saw)."""
        if self._cases is None:
            self._cases, _ = load_cases(self.config, None)
        diagnosis, where = gap_diagnosis(self.config, self._cases,
                                         {o.label: o for o in backtests})
        return as_result(diagnosis, GapDiagnosis, where=where, config=self.config)


__all__ = ["WEIGHTINGS", "Study", "open_results"]
