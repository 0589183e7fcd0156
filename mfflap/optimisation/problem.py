"""The penalised objective J(u, dt) of docs/theory.md and its exact gradient.

J = (1/N) sum_j L_j + J_s with
L_j = -(1 - beta) F_thrust,j + beta P_in,j + 1/2 sigma_P max(0, P_in,j - P_max)^2
      + 1/2 sigma_h max(0, |h_j| - h_max)^2
      + 1/2 sigma_theta sum_x (max(0, |x_j| - x_max) / x_max)^2 over x = theta, thetadot,
        thetaddot (the pitch envelope; mfflap's addition, off unless a limit is given),
J_s = 1/2 eps_theta [sum_{j<N} (acc_{j+1} - acc_j)^2 + (acc_1 + acc_N)^2] + the same for heave,
and, where a :class:`LinearModifier` is given (the first-order output correction of the rounds,
:mod:`mfflap.optimisation.output_correction`), + g . (z - z_c) over the packed controls z.
Where :class:`SampleOffsets` are given (a higher-fidelity model's correction,
:mod:`mfflap.optimisation.vortex_polish`), F_thrust,j and P_in,j are the model's plus fixed
offsets delta_T,j and delta_P,j (the P_max penalty may see its own power offsets): the
offsets move J and where the power penalty bites, not the model's derivatives.

Gradient (discrete adjoint, O(N)): a backward sweep of the semi-implicit Euler steps with
lambda_{N+1} = 0 gives dJ/dx_1 and the partial gradients at fixed x_1; the closed-form linear
map x_1(u, dt) of the antisymmetric closure is then chained in. This is algebraically the same
gradient as the paper's closure lambda_{N+1} = -lambda_1 and includes the dependence of x_1 on
u and dt that docs/theory.md warns about.
"""

from __future__ import annotations

import copy
from dataclasses import dataclass

import numpy as np

from mfflap.errors import ConfigError, shown
from mfflap.hydro.morison import MorisonModel
from mfflap.kinematics.discrete import SCHEMES, DiscreteMotion
from mfflap.optimisation.adjoint_kernel import objective_and_gradient
from mfflap.optimisation.state_adjoint import (
    Gradient,
    chain_state_partials,
    smoothness,
    smoothness_gradient,
)
from mfflap.performance import thrust_and_power


def _positive_part(x):
    if np.iscomplexobj(x):
        return np.where(x.real > 0, x, 0)
    return np.maximum(x, 0)


def _abs(x):
    return x * np.sign(x.real) if np.iscomplexobj(x) else np.abs(x)


@dataclass(frozen=True, eq=False)
class LinearModifier:
    """An affine term g . (z - z_c) added to J, z = [pitch acc (N), heave acc (N), dt].

    Attributes
    ----------
    gradient : g, shape (2N + 1,), units of J per unit of each packed control
    centre : z_c, shape (2N + 1,), the packed motion where the term vanishes
    """

    gradient: np.ndarray
    centre: np.ndarray

    def __post_init__(self) -> None:
        g = np.asarray(self.gradient, dtype=float)
        c = np.asarray(self.centre, dtype=float)
        if g.ndim != 1 or g.shape != c.shape or g.size < 5 or g.size % 2 != 1:
            raise ConfigError(f"a linear modifier needs a gradient and a centre of one length "
                              f"2N + 1, got shapes {g.shape} and {c.shape}",
                              key="linear_modifier")
        if not (np.isfinite(g).all() and np.isfinite(c).all()):
            raise ConfigError("a linear modifier's gradient and centre must be finite",
                              key="linear_modifier")
        object.__setattr__(self, "gradient", g)
        object.__setattr__(self, "centre", c)

    @property
    def n_steps(self) -> int:
        """N of the motions it applies to."""
        return (self.gradient.size - 1) // 2

    def value(self, motion: DiscreteMotion):
        """g . (z - z_c), shape (...). Complex-step safe."""
        n = self.n_steps
        g, c = self.gradient, self.centre
        dt = np.asarray(motion.time_step)
        return ((motion.pitch_acceleration - c[:n]) @ g[:n]
                + (motion.heave_acceleration - c[n:2 * n]) @ g[n:2 * n]
                + (dt - c[-1]) * g[-1])

    def packed_value(self, z: np.ndarray) -> float:
        """g . (z - z_c) at packed controls."""
        return float(self.gradient @ (z - self.centre))


