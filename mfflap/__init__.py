"""mfflap: Morison reduced-order model of flapping-foil propulsion, discrete adjoint
optimisation, and the CFD pipeline (OpenFOAM, Fluent) that identifies and checks it."""

from mfflap.errors import ConfigError, MfflapError, MotionError, ParseError
from mfflap.kinematics import (
    DiscreteMotion,
    HarmonicMotion,
    KinematicState,
    PeriodicSplineMotion,
    RampHarmonicMotion,
)

__version__ = "0.1.0"

__all__ = [
    "ConfigError",
    "DiscreteMotion",
    "HarmonicMotion",
    "KinematicState",
    "MfflapError",
    "MotionError",
    "ParseError",
    "PeriodicSplineMotion",
    "RampHarmonicMotion",
    "__version__",
]
