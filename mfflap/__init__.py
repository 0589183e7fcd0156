"""mfflap: Morison reduced-order model of flapping-foil propulsion, discrete adjoint
optimisation, and the CFD pipeline (OpenFOAM, Fluent) that identifies and checks it."""

# first: points numba's cache out of the installed package before any kernel compiles
from mfflap import compiled_cache as _compiled_cache  # noqa: F401
from mfflap.errors import ConfigError, MfflapError, MotionError, ParseError
from mfflap.kinematics import (
    DiscreteMotion,
    HarmonicMotion,
    KinematicState,
    PeriodicSplineMotion,
    RampHarmonicMotion,
)
from mfflap.version import __version__


def __getattr__(name: str):
    """``mfflap.Study`` and ``mfflap.open_results`` are imported on first use: the facade
    brings in every layer below it (identification, optimisation, CFD, the gap diagnosis),
    which ``import mfflap`` alone does not need."""
    if name in ("Study", "open_results"):
        from mfflap import api

        return getattr(api, name)
    raise AttributeError(f"module 'mfflap' has no attribute {name!r}")


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
    "Study",
    "__version__",
    "open_results",
]