@dataclass(frozen=True, eq=False)
class SampleOffsets:
    """Fixed offsets added to the model's thrust and input power at each of the N samples.

    Attributes
    ----------
    thrust : delta_T,j, N, shape (N,)
    power : delta_P,j, W, shape (N,)
        What the beta-weighted mean power sees.
    peak_power : W, shape (N,), optional
        What the P_max penalty sees instead of ``power`` (e.g. the largest power over each
        sample's share of the cycle, so that the limit holds between the samples too);
        None: ``power``.

    Examples
    --------
    >>> offsets = SampleOffsets(np.zeros(4), np.ones(4))
    >>> offsets.n_steps, offsets.peak_power.tolist()
    (4, [1.0, 1.0, 1.0, 1.0])
    """

    thrust: np.ndarray
    power: np.ndarray
    peak_power: np.ndarray | None = None

    def __post_init__(self) -> None:
        t = np.asarray(self.thrust, dtype=float)
        p = np.asarray(self.power, dtype=float)
        q = p if self.peak_power is None else np.asarray(self.peak_power, dtype=float)
        if t.ndim != 1 or t.shape != p.shape or q.shape != p.shape or t.size < 2:
            raise ConfigError(f"sample offsets need thrust, power and peak power of one "
                              f"length N >= 2, got shapes {t.shape}, {p.shape} and "
                              f"{q.shape}", key="sample_offsets")
        if not (np.isfinite(t).all() and np.isfinite(p).all() and np.isfinite(q).all()):
            raise ConfigError("sample offsets must be finite", key="sample_offsets")
        object.__setattr__(self, "thrust", t)
        object.__setattr__(self, "power", p)
        object.__setattr__(self, "peak_power", q)

    @property
    def n_steps(self) -> int:
        """N of the motions they apply to."""
        return self.thrust.size


_NO_GRAD = np.empty(0)
_MORISON_TERMS = ("normal_added_mass", "tangential_added_mass", "normal_drag",
                  "tangential_drag")


