"""The edits a retry makes to a written case, and what a case holds now: its Courant limit,
the convection scheme of k and epsilon, and its far field.

Every dictionary and field file is read and written through foamlib's parser
(:class:`foamlib.FoamFile`, ASCII and binary fields alike), so an edit changes the entry it
means and nothing else.
"""

from __future__ import annotations

from pathlib import Path

from mfflap.cfd.openfoam.foam_files import foam_file
from mfflap.cfd.openfoam.time_folders import is_time_folder
from mfflap.cfd.openfoam.writer import TURBULENCE_CONVECTION_SCHEMES
from mfflap.errors import CfdRunError

#: the convected fields whose schemes change together
TURBULENCE_FIELDS = ("k", "epsilon")


def courant_limit(case_dir: str | Path) -> float:
    """The case's ``maxCo`` (system/controlDict).

    Raises
    ------
    CfdRunError
        If the controlDict has no numeric ``maxCo``.
    """
    value = foam_file(Path(case_dir) / "system" / "controlDict").get("maxCo")
    if not isinstance(value, int | float):
        raise CfdRunError("no maxCo entry in system/controlDict", case=str(case_dir))
    return float(value)


def lower_courant_limit(case_dir: str | Path, factor: float = 0.5) -> float:
    """Multiply ``maxCo`` in the case's controlDict by ``factor``; return the new limit."""
    value = float(f"{courant_limit(case_dir) * factor:g}")
    foam_file(Path(case_dir) / "system" / "controlDict")["maxCo"] = value
    return value


def _div_key(field: str) -> str:
    return f"div(phi,{field})"


def turbulence_convection(case_dir: str | Path) -> str:
    """The convection scheme of k (and epsilon, written and changed together) in
    system/fvSchemes as a ``SolverSettings.turbulence_convection`` name, or "other"."""
    path = Path(case_dir) / "system" / "fvSchemes"
    if not path.is_file():
        return "other"
    entry = foam_file(path).get("divSchemes", {}).get(_div_key(TURBULENCE_FIELDS[0]))
    words = entry if isinstance(entry, tuple | list) else (entry,)
    if not words or words[0] != "Gauss":
        return "other"
    text = " ".join(str(w) for w in words[1:])
    names = {scheme: name for name, scheme in TURBULENCE_CONVECTION_SCHEMES.items()}
    return names.get(text, "other")


def use_upwind_turbulence(case_dir: str | Path) -> bool:
    """Switch k and epsilon convection to bounded first-order upwind (the most robust choice
    for a k-epsilon blow-up); True if the schemes changed."""
    schemes = foam_file(Path(case_dir) / "system" / "fvSchemes")
    divs = schemes.get("divSchemes", {})
    changed = False
    with schemes:
        for field in TURBULENCE_FIELDS:
            key = _div_key(field)
            if key in divs and divs[key] != ("Gauss", "upwind"):
                schemes["divSchemes"][key] = ("Gauss", "upwind")
                changed = True
    return changed


def far_field(case_dir: str | Path) -> str:
    """The far field the case's 0/U holds: "freestream", "inletOutlet" or "other"."""
    path = Path(case_dir) / "0" / "U"
    if not path.is_file():
        return "other"
    types = {patch.get("type") for patch in _patches(foam_file(path)).values()}
    return ("inletOutlet" if "inletOutlet" in types
            else "freestream" if "freestreamVelocity" in types else "other")


def _patches(field) -> dict:
    """The patches of a field file's boundaryField by name (each a sub-dictionary)."""
    if "boundaryField" not in field:
        return {}
    boundary = field["boundaryField"]
    patches = {name: boundary[name] for name in boundary}  # values() gives None for these
    return {name: patch for name, patch in patches.items() if hasattr(patch, "get")}


def _field_files(case: Path, field: str) -> list[Path]:
    """``field`` in 0/ and every written time folder, those of processor folders too."""
    return [path for path in [*case.glob(f"*/{field}"), *case.glob(f"processor*/*/{field}")]
            if is_time_folder(path.parent.name)]


def use_inlet_outlet_far_field(case_dir: str | Path) -> bool:
    """Switch the far field from freestreamVelocity/freestreamPressure to inletOutlet
    velocity (its inlet value the free stream's) and a fixed pressure, in 0/ and in every
    written time folder, those of a decomposed case's processor folders too; True if
    anything changed.

    Where the whole mesh heaves several times faster than the stream (h = 0.5 m at
    f = 0.5 Hz, U = 0.3 m/s) the freestream pair let the velocity grow without bound in the
    outer cells along the heave path; restarted from the same fields with this far field
    the run went on with a normal time step.
    """
    changed = False
    case = Path(case_dir)
    for field, old, new in (("U", "freestreamVelocity", "inletOutlet"),
                            ("p", "freestreamPressure", "fixedValue")):
        for path in _field_files(case, field):
            data = foam_file(path)
            names = [name for name, patch in _patches(data).items()
                     if patch.get("type") == old]
            if not names:
                continue
            with data:
                for name in names:
                    patch = data["boundaryField"][name]
                    stream = patch.get("freestreamValue")
                    patch["type"] = new
                    if new == "inletOutlet":
                        patch["inletValue"] = stream
                    del patch["freestreamValue"]
            changed = True
    return changed
