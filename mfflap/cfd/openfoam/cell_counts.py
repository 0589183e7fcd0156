"""The check every mesh resolution makes of its cell counts."""

from __future__ import annotations

import numbers

from mfflap.errors import ConfigError


def check_cell_counts(mesh_name: str, counts: dict[str, object]) -> None:
    """Refuse a cell count that is not a whole number of at least one.

    Parameters
    ----------
    mesh_name
        The resolution's name, for the message.
    counts
        Key (as in meshes.toml) and value of each cell count.

    Raises
    ------
    ConfigError
        Naming the mesh and the key: for a count below 1, a fraction (blockMesh cannot make
        2.5 cells) or a value that is not a number (``true`` in meshes.toml included).
    """
    for key, value in counts.items():
        whole = isinstance(value, numbers.Integral) and not isinstance(value, bool)
        if not whole or value < 1:
            raise ConfigError(f"mesh {mesh_name!r}: {key} must be a whole number >= 1, got "
                              f"{value!r}", key=key)