class FlappingProblem:
    """beta-weighted thrust/power objective with power, heave and smoothness penalties.

    Parameters
    ----------
    model
        The Morison model.
    beta : 1, in [0, 1]
    max_power : W, P_max > 0
    max_heave : m, h_max > 0
    penalty_power : sigma_P >= 0, 1/W
    penalty_heave : sigma_h >= 0, N/m^2 (in units of J)
    smoothing_pitch, smoothing_heave : eps_theta, eps_h >= 0
    scheme : ``"paper"`` or ``"midpoint"``
    max_pitch : rad; max_pitch_rate : rad/s; max_pitch_acceleration : rad/s^2
        The pitch envelope, > 0 (inf: no limit): e.g. what the identification data reach
        (:mod:`mfflap.identification.coverage`), so that the optimum stays where the
        coefficients rest on CFD. The rate is the one the forces see (the scheme's).
    penalty_pitch : sigma_theta >= 0, N (in units of J) per squared relative excess
    linear_modifier
        An affine term added to J (:class:`LinearModifier`; None: none).
    sample_offsets
        Fixed offsets of the thrust and power at each sample (:class:`SampleOffsets`;
        None: none).
    compiled
        Evaluate single real motions with the compiled kernel
        (:mod:`mfflap.optimisation.adjoint_kernel`) when the model allows it; the array code
        below is the reference and serves complex steps, batches and other models.
    """

    def __init__(self, model: MorisonModel, beta: float = 0.0, max_power: float = 50.0,
                 max_heave: float = 0.5, penalty_power: float = 10.0,
                 penalty_heave: float = 1.0e4, smoothing_pitch: float = 1e-4,
                 smoothing_heave: float = 1e-2, scheme: str = "paper", compiled: bool = True,
                 max_pitch: float = np.inf, max_pitch_rate: float = np.inf,
                 max_pitch_acceleration: float = np.inf, penalty_pitch: float = 1.0e4,
                 linear_modifier: LinearModifier | None = None,
                 sample_offsets: SampleOffsets | None = None):
        checks = [
            ("beta", beta, 0 <= beta <= 1, "[0, 1]"),
            ("max_power", max_power, max_power > 0, "(0, inf) W"),
            ("max_heave", max_heave, max_heave > 0, "(0, inf) m"),
            ("penalty_power", penalty_power, penalty_power >= 0, "[0, inf)"),
            ("penalty_heave", penalty_heave, penalty_heave >= 0, "[0, inf)"),
            ("smoothing_pitch", smoothing_pitch, smoothing_pitch >= 0, "[0, inf)"),
            ("smoothing_heave", smoothing_heave, smoothing_heave >= 0, "[0, inf)"),
            ("penalty_pitch", penalty_pitch, penalty_pitch >= 0, "[0, inf)"),
        ]
        for name, value, ok, allowed in checks:
            if not (ok and np.isfinite(value)):
                raise ConfigError(f"value {value!r} is not allowed; allowed: {allowed}",
                                  key=f"optimisation.{name}")
        for name, value, unit in (("max_pitch", max_pitch, "rad"),
                                  ("max_pitch_rate", max_pitch_rate, "rad/s"),
                                  ("max_pitch_acceleration", max_pitch_acceleration, "rad/s^2")):
            if not value > 0:  # NaN too; inf is no limit
                raise ConfigError(f"value {value!r} is not allowed; allowed: (0, inf] {unit}",
                                  key=f"optimisation.{name}")
        if scheme not in SCHEMES:
            raise ConfigError(f"value {shown(scheme)}; allowed: {SCHEMES}",
                              key="optimisation.scheme")
        names = sorted(getattr(model, "coefficients", {}))
        if not isinstance(model, MorisonModel) or names != sorted(_MORISON_TERMS):
            raise ConfigError(
                f"the optimiser's adjoint covers the four Morison terms only; the model "
                f"{getattr(model, 'name', model)!r} has terms {names}", key="model")
        self.model = model
        self.beta = float(beta)
        self.max_power = float(max_power)
        self.max_heave = float(max_heave)
        self.penalty_power = float(penalty_power)
        self.penalty_heave = float(penalty_heave)
        self.smoothing_pitch = float(smoothing_pitch)
        self.smoothing_heave = float(smoothing_heave)
        self.scheme = scheme
        self.compiled = bool(compiled)
        self.max_pitch = float(max_pitch)
        self.max_pitch_rate = float(max_pitch_rate)
        self.max_pitch_acceleration = float(max_pitch_acceleration)
        self.penalty_pitch = float(penalty_pitch)
        self.linear_modifier = linear_modifier
        self.sample_offsets = sample_offsets
        self._kernel_args: tuple | bool | None = False  # False: not looked up yet

    def without_penalties(self) -> FlappingProblem:
        """The same problem with the power, heave and pitch penalties set to zero (what J
        is made of besides them: thrust, power and smoothness)."""
        free = copy.copy(self)
        free.penalty_power = free.penalty_heave = free.penalty_pitch = 0.0
        free._kernel_args = False  # the compiled kernel's constants hold the penalties
        return free

    def _kernel(self, motion: DiscreteMotion) -> tuple | None:
        """The compiled kernel's constants if it can evaluate ``motion``, else None."""
        if not self.compiled:
            return None
        pa, ha = motion.pitch_acceleration, motion.heave_acceleration
        if (pa.ndim != 1 or np.ndim(motion.time_step) != 0 or np.iscomplexobj(pa)
                or np.iscomplexobj(ha) or np.iscomplexobj(motion.time_step)):
            return None
        if self._kernel_args is False:
            # the compiled (numba) kernel loads in about a second: only the compiled path needs it
            from mfflap.optimisation.adjoint_kernel import problem_constants

            self._kernel_args = problem_constants(self)
        return self._kernel_args  # type: ignore[return-value]

    # -- objective ---------------------------------------------------------------------------
    def stage_costs(self, motion: DiscreteMotion) -> np.ndarray:
        """L_j, shape (..., N). Complex-step safe."""
        state = motion.states(self.scheme)  # type: ignore[arg-type]
        thrust, power = thrust_and_power(self.model.loads(state), state)
        peak = power
        if self.sample_offsets is not None:
            self._check_offsets(motion.n_steps)
            thrust = thrust + self.sample_offsets.thrust
            peak = power + self.sample_offsets.peak_power
            power = power + self.sample_offsets.power
        excess_p = _positive_part(peak - self.max_power)
        excess_h = _positive_part(_abs(state.heave_position) - self.max_heave)
        return (-(1 - self.beta) * thrust + self.beta * power
                + 0.5 * self.penalty_power * excess_p**2 + 0.5 * self.penalty_heave * excess_h**2
                + self.pitch_envelope_cost(state))

    @property
    def pitch_limits(self) -> dict[str, float]:
        """The pitch envelope: state name -> limit (inf: none)."""
        return {"pitch_angle": self.max_pitch, "pitch_rate": self.max_pitch_rate,
                "pitch_acceleration": self.max_pitch_acceleration}

    def pitch_envelope_cost(self, state):
        """1/2 sigma_theta sum over the limited pitch states of the squared relative excess,
        shape (..., N). Complex-step safe."""
        out = 0.0
        for name, limit in self.pitch_limits.items():
            if np.isfinite(limit):
                excess = _positive_part(_abs(getattr(state, name)) - limit) / limit
                out = out + 0.5 * self.penalty_pitch * excess**2
        return out

    def smoothness(self, motion: DiscreteMotion):
        """J_s with the wrap term (acc_1 + acc_N), shape (...)."""
        return smoothness(motion, self.smoothing_pitch, self.smoothing_heave)

    def objective(self, motion: DiscreteMotion):
        """J = mean_j L_j + J_s (+ the linear modifier), shape (...)."""
        self._check_modifier(motion.n_steps)
        self._check_offsets(motion.n_steps)
        extra = 0.0 if self.linear_modifier is None else self.linear_modifier.value(motion)
        args = self._kernel(motion)
        if args is not None:
            # the compiled (numba) kernel loads in about a second: only the compiled path needs it
            from mfflap.optimisation.adjoint_kernel import objective_and_gradient

            return objective_and_gradient(
                np.ascontiguousarray(motion.pitch_acceleration, dtype=float),
                np.ascontiguousarray(motion.heave_acceleration, dtype=float),
                float(motion.time_step), self.scheme == "midpoint", False, *args,
                _NO_GRAD) + extra
        return self.stage_costs(motion).mean(axis=-1) + self.smoothness(motion) + extra

    def _check_modifier(self, n_steps: int) -> None:
        """Refuse motions of another N than the linear modifier's."""
        if self.linear_modifier is not None and self.linear_modifier.n_steps != n_steps:
            raise ConfigError(f"the objective's linear modifier is for N = "
                              f"{self.linear_modifier.n_steps} steps, the motion has {n_steps}",
                              key="linear_modifier")

    def _check_offsets(self, n_steps: int) -> None:
        """Refuse motions of another N than the sample offsets'."""
        if self.sample_offsets is not None and self.sample_offsets.n_steps != n_steps:
            raise ConfigError(f"the objective's sample offsets are for N = "
                              f"{self.sample_offsets.n_steps} steps, the motion has {n_steps}",
                              key="sample_offsets")

    # -- gradient ----------------------------------------------------------------------------
    def _local_partials(self, motion: DiscreteMotion,
                        trajectory: dict[str, np.ndarray] | None = None
                        ) -> dict[str, np.ndarray]:
        """dL_j/dz for z in pitch angle/rate/acc, heave position/velocity/acc (hydro rates)."""
        m = self.model
        st = motion.states(self.scheme, trajectory)  # type: ignore[arg-type]
        g, rho, u = m.geometry, m.fluid.density, m.stream.velocity
        c_ = m.coefficients
        pos = np.asarray(g.positions)
        lb, l2b = pos.mean(), (pos**2).mean()
        ka = c_["normal_added_mass"] * rho * g.volume_normal
        kd = 0.5 * rho * c_["normal_drag"] * g.area_normal / g.n_strips
        kt = c_["tangential_added_mass"] * rho * g.volume_tangential
        kdt = 0.5 * rho * c_["tangential_drag"] * g.area_tangential
        th, td, tdd = st.pitch_angle, st.pitch_rate, st.pitch_acceleration
        hp, hd, hdd = st.heave_position, st.heave_velocity, st.heave_acceleration
        s, c = np.sin(th), np.cos(th)
        an = hd * c + u * s
        adn = hdd * c - hd * td * s + u * td * c
        vt = hd * s - u * c
        avt = hdd * s + hd * td * c + u * td * s
        drag = next(t for t in m.terms if t.name == "normal_drag")
        q0, q1 = drag.strip_sums(an, td)  # closed-form strip sums, O(1) per step
        d0, d1, d2 = (2 * x for x in drag.strip_abs_sums(an, td))
        fn = -ka * (adn + tdd * lb) - kd * q0
        mo = -ka * (adn * lb + tdd * l2b) - kd * q1
        ft = -kt * avt - kdt * np.abs(vt) * vt
        zero = np.zeros_like(th)
        # derivatives of the intermediate quantities, per input
        d_an = {"th": -hd * s + u * c, "td": zero, "tdd": zero, "hd": c, "hdd": zero}
        d_adn = {"th": -hdd * s - hd * td * c - u * td * s, "td": -hd * s + u * c, "tdd": zero,
                 "hd": -td * s, "hdd": c}
        d_vt = {"th": an, "td": zero, "tdd": zero, "hd": s, "hdd": zero}
        d_avt = {"th": adn, "td": an, "tdd": zero, "hd": td * c, "hdd": s}
        power = -(fn * c + ft * s) * hd - mo * td
        if self.sample_offsets is not None:
            self._check_offsets(motion.n_steps)
            power = power + self.sample_offsets.peak_power
        dl_dp = self.beta + self.penalty_power * np.maximum(power - self.max_power, 0)
        dl_dt = -(1 - self.beta)
        out = {}
        for z in ("th", "td", "tdd", "hd", "hdd"):
            is_td = 1.0 if z == "td" else 0.0
            is_tdd = 1.0 if z == "tdd" else 0.0
            fn_z = -ka * (d_adn[z] + is_tdd * lb) - kd * (d0 * d_an[z] + d1 * is_td)
            mo_z = -ka * (d_adn[z] * lb + is_tdd * l2b) - kd * (d1 * d_an[z] + d2 * is_td)
            ft_z = -kt * d_avt[z] - kdt * 2 * np.abs(vt) * d_vt[z]
            t_z = fn_z * s - ft_z * c
            p_z = -(fn_z * c + ft_z * s) * hd - mo_z * td
            if z == "th":
                t_z = t_z + fn * c + ft * s
                p_z = p_z - (-fn * s + ft * c) * hd
            elif z == "hd":
                p_z = p_z - (fn * c + ft * s)
            elif z == "td":
                p_z = p_z - mo
            out[z] = dl_dt * t_z + dl_dp * p_z
        excess_h = np.maximum(np.abs(hp) - self.max_heave, 0)
        out["hp"] = self.penalty_heave * excess_h * np.sign(hp)
        for z, x, limit in (("th", th, self.max_pitch), ("td", td, self.max_pitch_rate),
                            ("tdd", tdd, self.max_pitch_acceleration)):
            if np.isfinite(limit):
                excess = np.maximum(np.abs(x) - limit, 0)
                out[z] = out[z] + self.penalty_pitch * excess / limit**2 * np.sign(x)
        return out

    def value_and_gradient(self, motion: DiscreteMotion) -> tuple[float, np.ndarray]:
        """J and the flat gradient [d/d pitch (N), d/d heave (N), d/d dt] of one motion, in
        one pass when the compiled kernel applies (what the optimisers call)."""
        args = self._kernel(motion)
        if args is None:
            return float(self.objective(motion)), self.gradient(motion).flat()

        self._check_modifier(motion.n_steps)
        self._check_offsets(motion.n_steps)
        out = np.empty(2 * motion.n_steps + 1)
        value = objective_and_gradient(
            np.ascontiguousarray(motion.pitch_acceleration, dtype=float),
            np.ascontiguousarray(motion.heave_acceleration, dtype=float),
            float(motion.time_step), self.scheme == "midpoint", True, *args, out)
        if self.linear_modifier is not None:
            value += float(self.linear_modifier.value(motion))
            out += self.linear_modifier.gradient
        return value, out

    def packed_value_and_gradient(self, z: np.ndarray, want_gradient: bool = True
                                  ) -> tuple[float, np.ndarray | None]:
        """J and its flat gradient at the packed controls z = [pitch (N), heave (N), dt].

        The optimisers' entry point: with the compiled kernel it skips building a
        :class:`DiscreteMotion` (whose input checks cost more than the kernel at N = 50).
        """
        z = np.asarray(z, dtype=float)
        n = (z.size - 1) // 2
        motion = None
        if self._kernel_args is False or not np.isfinite(z).all() or z[-1] <= 0 or n < 2:
            motion = DiscreteMotion(z[:n], z[n:2 * n], float(z[-1]))  # validates, or raises
        args = self._kernel(motion) if motion is not None else (
            self._kernel_args if self.compiled else None)
        if args is None:
            motion = motion or DiscreteMotion(z[:n], z[n:2 * n], float(z[-1]))
            if not want_gradient:
                return float(self.objective(motion)), None
            return float(self.objective(motion)), self.adjoint_gradient(motion).flat()

        self._check_modifier(n)
        self._check_offsets(n)
        out = np.empty(2 * n + 1) if want_gradient else _NO_GRAD
        value = objective_and_gradient(np.ascontiguousarray(z[:n]),
                                       np.ascontiguousarray(z[n:2 * n]), float(z[-1]),
                                       self.scheme == "midpoint", want_gradient, *args, out)
        if self.linear_modifier is not None:
            value += self.linear_modifier.packed_value(z)
            if want_gradient:
                out += self.linear_modifier.gradient
        return value, (out if want_gradient else None)

    def gradient(self, motion: DiscreteMotion) -> Gradient:
        """Exact gradient of :meth:`objective` by the discrete adjoint, O(N)."""
        n = motion.n_steps
        if self._kernel(motion) is not None:
            _, flat = self.value_and_gradient(motion)
            return Gradient(flat[:n], flat[n:2 * n], np.asarray(flat[2 * n]))
        return self.adjoint_gradient(motion)

    def adjoint_gradient(self, motion: DiscreteMotion) -> Gradient:
        """The array implementation of the adjoint (any batch shape; the reference)."""
        n = motion.n_steps
        tr = motion.trajectory()
        partials = {k: v / n for k, v in self._local_partials(motion, tr).items()}
        chained = chain_state_partials(motion, partials, self.scheme, tr)
        smooth = smoothness_gradient(motion, self.smoothing_pitch, self.smoothing_heave)
        grads = {"pitch": chained.pitch_acceleration + smooth["pitch"],
                 "heave": chained.heave_acceleration + smooth["heave"]}
        grad_dt = chained.time_step
        if self.linear_modifier is not None:
            self._check_modifier(n)
            g = self.linear_modifier.gradient
            grads = {"pitch": grads["pitch"] + g[:n], "heave": grads["heave"] + g[n:2 * n]}
            grad_dt = grad_dt + g[-1]
        return Gradient(grads["pitch"], grads["heave"], grad_dt)
