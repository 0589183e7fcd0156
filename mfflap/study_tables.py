"""The case-file tables of the main job's back-tests and of CFD in the loop.

``[backtest]`` says how ``mfflap run`` checks its optima in CFD; ``[rounds]`` holds the
settings that only studies of the method use (rounds of CFD in the loop, the output
correction, the trust region, first-order corrections, CFD's repeatability). Each table
refuses a combination that cannot run, naming the key, so that what a case file says is
what runs.
"""

from __future__ import annotations

from dataclasses import dataclass, fields

from mfflap.errors import ConfigError
from mfflap.validation import bounded, check_fields

#: the largest trust-region radius, as a fraction of the centre motion's accelerations and
#: time step
MAX_TRUST_RADIUS = 2.0

#: the [rounds] keys that act from round 2 on: given for one round, they are refused
LATER_ROUNDS_KEYS = ("refit", "correct_outputs", "trust_radius", "first_order",
                     "cfd_repeatability")


@dataclass(frozen=True)
class BacktestSettings:
    """How ``mfflap run`` back-tests its optima in CFD: the periods a live run simulates,
    the whole cycles its means are taken over and how a retried run restarts.

    Examples
    --------
    >>> BacktestSettings().average_cycles
    2
    >>> BacktestSettings(cycles=1.0, average_cycles=2)  # doctest: +IGNORE_EXCEPTION_DETAIL
    Traceback (most recent call last):
    mfflap.errors.ConfigError: backtest.average_cycles: 2 whole cycles need cycles >= 2
    """

    cycles: float = bounded(3.0, low=1.0, high=100.0, unit="1",
                            doc="periods a live back-test runs after its start-up ramp of "
                                "half a period")
    average_cycles: int = bounded(2, low=1, high=100, unit="1",
                                  doc="the CFD and model means are taken over the last this "
                                      "many whole cycles, with CFD's cycle-to-cycle scatter")
    retries_from_start: bool = bounded(True, choices=(True, False), unit="",
                                       doc="a retried live run reruns from t = 0 s, so that "
                                           "every cycle ran one set-up (false: it resumes "
                                           "from its last written time)")

    def __post_init__(self) -> None:
        check_fields(self, prefix="backtest.")
        if self.average_cycles > self.cycles:
            raise ConfigError(
                f"{self.average_cycles} whole cycles need cycles >= {self.average_cycles}; "
                f"a live back-test runs {self.cycles:g} after its start-up ramp",
                key="backtest.average_cycles")

    @property
    def simulated_periods(self) -> float:
        """The periods a live back-test simulates, its start-up ramp of half a period
        included.

        Examples
        --------
        >>> BacktestSettings().simulated_periods
        3.5
        """
        return self.cycles + 0.5


@dataclass(frozen=True)
class RoundsSettings:
    """CFD in the loop: the main job run up to ``count`` times, each round identifying the
    model with the back-test CFD of the rounds before, until the model predicts its
    back-tested motions' mean thrust and power within ``tolerance``.

    Examples
    --------
    >>> RoundsSettings().count
    1
    >>> RoundsSettings(count=3, trust_radius=0.25).trust_radius
    0.25
    >>> RoundsSettings(trust_radius=0.25)  # doctest: +IGNORE_EXCEPTION_DETAIL
    Traceback (most recent call last):
    mfflap.errors.ConfigError: rounds.trust_radius: needs rounds.count >= 2
    """

    count: int = bounded(1, low=1, high=100, unit="1",
                         doc="rounds of CFD in the loop (1: the main job once)")
    tolerance: float = bounded(0.1, low=0.0, high=1.0, low_open=True, high_open=True,
                               unit="1", doc="relative error of the model's mean thrust and "
                                             "power against CFD at which the rounds stop")
    refit: bool = bounded(True, choices=(True, False), unit="",
                          doc="refit the identified coefficients on the back-tests of the "
                              "rounds before (false: round 1's coefficients throughout)")
    correct_outputs: bool = bounded(False, choices=(True, False), unit="",
                                    doc="from round 2 on, optimise each beta with the model's "
                                        "thrust and power scaled to predict the CFD means of "
                                        "the previous round's optimum (output space mapping)")
    correction_gain: float = bounded(1.0, low=0.0, high=1.0, low_open=True, unit="1",
                                     doc="K of a first-order filter of the output scales "
                                         "(1: no filter)")
    trust_radius: float | None = bounded(None, low=0.0, high=MAX_TRUST_RADIUS, low_open=True,
                                         unit="1",
                                         doc="keep each beta's optimum within this fraction "
                                             "of the last confirmed optimum's accelerations "
                                             "and time step (trust-region modifier "
                                             "adaptation; left out: no trust region)")
    first_order: bool = bounded(False, choices=(True, False), unit="",
                                doc="give the corrected objective a secant slope too "
                                    "(needs correct_outputs and trust_radius)")
    cfd_repeatability: float | None = bounded(None, low=0.0, high=1.0, low_open=True,
                                              high_open=True, unit="1",
                                              doc="share by which two CFD runs of one motion "
                                                  "differ in their means; relaxes the trust "
                                                  "region's judgement of each step")

    def __post_init__(self) -> None:
        check_fields(self, prefix="rounds.")
        if self.count == 1:
            given = [f.name for f in fields(self) if f.name in LATER_ROUNDS_KEYS
                     and getattr(self, f.name) != f.default]
            if given:
                raise ConfigError("rounds of CFD in the loop take this from round 2 on; "
                                  "it needs rounds.count >= 2", key=f"rounds.{given[0]}")
        if self.count > 1 and not self.refit and not self.correct_outputs:
            raise ConfigError("refit = false keeps the coefficients of round 1, so without "
                              "correct_outputs every round would optimise the same motions",
                              key="rounds.refit")
        if self.correction_gain != 1.0 and not self.correct_outputs:
            raise ConfigError("the gain filters the output correction's scales; it needs "
                              "correct_outputs = true", key="rounds.correction_gain")
        if self.cfd_repeatability is not None and self.trust_radius is None:
            raise ConfigError("CFD's repeatability relaxes the trust region's judgement of "
                              "each step; it needs trust_radius", key="rounds.cfd_repeatability")
        if self.first_order:
            missing = [k for k, given in (("correct_outputs", self.correct_outputs),
                                          ("trust_radius", self.trust_radius is not None))
                       if not given]
            if missing:
                raise ConfigError("a slope on the corrected objective would lead the "
                                  "optimiser off along a secant without a trust region; it "
                                  f"needs {' and '.join(missing)}", key="rounds.first_order")
            if self.correction_gain != 1.0:
                raise ConfigError("first-order corrections meet CFD at the centre with the "
                                  f"measured scales; correction_gain {self.correction_gain:g} "
                                  "filters them", key="rounds.first_order")


__all__ = ["MAX_TRUST_RADIUS", "BacktestSettings", "RoundsSettings"]
