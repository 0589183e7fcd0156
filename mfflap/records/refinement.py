"""A CFD record's numerical uncertainty from refinement: its mesh and time-step parts.

A record's cycle scatter (:mod:`mfflap.records.cycle_scatter`) is the uncertainty one run
shows by itself; how far the answer moves when the mesh is refined or the time step halved
needs a second run of the same motion. :class:`RefinementChange` holds what such a pair
gives the coarser record: how far its F_n history is from the refined run's (NRMSE and
Pearson, on the same footing as a model's NRMSE against the record), and each of its means
(thrust, input power, RMS F_n) beside the refined run's with Roache's two-level index
(:func:`mfflap.campaign.refinement.refinement_change` computes it).

Stored in the coarser record as the attributes of ``/refinement/mesh`` and
``/refinement/time_step``, each naming the refined record it came from and that file's
SHA-256; :func:`mfflap.records.record.read_record` reads them into
:attr:`~mfflap.records.record.CfdRecord.refinement`.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import Any

import h5py

#: the group of a record that holds its refinement changes, one subgroup per kind
GROUP = "refinement"
#: what a refinement refines: the mesh (medium against coarse) or the time step (the
#: Courant limit halved)
KINDS = ("mesh", "time_step")
#: the means each change compares, as named in :class:`RefinementChange`
MEANS = ("mean_thrust", "mean_power", "rms_normal_force")


@dataclass(frozen=True)
class RefinementChange:
    """How a record's answer moves when its mesh or time step is refined.

    Attributes
    ----------
    kind : str
        ``"mesh"`` or ``"time_step"``.
    refined_record : str
        The refined run's file name; ``refined_folder`` the folder it was read from.
    refined_sha256 : str
        That file's SHA-256 when the change was computed.
    refinement_ratio : float
        r = h_coarse / h_fine: sqrt of the cell-count ratio for a 2-D mesh, the ratio of the
        Courant limits for the time step.
    n_cycles : int
        The whole periods compared, counted back from the records' common end.
    normal_force_nrmse : float
        RMS of (F_n coarse - F_n refined) over those periods, normalised by the coarse
        record's range of F_n there, as a model's NRMSE against the record is.
    normal_force_pearson : float
        Pearson r of the two F_n histories over those periods.
    mean_thrust_n, mean_power_w, rms_normal_force_n : tuple of float
        (coarse, refined) means over those periods: thrust N, input power W, RMS F_n N.
    gci_mean_thrust, gci_mean_power, gci_rms_normal_force : float
        Roache's two-level index of each coarse mean (a fraction of its magnitude; safety
        factor 3, the schemes' formal order 2).
    """

    kind: str
    refined_record: str
    refined_folder: str
    refined_sha256: str
    refinement_ratio: float
    n_cycles: int
    normal_force_nrmse: float
    normal_force_pearson: float
    mean_thrust_n: tuple[float, float]
    mean_power_w: tuple[float, float]
    rms_normal_force_n: tuple[float, float]
    gci_mean_thrust: float
    gci_mean_power: float
    gci_rms_normal_force: float

    def relative_change(self, mean: str) -> float:
        """(refined - coarse) / |coarse| of ``mean`` (one of :data:`MEANS`).

        Examples
        --------
        >>> c = RefinementChange("mesh", "a.h5", "m", "0", 1.5, 2, 0.05, 0.99, (2.0, 2.2),
        ...                      (-10.0, -11.0), (5.0, 5.0), 0.3, 0.3, 0.0)
        >>> round(c.relative_change("mean_power"), 6), c.relative_change("rms_normal_force")
        (-0.1, 0.0)
        """
        field = {"mean_thrust": "mean_thrust_n", "mean_power": "mean_power_w",
                 "rms_normal_force": "rms_normal_force_n"}.get(mean)
        if field is None:
            raise KeyError(f"no mean {mean!r}: one of {list(MEANS)}")
        coarse, refined = getattr(self, field)
        return (refined - coarse) / abs(coarse) if coarse else float("nan")


def write_refinement(h5: h5py.File, change: RefinementChange) -> None:
    """Store ``change`` in the open record ``h5`` as ``/refinement/<kind>`` (replaced if
    there)."""
    group = h5.require_group(GROUP)
    if change.kind in group:
        del group[change.kind]
    sub = group.create_group(change.kind)
    sub.attrs.update({k: list(v) if isinstance(v, tuple) else v
                      for k, v in asdict(change).items()})
    sub.attrs["units"] = "N, W, N (thrust, input power, RMS normal force)"


def read_refinement(h5: h5py.File) -> dict[str, RefinementChange]:
    """The refinement changes stored in the open record ``h5``, by kind (empty if none)."""
    if GROUP not in h5:
        return {}
    out = {}
    for kind, sub in h5[GROUP].items():
        attrs: dict[str, Any] = dict(sub.attrs)
        values = {}
        for name, spec in RefinementChange.__dataclass_fields__.items():
            v = attrs[name]
            if spec.type == "tuple[float, float]":
                values[name] = tuple(float(x) for x in v)
            elif spec.type == "int":
                values[name] = int(v)
            elif spec.type == "float":
                values[name] = float(v)
            else:
                values[name] = v.decode() if isinstance(v, bytes) else str(v)
        out[kind] = RefinementChange(**values)
    return out


__all__ = ["GROUP", "KINDS", "MEANS", "RefinementChange", "read_refinement",
           "write_refinement"]
