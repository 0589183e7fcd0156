"""Physical parameters: fluid, plate, free stream and Morison coefficients (SI units).

All are frozen dataclasses whose fields carry their unit and allowed range; constructing one
with an impossible value raises :class:`mfflap.errors.ConfigError` naming the field. The
upper bounds lie far beyond any flapping foil (a 100 m chord, a 1000 m/s stream, water
100 times denser) but below where the model's arithmetic overflows.
Defaults are the paper's set-up (Yin et al. 2026, Biomimetics 11, 393).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, fields, replace

from mfflap.errors import ConfigError
from mfflap.validation import bounded, check_fields


@dataclass(frozen=True)
class Fluid:
    """Incompressible fluid."""

    density: float = bounded(1000.0, low=0.0, low_open=True, high=1.0e5, unit="kg/m^3",
                             doc="rho")
    kinematic_viscosity: float = bounded(1.0e-6, low=0.0, low_open=True, high=1.0,
                                         unit="m^2/s", doc="nu")

    def __post_init__(self) -> None:
        check_fields(self, prefix="fluid.")


@dataclass(frozen=True)
class Plate:
    """Rigid flat plate that heaves and pitches about a pivot on its chord.

    The heave h is the pivot's displacement across the stream and the moment M is taken
    about the pivot; the pivot lies ``pivot_chord_fraction`` of the chord behind the leading
    edge (0: the leading edge, the paper's set-up; 0.25: the quarter chord).

    Examples
    --------
    >>> Plate(pivot_chord_fraction=0.25).pivot_m
    0.04
    """

    chord: float = bounded(0.16, low=0.0, low_open=True, high=100.0, unit="m",
                           doc="chord length l")
    span: float = bounded(0.18, low=0.0, low_open=True, high=1000.0, unit="m", doc="span s")
    thickness: float = bounded(0.003, low=0.0, low_open=True, high=10.0, unit="m",
                               doc="thickness d")
    pivot_chord_fraction: float = bounded(0.0, low=0.0, high=1.0, unit="1",
                                          doc="pivot's distance behind the leading edge / chord")

    def __post_init__(self) -> None:
        check_fields(self, prefix="plate.")
        if self.thickness >= self.chord:

            raise ConfigError(
                f"value {self.thickness!r} must be smaller than the chord {self.chord!r} m",
                key="plate.thickness",
            )

    @property
    def pivot_m(self) -> float:
        """The pivot's distance behind the leading edge, m."""
        return self.pivot_chord_fraction * self.chord


@dataclass(frozen=True)
class FreeStream:
    """Uniform stream along +Y0 relative to the foil's mean position."""

    velocity: float = bounded(0.3, low=0.0, high=1000.0, unit="m/s", doc="free-stream speed U")

    def __post_init__(self) -> None:
        check_fields(self, prefix="flow.")


@dataclass(frozen=True)
class MorisonCoefficients:
    """The four Morison coefficients (dimensionless). Paper's identified values by default."""

    normal_drag: float = bounded(2.49, low=0.0, high=1000.0, unit="1", doc="C_Dn")
    tangential_drag: float = bounded(3.12, low=0.0, high=1000.0, unit="1", doc="C_Dt")
    normal_added_mass: float = bounded(1.02, low=0.0, high=1000.0, unit="1", doc="C_an")
    tangential_added_mass: float = bounded(0.87, low=0.0, high=1000.0, unit="1", doc="C_at")

    def __post_init__(self) -> None:
        check_fields(self, prefix="coefficients.")

    def as_term_values(self) -> dict[str, float]:
        """Coefficient per Morison term name (see :mod:`mfflap.hydro.morison`): the fields
        are named as the terms."""
        return {f.name: getattr(self, f.name) for f in fields(self)}

    @classmethod
    def from_term_values(cls, values: dict[str, float]) -> MorisonCoefficients:
        """Inverse of :meth:`as_term_values` (missing terms keep the paper's values)."""
        return replace(cls(), **{f.name: float(values[f.name]) for f in fields(cls)
                                 if f.name in values})


@dataclass(frozen=True)
class StripSettings:
    """How the plate is cut into strips and which volumes and areas each strip carries.

    ``None`` for a volume or area selects the default of docs/theory.md:
    V_n = pi (l/2)^2 s (flat-plate added mass), V_t = l s d, S_n = l s, S_t = d s;
    each shared equally between the strips.
    """

    n_strips: int = bounded(20, low=1, high=100000, unit="1", doc="number of chordwise strips")
    added_mass_volume_normal: float | None = None
    added_mass_volume_tangential: float | None = None
    drag_area_normal: float | None = None
    drag_area_tangential: float | None = None

    def __post_init__(self) -> None:
        if isinstance(self.n_strips, bool) or not isinstance(self.n_strips, int):

            raise ConfigError(f"value {self.n_strips!r} must be a whole number >= 1",
                              key="model.n_strips")
        check_fields(self, prefix="model.")
        for name in ("added_mass_volume_normal", "added_mass_volume_tangential",
                     "drag_area_normal", "drag_area_tangential"):
            v = getattr(self, name)
            if v is not None and not (v >= 0.0 and v < float("inf")):

                raise ConfigError(f"value {v!r} out of range; allowed: [0, inf)",
                                  key=f"model.{name}")


@dataclass(frozen=True)
class StripGeometry:
    """Resolved per-strip geometry (all strips equal): positions, volumes, areas.

    ``positions`` are the strip centres' signed distances along the chord from the pivot
    (:attr:`Plate.pivot_m`), m: negative ahead of it.
    """

    chord: float
    n_strips: int
    volume_normal: float  # total V_n, m^3
    volume_tangential: float  # total V_t, m^3
    area_normal: float  # total S_n, m^2
    area_tangential: float  # total S_t, m^2
    positions: tuple[float, ...] = field(repr=False, default=())

    @classmethod
    def from_settings(cls, plate: Plate, settings: StripSettings) -> StripGeometry:
        """Resolve the defaults of :class:`StripSettings` against a plate."""
        n = settings.n_strips
        chord, s, d = plate.chord, plate.span, plate.thickness
        vn = settings.added_mass_volume_normal
        vt = settings.added_mass_volume_tangential
        sn = settings.drag_area_normal
        st = settings.drag_area_tangential
        return cls(
            chord=chord,
            n_strips=n,
            volume_normal=math.pi * (chord / 2) ** 2 * s if vn is None else vn,
            volume_tangential=chord * s * d if vt is None else vt,
            area_normal=chord * s if sn is None else sn,
            area_tangential=d * s if st is None else st,
            positions=tuple(chord * (2 * k - 1) / (2 * n) - plate.pivot_m
                            for k in range(1, n + 1)),
        )


#: the critical leading-edge suction parameter that means "never shed from the leading edge":
#: the attached-flow limit of the model (linear theory's small motions)
ATTACHED_FLOW = float("inf")


@dataclass(frozen=True)
class VortexModelSettings:
    """The free parameters and the discretisation of the discrete-vortex model.

    Attributes
    ----------
    critical_lesp : float
        The leading-edge suction parameter |A_0| (reference speed U) above which the plate
        sheds from its leading edge. :data:`ATTACHED_FLOW` never sheds there. Ramesh et al.
        find 0.1-0.25 for round-nosed aerofoils at Re 1e4-1e5; a sharp plate sheds sooner.
    core_radius_chords : float
        The radius of the free vortices' regularising core, in chords.
    chord_points : int
        Midpoints in phi on the chord (the bound sheet's vortices and the quadrature).
    wake_chords : float
        The far-wake cut-off: the vortices shed while the stream travels this many chords are
        kept (at least one period of the motion is the rule: a shorter wake loses the plate's
        own wake of the last stroke).

    Examples
    --------
    >>> VortexModelSettings(critical_lesp=ATTACHED_FLOW, core_radius_chords=0.001)
    ... # doctest: +ELLIPSIS
    VortexModelSettings(critical_lesp=inf, core_radius_chords=0.001, ...)
    >>> VortexModelSettings().wake_steps(chord=0.16, velocity=0.3, time_step=0.005)
    320
    """

    critical_lesp: float = bounded(0.2, low=0.0, low_open=True, high=math.inf, unit="1",
                                   doc="leading-edge suction parameter above which it sheds "
                                       "(inf: never)")
    core_radius_chords: float = bounded(0.02, low=0.0, high=1.0, low_open=True,
                                        high_open=True, unit="1",
                                        doc="free vortices' core radius / chord")
    chord_points: int = bounded(64, low=4, high=1024, unit="1",
                                doc="points on the chord (bound sheet and quadrature)")
    wake_chords: float = bounded(3.0, low=0.0, low_open=True, high=1000.0, unit="1",
                                 doc="far-wake cut-off, in chords the stream travels")

    def __post_init__(self) -> None:
        check_fields(self, prefix="vortex.")

    def wake_steps(self, chord: float, velocity: float, time_step: float) -> int:
        """The steps of shed vortices that the wake ring keeps."""
        return max(math.ceil(self.wake_chords * chord / (velocity * time_step)), 1)
