"""Which OpenFOAM the solvers on PATH belong to.

Two lines of OpenFOAM share the name. mfflap writes its cases for openfoam.com's (the ESI
line: v1912, as Debian packages it, and later), whose dictionaries it uses:
``turbulenceProperties``, ``transportProperties`` and a ``dynamicMeshDict`` naming its
motion solver at the top level. The openfoam.org line (the Foundation's numbered releases)
renamed or restructured those dictionaries (``momentumTransport``, ``physicalProperties``, a
``mover`` sub-dictionary) and, from release 11, replaced pimpleFoam by ``foamRun -solver
incompressibleFluid``. Its force logs are still read (:mod:`mfflap.cfd.openfoam.forces`);
its solvers are refused before a case is meshed, with the release they are, instead of
failing on a missing dictionary part-way through a run.

Every application prints the release it was built from at the end of its ``-help``:
``Using: OpenFOAM- (1912) - visit www.openfoam.com`` (Debian's v1912),
``Using: OpenFOAM-v2312 (2312) - visit www.openfoam.com``, or
``Using: OpenFOAM-11 (see https://openfoam.org)``.
"""

from __future__ import annotations

import functools
import os
import re
import shutil
import subprocess
from dataclasses import dataclass

from mfflap.errors import CfdRunError

_USING = re.compile(r"^Using:\s*OpenFOAM-(\S*)(?:\s+\((\d+)\))?(.*)$", re.M)

#: the line whose cases mfflap writes
SUPPORTED_LINE = "openfoam.com"


@dataclass(frozen=True)
class OpenFOAMRelease:
    """The release an OpenFOAM application was built from."""

    #: "openfoam.com" (ESI), "openfoam.org" (the Foundation) or "unknown"
    line: str
    #: the release as it names itself: "v1912", "v2312", "11"; "" when it does not say
    version: str
    #: the ``Using:`` line it printed ("" if none)
    usage_line: str

    def describe(self) -> str:
        """The release in words, e.g. ``OpenFOAM v1912 of openfoam.com``."""
        name = f"OpenFOAM {self.version}".rstrip()
        return name if self.line == "unknown" else f"{name} of {self.line}"


def release_from_help(help_text: str) -> OpenFOAMRelease:
    """The release an application's ``-help`` output names.

    Parameters
    ----------
    help_text
        What ``<application> -help`` printed.

    Returns
    -------
    OpenFOAMRelease
        Line ``unknown`` when no ``Using:`` line names a web site of either line.
    """
    match = _USING.search(help_text)
    if match is None:
        return OpenFOAMRelease("unknown", "", "")
    name, api, rest = match.group(1), match.group(2), match.group(3)
    line = ("openfoam.org" if "openfoam.org" in rest else
            "openfoam.com" if "openfoam.com" in rest else "unknown")
    version = name or (f"v{api}" if api else "")  # Debian's v1912 leaves the name empty
    return OpenFOAMRelease(line, version, match.group(0).strip())


@functools.lru_cache(maxsize=8)
def installed_release(application: str = "blockMesh",
                      path: str | None = None) -> OpenFOAMRelease | None:
    """The release of ``application`` on PATH (``path``: the PATH to search, default the
    process's), from its ``-help``; None if it is not there. Cached per application and PATH.
    """
    search = os.environ.get("PATH", "") if path is None else path
    exe = shutil.which(application, path=search)
    if exe is None:
        return None
    env = dict(os.environ, PATH=search)
    env.setdefault("WM_PROJECT_DIR", "/usr/share/openfoam")
    try:
        done = subprocess.run([exe, "-help"], capture_output=True, text=True, timeout=60,
                              env=env, errors="replace")
    except (OSError, subprocess.TimeoutExpired):
        return OpenFOAMRelease("unknown", "", "")
    return release_from_help(done.stdout + done.stderr)


def require_supported_release(case: str, application: str = "blockMesh") -> OpenFOAMRelease:
    """Refuse to run a case with the openfoam.org line's solvers.

    Parameters
    ----------
    case
        The case about to be run (for the error).
    application
        The application whose release is asked.

    Returns
    -------
    OpenFOAMRelease
        The release found (openfoam.com, or unknown: a build that does not say is let run).

    Raises
    ------
    CfdRunError
        If the application is missing (naming foamRun when that is there instead), or is of
        the openfoam.org line.
    """
    release = installed_release(application, os.environ.get("PATH", ""))
    if release is None:
        hint = ("foamRun is there instead: that is the openfoam.org line (release 11 or "
                "later), whose cases differ from the ones mfflap writes; "
                if shutil.which("foamRun") else "")
        raise CfdRunError(f"OpenFOAM's {application} is not on PATH ({hint}install "
                          "openfoam.com's OpenFOAM, e.g. Debian's: apt-get install openfoam)",
                          case=case)
    if release.line == "openfoam.org":
        raise CfdRunError(
            f"{application} on PATH is {release.describe()} ({release.usage_line!r}), but "
            f"mfflap writes cases for the {SUPPORTED_LINE} line (v1912 and later; "
            "turbulenceProperties, transportProperties, a top-level motion solver in "
            "dynamicMeshDict), which that line renamed or restructured: install "
            f"{SUPPORTED_LINE}'s OpenFOAM (Debian: apt-get install openfoam) or put it first "
            "on PATH. Force logs of either line are read by `mfflap cfd parse`", case=case)
    return release
