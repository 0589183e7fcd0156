"""Check the adjoint gradient against complex step, central differences and CasADi AD."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from mfflap.kinematics.discrete import DiscreteMotion
from mfflap.metrics import cosine_similarity
from mfflap.optimisation.problem import FlappingProblem

FD_NOTE = (
    "Central finite differences step across the kinks of max(0, P - P_max) and "
    "max(0, |h| - h_max) wherever a sample sits within one FD step of a limit; there the "
    "one-sided slopes differ and FD averages them, so FD disagrees with the exact derivative "
    "at those components (complex step and the adjoint do not: they differentiate the branch "
    "the point is on)."
)


@dataclass(frozen=True)
class GradCheck:
    """Gradients of one motion by three methods and their agreement."""

    adjoint: np.ndarray
    complex_step: np.ndarray
    finite_difference: np.ndarray
    max_rel_error_complex_step: float
    max_rel_error_finite_difference: float
    max_rel_error_casadi: float
    cosine_similarity_controls_fd: float
    cosine_similarity_controls_cs: float

    def as_dict(self) -> dict[str, float]:
        """Scalars as a JSON-friendly dict."""
        return {k: float(getattr(self, k)) for k in (
            "max_rel_error_complex_step", "max_rel_error_finite_difference",
            "max_rel_error_casadi",
            "cosine_similarity_controls_fd", "cosine_similarity_controls_cs")}


def _pack(d: DiscreteMotion) -> np.ndarray:
    return np.concatenate([d.pitch_acceleration, d.heave_acceleration,
                           [np.asarray(d.time_step).item()]])


def _unpack(x: np.ndarray, n: int) -> DiscreteMotion:
    return DiscreteMotion(x[:n], x[n:2 * n], x[2 * n])


def check_gradient(problem: FlappingProblem, motion: DiscreteMotion,
                   fd_relative_step: float = 1e-6,
                   progress: Callable[[int, int], None] | None = None) -> GradCheck:
    """Adjoint vs complex step (h = 1e-30) vs central differences, all 2N + 1 components.

    Each component costs three evaluations of the objective, so the check's work grows as
    N^2; ``progress``, if given, is called with (components done, 2N + 1) after each.
    """
    n = motion.n_steps
    x = _pack(motion)
    adj = problem.gradient(motion).flat()
    cs = np.empty_like(x)
    fd = np.empty_like(x)
    for i in range(x.size):
        xc = x.astype(complex)
        xc[i] += 1e-30j
        cs[i] = np.imag(problem.objective(_unpack(xc, n))) / 1e-30
        step = fd_relative_step * max(abs(x[i]), 1e-3 if i < 2 * n else 1e-6)
        xp, xm = x.copy(), x.copy()
        xp[i] += step
        xm[i] -= step
        fd[i] = (problem.objective(_unpack(xp, n)) - problem.objective(_unpack(xm, n))) / (
            2 * step)
        if progress is not None:
            progress(i + 1, x.size)
    scale = np.max(np.abs(cs))
    from mfflap.optimisation.casadi_objective import casadi_gradient

    ca_grad = casadi_gradient(problem, motion)
    return GradCheck(
        adjoint=adj, complex_step=cs, finite_difference=fd,
        max_rel_error_complex_step=float(np.max(np.abs(adj - cs)) / scale),
        max_rel_error_finite_difference=float(np.max(np.abs(adj - fd)) / scale),
        max_rel_error_casadi=float(np.max(np.abs(adj - ca_grad)) / scale),
        cosine_similarity_controls_fd=cosine_similarity(adj[:-1], fd[:-1]),
        cosine_similarity_controls_cs=cosine_similarity(adj[:-1], cs[:-1]),
    )


def scatter_figure(checks: dict[float, GradCheck]):
    """Adjoint vs FD per beta (the paper's Figure 6); the dt component scaled separately."""
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, len(checks), figsize=(4.2 * len(checks), 4), squeeze=False)
    for ax, (beta, c) in zip(axes[0], checks.items(), strict=True):
        ax.scatter(c.finite_difference[:-1], c.adjoint[:-1], s=10, label="controls u_j")
        dscale = max(abs(c.adjoint[-1]), abs(c.finite_difference[-1])) or 1.0
        lim = np.max(np.abs(c.adjoint[:-1])) or 1.0
        ax.scatter([c.finite_difference[-1] / dscale * lim], [c.adjoint[-1] / dscale * lim],
                   marker="*", s=120, color="C3", label="dt (scaled)")
        ax.plot([-lim, lim], [-lim, lim], "k--", lw=0.8)
        ax.set_title(f"beta = {beta:g}, cos sim {c.cosine_similarity_controls_fd:.6f}")
        ax.set_xlabel("finite difference")
        ax.set_ylabel("adjoint")
        ax.legend(fontsize=8)
    fig.tight_layout()
    return fig
