"""Where the solver templates live: the package ``mfflap.cfd_templates`` (the repository's
top-level ``cfd_templates/`` folder, installed into the wheel under that name)."""

from __future__ import annotations

import importlib.resources
from pathlib import Path

from mfflap.errors import ConfigError


def template_dir(solver: str) -> Path:
    """The templates of ``solver`` (``openfoam`` or ``fluent``).

    Raises
    ------
    ConfigError
        If they are not installed with the package (nor beside it, in a source tree).

    Examples
    --------
    >>> (template_dir("openfoam") / "setups.toml").is_file()
    True
    """
    try:
        root = Path(str(importlib.resources.files("mfflap.cfd_templates")))
    except ModuleNotFoundError:  # a source tree on sys.path, not installed
        root = Path(__file__).resolve().parents[2] / "cfd_templates"
    candidate = root / solver
    if not candidate.is_dir():
        raise ConfigError(f"cannot find the {solver} templates ({candidate}): mfflap was "
                          "installed without mfflap.cfd_templates")
    return candidate
