"""Loads: the hydrodynamic force on the plate in the body frame, on a time base."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

#: SI units of the load components.
LOAD_UNITS: dict[str, str] = {
    "normal_force": "N",
    "tangential_force": "N",
    "moment": "N*m",
}
#: the load components, in the order of :meth:`Loads.stacked`
LOAD_COMPONENTS: tuple[str, ...] = tuple(LOAD_UNITS)


@dataclass(frozen=True)
class Loads:
    """Force on the plate: normal and tangential components and moment about the pivot.

    Body frame: e_t = (sin theta, cos theta) from leading to trailing edge, e_n =
    (cos theta, -sin theta) in the global (X0 = heave, Y0 = stream) frame. The moment is
    positive in the sense of the normal force acting at positive chord positions
    (M = sum_k F_nk l_k).

    Attributes
    ----------
    time : ndarray, s, shape (n_times,) or (..., n_times)
    normal_force : ndarray, N, shape (..., n_times)
    tangential_force : ndarray, N
    moment : ndarray, N*m
    source : str
        Where the loads come from: a model name, or ``"openfoam:<case>"`` etc.
    """

    time: np.ndarray
    normal_force: np.ndarray
    tangential_force: np.ndarray
    moment: np.ndarray
    source: str = "unknown"
    metadata: dict = field(default_factory=dict, compare=False)

    def __add__(self, other: Loads) -> Loads:
        return Loads(self.time, self.normal_force + other.normal_force,
                     self.tangential_force + other.tangential_force,
                     self.moment + other.moment, source=f"{self.source}+{other.source}")

    def scaled(self, factor: float) -> Loads:
        """Loads multiplied by ``factor`` (e.g. a coefficient)."""
        return Loads(self.time, factor * self.normal_force, factor * self.tangential_force,
                     factor * self.moment, source=self.source)

    def stacked(self) -> np.ndarray:
        """Components stacked on a new leading axis: shape (3, ..., n_times)."""
        return np.stack([self.normal_force, self.tangential_force, self.moment])
