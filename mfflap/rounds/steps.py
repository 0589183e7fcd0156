"""What a round hands the next: each back-tested optimum as a point of the output correction,
and each trust region's step judged by CFD, with whatever made its two runs differ."""

from __future__ import annotations

from mfflap.config import CaseConfig
from mfflap.optimisation.output_correction import CorrectionPoint, OutputCorrection, cfd_objective
from mfflap.optimisation.store import beta_label
from mfflap.optimisation.study import problem_for
from mfflap.optimisation.trust_region import TrustStep, noise_of_objective
from mfflap.rounds.checks import MotionCheck


def correction_points(outcome, checks: dict[str, MotionCheck], index: int) -> dict:
    """beta -> :class:`~mfflap.optimisation.output_correction.CorrectionPoint`: each
    back-tested optimum of round ``index`` with its CFD means, for the next round's output
    correction."""
    points = {}
    for beta, result in (outcome.study.sqp.items() if outcome.study is not None else ()):
        label = beta_label(beta)
        if label in checks:
            c = checks[label]
            points[beta] = CorrectionPoint(
                result.motion, c.cfd_mean_thrust, c.cfd_mean_power,
                f"round {index}'s beta = {beta:g} (back-test {c.key})",
                thrust_usable=c.thrust_counted, scales=(c.thrust_scale, c.power_scale))
    return points


def secant_points(points: dict, checks: dict[str, MotionCheck],
                  records_used: dict[float, set[str]]) -> dict:
    """beta -> the point of ``points`` (:func:`correction_points`) the first-order slopes may
    take: a motion checked on its own CFD, or on a neighbour's (a record the back-test
    look-up found within its tolerance, or the same periodic motion shifted in time, as
    every optimum made with the phase fixed finds the shipped free series' records) that
    has not yet given that beta a point. A trust region's short step that reuses an earlier
    run adds no second point with that run's CFD. ``records_used`` (beta -> the record
    names its points were measured on) is brought up to date."""
    kept = {}
    for beta, point in points.items():
        check = checks[beta_label(beta)]
        used = records_used.setdefault(beta, set())
        if not check.cfd_of_neighbour or check.cfd_record not in used:
            kept[beta] = point
        used.add(check.cfd_record)
    return kept


def trust_steps(outcome, checks: dict[str, MotionCheck], regions: dict, centres: dict,
                config: CaseConfig, repeatability: float | None = None) -> dict:
    """beta -> :class:`~mfflap.optimisation.trust_region.TrustStep`: each back-tested
    optimum of a round with trust ``regions`` (beta -> region) judged against its centre
    (``centres``: beta -> the centre's
    :class:`~mfflap.optimisation.output_correction.CorrectionPoint`).

    The predicted objective is the one the round optimised (``config``'s problem with the
    round's model, its outputs corrected as they were); CFD's is the same problem with the
    model's outputs scaled to each motion's own CFD means. ``repeatability``: the share by
    which two CFD runs of one motion differ, which relaxes the ratio by the noise of J at the
    centre (:func:`~mfflap.optimisation.trust_region.noise_of_objective`; None: not known).
    """
    steps = {}
    sqp = outcome.study.sqp if outcome.study is not None else {}
    cfg = outcome.config or config
    for beta, region in regions.items():
        label = beta_label(beta)
        if beta not in sqp or label not in checks or outcome.model is None:
            continue
        c, centre, optimum = checks[label], centres[beta], sqp[beta].motion
        base = problem_for(cfg, beta, outcome.model)

        def corrected(correction: OutputCorrection | None, motion, base=base) -> float:
            if correction is None:
                return float(base.objective(motion))
            return correction.objective_factor(base.beta) * float(
                correction.problem(base).objective(motion))

        own = outcome.corrections.get(beta)
        steps[beta] = TrustStep.judged(
            region, beta, optimum, cfd_objective(centre, base),
            cfd_objective(CorrectionPoint(optimum, c.cfd_mean_thrust, c.cfd_mean_power, label,
                                          thrust_usable=c.thrust_counted), base),
            corrected(own, centre.motion), corrected(own, optimum),
            0.0 if repeatability is None else noise_of_objective(
                repeatability, beta, centre.cfd_mean_thrust, centre.cfd_mean_power))
    return steps


def backtest_record_of(outcome, beta: float):
    """The CFD record of this round's back-test of ``beta``'s optimum, or None."""
    found = outcome.backtests.get(beta_label(beta))
    return None if found is None else found.record


def mixed_set_up_notes(outcome, beta: float, whose: str) -> list[str]:
    """``whose`` run's compared cycles mixing two set-ups (a retry resumed it part-way
    through them), said for a trust step's ``ran_otherwise``; empty if not."""
    found = outcome.backtests.get(beta_label(beta))
    c = None if found is None else found.comparison
    if c is None or not c.compared_cycles_mixed_set_up:
        return []
    return [f"{whose}'s compared cycles mix two set-ups (its settings changed at t = "
            f"{c.cfd_settings_since_s:.4g} s, after t = {c.compared_from_s:.4g} s)"]


__all__ = ["backtest_record_of", "correction_points", "mixed_set_up_notes", "trust_steps"]
