"""Does a diagnosed effect carry over to motions outside the identification data?

The diagnosis claims an effect on held-out folds of its own cases, the sinusoids of the
identification grid. Optimised motions lie outside that grid (other periods, amplitudes and
harmonic content): a reduced model with the effect is only worth optimising with if it
predicts their CFD better too. This check fits the base model, and the base model plus each
candidate, on every identification case (scaled as the diagnosis scaled them), and compares
their predictions with CFD runs none of the fits saw, such as the back-tested motions, each
over its last simulated period.

Each held-out motion weighs alike: its error is the mean over the load components of the
squared NRMSE (RMS error over the CFD's range in that motion), and a set of terms' gain is
one minus the sum of its errors over the base model's.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np

from mfflap.errors import MfflapError
from mfflap.gap.system import GapSystem
from mfflap.hydro.base import ForceModel, ForceTerm
from mfflap.hydro.loads import Loads
from mfflap.identification.data import COMPONENTS, CaseData, prepare_case
from mfflap.kinematics.state import KinematicState
from mfflap.metrics import nrmse, time_mean
from mfflap.parameters import Fluid, FreeStream, Plate
from mfflap.performance import thrust_and_power
from mfflap.records.record import CfdRecord

#: Label of the base model's predictions.
BASE = "base"


@dataclass
class HeldOutMotion:
    """A CFD run none of the fits saw.

    Attributes
    ----------
    case : CaseData
        The compared window (the run's last full period when it has one), CFD loads and
        imposed kinematics on a uniform time base.
    history : KinematicState
        The whole imposed motion from the run's start, on which the predictions are
        evaluated: a lagged term (the wake's) sees the run's history, not a window that
        starts in equilibrium.
    cfd_repeat_nrmse : dict of str to float
        CFD's own NRMSE per load component: the compared period against the period before
        it, normalised as the model's NRMSE is (NaN when the run holds no whole period
        before it): the closest a model that repeats each cycle can come.
    """

    case: CaseData
    history: KinematicState
    cfd_repeat_nrmse: dict[str, float] = field(default_factory=dict)

    @property
    def name(self) -> str:
        """The record's name."""
        return self.case.name

    @property
    def label(self) -> str:
        """What the motion is (a back-test's label, e.g. "β = 0"), else its name."""
        return str(self.case.parameters.get("label", self.case.name))


def motion_period(record: CfdRecord) -> float | None:
    """The record's period, s: its ``period`` parameter, else one over its ``frequency``;
    None when it has neither (or they are not positive)."""
    for key, to_period in (("period", float), ("frequency", lambda f: 1.0 / float(f))):
        value = record.parameters.get(key)
        try:
            if value is not None and float(value) > 0:
                return to_period(value)
        except (TypeError, ValueError):
            continue
    return None


def held_out_motions(records: Sequence[CfdRecord], discard_time: float = 0.75,
                     n_samples: int = 400, *, plate: Plate | None = None,
                     fluid: Fluid | None = None, stream: FreeStream | None = None
                     ) -> tuple[list[HeldOutMotion], dict[str, str]]:
    """Prepare each record's last full period (its whole run after ``discard_time`` when it
    has no period) as :func:`~mfflap.identification.data.prepare_case` does; records that
    cannot be used are returned with the reason."""
    motions, excluded = [], {}
    for rec in records:
        period = motion_period(rec)
        start = float(rec.time[-1]) - period if period is not None else discard_time
        if period is not None and start < float(rec.time[0]):
            excluded[rec.name] = (f"it ran {float(rec.time[-1] - rec.time[0]):.4g} s, less "
                                  f"than one period ({period:.4g} s)")
            continue
        try:
            case = prepare_case(rec, start, n_samples, plate=plate, fluid=fluid, stream=stream)
        except MfflapError as exc:
            excluded[rec.name] = str(exc)
            continue
        motions.append(HeldOutMotion(case, rec.state, _repeat_nrmse(rec, case, period)))
    return motions, excluded


def _repeat_nrmse(record: CfdRecord, case: CaseData, period: float | None
                  ) -> dict[str, float]:
    """Each component's NRMSE of the record's period before the compared one against it."""
    t = case.state.time
    if period is None or t[0] - period < float(record.time[0]) - 1e-9 * period:
        return {k: float("nan") for k in COMPONENTS}
    return {k: float(nrmse(np.interp(t - period, record.time, getattr(record.loads, k)),
                           case.cfd_signal(k))) for k in COMPONENTS}


@dataclass
class MotionErrors:
    """Each set of terms' errors on one held-out motion.

    nrmse : set label -> component -> NRMSE
    error : set label -> mean over the components of the squared NRMSE
    mean_thrust, mean_power : "cfd" and set label -> the period's mean, N and W
    cfd_repeat_nrmse : component -> CFD's own NRMSE, the period before against the compared
        one (:attr:`HeldOutMotion.cfd_repeat_nrmse`)
    """

    name: str
    label: str
    nrmse: dict[str, dict[str, float]]
    error: dict[str, float]
    mean_thrust: dict[str, float]
    mean_power: dict[str, float]
    cfd_repeat_nrmse: dict[str, float] = field(default_factory=dict)


@dataclass
class TransferCheck:
    """Whether the effect (and each candidate) predicts held-out motions better.

    Attributes
    ----------
    effect : the candidate(s) checked: the claimed effect, else the best candidate
    claimed : whether the diagnosis claimed it
    coefficients : set label -> coefficients fitted on every identification case
    motions : per held-out motion, every set's errors
    gains : set label -> 1 - sum of its errors / sum of the base model's
    n_better : set label -> motions on which its error is below the base model's
    residual_scaling : how the identification cases' residuals were scaled in the fits
    excluded : records that could not be used, with the reason
    verdict : one sentence
    """

    effect: tuple[str, ...]
    claimed: bool
    coefficients: dict[str, dict[str, float]]
    motions: list[MotionErrors]
    gains: dict[str, float]
    n_better: dict[str, int]
    residual_scaling: str
    excluded: dict[str, str] = field(default_factory=dict)
    verdict: str = ""

    @property
    def label(self) -> str:
        """The checked effect's set label (``a + b``)."""
        return " + ".join(self.effect)

    @property
    def gain(self) -> float:
        """The checked effect's gain (NaN without motions)."""
        return self.gains.get(self.label, float("nan"))

    @property
    def carries_over(self) -> bool:
        """It lowers the held-out motions' total error, and on at least half of them."""
        n = len(self.motions)
        return bool(n and self.gain > 0 and 2 * self.n_better[self.label] >= n)

    def as_dict(self) -> dict:
        """Everything, for JSON."""
        return {"effect": list(self.effect), "claimed": self.claimed,
                "carries_over": self.carries_over, "gain": self.gain,
                "verdict": self.verdict, "residual_scaling": self.residual_scaling,
                "gains": self.gains, "n_better": self.n_better,
                "coefficients": self.coefficients, "excluded": self.excluded,
                "motions": [{"name": m.name, "label": m.label, "nrmse": m.nrmse,
                             "error": m.error, "mean_thrust": m.mean_thrust,
                             "mean_power": m.mean_power,
                             "cfd_repeat_nrmse": {k: None if np.isnan(v) else v
                                                  for k, v in m.cfd_repeat_nrmse.items()}}
                            for m in self.motions]}


def _window(loads: Loads, time: np.ndarray) -> Loads:
    """``loads`` interpolated onto ``time``."""
    return Loads(time, *(np.interp(time, loads.time, getattr(loads, k)) for k in COMPONENTS),
                 source=loads.source)


def _errors(motion: HeldOutMotion, models: Mapping[str, ForceModel],
            components: Sequence[str]) -> MotionErrors:
    case = motion.case
    t = case.state.time
    thrust, power = thrust_and_power(case.cfd, case.state)
    out = MotionErrors(motion.name, motion.label, {}, {}, {"cfd": time_mean(t, thrust)},
                       {"cfd": time_mean(t, power)}, dict(motion.cfd_repeat_nrmse))
    for label, model in models.items():
        pred = _window(model.loads(motion.history), t)
        out.nrmse[label] = {k: float(nrmse(getattr(pred, k), case.cfd_signal(k)))
                            for k in components}
        out.error[label] = float(np.mean([v**2 for v in out.nrmse[label].values()]))
        m_thrust, m_power = thrust_and_power(pred, case.state)
        out.mean_thrust[label] = time_mean(t, m_thrust)
        out.mean_power[label] = time_mean(t, m_power)
    return out


def check_transfer(fit_cases: Sequence[CaseData], motions: Sequence[HeldOutMotion],
                   base: Sequence[ForceTerm], candidates: Mapping[str, ForceTerm],
                   effect: Sequence[str], *, claimed: bool = True,
                   residual_scaling: str = "grid", components: Sequence[str] = COMPONENTS,
                   excluded: Mapping[str, str] | None = None, alpha: float = 0.01
                   ) -> TransferCheck:
    """Fit the base terms alone, with each candidate and with ``effect`` on every case of
    ``fit_cases``; compare their predictions of ``motions`` with the CFD.

    Parameters
    ----------
    effect
        Names of the candidate(s) the verdict is about (keys of ``candidates``).
    claimed
        Whether the diagnosis claimed ``effect`` (else it is its best candidate).
    alpha
        The diagnosis's significance level: the verdict says when there are too few motions
        for a one-sided signed-rank test to reach it.

    Raises
    ------
    MfflapError
        If ``effect`` names no candidate, or there are too few ``fit_cases``
        (:meth:`GapSystem.build`).
    """
    effect = tuple(effect)
    unknown = [n for n in effect if n not in candidates]
    if not effect or unknown:
        raise MfflapError(f"the effect to check must name candidates among "
                          f"{', '.join(candidates)}; got {list(effect)}")
    system = GapSystem.build(fit_cases, base, list(candidates.values()), components,
                             residual_scaling)
    terms = list(base) + list(candidates.values())
    n_base = len(base)
    sets = [()] + [(n,) for n in candidates] + ([effect] if len(effect) > 1 else [])
    every = np.arange(len(fit_cases))
    models, coefficients = {}, {}
    for names in sets:
        cols = list(range(n_base)) + [system.names.index(n) for n in names]
        x = system.fit(cols, every)
        label = " + ".join(names) or BASE
        coefficients[label] = {system.names[c]: float(v) for c, v in zip(cols, x, strict=True)}
        models[label] = ForceModel([terms[c] for c in cols], coefficients[label], name=label)
    errors = [_errors(m, models, components) for m in motions]
    gains, n_better = {}, {}
    base_total = sum(e.error[BASE] for e in errors)
    for label in models:
        if label == BASE:
            continue
        total = sum(e.error[label] for e in errors)
        gains[label] = float(1.0 - total / base_total) if base_total > 0 else float("nan")
        n_better[label] = sum(e.error[label] < e.error[BASE] for e in errors)
    check = TransferCheck(effect, claimed, coefficients, errors, gains, n_better,
                          residual_scaling, dict(excluded or {}))
    check.verdict = _verdict(check, alpha)
    return check


def _verdict(check: TransferCheck, alpha: float) -> str:
    n = len(check.motions)
    what = check.label + ("" if check.claimed else " (the best candidate, not claimed)")
    if n == 0:
        return (f"{what}: no held-out motion to check it on"
                + (f" ({len(check.excluded)} record(s) could not be used)"
                   if check.excluded else ""))
    gain, better = check.gain, check.n_better[check.label]
    said = "carries over to" if check.carries_over else "does not carry over to"
    text = (f"{what} {said} the {n} held-out motion(s): their error "
            f"{abs(gain):.1%} {'lower' if gain > 0 else 'higher'} with it, lower on "
            f"{better} of {n}")
    best = max(check.gains, key=lambda k: check.gains[k])
    if best != check.label and check.gains[best] > max(gain, 0.0):
        text += f"; the best there is {best} ({check.gains[best]:.1%} lower)"
    if 0.5**n > alpha:
        text += f"; {n} motion(s) are too few for a significance test at {alpha:g}"
    return text
