"""Check the adjoint gradient against complex step, central differences and CasADi AD."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from mfflap.kinematics.discrete import DiscreteMotion
from mfflap.metrics import cosine_similarity
from mfflap.optimisation.casadi_objective import casadi_gradient
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
    """Gradients of one motion by three methods and their agreement.

    The controls block (dJ/du_j, 2N components) and dJ/d(dt) are compared separately:
    |dJ/d(dt)| is of the order of 1e4 times max |dJ/du_j|, so one ratio over the whole
    vector would hide an error of a per cent in the controls.

    Attributes
    ----------
    adjoint, complex_step, finite_difference : ndarray
        The 2N + 1 gradient components by each method (controls, then dt).
    controls_error_complex_step, controls_error_finite_difference, controls_error_casadi
        max |adjoint - other| / max |complex step| over the controls.
    time_step_error_complex_step, time_step_error_finite_difference, time_step_error_casadi
        |adjoint - other| / |complex step| of dJ/d(dt).
    cosine_similarity_controls_fd, cosine_similarity_controls_cs
        Cosine similarity of the controls blocks.
    penalty_share
        The share of J that the power, heave and pitch penalties make at the point, in
        [0, 1] (NaN when not given): a check where they dominate says little about the
        thrust and power part.
    """

    adjoint: np.ndarray
    complex_step: np.ndarray
    finite_difference: np.ndarray
    controls_error_complex_step: float
    controls_error_finite_difference: float
    controls_error_casadi: float
    time_step_error_complex_step: float
    time_step_error_finite_difference: float
    time_step_error_casadi: float
    cosine_similarity_controls_fd: float
    cosine_similarity_controls_cs: float
    penalty_share: float = float("nan")

    def as_dict(self) -> dict[str, float]:
        """Scalars as a JSON-friendly dict."""
        return {k: float(getattr(self, k)) for k in (
            "controls_error_complex_step", "controls_error_finite_difference",
            "controls_error_casadi", "time_step_error_complex_step",
            "time_step_error_finite_difference", "time_step_error_casadi",
            "cosine_similarity_controls_fd", "cosine_similarity_controls_cs",
            "penalty_share")}


def check_gradient(problem: FlappingProblem, motion: DiscreteMotion,
                   fd_relative_step: float = 1e-6,
                   progress: Callable[[int, int], None] | None = None) -> GradCheck:
    """Adjoint vs complex step (h = 1e-30) vs central differences, all 2N + 1 components.

    Each component costs three evaluations of the objective, so the check's work grows as
    N^2; ``progress``, if given, is called with (components done, 2N + 1) after each.
    """
    n = motion.n_steps
    x = motion.controls()
    adj = problem.gradient(motion).flat()
    cs = np.empty_like(x)
    fd = np.empty_like(x)
    for i in range(x.size):
        xc = x.astype(complex)
        xc[i] += 1e-30j
        cs[i] = np.imag(problem.objective(DiscreteMotion.from_controls(xc))) / 1e-30
        step = fd_relative_step * max(abs(x[i]), 1e-3 if i < 2 * n else 1e-6)
        xp, xm = x.copy(), x.copy()
        xp[i] += step
        xm[i] -= step
        fd[i] = (problem.objective(DiscreteMotion.from_controls(xp))
                 - problem.objective(DiscreteMotion.from_controls(xm))) / (2 * step)
        if progress is not None:
            progress(i + 1, x.size)

    ca_grad = casadi_gradient(problem, motion)
    controls_scale = np.max(np.abs(cs[:-1]))
    dt_scale = abs(cs[-1])

    def controls(other: np.ndarray) -> float:
        return float(np.max(np.abs(adj[:-1] - other[:-1])) / controls_scale)

    def time_step(other: np.ndarray) -> float:
        return float(abs(adj[-1] - other[-1]) / dt_scale)

    return GradCheck(
        adjoint=adj, complex_step=cs, finite_difference=fd,
        controls_error_complex_step=controls(cs),
        controls_error_finite_difference=controls(fd),
        controls_error_casadi=controls(ca_grad),
        time_step_error_complex_step=time_step(cs),
        time_step_error_finite_difference=time_step(fd),
        time_step_error_casadi=time_step(ca_grad),
        cosine_similarity_controls_fd=cosine_similarity(adj[:-1], fd[:-1]),
        cosine_similarity_controls_cs=cosine_similarity(adj[:-1], cs[:-1]),
        penalty_share=penalty_share(problem, motion),
    )


#: the largest share of J the penalties may make at the point :func:`check_point` picks
MAX_PENALTY_SHARE = 0.1


def penalty_share(problem: FlappingProblem, motion: DiscreteMotion) -> float:
    """The share of |J| that the power, heave and pitch penalties make at ``motion``.

    Examples
    --------
    >>> from mfflap.hydro import MorisonModel
    >>> from mfflap.kinematics import HarmonicMotion, to_discrete
    >>> slow = to_discrete(HarmonicMotion(0.5, 0.05, 0.1, 1.5), 2.0, 20)
    >>> penalty_share(FlappingProblem(MorisonModel(), 0.5), slow)
    0.0
    """
    total = float(problem.objective(motion))
    free = float(problem.without_penalties().objective(motion))
    return min(abs(total - free) / max(abs(total), 1e-300), 1.0)


def check_point(problems: list[FlappingProblem], motion: DiscreteMotion,
                max_share: float = MAX_PENALTY_SHARE) -> DiscreteMotion:
    """``motion`` with its accelerations scaled down by steps of 0.8 until the penalties
    make at most ``max_share`` of J for every problem (at most 20 steps): the point at
    which a gradient check tests the thrust and power part rather than the penalties."""
    scaled = motion
    for _ in range(20):
        if all(penalty_share(p, scaled) <= max_share for p in problems):
            return scaled
        scaled = DiscreteMotion(0.8 * scaled.pitch_acceleration,
                                0.8 * scaled.heave_acceleration, scaled.time_step)
    return scaled


#: the betas a gradient check covers
CHECKED_BETAS = (0.0, 0.5, 1.0)


def gradient_checks(config, n_steps: int = 20,
                    progress: Callable[[], None] | None = None) -> dict[float, GradCheck]:
    """The adjoint gradient of ``config``'s optimisation problem checked at each of
    :data:`CHECKED_BETAS`, at its [motion] sinusoid in ``n_steps`` steps per half cycle,
    perturbed so that no symmetry hides an error and scaled down until the penalties make
    at most a tenth of J (:func:`check_point`).

    Parameters
    ----------
    config
        A :class:`~mfflap.config.CaseConfig`.
    n_steps
        N per half cycle: three evaluations of J per component, so the work grows as N^2.
    progress
        Called once per gradient component checked.

    Examples
    --------
    >>> from mfflap.config import CaseConfig
    >>> checks = gradient_checks(CaseConfig(), n_steps=6)
    >>> sorted(checks), all(c.controls_error_complex_step < 1e-10 for c in checks.values())
    ([0.0, 0.5, 1.0], True)
    """
    from mfflap.kinematics.convert import to_discrete

    o = config.optimisation
    base = to_discrete(config.motion.build(), 1 / config.motion.frequency, n_steps)
    rng = np.random.default_rng(0)
    motion = DiscreteMotion(base.pitch_acceleration * (1 + 0.1 * rng.normal(size=n_steps)),
                            base.heave_acceleration * (1 + 0.1 * rng.normal(size=n_steps)),
                            base.time_step)
    problems = {beta: FlappingProblem(config.morison_model(), beta, o.max_power, o.max_heave,
                                      o.penalty_power, o.penalty_heave, o.smoothing_pitch,
                                      o.smoothing_heave, o.scheme, **o.pitch_envelope(),
                                      penalty_pitch=o.penalty_pitch)
                for beta in CHECKED_BETAS}
    motion = check_point(list(problems.values()), motion)
    step = (lambda done, total: progress()) if progress is not None else None
    return {beta: check_gradient(problem, motion, progress=step)
            for beta, problem in problems.items()}


def scatter_figure(checks: dict[float, GradCheck]):
    """Adjoint vs FD per beta (the paper's Figure 6); the dt component scaled separately."""
    # matplotlib takes about a second to load: only figures need it
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
        ax.set_xlabel("dJ/du_j by central differences")
        ax.set_ylabel("dJ/du_j by the adjoint")
        ax.legend(fontsize=8)
    fig.tight_layout()
    return fig
