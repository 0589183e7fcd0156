"""The blind benchmark: datasets with one hidden effect (or none) are diagnosed without the
tool being told; attribution accuracy, confusion matrix, gap shrinkage and false alarms.

Each trial draws Morison coefficients around the paper's values, a set of identification
motions, optionally one effect from the library at a physical strength (its typical
coefficient, +-20 %), and coloured noise (AR(1), like CFD's own residual wiggles) sized for
the requested signal-to-noise ratio. SNR is the RMS of the effect over the RMS of the noise,
on the load component where the effect is largest (each component normalised by its RMS),
counting only the part of the effect that the base model cannot absorb by refitting its own
coefficients (the effect's residual after a least-squares projection on the base
regressors): what the base model can represent is not a gap, and no test can attribute it.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np

from mfflap.campaign.cases import CfdCase
from mfflap.errors import ConfigError
from mfflap.gap.diagnose import default_candidates, diagnose
from mfflap.gap.system import COMPONENTS
from mfflap.hydro.loads import Loads
from mfflap.hydro.morison import MorisonModel
from mfflap.identification.data import CaseData

NULL = "none"
#: How the noise of a synthetic dataset is sized, case by case
NOISE_MODELS = {
    "absolute": "the same size in every case: each component's RMS over all cases",
    "relative": "in proportion to each case's own loads: each component's RMS in the case "
                "(the model errors of CFD, about the same NRMSE in every run, look so)",
}


def trial_cases(rng: np.random.Generator, n_cases: int = 20, n_samples: int = 240
                ) -> list[CaseData]:
    """Random identification motions (ramp sinusoids) spanning Table 1's ranges."""
    out = []
    for i in range(n_cases):
        f = float(np.exp(rng.uniform(np.log(0.1), np.log(2.0))))
        h = float(rng.uniform(0.1, 0.5))
        phi = float(rng.uniform(45, 135))
        duration = min(3.0 / f, 6.0)
        case = CfdCase(f, h, phi, 10.0, duration, 0.0)
        t = np.linspace(0.75, duration, n_samples)
        state = case.motion().sample(t)
        out.append(CaseData(f"trial_case_{i}", {**case.as_dict()}, state,
                            Loads(t, 0 * t, 0 * t, 0 * t)))
    return out


def ar1_noise(rng: np.random.Generator, n: int, rho: float = 0.9) -> np.ndarray:
    """``n`` samples of AR(1) noise, x[i] = rho x[i-1] + sqrt(1 - rho^2) e[i], from
    x[0] = e[0] (e standard normal)."""
    e = rng.standard_normal(n)
    x = np.empty(n)
    x[0] = e[0]
    for i in range(1, n):
        x[i] = rho * x[i - 1] + np.sqrt(1 - rho**2) * e[i]
    return x


def unabsorbed_rms(base: MorisonModel, cases: Sequence[CaseData], effects: Sequence[Loads],
                   scale: dict[str, float]) -> float:
    """The largest per-component RMS of the part of ``effects`` (one per case) that no refit
    of ``base``'s coefficients absorbs: the effect's residual after a least-squares
    projection on the base regressors, each component over its grid ``scale``."""
    regs = [base.regressors(c.state) for c in cases]
    a = np.vstack([np.column_stack([np.concatenate([getattr(r[t.name], k) for r in regs])
                                    / scale[k] for t in base.terms]) for k in COMPONENTS])
    e = np.concatenate([np.concatenate([getattr(ld, k) for ld in effects]) / scale[k]
                        for k in COMPONENTS])
    orth = e - a @ np.linalg.lstsq(a, e, rcond=None)[0]
    n = len(orth) // len(COMPONENTS)
    return max(float(np.sqrt(np.mean(orth[i * n:(i + 1) * n] ** 2)))
               for i in range(len(COMPONENTS)))


def synthesize(rng: np.random.Generator, effect: str, snr: float, noise_level: float = 0.05,
               n_cases: int = 20, noise: str = "absolute") -> list[CaseData]:
    """A dataset with a hidden ``effect`` (or :data:`NULL`) at signal-to-noise ratio ``snr``,
    its noise sized as ``noise`` (a key of :data:`NOISE_MODELS`) says."""
    return synthesize_with_strength(rng, effect, snr, noise_level, n_cases, noise)[0]


