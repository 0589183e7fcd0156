"""Where the residual (CFD minus model) lies: by component, phase, regime, instantaneous
state and frequency, each ranked by the share of the error it accounts for.

Shares are correlation ratios: the fraction of the residual's variance that its mean within
bins of a variable explains (eta^2). A factor with eta^2 near 1 says "the error is a function
of this"; near 0, "this does not organise the error".
"""

from __future__ import annotations

import numpy as np

from mfflap.gap.system import COMPONENTS, GapSystem
from mfflap.hydro.morison import RelativeFlow


def correlation_ratio(values: np.ndarray, labels: np.ndarray) -> float:
    """eta^2 of ``values`` grouped by ``labels``."""
    total = float(np.sum((values - values.mean()) ** 2))
    if total == 0:
        return 0.0
    between = 0.0
    for lab in np.unique(labels):
        sel = labels == lab
        between += sel.sum() * (values[sel].mean() - values.mean()) ** 2
    return float(between / total)


def _bins(x: np.ndarray, n: int = 10) -> np.ndarray:
    edges = np.unique(np.quantile(x, np.linspace(0, 1, n + 1)))
    return np.clip(np.searchsorted(edges, x, side="right") - 1, 0, max(len(edges) - 2, 0))


def decompose(system: GapSystem, predictions: list[dict[str, np.ndarray]], velocity: float,
              chord: float, component: str = "normal_force") -> dict:
    """Residual shares by component, phase, state, regime and harmonic; and a ranking.

    Returns a dict with ``by_component`` (share of the total scaled squared error),
    ``by_phase`` (12 bins of the carrier phase: share of squared residual and mean residual),
    ``by_state`` / ``by_regime`` (eta^2 per variable), ``by_harmonic`` (share of residual power
    at harmonics 0-4 of the carrier and elsewhere), ``phase_lag_deg`` per case (CFD's first
    harmonic of ``component`` behind the model's), and ``ranking`` (factor, share) sorted.
    """
    cases = system.cases
    sq = {k: 0.0 for k in COMPONENTS}
    res, phase, alpha, acc_p, acc_h, case_idx = [], [], [], [], [], []
    harm = np.zeros(6)
    lags = np.full(len(cases), np.nan)
    for i, c in enumerate(cases):
        for k in COMPONENTS:
            r = (c.cfd_signal(k) - predictions[i][k]) / system.scales[i][k]
            sq[k] += float(np.mean(r**2))
        r = (c.cfd_signal(component) - predictions[i][component]) / system.scales[i][component]
        t = c.state.time
        f = float(c.parameters.get("frequency", np.nan))
        if not np.isfinite(f) and "period" in c.parameters:
            f = 1.0 / float(c.parameters["period"])
        res.append(r)
        phase.append(np.mod(2 * np.pi * f * t, 2 * np.pi) if np.isfinite(f) else 0 * t)
        flow = RelativeFlow.of(c.state, velocity)
        alpha.append(np.degrees(np.arctan2(flow.normal_velocity,
                                           -flow.tangential_velocity)))
        acc_p.append(np.abs(c.state.pitch_acceleration))
        acc_h.append(np.abs(c.state.heave_acceleration))
        case_idx.append(np.full(len(t), i))
        if np.isfinite(f) and len(t) > 8:
            dt = t[1] - t[0]
            spec = np.abs(np.fft.rfft(r - 0 * r.mean())) ** 2
            freqs = np.fft.rfftfreq(len(r), dt)
            width = 0.5 * f
            for n in range(5):
                harm[n] += spec[np.abs(freqs - n * f) < width].sum()
            harm[5] += spec.sum() - sum(spec[np.abs(freqs - n * f) < width].sum()
                                        for n in range(5))
            w = 2 * np.pi * f
            basis = np.exp(-1j * w * t)
            cfd1 = np.sum(c.cfd_signal(component) * basis)
            mod1 = np.sum(predictions[i][component] * basis)
            if abs(cfd1) > 0 and abs(mod1) > 0:
                lags[i] = float(np.degrees(np.angle(mod1 / cfd1)))
    r_all, ph_all = np.concatenate(res), np.concatenate(phase)
    total_sq = sum(sq.values())
    by_component = {k: v / total_sq for k, v in sq.items()}
    ph_bins = np.minimum((ph_all / (2 * np.pi) * 12).astype(int), 11)
    by_phase = {"bin_centres_deg": (np.arange(12) + 0.5) * 30.0,
                "squared_share": np.array([np.sum(r_all[ph_bins == b] ** 2) for b in
                                           range(12)]) / max(np.sum(r_all**2), 1e-300),
                "mean_residual": np.array([r_all[ph_bins == b].mean() if np.any(ph_bins == b)
                                           else np.nan for b in range(12)])}
    state_vars = {"effective angle of attack": np.concatenate(alpha),
                  "|pitch acceleration|": np.concatenate(acc_p),
                  "|heave acceleration|": np.concatenate(acc_h)}
    by_state = {name: correlation_ratio(r_all, _bins(x)) for name, x in state_vars.items()}
    by_state["phase in the cycle"] = correlation_ratio(r_all, ph_bins)
    case_sse = np.array([np.mean(r**2) for r in res])
    regime_vars = {}
    for key in ("frequency", "heave_amplitude", "phase_deg"):
        vals = np.array([float(c.parameters.get(key, np.nan)) for c in cases])
        if np.all(np.isfinite(vals)):
            regime_vars[key] = vals
    if "frequency" in regime_vars and "heave_amplitude" in regime_vars:
        regime_vars["Strouhal number 2 f h / U"] = (2 * regime_vars["frequency"]
                                                    * regime_vars["heave_amplitude"] / velocity)
        regime_vars["reduced frequency k = pi f c / U"] = (np.pi * regime_vars["frequency"]
                                                           * chord / velocity)
    regime_vars["peak effective angle of attack"] = np.array(
        [np.max(np.abs(a)) for a in alpha])
    by_regime = {name: correlation_ratio(case_sse, _bins(v, 5)) for name, v in
                 regime_vars.items()}
    by_harmonic = dict(zip(["mean (0 f)", "1 f", "2 f", "3 f", "4 f", "elsewhere"],
                           (harm / max(harm.sum(), 1e-300)).tolist(), strict=True))
    ranking = sorted([(f"component {k}", v) for k, v in by_component.items()]
                     + [(f"state: {k}", v) for k, v in by_state.items()]
                     + [(f"regime: {k}", v) for k, v in by_regime.items()]
                     + [(f"harmonic {k}", v) for k, v in by_harmonic.items()],
                     key=lambda kv: -kv[1])
    return {"by_component": by_component, "by_phase": by_phase, "by_state": by_state,
            "by_regime": by_regime, "regime_values": regime_vars, "case_sse": case_sse,
            "by_harmonic": by_harmonic, "phase_lag_deg": lags, "ranking": ranking}
