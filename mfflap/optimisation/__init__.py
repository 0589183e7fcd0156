"""The penalised optimisation problem of the paper and its exact discrete adjoint."""

from mfflap.optimisation.problem import FlappingProblem, Gradient

__all__ = ["FlappingProblem", "Gradient"]
