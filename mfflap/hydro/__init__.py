"""Hydrodynamic force models: loads, the term mechanism, the Morison strip model, and linear
unsteady thin-aerofoil theory as the small-motion yardstick."""

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
from mfflap.hydro.thin_aerofoil import (
    theodorsen_function,
    thin_aerofoil_loads,
    wagner_function,
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
    "theodorsen_function",
    "thin_aerofoil_loads",
    "wagner_function",
]
