"""Agreement metrics between a prediction and a reference signal."""

from __future__ import annotations

import numpy as np

from mfflap.errors import MfflapError


def _pair(prediction, reference) -> tuple[np.ndarray, np.ndarray]:
    p = np.real(np.asarray(prediction, dtype=complex if np.iscomplexobj(prediction) else float))
    r = np.real(np.asarray(reference))
    if p.shape != r.shape:
        raise MfflapError(f"prediction shape {p.shape} differs from reference shape {r.shape}")
    if p.shape[-1] < 2:
        raise MfflapError("metrics need at least two samples")
    if not (np.all(np.isfinite(p)) and np.all(np.isfinite(r))):
        raise MfflapError("metrics got NaN or infinite samples")
    return p, r


def time_mean(time, values) -> float:
    """Trapezoidal time average of ``values`` over ``time`` (non-uniform steps allowed)."""
    t = np.asarray(time, dtype=float)
    return float(np.trapezoid(values, t) / (t[-1] - t[0]))


def nrmse(prediction, reference, axis: int = -1) -> np.ndarray:
    """RMS error normalised by the reference's range (the paper's NRMSE).

    NRMSE = sqrt(mean((p - r)^2)) / (max(r) - min(r)). Infinite if the reference is constant
    and the error is not zero.
    """
    p, r = _pair(prediction, reference)
    rms = np.sqrt(np.mean((p - r) ** 2, axis=axis))
    span = np.ptp(r, axis=axis)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(span > 0, rms / np.where(span > 0, span, 1), np.where(rms > 0, np.inf, 0))


def pearson(prediction, reference, axis: int = -1) -> np.ndarray:
    """Pearson correlation coefficient r (NaN if either signal is constant)."""
    p, r = _pair(prediction, reference)
    pc = p - p.mean(axis=axis, keepdims=True)
    rc = r - r.mean(axis=axis, keepdims=True)
    den = np.sqrt((pc**2).sum(axis=axis) * (rc**2).sum(axis=axis))
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(den > 0, (pc * rc).sum(axis=axis) / np.where(den > 0, den, 1), np.nan)


def cosine_similarity(a, b) -> float:
    """a.b / (|a| |b|) of two flattened vectors (NaN if either is zero)."""
    a, b = np.ravel(np.real(a)), np.ravel(np.real(b))
    den = np.linalg.norm(a) * np.linalg.norm(b)
    return float(a @ b / den) if den > 0 else float("nan")
