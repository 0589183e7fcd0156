"""Hydrodynamic force models: loads, the term mechanism, the Morison strip model."""

from mfflap.hydro.base import ForceModel, ForceTerm, signed_square
from mfflap.hydro.loads import LOAD_UNITS, Loads
from mfflap.hydro.morison import (
    MorisonModel,
    NormalAddedMass,
    NormalDrag,
    RelativeFlow,
    TangentialAddedMass,
    TangentialDrag,
)

__all__ = [
    "LOAD_UNITS",
    "ForceModel",
    "ForceTerm",
    "Loads",
    "MorisonModel",
    "NormalAddedMass",
    "NormalDrag",
    "RelativeFlow",
    "TangentialAddedMass",
    "TangentialDrag",
    "signed_square",
]
