"""Base class and registry of candidate effects."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from mfflap.hydro.base import ForceTerm
from mfflap.hydro.loads import Loads
from mfflap.hydro.morison import RelativeFlow
from mfflap.kinematics.state import KinematicState
from mfflap.parameters import Fluid, FreeStream, Plate

_REGISTRY: dict[str, type[CandidateEffect]] = {}


@dataclass(frozen=True)
class FlowContext:
    """What a candidate needs to know about the plate and the flow."""

    plate: Plate = field(default_factory=Plate)
    fluid: Fluid = field(default_factory=Fluid)
    stream: FreeStream = field(default_factory=FreeStream)

    @property
    def area(self) -> float:
        """Planform area c s, m^2."""
        return self.plate.chord * self.plate.span


def register(cls: type[CandidateEffect]) -> type[CandidateEffect]:
    """Class decorator: add a candidate to the library under its ``name``."""
    if cls.name in _REGISTRY and _REGISTRY[cls.name] is not cls:
        raise ValueError(f"two candidate effects are named {cls.name!r}")
    _REGISTRY[cls.name] = cls
    return cls


def registry() -> dict[str, type[CandidateEffect]]:
    """Registered candidates, name -> class."""
    return dict(_REGISTRY)


class CandidateEffect(ForceTerm):
    """A physically named effect the strip model leaves out, linear in one coefficient.

    Class attributes
    ----------------
    name : str
    physical_name : str
        What a report calls it.
    coefficient_name : str
        What its coefficient is (e.g. "lift slope dC_L/dalpha").
    plausible : (float, float)
        Range of physically plausible coefficient values.
    typical : float
        A typical value (used by the blind benchmark to draw strengths).
    family : str or None
        The effect several candidates are forms of (e.g. laminar and turbulent skin
        friction): candidates of one family are never fitted together, and a diagnosis that
        cannot tell them apart names the family.
    """

    physical_name = "candidate"
    coefficient_name = "coefficient"
    plausible: tuple[float, float] = (-np.inf, np.inf)
    typical: float = 1.0
    family: str | None = None

    def __init__(self, context: FlowContext | None = None):
        self.context = context or FlowContext()

    def flow(self, state: KinematicState) -> RelativeFlow:
        """Relative velocities at the leading edge (the state is the pivot's)."""
        return RelativeFlow.of(state, self.context.stream.velocity,
                               from_pivot_m=-self.context.plate.pivot_m)

    def loads(self, state: KinematicState, normal=None, tangential=None, moment=None) -> Loads:
        """Loads with zeros where a component is not given; ``moment`` is about the leading
        edge and is returned about the pivot, M_pivot = M_LE - x_p F_n (the tangential force
        acts along the chord, through both)."""
        z = np.zeros(state.shape)
        fn = z if normal is None else z + normal
        mo = z if moment is None else z + moment
        pivot = self.context.plate.pivot_m
        return Loads(state.time, fn, z if tangential is None else z + tangential,
                     mo - pivot * fn if pivot else mo, source=self.name)

    def is_plausible(self, value: float) -> bool:
        """Whether a fitted coefficient lies in the plausible range."""
        lo, hi = self.plausible
        return lo <= value <= hi
