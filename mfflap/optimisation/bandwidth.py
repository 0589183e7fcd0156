"""The harmonics a motion may contain: an actuator's bandwidth as a constraint, and the
measure of chatter that says whether a motion respects one.

A periodic optimum is its half period's accelerations u_0 ... u_{N-1} extended
antisymmetrically (u_{j+N} = -u_j), so it holds the odd harmonics k = 1, 3, ... of the
flapping frequency only. Over the half period the sequences cos(pi k (j + 1/2) / N) and
sin(pi k (j + 1/2) / N) of the odd k up to N are orthogonal and span every such motion: a
bandwidth of K harmonics keeps those with k <= K and asks the others to vanish, N - 2 ceil(K/2)
linear equalities on each channel's accelerations (:func:`bandwidth_rows`), which SQP
holds at every iterate.

Chatter is measured as the multifidelity notes define it: the share of the extended
accelerations' spectral energy above a quarter of the sampling frequency (harmonics above
N / 2). Smooth optima hold a few thousandths of a per cent there; sample-to-sample
alternation a few per cent.

Examples
--------
>>> import numpy as np
>>> from mfflap.kinematics.discrete import DiscreteMotion
>>> j = np.arange(50)
>>> smooth = np.sin(np.pi * (j + 0.5) / 50)
>>> chatter = smooth + 0.3 * (-1.0) ** j
>>> round(high_frequency_share(smooth), 6), round(high_frequency_share(chatter), 3)
(0.0, 0.15)
>>> limited = band_limited(DiscreteMotion(chatter, smooth, 0.01), 11)
>>> round(high_frequency_share(limited.pitch_acceleration), 6)
0.0
"""

from __future__ import annotations

import numpy as np

from mfflap.errors import ConfigError
from mfflap.kinematics.discrete import DiscreteMotion

#: the largest share of a delivered motion's acceleration energy above a quarter of the
#: sampling frequency
MAX_HIGH_FREQUENCY_SHARE = 0.005


def _harmonic_basis(n_steps: int, harmonics: list[int]) -> np.ndarray:
    """Orthonormal columns spanning cos and sin of the odd ``harmonics`` over the half
    period's samples, shape (n_steps, m)."""
    phase = np.pi * (np.arange(n_steps) + 0.5) / n_steps
    # orthogonal already (module notes): normalised, the one that vanishes (the cosine of
    # k = N, zero at every sample) left out
    columns = [c / np.linalg.norm(c) for k in harmonics for f in (np.cos, np.sin)
               if np.linalg.norm(c := f(k * phase)) > 1e-9 * np.sqrt(n_steps)]
    return np.column_stack(columns) if columns else np.zeros((n_steps, 0))


def _odd_harmonics(n_steps: int) -> list[int]:
    return list(range(1, n_steps + 1, 2))


def check_bandwidth(n_steps: int, highest_harmonic: int) -> None:
    """Refuse a bandwidth that keeps no harmonic or that the samples cannot resolve.

    Raises
    ------
    ConfigError
        Naming ``optimisation.bandwidth_harmonics``.
    """
    if not 1 <= highest_harmonic:
        raise ConfigError(f"value {highest_harmonic!r}: a motion needs its first harmonic; "
                          "allowed: an integer >= 1", key="optimisation.bandwidth_harmonics")
    if n_steps < 4:
        raise ConfigError(f"{n_steps} steps a half period cannot hold a bandwidth",
                          key="optimisation.n_steps")


def bandwidth_rows(n_steps: int, highest_harmonic: int) -> np.ndarray:
    """The rows R over a packed design vector z = [pitch acc (N), heave acc (N), dt] with
    R z = 0 exactly when both channels hold no harmonic above ``highest_harmonic``
    (module notes); shape (2 m, 2N + 1), no rows when every odd harmonic up to N is kept."""
    check_bandwidth(n_steps, highest_harmonic)
    high = [k for k in _odd_harmonics(n_steps) if k > highest_harmonic]
    basis = _harmonic_basis(n_steps, high)
    m = basis.shape[1]
    rows = np.zeros((2 * m, 2 * n_steps + 1))
    rows[:m, :n_steps] = basis.T
    rows[m:, n_steps:2 * n_steps] = basis.T
    return rows


def band_limited(motion: DiscreteMotion, highest_harmonic: int) -> DiscreteMotion:
    """``motion`` with the harmonics above ``highest_harmonic`` removed from both channels'
    accelerations (the orthogonal projection onto the band), its time step kept."""
    n = motion.n_steps
    check_bandwidth(n, highest_harmonic)
    kept = [k for k in _odd_harmonics(n) if k <= highest_harmonic]
    basis = _harmonic_basis(n, kept)

    def project(u: np.ndarray) -> np.ndarray:
        return basis @ (basis.T @ np.real(np.asarray(u, dtype=complex)))

    return DiscreteMotion(project(motion.pitch_acceleration),
                          project(motion.heave_acceleration), motion.time_step)


def high_frequency_share(accelerations: np.ndarray) -> float:
    """The share of the antisymmetrically extended accelerations' spectral energy above a
    quarter of the sampling frequency (module notes); 0 for a motion at rest."""
    u = np.real(np.asarray(accelerations, dtype=float))
    power = np.abs(np.fft.rfft(np.concatenate([u, -u]))) ** 2
    total = float(power.sum())
    return float(power[u.size // 2 + 1:].sum()) / total if total > 0 else 0.0


def motion_chatter(motion: DiscreteMotion) -> tuple[float, float]:
    """:func:`high_frequency_share` of the pitch and of the heave accelerations."""
    return (high_frequency_share(motion.pitch_acceleration),
            high_frequency_share(motion.heave_acceleration))


__all__ = ["MAX_HIGH_FREQUENCY_SHARE", "band_limited", "bandwidth_rows", "check_bandwidth",
           "high_frequency_share", "motion_chatter"]