def synthesize_with_strength(rng: np.random.Generator, effect: str, snr: float,
                             noise_level: float = 0.05, n_cases: int = 20,
                             noise: str = "absolute") -> tuple[list[CaseData], float]:
    """:func:`synthesize`, and the hidden effect's coefficient (0 for :data:`NULL`), which
    the data given to the diagnosis does not carry.

    Raises
    ------
    ConfigError
        If ``noise`` is none of :data:`NOISE_MODELS`.
    """
    if noise not in NOISE_MODELS:
        raise ConfigError(f"noise model {noise!r}: choose one of {', '.join(NOISE_MODELS)}",
                          key="noise")
    cases = trial_cases(rng, n_cases)
    base = MorisonModel().with_coefficients(
        {k: v * rng.uniform(0.8, 1.2) for k, v in MorisonModel().coefficients.items()})
    clean = [base.loads(c.state) for c in cases]
    scale = {k: float(np.sqrt(np.mean(np.concatenate([getattr(ld, k) for ld in clean])**2)))
             or 1.0 for k in COMPONENTS}
    extra = [None] * len(cases)
    if effect != NULL:
        term = default_candidates()[effect]
        regs = [term.regressor(c.state) for c in cases]
        rms = unabsorbed_rms(base, cases, regs, scale)
        # the effect at a physical strength (its typical coefficient, +-20 %), the noise
        # sized for the signal-to-noise ratio: a fitted coefficient can then be judged
        # plausible or not as it would be on real data
        strength = float(term.typical) * rng.uniform(0.8, 1.2)
        noise_level = abs(strength) * rms / snr
        extra = [(strength, r) for r in regs]
    else:
        strength = 0.0
    out = []
    for c, ld, ex in zip(cases, clean, extra, strict=True):
        comps = {}
        for k in COMPONENTS:
            y = getattr(ld, k).copy()
            if ex is not None:
                y = y + ex[0] * getattr(ex[1], k)
            size = scale[k]
            if noise == "relative":  # the case's own RMS (their mean square is scale's)
                size = float(np.sqrt(np.mean(getattr(ld, k)**2)))
            y = y + noise_level * size * ar1_noise(rng, len(y))
            comps[k] = y
        out.append(CaseData(c.name, c.parameters, c.state,
                            Loads(c.state.time, comps["normal_force"],
                                  comps["tangential_force"], comps["moment"])))
    return out, float(strength)


@dataclass
class BlindTestResult:
    """Scores over all trials."""

    labels: list[str]
    truth: list[str] = field(default_factory=list)
    claimed: list[str] = field(default_factory=list)
    #: per trial: the forms of a family the verdict could not tell apart, joined by "|";
    #: else, without a claim, the best candidate, named as not claimed because its
    #: coefficient is implausible or confounded ("" when none was)
    named: list[str] = field(default_factory=list)
    heldout_gain: list[float] = field(default_factory=list)
    #: the hidden effect's coefficient (0 for null trials)
    hidden_coefficient: list[float] = field(default_factory=list)
    #: the claimed effect's refitted coefficient where the right effect was claimed, else nan
    fitted_coefficient: list[float] = field(default_factory=list)
    snr: float = 3.0
    #: the datasets' noise model (a key of NOISE_MODELS) and the diagnosis's scaling
    noise: str = "absolute"
    residual_scaling: str = "grid"

    def confusion(self) -> np.ndarray:
        """Counts [true label, claimed label] in the order of ``labels``."""
        idx = {lab: i for i, lab in enumerate(self.labels)}
        m = np.zeros((len(self.labels), len(self.labels)), dtype=int)
        for t, c in zip(self.truth, self.claimed, strict=True):
            m[idx[t], idx.get(c, idx[NULL])] += 1
        return m

    @property
    def attribution_accuracy(self) -> float:
        """Share of effect trials whose hidden effect was claimed (ranked first), named as
        the best candidate and not claimed for its coefficient (the verdict then says the
        effect's form and why its strength is not told from the base terms), or named
        among the forms of a family the verdict says the cases cannot tell apart."""
        named = self.named or [""] * len(self.truth)
        pairs = [(t, c, n) for t, c, n in zip(self.truth, self.claimed, named, strict=True)
                 if t != NULL]
        return (float(np.mean([t in (c, *n.split("|")) for t, c, n in pairs])) if pairs
                else float("nan"))

    @property
    def claimed_accuracy(self) -> float:
        """Share of effect trials whose hidden effect was claimed."""
        pairs = [(t, c) for t, c in zip(self.truth, self.claimed, strict=True) if t != NULL]
        return float(np.mean([t == c for t, c in pairs])) if pairs else float("nan")

    @property
    def null_correct(self) -> float:
        """Share of null trials where no effect was claimed."""
        nulls = [c for t, c in zip(self.truth, self.claimed, strict=True) if t == NULL]
        return float(np.mean([c == NULL for c in nulls])) if nulls else float("nan")

    @property
    def mean_gain(self) -> float:
        """Mean held-out error reduction on effect trials where an effect was claimed."""
        g = [g for t, c, g in zip(self.truth, self.claimed, self.heldout_gain, strict=True)
             if t != NULL and c != NULL]
        return float(np.mean(g)) if g else float("nan")

    @property
    def coefficient_error(self) -> float:
        """Median of |fitted / hidden - 1| over the trials whose hidden effect was claimed:
        how well the claimed effect's strength is recovered, base terms refitted."""
        err = [abs(f / h - 1.0) for h, f in zip(self.hidden_coefficient,
                                                self.fitted_coefficient, strict=True)
               if h != 0.0 and np.isfinite(f)]
        return float(np.median(err)) if err else float("nan")

    def summary(self) -> str:
        """Printable scores and the confusion matrix."""
        m = self.confusion()
        width = max(len(x) for x in self.labels) + 2
        def percent(value: float, what: str, trials: str) -> str:
            return (f"{value:.1%} {what}" if np.isfinite(value)
                    else f"– (no {trials} trial among these)")

        lines = [f"blind benchmark at SNR {self.snr:g}: {len(self.truth)} trials ({self.noise} "
                 f"noise, residuals scaled by {self.residual_scaling})",
                 "  right effect ranked first : "
                 + percent(self.attribution_accuracy, "of effect trials", "effect")
                 + (f" ({self.claimed_accuracy:.1%} claimed, the rest named and not "
                    "claimed for an implausible or confounded coefficient)"
                    if np.isfinite(self.claimed_accuracy) else ""),
                 "  no claim on null datasets : "
                 + percent(self.null_correct, "of null trials", "null"),
                 "  held-out gap shrinkage    : "
                 + percent(self.mean_gain, "mean error reduction", "effect"),
                 "  right effect's coefficient: "
                 + percent(self.coefficient_error, "median error of the refitted value",
                           "effect"),
                 "  confusion (rows: hidden, columns: claimed):",
                 " " * (width + 2) + " ".join(f"{lab[:8]:>8s}" for lab in self.labels)]
        for lab, row in zip(self.labels, m, strict=True):
            lines.append(f"  {lab:<{width}s}" + " ".join(f"{v:8d}" for v in row))
        return "\n".join(lines)


