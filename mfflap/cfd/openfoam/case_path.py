"""Case folders OpenFOAM can run in: its file names hold no whitespace and no quotes.

OpenFOAM strips those characters from every file name it reads, the ``-case`` argument
included, so a case in ``/tmp/a b/case`` runs as ``/tmp/ab/case`` and fails ("cannot open
root directory"), or runs a case of that other name if one exists. Checked here on Debian's
openfoam (v1912) with blockMesh: a space, ``"`` and ``'`` are stripped; ``$ ~ # ; ( { * , @
= :`` and non-ASCII letters are kept.
"""

from __future__ import annotations

from pathlib import Path

from mfflap.errors import ConfigError

#: the characters OpenFOAM strips from a file name besides whitespace
STRIPPED_QUOTES = "\"'"


def stripped_characters(path: str | Path) -> list[str]:
    """The characters of ``path`` (made absolute, as OpenFOAM sees it from the working
    folder) that OpenFOAM strips from a file name, each once, in order."""
    found: list[str] = []
    for char in str(Path(path).absolute()):
        if (char.isspace() or char in STRIPPED_QUOTES) and char not in found:
            found.append(char)
    return found


def check_case_path(path: str | Path) -> Path:
    """``path`` if OpenFOAM can run a case in it (or in a folder below it).

    Raises
    ------
    ConfigError
        Naming the path and the characters OpenFOAM would strip from it, before anything is
        written or run.
    """
    path = Path(path)
    bad = stripped_characters(path)
    if bad:
        absolute = str(path.absolute())
        seen_as = "".join(c for c in absolute if c not in bad)
        raise ConfigError(
            f"OpenFOAM cannot run a case in {absolute!r}: it strips whitespace and quotes "
            f"from file names ({', '.join(repr(c) for c in bad)} here) and would look in "
            f"{seen_as!r} instead; choose a folder whose path has none")
    return path


__all__ = ["STRIPPED_QUOTES", "check_case_path", "stripped_characters"]
