"""Grid convergence index: the discretisation uncertainty of a quantity from three meshes.

The procedure of Celik et al. (2008), "Procedure for estimation and reporting of uncertainty
due to discretization in CFD applications", J. Fluids Eng. 130(7), 078001, which follows
Roache's GCI and is the one ASME V&V 20 and most journals ask for. Meshes are numbered finest
first (1 fine, 2 medium, 3 coarse); a mesh's representative cell size is h = N^(-1/d) for N
cells in d dimensions over the same domain, so only cell counts are needed (Celik et al.
recommend ratios h_coarse / h_fine above 1.3).

With eps21 = phi2 - phi1, eps32 = phi3 - phi2 and s = sign(eps32 / eps21), the apparent order p
solves

    p = |ln|eps32 / eps21| + ln((r21^p - s) / (r32^p - s))| / ln r21

(solved by bracketing rather than the paper's fixed-point iteration, which can diverge
for unequal refinement ratios), the extrapolated value is
phi_ext = (r21^p phi1 - phi2) / (r21^p - 1) and the fine-mesh index is
GCI21 = Fs |eps21 / phi1| / (r21^p - 1) with the safety factor Fs = 1.25 of a three-mesh
study. The sign of the convergence ratio R = eps21 / eps32 tells
monotone from oscillatory convergence; where no positive p solves the equation the errors do
not shrink like any power of the cell size and the behaviour is divergent: no order,
extrapolation or index is defined. (|R| < 1 is the test only for equal refinement ratios:
with r21 = 2 and r32 = 1.25 a first-order error has R = 2.)
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import asdict, dataclass

import numpy as np
from scipy.optimize import brentq

from mfflap.errors import ConfigError


@dataclass(frozen=True)
class GridConvergence:
    """Discretisation uncertainty of one quantity from three meshes (1 the finest).

    Attributes
    ----------
    values : (phi1, phi2, phi3) in the quantity's units, finest first
    cell_counts : (N1, N2, N3)
    refinement_ratios : (r21, r32) = (h2 / h1, h3 / h2)
    convergence_ratio : R = eps21 / eps32 (NaN when eps32 = 0)
    behaviour : "monotone", "oscillatory", "divergent", "oscillatory divergent" or "exact"
        (the two finer meshes agree to the last bit)
    apparent_order : p (NaN when divergent; inf when exact)
    extrapolated : phi_ext21, the Richardson extrapolation to zero cell size (NaN when divergent)
    relative_error_fine : e_a21 = |(phi1 - phi2) / phi1|
    extrapolated_relative_error : e_ext21 = |(phi_ext - phi1) / phi_ext|
    gci_fine : GCI21, relative uncertainty of phi1 (fraction; NaN when divergent)
    gci_medium : GCI32, relative uncertainty of phi2 (fraction; NaN when divergent)
    uncertainty_fine : Fs |eps21| / (r21^p - 1), the absolute band around phi1 (units of phi)
    uncertainty_medium : Fs |eps32| / (r32^p - 1), the absolute band around phi2
    asymptotic_ratio : GCI32 / (r21^p GCI21); near 1 in the asymptotic range
    """

    values: tuple[float, float, float]
    cell_counts: tuple[int, int, int]
    refinement_ratios: tuple[float, float]
    convergence_ratio: float
    behaviour: str
    apparent_order: float
    extrapolated: float
    relative_error_fine: float
    extrapolated_relative_error: float
    gci_fine: float
    gci_medium: float
    uncertainty_fine: float
    uncertainty_medium: float
    asymptotic_ratio: float

    @property
    def converging(self) -> bool:
        """Whether the three values converge (monotonically, oscillating, or exactly)."""
        return self.behaviour in ("monotone", "oscillatory", "exact")

    def as_dict(self) -> dict:
        """Fields plus ``converging``, with NaN and inf as None (strict JSON has neither;
        ``behaviour`` says why a number is missing)."""
        def finite(v):
            if isinstance(v, tuple):
                return [finite(x) for x in v]
            return v if not isinstance(v, float) or np.isfinite(v) else None
        return {k: finite(v) for k, v in asdict(self).items()} | {"converging": self.converging}


def _apparent_order(eps21: float, eps32: float, r21: float, r32: float,
                    max_order: float = 50.0) -> float:
    """The order p of Celik et al.'s eq. (3), or NaN if no p in (0, max_order] solves it.

    Eq. (3) is |eps32 / eps21| = r21^p (r32^p - s) / (r21^p - s), whose logarithm minus
    ln|eps32 / eps21| rises monotonically with p; it is solved by bracketing (Brent), which,
    unlike the paper's fixed-point iteration, converges for very unequal refinement ratios.
    """
    s = float(np.sign(eps32 / eps21))
    target = np.log(abs(eps32 / eps21))

    def residual(p: float) -> float:
        return float(p * np.log(r21) + np.log(r32**p - s) - np.log(r21**p - s) - target)

    low = 1e-9
    if residual(low) > 0 or residual(max_order) < 0:
        return float("nan")
    return float(brentq(residual, low, max_order, xtol=1e-14, rtol=4 * np.finfo(float).eps,
                        maxiter=500))


def grid_convergence(values: Sequence[float], cell_counts: Sequence[int], *, dims: int = 2,
                     safety_factor: float = 1.25) -> GridConvergence:
    """Grid convergence index of one quantity from three meshes, in any order.

    Parameters
    ----------
    values
        The quantity on each mesh (e.g. the mean thrust in N).
    cell_counts
        Cells of each mesh, in the order of ``values``; they are sorted finest first.
    dims
        Spatial dimensions of the meshes (2 for the plate's O-grids, one cell deep).
    safety_factor
        Fs: 1.25 for three meshes (Roache; Celik et al.), 3 for a more cautious estimate.

    Raises
    ------
    ConfigError
        For other than three values, a non-finite value, two meshes with the same number of
        cells, or a non-positive safety factor or dimension (naming the key).
    """
    phi = np.asarray(values, dtype=float)
    cells = np.asarray(cell_counts, dtype=float)
    if phi.shape != (3,) or cells.shape != (3,):
        raise ConfigError(f"need the quantity on exactly three meshes, got {phi.size} values "
                          f"and {cells.size} cell counts", key="values")
    if not np.all(np.isfinite(phi)):
        raise ConfigError(f"the values must be finite, got {phi.tolist()}", key="values")
    if not np.all(cells > 0) or len(set(cells.tolist())) < 3:
        raise ConfigError(f"the three meshes need different, positive cell counts, got "
                          f"{cells.astype(int).tolist()}", key="cell_counts")
    if dims not in (1, 2, 3):
        raise ConfigError(f"dims must be 1, 2 or 3, got {dims}", key="dims")
    if not safety_factor > 0:
        raise ConfigError(f"safety_factor must be positive, got {safety_factor}",
                          key="safety_factor")
    order = np.argsort(-cells)
    phi1, phi2, phi3 = (float(v) for v in phi[order])
    n1, n2, n3 = (int(c) for c in cells[order])
    h = cells[order] ** (-1.0 / dims)
    r21, r32 = float(h[1] / h[0]), float(h[2] / h[1])
    eps21, eps32 = phi2 - phi1, phi3 - phi2
    nan = float("nan")
    ratio = eps21 / eps32 if eps32 != 0 else nan
    e_a21 = abs(eps21 / phi1) if phi1 != 0 else nan
    e_a32 = abs(eps32 / phi2) if phi2 != 0 else nan
    common = dict(values=(phi1, phi2, phi3), cell_counts=(n1, n2, n3),
                  refinement_ratios=(r21, r32), convergence_ratio=ratio,
                  relative_error_fine=e_a21)
    if eps21 == 0:
        # the two finer meshes agree exactly: nothing left to extrapolate on the fine pair
        return GridConvergence(**common, behaviour="exact", apparent_order=float("inf"),
                               extrapolated=phi1, extrapolated_relative_error=0.0,
                               gci_fine=0.0, gci_medium=0.0 if eps32 == 0 else nan,
                               uncertainty_fine=0.0,
                               uncertainty_medium=0.0 if eps32 == 0 else nan,
                               asymptotic_ratio=nan)
    p = _apparent_order(eps21, eps32, r21, r32) if eps32 != 0 else nan
    if np.isnan(p):
        # the errors do not shrink like any positive power of the cell size
        return GridConvergence(**common, behaviour="oscillatory divergent"
                               if eps32 != 0 and ratio < 0 else "divergent",
                               apparent_order=nan, extrapolated=nan,
                               extrapolated_relative_error=nan, gci_fine=nan, gci_medium=nan,
                               uncertainty_fine=nan, uncertainty_medium=nan,
                               asymptotic_ratio=nan)
    g21, g32 = r21**p - 1.0, r32**p - 1.0
    extrapolated = (r21**p * phi1 - phi2) / g21
    e_ext = abs((extrapolated - phi1) / extrapolated) if extrapolated != 0 else nan
    gci_fine = safety_factor * e_a21 / g21
    gci_medium = safety_factor * e_a32 / g32
    return GridConvergence(**common, behaviour="monotone" if ratio > 0 else "oscillatory",
                           apparent_order=p, extrapolated=float(extrapolated),
                           extrapolated_relative_error=e_ext, gci_fine=gci_fine,
                           gci_medium=gci_medium,
                           uncertainty_fine=safety_factor * abs(eps21) / g21,
                           uncertainty_medium=safety_factor * abs(eps32) / g32,
                           asymptotic_ratio=gci_medium / (r21**p * gci_fine)
                           if gci_fine > 0 else nan)


@dataclass(frozen=True)
class TwoLevelIndex:
    """Roache's two-level index: the uncertainty of a coarse value from one refinement.

    Attributes
    ----------
    values : (phi_coarse, phi_fine) in the quantity's units
    refinement_ratio : r = h_coarse / h_fine (cell size, or time step)
    assumed_order : p, the scheme's formal order (two levels cannot measure it)
    safety_factor : Fs
    relative_difference : (phi_fine - phi_coarse) / |phi_coarse| (NaN at phi_coarse = 0)
    uncertainty_coarse : Fs |phi_fine - phi_coarse| r^p / (r^p - 1), the absolute band
        around phi_coarse: Fs times its distance from the Richardson extrapolation
    gci_coarse : that band as a fraction of |phi_coarse| (NaN at phi_coarse = 0)
    """

    values: tuple[float, float]
    refinement_ratio: float
    assumed_order: float
    safety_factor: float
    relative_difference: float
    uncertainty_coarse: float
    gci_coarse: float


def two_level_index(coarse: float, fine: float, refinement_ratio: float, *,
                    order: float = 2.0, safety_factor: float = 3.0) -> TwoLevelIndex:
    """The uncertainty of ``coarse`` from one refinement by ``refinement_ratio``.

    With two levels the order cannot be measured; it is assumed to be the schemes' formal
    order (2 for mfflap's set-ups: linearUpwind and linear in space, backward in time) and
    the safety factor is Roache's 3 for two levels, not the 1.25 of three. For the time
    step, halving the Courant limit at a fixed mesh halves the step: r = 2.

    Examples
    --------
    >>> ix = two_level_index(10.0, 10.75, 2.0)        # error C h^2: phi_exact = 11
    >>> round(ix.uncertainty_coarse / ix.safety_factor, 12)
    1.0

    Raises
    ------
    ConfigError
        For a non-finite value, a ratio not above 1, or a non-positive order or factor.
    """
    if not (np.isfinite(coarse) and np.isfinite(fine)):
        raise ConfigError(f"the values must be finite, got {coarse!r} and {fine!r}",
                          key="values")
    if not refinement_ratio > 1:
        raise ConfigError(f"the refinement ratio must be > 1, got {refinement_ratio!r}",
                          key="refinement_ratio")
    if not (order > 0 and safety_factor > 0):
        raise ConfigError(f"order and safety_factor must be positive, got {order!r} and "
                          f"{safety_factor!r}", key="order")
    gain = refinement_ratio**order
    band = safety_factor * abs(fine - coarse) * gain / (gain - 1.0)
    nan = float("nan")
    return TwoLevelIndex((float(coarse), float(fine)), float(refinement_ratio), float(order),
                         float(safety_factor),
                         (fine - coarse) / abs(coarse) if coarse else nan, float(band),
                         band / abs(coarse) if coarse else nan)
