"""Force models as sums of terms, each linear in one coefficient.

A :class:`ForceTerm` maps a kinematic state to its *regressor*: the loads it produces per
unit coefficient. A :class:`ForceModel` is a set of terms with a coefficient each. This one
mechanism serves the forward model (sum of coefficient x regressor), identification (a linear
least-squares fit over the regressors) and the gap diagnosis (candidate-effect terms added to
the same sum). Term libraries compose: ``model + other_term``.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Mapping, Sequence

import numpy as np

from mfflap.errors import ConfigError
from mfflap.hydro.loads import Loads
from mfflap.kinematics.state import KinematicState


def signed_square(v: np.ndarray) -> np.ndarray:
    """|v| v, written so that it stays analytic under complex-step differentiation."""
    if np.iscomplexobj(v):
        return v * v * np.sign(v.real)
    return np.abs(v) * v


class ForceTerm(ABC):
    """One physically named contribution to the loads, linear in its coefficient."""

    #: Unique name, used as the coefficient's key.
    name: str = "term"
    #: Default coefficient value.
    default_coefficient: float = 1.0

    @abstractmethod
    def regressor(self, state: KinematicState) -> Loads:
        """Loads per unit coefficient at every sample of ``state``."""

    def describe(self) -> str:
        """One line for reports."""
        return self.__class__.__doc__.strip().splitlines()[0] if self.__class__.__doc__ else ""


class ForceModel:
    """A sum of force terms with one coefficient each.

    Parameters
    ----------
    terms
        The terms; names must be unique.
    coefficients
        Coefficient per term name; a term not named keeps its default.
    name
        Name of the model (stored as the ``source`` of its loads).
    """

    def __init__(self, terms: Sequence[ForceTerm], coefficients: Mapping[str, float] | None = None,
                 name: str = "model"):
        names = [t.name for t in terms]
        if len(set(names)) != len(names):
            raise ConfigError(f"force-model term names must be unique, got {names}")
        coefficients = dict(coefficients or {})
        unknown = set(coefficients) - set(names)
        if unknown:
            raise ConfigError(f"coefficients for unknown terms {sorted(unknown)}; terms: {names}")
        self.terms: tuple[ForceTerm, ...] = tuple(terms)
        self.coefficients: dict[str, float] = {
            t.name: float(coefficients.get(t.name, t.default_coefficient)) for t in terms
        }
        self.name = name

    def __add__(self, other: ForceTerm | ForceModel) -> ForceModel:
        extra = other.terms if isinstance(other, ForceModel) else (other,)
        coeffs = dict(self.coefficients)
        if isinstance(other, ForceModel):
            coeffs.update(other.coefficients)
        return ForceModel(self.terms + tuple(extra), coeffs, name=f"{self.name}+" + "+".join(
            t.name for t in extra))

    def with_coefficients(self, coefficients: Mapping[str, float]) -> ForceModel:
        """A copy with some coefficients replaced."""
        new = dict(self.coefficients)
        new.update(coefficients)
        clone = object.__new__(type(self))
        clone.__dict__.update(self.__dict__)
        ForceModel.__init__(clone, self.terms, new, self.name)
        return clone

    def regressors(self, state: KinematicState) -> dict[str, Loads]:
        """Regressor of every term."""
        return {t.name: t.regressor(state) for t in self.terms}

    def loads(self, state: KinematicState) -> Loads:
        """Sum over terms of coefficient x regressor."""
        fn = ft = mo = 0.0
        for t in self.terms:
            c = self.coefficients[t.name]
            if c == 0.0:
                continue
            r = t.regressor(state)
            fn = fn + c * r.normal_force
            ft = ft + c * r.tangential_force
            mo = mo + c * r.moment
        zeros = np.zeros(state.shape, dtype=np.result_type(state.pitch_angle, float))
        return Loads(
            time=state.time,
            normal_force=zeros + fn,
            tangential_force=zeros + ft,
            moment=zeros + mo,
            source=self.name,
        )
