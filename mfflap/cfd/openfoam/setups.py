"""Named CFD set-ups: a mesh of meshes.toml together with the solver settings it was measured
with (``cfd_templates/openfoam/setups.toml``).

A mesh alone does not fix cost or accuracy: the same cells run with another convection scheme
or corrector count give other forces at another price. A set-up names the pair, so a case
written with ``--setup affordable`` is the one ``benchmarks/cfd_cost.py`` measured.
"""

from __future__ import annotations

from dataclasses import dataclass, fields, replace
from pathlib import Path

from mfflap.cfd.openfoam.writer import (
    AnyMeshSpec,
    SolverSettings,
    mesh_specs,
    resolve_mesh,
    template_dir,
)
from mfflap.errors import ConfigError, shown
from mfflap.study_tables import SOLVER_KEYS, CfdSettings
from mfflap.toml_io import read_toml


@dataclass(frozen=True)
class CfdSetup:
    """A named mesh with its solver settings."""

    name: str
    mesh: AnyMeshSpec
    solver: SolverSettings
    description: str = ""


def setups_path() -> Path:
    """The set-up file (``cfd_templates/openfoam/setups.toml``)."""
    return template_dir() / "setups.toml"


def named_setups(path: str | Path | None = None) -> dict[str, CfdSetup]:
    """The set-ups of ``path`` (setups.toml by default), keyed by name.

    Each table names a ``mesh`` of meshes.toml, an optional ``description`` and any fields of
    :class:`~mfflap.cfd.openfoam.writer.SolverSettings`; the rest keep their defaults.

    Raises
    ------
    ConfigError
        Naming the file and the dotted key, for an unknown mesh or setting or an impossible
        value.
    """
    path = Path(path) if path is not None else setups_path()
    data = read_toml(path)
    meshes = mesh_specs()
    allowed = {f.name for f in fields(SolverSettings)}
    out = {}
    for name, table in data.items():
        if not isinstance(table, dict):
            raise ConfigError(f"set-up {name!r} must be a table", source=str(path), key=name)
        table = dict(table)
        mesh = table.pop("mesh", None)
        if mesh not in meshes:
            raise ConfigError(f"set-up {name!r}: mesh must be one of {', '.join(meshes)}, got "
                              f"{mesh!r}", source=str(path), key=f"{name}.mesh")
        description = str(table.pop("description", ""))
        unknown = sorted(set(table) - allowed)
        if unknown:
            raise ConfigError(f"set-up {name!r}: unknown solver setting {unknown[0]!r}; "
                              f"allowed: {', '.join(sorted(allowed))}", source=str(path),
                              key=f"{name}.{unknown[0]}")
        try:
            solver = replace(SolverSettings(), **table)
        except ConfigError as err:
            raise ConfigError(f"set-up {name!r}: {err}", source=str(path),
                              key=f"{name}.{err.key}") from err
        except TypeError as err:  # e.g. a string where a number belongs
            raise ConfigError(f"set-up {name!r}: a setting has the wrong type ({err})",
                              source=str(path), key=name) from err
        out[name] = CfdSetup(name, meshes[mesh], solver, description)
    return out


def setup(name: str) -> CfdSetup:
    """One set-up of setups.toml by name.

    Raises
    ------
    ConfigError
        If there is no such set-up (the message lists those there are).
    """
    setups = named_setups()
    if name not in setups:
        raise ConfigError(f"unknown set-up {shown(name)}; setups.toml has: {', '.join(setups)}",
                          source=str(setups_path()), key="setup")
    return setups[name]


def mesh_and_solver(mesh: str | None = None, setup_name: str | None = None,
                    wall_treatment: str | None = None) -> tuple[AnyMeshSpec, SolverSettings]:
    """The mesh and solver settings a command asks for with ``--mesh``, ``--setup`` and
    ``--wall-treatment``.

    A named set-up gives both; with a mesh as well, its solver settings run on that mesh
    instead of its own (to tell a set-up's mesh from its solver settings); a mesh alone comes
    with the default solver settings; neither means the coarse mesh. A wall treatment
    replaces the set-up's (or the default) ``SolverSettings.wall_treatment``.

    Raises
    ------
    ConfigError
        If any is unknown.
    """
    if setup_name is not None:
        chosen = setup(setup_name)
        spec, solver = (chosen.mesh if mesh is None else resolve_mesh(mesh)), chosen.solver
    else:
        spec, solver = resolve_mesh(mesh or "coarse"), SolverSettings()
    if wall_treatment is not None:
        solver = replace(solver, wall_treatment=wall_treatment)
    return spec, solver


#: The wall treatment of a case without a named set-up: the plates' first cells lie at
#: y+ 2-21 on the shipped meshes, below the log law's range (docs/findings/known_limits.md),
#: where Spalding's law holds
DEFAULT_WALL_TREATMENT = "all_y_plus"


def case_mesh_and_solver(cfd: CfdSettings, source: str | None = None
                         ) -> tuple[AnyMeshSpec, SolverSettings]:
    """The mesh and solver settings of a case's ``[cfd]`` table: its set-up (or mesh, or
    the coarse mesh at the defaults, :func:`mesh_and_solver`) with the solver keys it gives
    in place of the set-up's.

    Parameters
    ----------
    cfd
        The case's ``[cfd]`` table.
    source
        The case file, for messages.

    Raises
    ------
    ConfigError
        An unknown mesh or set-up, or a combination the solver settings refuse, named by
        its ``cfd.`` key and the file.

    Examples
    --------
    >>> spec, solver = case_mesh_and_solver(CfdSettings(mesh="medium", correctors=2))
    >>> spec.name, solver.n_correctors, solver.max_courant  # the table1 set-up's Courant
    ('medium', 2, 2.0)
    >>> solver.wall_treatment, solver.far_field
    ('all_y_plus', 'inletOutlet')
    >>> _, bare = case_mesh_and_solver(CfdSettings(setup=None))  # the solver's defaults
    >>> bare.max_courant, bare.far_field, bare.wall_treatment
    (4.0, 'freestream', 'all_y_plus')
    """
    keys = {field: key for key, field in SOLVER_KEYS.items()}
    overrides = cfd.solver_overrides()
    if cfd.setup is None:  # a set-up keeps the wall treatment it was measured with
        overrides.setdefault("wall_treatment", DEFAULT_WALL_TREATMENT)
    try:
        spec, solver = mesh_and_solver(cfd.mesh, cfd.setup)
        return spec, replace(solver, **overrides)
    except ConfigError as exc:
        key = f"cfd.{keys.get(exc.key or '', exc.key or 'setup')}"
        raise ConfigError(exc.detail, source=source, key=key) from exc
