"""Kinematics: continuous motions, the discrete half-cycle scheme, and conversions."""

from mfflap.kinematics.continuous import (
    HarmonicMotion,
    Motion,
    PeriodicSplineMotion,
    RampHarmonicMotion,
    TabulatedMotion,
    check_times,
)
from mfflap.kinematics.convert import harmonic_to_discrete, resample, to_discrete, to_spline
from mfflap.kinematics.discrete import SCHEMES, DiscreteMotion, Scheme
from mfflap.kinematics.state import KINEMATIC_UNITS, KinematicState

__all__ = [
    "KINEMATIC_UNITS",
    "SCHEMES",
    "DiscreteMotion",
    "HarmonicMotion",
    "KinematicState",
    "Motion",
    "PeriodicSplineMotion",
    "RampHarmonicMotion",
    "Scheme",
    "TabulatedMotion",
    "check_times",
    "harmonic_to_discrete",
    "resample",
    "to_discrete",
    "to_spline",
]
