"""The Morison strip model of the paper, with the signs of docs/theory.md.

Relative velocities of strip k, whose centre lies l_k = l (2k - 1) / (2n) - x_p along the
chord from the pivot (x_p behind the leading edge, :attr:`mfflap.parameters.Plate.pivot_m`;
h is the pivot's heave):
    v_nk = hdot cos(theta) + U sin(theta) + thetadot l_k
    v_t  = hdot sin(theta) - U cos(theta)
and their full time derivatives. Each strip carries
    F_nk = -C_an rho V_nk dv_nk/dt - 1/2 rho C_Dn S_nk |v_nk| v_nk
    F_tk = -C_at rho V_tk dv_t/dt  - 1/2 rho C_Dt S_tk |v_t| v_t
and M = sum_k F_nk l_k about the pivot. All strips are equal, so the added-mass sums
collapse to chord means of l_k and l_k^2; the drag sum is evaluated strip by strip.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mfflap.hydro.base import ForceModel, ForceTerm, signed_square
from mfflap.hydro.loads import Loads
from mfflap.kinematics.state import KinematicState
from mfflap.parameters import (
    Fluid,
    FreeStream,
    MorisonCoefficients,
    Plate,
    StripGeometry,
    StripSettings,
)


@dataclass(frozen=True)
class RelativeFlow:
    """Relative velocities and their time derivatives at one point of the chord.

    normal_velocity : v_n there, m/s (at a point l further along the chord it is this
        + pitch_rate l)
    normal_acceleration : dv_n/dt there, m/s^2 (+ pitch_acceleration l)
    tangential_velocity, tangential_acceleration : v_t and dv_t/dt (the same all along the
        chord)
    """

    normal_velocity: np.ndarray
    normal_acceleration: np.ndarray
    tangential_velocity: np.ndarray
    tangential_acceleration: np.ndarray

    @classmethod
    def of(cls, state: KinematicState, free_stream_velocity: float,
           from_pivot_m: float = 0.0) -> RelativeFlow:
        """Evaluate from a kinematic state (the pivot's heave) and the free-stream speed U
        (m/s) at the point ``from_pivot_m`` along the chord from the pivot (m; the leading
        edge is at minus :attr:`~mfflap.parameters.Plate.pivot_m`)."""
        u = free_stream_velocity
        s, c = np.sin(state.pitch_angle), np.cos(state.pitch_angle)
        hd, hdd = state.heave_velocity, state.heave_acceleration
        td = state.pitch_rate
        arm = from_pivot_m
        return cls(
            normal_velocity=hd * c + u * s + (td * arm if arm else 0.0),
            normal_acceleration=(hdd * c - hd * td * s + u * td * c
                                 + (state.pitch_acceleration * arm if arm else 0.0)),
            tangential_velocity=hd * s - u * c,
            tangential_acceleration=hdd * s + hd * td * c + u * td * s,
        )


class _MorisonTerm(ForceTerm):
    def __init__(self, geometry: StripGeometry, fluid: Fluid, stream: FreeStream):
        self.geometry = geometry
        self.fluid = fluid
        self.stream = stream
        pos = np.asarray(geometry.positions)
        self.positions = pos
        self.mean_position = float(pos.mean())
        self.mean_position_sq = float((pos**2).mean())

    def _flow(self, state: KinematicState) -> RelativeFlow:
        return RelativeFlow.of(state, self.stream.velocity)

    def _zeros(self, state: KinematicState) -> np.ndarray:
        return np.zeros(state.shape, dtype=np.result_type(state.pitch_angle, float))


class NormalAddedMass(_MorisonTerm):
    """Normal added mass: -rho V_nk dv_nk/dt per strip (coefficient C_an)."""

    name = "normal_added_mass"
    default_coefficient = MorisonCoefficients().normal_added_mass

    def regressor(self, state: KinematicState) -> Loads:
        flow = self._flow(state)
        rv = self.fluid.density * self.geometry.volume_normal
        a0, tdd = flow.normal_acceleration, state.pitch_acceleration
        fn = -rv * (a0 + tdd * self.mean_position)
        mo = -rv * (a0 * self.mean_position + tdd * self.mean_position_sq)
        return Loads(state.time, fn, self._zeros(state), mo, source=self.name)


class TangentialAddedMass(_MorisonTerm):
    """Tangential added mass: -rho V_tk dv_t/dt per strip (coefficient C_at)."""

    name = "tangential_added_mass"
    default_coefficient = MorisonCoefficients().tangential_added_mass

    def regressor(self, state: KinematicState) -> Loads:
        flow = self._flow(state)
        ft = -self.fluid.density * self.geometry.volume_tangential * flow.tangential_acceleration
        z = self._zeros(state)
        return Loads(state.time, z, z + ft, z, source=self.name)


class NormalDrag(_MorisonTerm):
    """Normal quadratic drag: -1/2 rho S_nk |v_nk| v_nk per strip (coefficient C_Dn)."""

    name = "normal_drag"
    default_coefficient = MorisonCoefficients().normal_drag

    def strip_velocities(self, state: KinematicState) -> np.ndarray:
        """v_nk, shape (..., n_times, n_strips)."""
        flow = self._flow(state)
        return flow.normal_velocity[..., None] + state.pitch_rate[..., None] * self.positions

    def regressor(self, state: KinematicState) -> Loads:
        k = 0.5 * self.fluid.density * self.geometry.area_normal / self.geometry.n_strips
        if np.iscomplexobj(state.pitch_angle) or np.iscomplexobj(state.heave_velocity):
            q = signed_square(self.strip_velocities(state))  # complex step: strip by strip
            fn, mo = q.sum(axis=-1), q @ self.positions
        else:
            flow = self._flow(state)
            fn, mo = self.strip_sums(flow.normal_velocity, state.pitch_rate)
        return Loads(state.time, -k * fn, self._zeros(state), -k * mo, source=self.name)

    def _runs(self, a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, ...]:
        """Split the strips at the sign change of v_k = a + b l_k.

        Returns a, b (broadcast), the power sums of l_k (p = 0..3) over the first run and
        over all strips, the sign weight of the first run relative to the rest, and the
        rest's sign: any sum_k sign(v_k) P(v_k, l_k) is w * P(head) + sb * P(total).
        """
        a, b = np.broadcast_arrays(np.asarray(a, dtype=float), np.asarray(b, dtype=float))
        pos = self.positions
        n = len(pos)
        table = self._power_table()
        with np.errstate(divide="ignore", invalid="ignore"):
            zero = np.where(b != 0, -a / np.where(b != 0, b, 1.0), np.inf)
        m = np.searchsorted(pos, zero)  # strips with l_k < l*: the first run
        m = np.where(b == 0, n, m)
        sb = np.sign(b)
        first = np.where(b == 0, np.sign(a), -sb)
        return a, b, table[:, m], table[:, n], first - sb, sb

    def strip_sums(self, a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """sum_k |v_k| v_k and sum_k |v_k| v_k l_k for v_k = a + b l_k, in O(1) per sample.

        v_k is linear in l_k, so it changes sign at most once along the chord: the strips
        split into two contiguous runs of one sign each, and on each run sum v_k^2 and
        sum v_k^2 l_k are polynomials in a and b with the run's power sums of l_k (a
        cumulative table built once). Exact up to rounding.
        """
        a, b, head, total, w, sb = self._runs(a, b)
        aa, ab2, bb = a * a, 2 * a * b, b * b

        def sq(s, p):  # sum over a run of v^2 l^p
            return aa * s[p] + ab2 * s[p + 1] + bb * s[p + 2]

        return w * sq(head, 0) + sb * sq(total, 0), w * sq(head, 1) + sb * sq(total, 1)

    def strip_abs_sums(self, a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, ...]:
        """sum_k |v_k| l_k^p for p = 0, 1, 2 (the drag terms' derivatives), O(1) per sample."""
        a, b, head, total, w, sb = self._runs(a, b)
        return tuple(w * (a * head[p] + b * head[p + 1]) + sb * (a * total[p] + b * total[p + 1])
                     for p in range(3))

    def strip_abs_cubes(self, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        """sum_k |v_k|^3 for v_k = a + b l_k in O(1) per sample (see :meth:`strip_sums`)."""
        a, b, head, total, w, sb = self._runs(a, b)
        c3 = (a**3, 3 * a * a * b, 3 * a * b * b, b**3)
        return w * sum(c * h for c, h in zip(c3, head, strict=True)) + sb * sum(
            c * t for c, t in zip(c3, total, strict=True))

    def _power_table(self) -> np.ndarray:
        table = getattr(self, "_table", None)
        if table is None:
            pos = self.positions
            table = np.zeros((4, len(pos) + 1))
            for p in range(4):
                table[p, 1:] = np.cumsum(pos**p)
            self._table = table
        return table

    def dissipation(self, state: KinematicState) -> np.ndarray:
        """Power dissipated per unit coefficient, sum_k 1/2 rho S_nk |v_nk|^3, W."""
        k = 0.5 * self.fluid.density * self.geometry.area_normal / self.geometry.n_strips
        a = np.real(self._flow(state).normal_velocity)
        return k * self.strip_abs_cubes(a, np.real(state.pitch_rate))


class TangentialDrag(_MorisonTerm):
    """Tangential quadratic drag: -1/2 rho S_t |v_t| v_t (coefficient C_Dt)."""

    name = "tangential_drag"
    default_coefficient = MorisonCoefficients().tangential_drag

    def regressor(self, state: KinematicState) -> Loads:
        flow = self._flow(state)
        ft = -0.5 * self.fluid.density * self.geometry.area_tangential * signed_square(
            flow.tangential_velocity)
        z = self._zeros(state)
        return Loads(state.time, z, z + ft, z, source=self.name)

    def dissipation(self, state: KinematicState) -> np.ndarray:
        """1/2 rho S_t |v_t|^3 per unit coefficient, W."""
        v = np.real(self._flow(state).tangential_velocity)
        return 0.5 * self.fluid.density * self.geometry.area_tangential * np.abs(v) ** 3


class MorisonModel(ForceModel):
    """The paper's Morison strip model: four terms with coefficients C_an, C_at, C_Dn, C_Dt.

    Parameters
    ----------
    plate, fluid, stream
        Geometry, fluid and free stream (paper's values by default).
    coefficients
        The four Morison coefficients (paper's identified values by default).
    strips
        Strip count and the volumes and areas the strips carry.
    """

    def __init__(
        self,
        plate: Plate | None = None,
        fluid: Fluid | None = None,
        stream: FreeStream | None = None,
        coefficients: MorisonCoefficients | None = None,
        strips: StripSettings | None = None,
    ):
        self.plate = plate or Plate()
        self.fluid = fluid or Fluid()
        self.stream = stream or FreeStream()
        self.strips = strips or StripSettings()
        self.geometry = StripGeometry.from_settings(self.plate, self.strips)
        args = (self.geometry, self.fluid, self.stream)
        terms = (NormalAddedMass(*args), TangentialAddedMass(*args), NormalDrag(*args),
                 TangentialDrag(*args))
        coefficients = coefficients or MorisonCoefficients()
        super().__init__(terms, coefficients.as_term_values(), name="morison")

    @property
    def morison_coefficients(self) -> MorisonCoefficients:
        """The current coefficients as a :class:`MorisonCoefficients`."""
        return MorisonCoefficients.from_term_values(self.coefficients)

    def dissipation(self, state: KinematicState) -> np.ndarray:
        """Drag dissipation D = sum_k 1/2 rho C_D S |v|^3 (normal and tangential), W."""
        c = self.coefficients
        nd, td = self.terms[2], self.terms[3]
        return c["normal_drag"] * nd.dissipation(state) + c["tangential_drag"] * td.dissipation(
            state)

    def added_mass_work(self, state: KinematicState) -> np.ndarray:
        """Rate of added-mass work sum_k C_a rho V v dv/dt (normal and tangential), W.

        Over a period of the continuous motion it averages to zero; for the discrete
        scheme its cycle mean is the energy residual (docs/theory.md).
        """
        flow = RelativeFlow.of(state, self.stream.velocity)
        g, rho, c = self.geometry, self.fluid.density, self.coefficients
        pos = np.asarray(g.positions)
        vn = flow.normal_velocity[..., None] + state.pitch_rate[..., None] * pos
        an = flow.normal_acceleration[..., None] + state.pitch_acceleration[..., None] * pos
        normal = c["normal_added_mass"] * rho * g.volume_normal / g.n_strips * (vn * an).sum(-1)
        tangential = (c["tangential_added_mass"] * rho * g.volume_tangential
                      * flow.tangential_velocity * flow.tangential_acceleration)
        return np.real(normal + tangential)