def blind_test(n_trials: int = 70, snr: float = 3.0, seed: int = 0,
               null_share: float = 0.3, effects: Sequence[str] | None = None,
               progress: Callable[[int, int], None] | None = None, noise: str = "absolute",
               residual_scaling: str = "grid") -> BlindTestResult:
    """Run the blind benchmark; the diagnosis never sees which effect was hidden.

    Raises
    ------
    ConfigError
        If ``n_trials`` is below 1, ``snr`` is not a finite number > 0, or ``noise`` or
        ``residual_scaling`` is none of its choices.
    """
    if n_trials < 1:
        raise ConfigError(f"the blind test needs at least one trial, got {n_trials!r}",
                          key="n_trials")
    if not (np.isfinite(snr) and snr > 0):
        raise ConfigError(f"the signal-to-noise ratio must be a finite number > 0, got "
                          f"{snr!r}", key="snr")
    rng = np.random.default_rng(seed)
    names = list(effects or default_candidates())
    result = BlindTestResult([*names, NULL], snr=snr, noise=noise,
                             residual_scaling=residual_scaling)
    base = MorisonModel()
    for k in range(n_trials):
        truth = NULL if rng.uniform() < null_share else names[int(rng.integers(len(names)))]
        data, strength = synthesize_with_strength(rng, truth, snr, noise=noise)
        diag = diagnose(data, base, validate_by=(), residual_scaling=residual_scaling)
        claimed = NULL if diag.chosen is None else diag.chosen.names[0]
        result.truth.append(truth)
        result.claimed.append(claimed)
        # the forms of a family the verdict says the cases cannot tell apart, else the best
        # candidate named and not claimed
        result.named.append("|".join(diag.family[1:]) if diag.family
                            else "" if diag.chosen is not None
                            else next((k.split(" + ")[0] for k in diag.not_claimed), ""))
        result.heldout_gain.append(diag.chosen.gain if diag.chosen else 0.0)
        result.hidden_coefficient.append(strength)
        result.fitted_coefficient.append(
            diag.chosen.coefficients[truth] if claimed == truth != NULL else float("nan"))
        if progress is not None:
            progress(k + 1, n_trials)
    return result
