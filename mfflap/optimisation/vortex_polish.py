"""Polishing a motion on the discrete-vortex model: a few quasi-Newton steps of
:class:`~mfflap.optimisation.vortex_problem.VortexFlappingProblem` from a motion optimised on
Morison.

L-BFGS-B on the controls scaled as the Morison optimiser scales them, with the time step
bounded by the period's bounds; every step costs one forward run and one reverse sweep of
the vortex model. A polish is a local refinement: it starts where the cheap model's optimum
is and moves as far as the vortex model's exact gradient leads it within ``max_iterations``.
"""

from __future__ import annotations

import time
import warnings
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from scipy.optimize import minimize

from mfflap.kinematics.discrete import DiscreteMotion
from mfflap.optimisation.optimise import time_step_bounds
from mfflap.optimisation.vortex_problem import VortexFlappingProblem


@dataclass(frozen=True)
class PolishResult:
    """A motion polished on the discrete-vortex model.

    Attributes
    ----------
    motion : DiscreteMotion
        The polished motion (the last iterate when ``converged`` is False).
    start_objective, objective : float
        J on the vortex model at the start and at the end.
    history : ndarray
        J after each iteration.
    converged : bool
    message : str
        The optimiser's own message.
    n_iterations : int
    wall_time_s : float
    """

    motion: DiscreteMotion
    start_objective: float
    objective: float
    history: np.ndarray
    converged: bool
    message: str
    n_iterations: int
    wall_time_s: float


def polish_on_vortex_model(problem: VortexFlappingProblem, start: DiscreteMotion, *,
                           min_period: float, max_period: float, max_iterations: int = 30,
                           callback: Callable[[int, float], None] | None = None
                           ) -> PolishResult:
    """Refine ``start`` on the vortex model's objective (module docstring).

    Parameters
    ----------
    problem : VortexFlappingProblem
    start : DiscreteMotion
        Typically the Morison optimum.
    min_period, max_period : float, s
        The period's bounds (the time step's are T / 2N).
    max_iterations : int
    callback : callable(iteration, J), optional
        Called after each iteration (progress).

    Returns
    -------
    PolishResult

    Examples
    --------
    >>> import numpy as np
    >>> from mfflap.hydro.discrete_vortex import VortexModelSettings
    >>> n = 16
    >>> phase = (np.arange(n) + 0.5) * np.pi / n
    >>> start = DiscreteMotion(-20 * np.sin(phase), -4 * np.sin(phase + 1.2), 0.03)
    >>> problem = VortexFlappingProblem(VortexModelSettings(wake_chords=0.5,
    ...                                                     chord_points=16), cycles=2)
    >>> result = polish_on_vortex_model(problem, start, min_period=0.5, max_period=2.0,
    ...                                 max_iterations=3)
    >>> bool(result.objective < result.start_objective)
    True
    """
    n = start.n_steps
    lo, hi = time_step_bounds(n, min_period, max_period)
    start = DiscreteMotion(start.pitch_acceleration, start.heave_acceleration,
                           float(np.clip(start.time_step, lo, hi)))
    scale = start.control_scales()
    bounds = [(None, None)] * (2 * n) + [(lo / scale[-1], hi / scale[-1])]
    x0 = np.real(start.controls()) / scale
    history: list[float] = []
    last: dict[str, np.ndarray | float] = {}

    def fun(xs):
        value, grad = problem.packed_value_and_gradient(xs * scale)
        last.update(x=xs.copy(), value=value)
        return value, grad * scale

    def record(xs):
        # the iterate is the one the line search evaluated last: no second forward run
        seen = "x" in last and np.array_equal(xs, last["x"])
        history.append(float(last["value"]) if seen else
                       problem.packed_value_and_gradient(xs * scale, False)[0])
        if callback is not None:
            callback(len(history), history[-1])

    t0 = time.perf_counter()
    start_objective = problem.objective(start)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        res = minimize(fun, x0, jac=True, method="L-BFGS-B", bounds=bounds, callback=record,
                       options={"maxiter": max_iterations})
    motion = DiscreteMotion.from_controls(res.x * scale)
    return PolishResult(motion, float(start_objective), float(problem.objective(motion)),
                        np.array(history), bool(res.success), str(res.message), int(res.nit),
                        time.perf_counter() - t0)


__all__ = ["PolishResult", "polish_on_vortex_model"]
