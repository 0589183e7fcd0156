"""The H-type multi-block mesh of a reference OpenFOAM set-up (4.4 min per cycle at f = 1 Hz,
h = 0.3 m on its own machine), against which the cost of mfflap's set-ups is measured.

A 3 x 3 block grid with the plate as the missing middle block: columns upstream, along the
chord and downstream; rows below, across the thickness and above. Every row and column
runs out to the far field, so the thin rows that meet the plate (its first cells and the
band that continues its thickness) cross the whole domain: when the mesh turns about the
pivot they sweep through the water at up to the far field's distance times the
pitch rate, and the faster it turns, the more they set the time step (openfoam.md, "What
sets the time step"): at f = 1 Hz, h = 0.3 m and max Co 2 it took 2,722, 3,090 and 4,216
time steps per cycle at a pitch of 5, 10 and 20 degrees. mfflap's O-grids
(:class:`mfflap.cfd.openfoam.writer.MeshSpec`) keep their fine cells at the plate; this
mesh is here as the baseline of the cost study (benchmarks/cfd_cost.py).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from scipy.optimize import brentq

from mfflap.cfd.openfoam.cell_counts import check_cell_counts
from mfflap.errors import ConfigError


def expansion_ratio(length: float, n_cells: int, first_cell: float) -> float:
    """blockMesh's simpleGrading value (last cell / first cell) of a geometric series of
    ``n_cells`` cells over ``length`` whose first cell is ``first_cell`` long.

    Parameters
    ----------
    length : m
        Length of the edge.
    n_cells
        Cells along it.
    first_cell : m
        Length of the cell at the edge's start.

    Returns
    -------
    float
        r**(n - 1) with first_cell * (r**n - 1) / (r - 1) = length: above 1 where the
        cells grow away from the start, below 1 where they shrink, 1 for a uniform edge.

    Raises
    ------
    ConfigError
        If ``first_cell`` is not in (0, length) or ``n_cells`` < 1.
    """
    if n_cells < 1 or not 0 < first_cell < length:
        raise ConfigError(f"a graded edge needs n_cells >= 1 and 0 < first_cell < length; got "
                          f"n_cells {n_cells}, first_cell {first_cell!r} m over {length!r} m",
                          key="first_cell_m")
    uniform = length / n_cells
    if n_cells == 1 or math.isclose(first_cell, uniform, rel_tol=1e-12):
        return 1.0

    def excess(ratio: float) -> float:
        return first_cell * (ratio**n_cells - 1) / (ratio - 1) - length

    # the sum grows with the ratio; the bracket holds it on the side the first cell asks for
    ratio = (brentq(excess, 1 + 1e-12, 2.0 ** (64 / n_cells) + 1) if uniform > first_cell
             else brentq(excess, 1e-9, 1 - 1e-12))
    return ratio ** (n_cells - 1)


@dataclass(frozen=True)
class HGridSpec:
    """An H-type multi-block resolution (see meshes.toml, ``topology = "H"``).

    Cells are counted per block row and column; lengths are in chords except the first
    cells, in metres.
    """

    name: str
    n_chord: int  # along the plate, uniform
    n_thickness: int  # across the plate's thickness, uniform (the band to the far field)
    n_upstream: int  # from the inflow boundary to the leading edge
    n_downstream: int  # from the trailing edge to the outflow boundary
    n_side: int  # from the plate's faces to each side boundary
    first_cell_m: float  # height of the first cell off the plate's faces
    upstream_chords: float = 10.0
    downstream_chords: float = 15.0
    side_chords: float = 10.0

    def __post_init__(self) -> None:
        check_cell_counts(self.name, {"n_chord": self.n_chord, "n_thickness": self.n_thickness,
                                      "n_upstream": self.n_upstream,
                                      "n_downstream": self.n_downstream, "n_side": self.n_side})
        for key in ("upstream_chords", "downstream_chords", "side_chords"):
            if not getattr(self, key) > 1:
                raise ConfigError(f"mesh {self.name!r}: {key} must be > 1, got "
                                  f"{getattr(self, key)!r}", key=key)
        if not 0 < self.first_cell_m < 0.01:
            raise ConfigError(f"mesh {self.name!r}: first_cell_m must be in (0, 0.01) m, got "
                              f"{self.first_cell_m!r}", key="first_cell_m")

    @property
    def n_cells(self) -> int:
        """Cells of the one-cell-thick mesh (the plate's block left out)."""
        columns = self.n_upstream + self.n_chord + self.n_downstream
        return columns * (2 * self.n_side + self.n_thickness) - self.n_chord * self.n_thickness

    def block_mesh_context(self, chord: float, thickness: float, pivot_m: float = 0.0
                           ) -> dict:
        """What the H-grid blockMeshDict template needs, for a plate of ``chord`` and
        ``thickness`` (m) with the point ``pivot_m`` behind its leading edge at the origin.

        Returns
        -------
        dict
            ``x`` and ``y``: the four block-boundary coordinates along each axis, m;
            ``cells_x``, ``cells_y``: cells per block column and row; ``grading_x``,
            ``grading_y``: their simpleGrading values (cells shrink toward the plate in the
            upstream column and the row below it, grow away from it downstream and above;
            the chordwise cells continue into the columns up- and downstream at the size of
            a chordwise cell).
        """
        x = [x - pivot_m for x in (-self.upstream_chords * chord, 0.0, chord,
                                   chord * (1 + self.downstream_chords))]
        y = [-self.side_chords * chord, -thickness / 2, thickness / 2, self.side_chords * chord]
        chord_cell = chord / self.n_chord
        side = expansion_ratio(y[3] - y[2], self.n_side, self.first_cell_m)
        return {
            "x": x, "y": y,
            "cells_x": [self.n_upstream, self.n_chord, self.n_downstream],
            "cells_y": [self.n_side, self.n_thickness, self.n_side],
            "grading_x": [1 / expansion_ratio(x[1] - x[0], self.n_upstream, chord_cell), 1.0,
                          expansion_ratio(x[3] - x[2], self.n_downstream, chord_cell)],
            "grading_y": [1 / side, 1.0, side],
        }
