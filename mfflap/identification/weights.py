"""Weighting strategies across frequencies (the paper's sensitivity study)."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from mfflap.errors import ConfigError

#: Named strategies: weights over the *sorted* distinct frequencies (five in Table 1).
STRATEGIES: dict[str, tuple[float, ...] | None] = {
    "uniform": None,
    "low": (0.4, 0.3, 0.15, 0.1, 0.05),
    "high": (0.05, 0.1, 0.15, 0.3, 0.4),
}


def frequency_weights(frequencies: Sequence[float],
                      strategy: str | Sequence[float] = "uniform") -> dict[float, float]:
    """Weight of each distinct frequency, summing to one.

    Parameters
    ----------
    frequencies
        Frequencies of the cases (Hz); duplicates are allowed.
    strategy
        ``"uniform"``, ``"low"`` (low-frequency biased, [0.4, 0.3, 0.15, 0.1, 0.05]),
        ``"high"`` (reversed), or one weight >= 0 per distinct frequency in ascending order.
        A named biased strategy needs exactly five frequencies; for another count its weights
        are interpolated geometrically over the rank (first to last weight).
    """
    distinct = sorted({float(f) for f in frequencies})
    n = len(distinct)
    if n == 0:
        raise ConfigError("no frequencies to weight", key="identification.frequency_weights")
    if isinstance(strategy, str):
        if strategy not in STRATEGIES:
            raise ConfigError(f"unknown weighting strategy {strategy!r}; choose one of "
                              f"{', '.join(STRATEGIES)} or give weights",
                              key="identification.strategy")
        base = STRATEGIES[strategy]
        if base is None:
            w = np.ones(n)
        elif n == len(base):
            w = np.array(base, dtype=float)
        elif n == 1:
            w = np.ones(1)
        else:
            w = np.geomspace(base[0], base[-1], n)
    else:
        w = np.asarray(list(strategy), dtype=float)
        if w.shape != (n,) or np.any(w < 0) or not np.all(np.isfinite(w)) or w.sum() <= 0:
            raise ConfigError(f"weights {w.tolist()}: need one finite weight >= 0 per distinct "
                              f"frequency {distinct} and a positive sum",
                              key="identification.frequency_weights")
    w = w / w.sum()
    return dict(zip(distinct, w.tolist(), strict=True))
