"""Where the solver templates live (``cfd_templates/<solver>`` beside the package)."""

from __future__ import annotations

from pathlib import Path

from mfflap.errors import ConfigError


def template_dir(solver: str) -> Path:
    """``cfd_templates/<solver>`` (``openfoam`` or ``fluent``) beside the mfflap package."""
    here = Path(__file__).resolve()
    for parent in here.parents:
        candidate = parent / "cfd_templates" / solver
        if candidate.is_dir():
            return candidate
    raise ConfigError(f"cannot find cfd_templates/{solver} beside the mfflap package")
