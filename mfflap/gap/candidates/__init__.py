"""The library of candidate unmodelled effects.

Each effect is a :class:`CandidateEffect`: a :class:`~mfflap.hydro.base.ForceTerm` (linear in
its one coefficient, with internal states where it needs them) plus a physical name, a
plausible coefficient range and a short description. Adding a candidate is one new module in
this package that defines a subclass decorated with :func:`register`; every module here is
imported on first use.
"""

from __future__ import annotations

import importlib
import pkgutil

from mfflap.gap.candidates.base import CandidateEffect, FlowContext, register, registry

_loaded = False


def load_all() -> dict[str, type[CandidateEffect]]:
    """Import every candidate module of this package; return the registry (name -> class)."""
    global _loaded
    if not _loaded:
        for info in pkgutil.iter_modules(__path__):
            if info.name != "base":
                importlib.import_module(f"{__name__}.{info.name}")
        _loaded = True
    return registry()


__all__ = ["CandidateEffect", "FlowContext", "load_all", "register", "registry"]
