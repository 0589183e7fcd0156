"""What each round found (:class:`RoundSummary`), the rounds as run (:class:`LoopResult`) and
a round in words."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from mfflap.optimisation.output_correction import describe_correction
from mfflap.rounds.checks import MotionCheck


@dataclass
class RoundSummary:
    """What one round fitted, optimised and found in CFD.

    Attributes
    ----------
    index : 1, 2, ...
    out_dir : the round's report.html and results.h5
    n_cases : CFD runs the round's identification used
    loop_records_in_fit : the earlier rounds' back-test records among them
    coefficients : the coefficients the round optimised with (name -> value)
    checks : per back-tested motion
    not_backtested : label -> why
    corrections : beta -> the output correction the round optimised it with (as a dict)
    trust_steps : beta -> the round's step in that beta's trust region, judged by its CFD
        (:class:`~mfflap.optimisation.trust_region.TrustStep`)
    """

    index: int
    out_dir: Path
    n_cases: int
    loop_records_in_fit: int
    coefficients: dict[str, float]
    checks: dict[str, MotionCheck] = field(default_factory=dict)
    not_backtested: dict[str, str] = field(default_factory=dict)
    corrections: dict[float, dict] = field(default_factory=dict)
    trust_steps: dict = field(default_factory=dict)

    @property
    def largest_error(self) -> float | None:
        """The largest counted error over the back-tested motions whose CFD the round's fit
        had not seen (None: none such)."""
        return max((c.error for c in self.checks.values() if not c.in_fit), default=None)

    def as_dict(self) -> dict:
        """JSON-friendly."""
        return {"round": self.index, "out_dir": str(self.out_dir), "n_cases": self.n_cases,
                "loop_records_in_fit": self.loop_records_in_fit,
                "coefficients": self.coefficients, "largest_error": self.largest_error,
                "checks": {k: c.as_dict() for k, c in self.checks.items()},
                "not_backtested": self.not_backtested,
                "corrections": {f"{b:g}": c for b, c in self.corrections.items()},
                "trust_steps": {f"{b:g}": t.as_dict() for b, t in self.trust_steps.items()}}


@dataclass
class LoopResult:
    """The rounds run and why they stopped."""

    rounds: list[RoundSummary]
    tolerance: float
    converged: bool
    stopped_because: str
    correct_outputs: bool = False
    correction_gain: float = 1.0
    refit: bool = True
    #: the trust region's first radius (None: none)
    trust_radius: float | None = None
    #: with a trust region, beta -> the rounds' answer: the last motion of that beta CFD
    #: confirmed (its region's centre when the rounds stopped), in words with its CFD means
    answers: dict = field(default_factory=dict)
    #: whether the output corrections had slopes through the earlier motions (first order)
    first_order: bool = False
    #: the share by which two CFD runs of one motion differ, as given (None: not known)
    cfd_repeatability: float | None = None

    def as_dict(self) -> dict:
        """JSON-friendly."""
        return {"tolerance": self.tolerance, "converged": self.converged,
                "stopped_because": self.stopped_because,
                "correct_outputs": self.correct_outputs,
                "correction_gain": self.correction_gain, "refit": self.refit,
                "trust_radius": self.trust_radius, "first_order": self.first_order,
                "cfd_repeatability": self.cfd_repeatability,
                "answers": {f"{b:g}": a for b, a in self.answers.items()},
                "rounds": [r.as_dict() for r in self.rounds]}


def describe_round(summary: RoundSummary, tolerance: float) -> str:
    """One line per motion: model against CFD mean thrust and power."""
    lines = [f"round {summary.index}: {summary.n_cases} CFD runs in the fit "
             f"({summary.loop_records_in_fit} from earlier rounds); "
             + ", ".join(f"{k} {v:.3g}" for k, v in summary.coefficients.items())]
    for beta, corr in summary.corrections.items():
        lines.append(f"  beta {beta:g} optimised with the outputs corrected: "
                     + describe_correction(corr))
    for beta, step in summary.trust_steps.items():
        lines.append(f"  beta {beta:g}: {step.describe()}")
    for c in summary.checks.values():
        thrust = (f"{c.thrust_error:+.1%}" if c.thrust_counted
                  else f"{c.thrust_error:+.1%} (not counted: small thrust)")
        who = "model" if (c.thrust_scale, c.power_scale) == (1.0, 1.0) else "corrected model"
        lines.append(f"  {c.label}: thrust {who} {c.predicted_thrust:.3g} N / CFD "
                     f"{c.cfd_mean_thrust:.3g} N ({thrust}); power {who} "
                     f"{c.predicted_power:.3g} W / CFD {c.cfd_mean_power:.3g} W "
                     f"({c.power_error:+.1%})" + ("; its CFD was in the fit (not counted)"
                                                   if c.in_fit else "")
                     + (f"; the CFD of {c.cfd_record}, a motion within the back-test "
                        "look-up's tolerance" if c.cfd_of_neighbour else ""))
    for label, reason in summary.not_backtested.items():
        lines.append(f"  {label}: not back-tested: {reason.splitlines()[0]}")
    largest = summary.largest_error
    if largest is not None:
        lines.append(f"  largest counted error {largest:.1%} "
                     f"({'within' if largest <= tolerance else 'beyond'} {tolerance:.0%})")
    return "\n".join(lines)


__all__ = ["LoopResult", "RoundSummary", "describe_round"]
