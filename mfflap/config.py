"""Case files: TOML validated at load into frozen dataclasses.

A case file has these tables (all optional but ``[study]``; missing ones take the paper's
values)::

    [study]           name, description
    [fluid]           density, kinematic_viscosity
    [plate]           chord, span, thickness, pivot_chord_fraction
    [flow]            velocity
    [model]           n_strips, scheme, and [model.coefficients] (the four Morison values)
    [vortex]          the discrete-vortex model: critical_lesp, core_radius_chords,
                      chord_points, wake_chords
    [motion]          the motion evaluated by ``mfflap evaluate``
    [discretisation]  n_steps (N per half cycle)
    [optimisation]    beta values, limits, penalties, smoothing, period bounds, and the
                      coefficients ``mfflap run`` optimises with
    [identification]  the Table 1 grid and the pitch ramp rate
    [harmonic_set]    the second identification set: harmonic motions at large pitch
    [cfd]             how OpenFOAM runs are set up and kept (mesh, set-up, solver, ranks)
    [backtest]        how ``mfflap run`` and ``mfflap backtest`` check optima in CFD
    [rounds]          CFD in the loop (studies of the method)

Any key can be set from the command line too (``--set table.key=value``,
:func:`apply_settings`), checked like the file.

Every error names the file, the key, the value and the allowed range.
"""

from __future__ import annotations

import copy
import dataclasses
import math
import tomllib
import warnings
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from mfflap.errors import ConfigError, shown
from mfflap.hydro.morison import MorisonModel
from mfflap.kinematics.continuous import UPRIGHT_PITCH, HarmonicMotion, RampHarmonicMotion
from mfflap.parameters import (
    Fluid,
    FreeStream,
    MorisonCoefficients,
    Plate,
    StripSettings,
    VortexModelSettings,
)
from mfflap.study_tables import BacktestSettings, CfdSettings, HarmonicSet, RoundsSettings
from mfflap.toml_io import dumps, read_toml
from mfflap.validation import bounded, check_fields, from_mapping


@dataclass(frozen=True)
class StudyInfo:
    """Name and description of a study.

    The name becomes file and folder names (``<name>_run``), so it is one plain name: at
    most 100 printable characters, no path separator, not beginning with a dot.

    Examples
    --------
    >>> StudyInfo("paper2026").name
    'paper2026'
    >>> StudyInfo("../x")  # doctest: +IGNORE_EXCEPTION_DETAIL
    Traceback (most recent call last):
    mfflap.errors.ConfigError: study.name: value '../x' cannot name a file
    """

    name: str = "study"
    description: str = ""

    def __post_init__(self) -> None:
        name = self.name
        if not isinstance(name, str):
            raise ConfigError(f"value {str(name)[:60]!r} is not text", key="study.name")
        if (not name or len(name) > 100 or not name.isprintable() or name.startswith(".")
                or any(sep in name for sep in ("/", "\\"))):
            raise ConfigError(
                f"value {name[:60]!r}{'...' if len(name) > 60 else ''} cannot name a file: "
                "give 1-100 printable characters without / or \\, not beginning with a dot",
                key="study.name")


@dataclass(frozen=True)
class ModelSettings:
    """Strip model settings (see :class:`~mfflap.parameters.StripSettings`)."""

    n_strips: int = bounded(20, low=1, high=100000, unit="1", doc="chordwise strips")
    scheme: str = bounded("paper", choices=("paper", "midpoint"), unit="",
                          doc="discrete evaluation scheme")
    added_mass_volume_normal: float | None = bounded(None, low=0.0, unit="m^3")
    added_mass_volume_tangential: float | None = bounded(None, low=0.0, unit="m^3")
    drag_area_normal: float | None = bounded(None, low=0.0, unit="m^2")
    drag_area_tangential: float | None = bounded(None, low=0.0, unit="m^2")

    def __post_init__(self) -> None:
        check_fields(self, prefix="model.")

    def strip_settings(self) -> StripSettings:
        """The strip settings of the model."""
        return StripSettings(
            n_strips=self.n_strips,
            added_mass_volume_normal=self.added_mass_volume_normal,
            added_mass_volume_tangential=self.added_mass_volume_tangential,
            drag_area_normal=self.drag_area_normal,
            drag_area_tangential=self.drag_area_tangential,
        )


def _rate_under_upright(rate_deg: float, peak: float) -> float:
    """The pitch ramp rate, deg/s, at which a ramp that reaches ``peak`` rad at ``rate_deg``
    reaches :data:`UPRIGHT_PITCH` instead (the pitch is linear in the rate), rounded down to
    1e-3 deg/s: any rate below it stays under."""
    return math.floor(rate_deg * UPRIGHT_PITCH / peak * 1e3) / 1e3


@dataclass(frozen=True)
class MotionSpec:
    """A continuous motion given in engineering units (degrees)."""

    kind: str = bounded("harmonic", choices=("harmonic", "ramp_harmonic"), unit="")
    frequency: float = bounded(1.0, low=1.0e-3, high=100.0, unit="Hz")
    heave_amplitude: float = bounded(0.3, low=0.0, high=10.0, unit="m")
    pitch_amplitude_deg: float = bounded(20.0, low=0.0, high=90.0, high_open=True, unit="deg")
    pitch_ramp_rate_deg: float = bounded(10.0, low=0.0, high=1000.0, unit="deg/s",
                                         doc="theta_kamp of the identification motion")
    phase_deg: float = bounded(90.0, low=-360.0, high=360.0, unit="deg",
                               doc="phase by which heave leads pitch")

    def __post_init__(self) -> None:
        check_fields(self, prefix="motion.")

    def build(self) -> HarmonicMotion | RampHarmonicMotion:
        """The motion object."""
        phase = math.radians(self.phase_deg)
        if self.kind == "harmonic":
            return HarmonicMotion(self.frequency, self.heave_amplitude,
                                  math.radians(self.pitch_amplitude_deg), phase)
        return RampHarmonicMotion(self.frequency, self.heave_amplitude,
                                  math.radians(self.pitch_ramp_rate_deg), phase)

    def check_upright(self, end_time: float, over: str, source: str | None = None) -> None:
        """Refuse a ramp motion whose pitch reaches 90 deg (across the stream) by
        ``end_time``; a harmonic motion's amplitude is already bounded below it.

        Parameters
        ----------
        end_time : float, s
        over : str
            What sets ``end_time``, for the message (e.g. ``"--cycles 3"``).
        source : str, optional
            The case file, for the message.

        Raises
        ------
        ConfigError
            Naming ``motion.pitch_ramp_rate_deg``, the pitch reached, and the rate that
            keeps the run under 90 deg.
        """
        motion = self.build()
        if not isinstance(motion, RampHarmonicMotion) or self.pitch_ramp_rate_deg == 0.0:
            return
        pitch, time = motion.largest_pitch(end_time)
        if abs(pitch) >= UPRIGHT_PITCH:
            allowed = _rate_under_upright(self.pitch_ramp_rate_deg, abs(pitch))
            raise ConfigError(
                f"value {self.pitch_ramp_rate_deg} deg/s turns the plate past "
                f"{math.degrees(UPRIGHT_PITCH):g} deg: the pitch reaches "
                f"{math.degrees(pitch):.4g} deg at t = {time:.4g} s of the {end_time:g} s "
                f"run ({over}); below {allowed:g} deg/s, or a shorter run, keeps it under it",
                source=source, key="motion.pitch_ramp_rate_deg",
            )


@dataclass(frozen=True)
class Discretisation:
    """Time discretisation of the half cycle."""

    n_steps: int = bounded(50, low=2, high=10_000_000, unit="1", doc="N, steps per half cycle")

    def __post_init__(self) -> None:
        check_fields(self, prefix="discretisation.")


@dataclass(frozen=True)
class OptimisationSettings:
    """The penalised optimisation problem of the paper (docs/theory.md)."""

    betas: tuple[float, ...] = bounded((0.0, 0.5, 1.0), low=0.0, high=1.0, unit="1", unique=True,
                                       doc="thrust/power weights beta")
    max_power: float = bounded(50.0, low=0.0, low_open=True, unit="W", doc="P_max")
    max_heave: float = bounded(0.5, low=0.0, low_open=True, unit="m", doc="h_max")
    penalty_power: float = bounded(10.0, low=0.0, unit="1/W", doc="sigma_P")
    penalty_heave: float = bounded(1.0e4, low=0.0, unit="N/m^2", doc="sigma_h")
    # 1e-6 / 1e-4 let the optimiser exploit the paper scheme's energy error (a 4.5 Hz
    # optimum with a 27 % energy residual); 1e-4 / 1e-2 do not (docs/theory.md)
    smoothing_pitch: float = bounded(1.0e-4, low=0.0, unit="N s^4", doc="epsilon_theta")
    smoothing_heave: float = bounded(1.0e-2, low=0.0, unit="N s^4/m^2", doc="epsilon_h")
    n_steps: int = bounded(50, low=2, high=1_000_000, unit="1", doc="N per half cycle")
    min_period: float = bounded(0.2, low=0.0, low_open=True, unit="s")
    max_period: float = bounded(20.0, low=0.0, low_open=True, unit="s")
    scheme: str = bounded("paper", choices=("paper", "midpoint"), unit="")
    # the pitch envelope (mfflap; left out: no limit), e.g. what the identification data
    # reach, so that the optimum stays where the coefficients rest on CFD
    max_pitch_deg: float | None = bounded(None, low=0.0, low_open=True, unit="deg",
                                          doc="theta_max")
    max_pitch_rate: float | None = bounded(None, low=0.0, low_open=True, unit="rad/s",
                                           doc="thetadot_max")
    max_pitch_acceleration: float | None = bounded(None, low=0.0, low_open=True,
                                                   unit="rad/s^2", doc="thetaddot_max")
    penalty_pitch: float = bounded(1.0e4, low=0.0, unit="N", doc="sigma_theta, per squared "
                                   "relative excess over the pitch envelope")
    # mfflap: "fixed" keeps the pitch's first harmonic at the phase of sin(2 pi t / T), so
    # that round-off cannot move a periodic optimum along its cycle (mfflap.optimisation.phase)
    phase: str = bounded("fixed", choices=("fixed", "free"), unit="",
                         doc="the phase of the optimised motions: fixed (the pitch's first "
                             "harmonic in phase with sin(2 pi t/T)) or free (the paper's "
                             "problem, where round-off can move a periodic optimum along "
                             "its cycle)")
    coefficients: str = bounded("uniform", choices=("uniform", "low", "high", "case"), unit="",
                                doc="the coefficients `mfflap run` optimises with: those it "
                                    "identifies with this frequency weighting, or the case "
                                    "file's [model.coefficients] (case)")
    starts: int = bounded(3, low=1, high=100, unit="1", doc="multi-start points per beta")
    gain_table: bool = bounded(True, choices=(True, False), unit="",
                               doc="tabulate the beta = 0 gain against N and the smoothing "
                                   "weights")
    ipopt: bool = bounded(True, choices=(True, False), unit="",
                          doc="compare each optimum with IPOPT's hard-constrained problem")
    within_data: bool = bounded(False, choices=(True, False), unit="",
                                doc="bound the optimisation by what the identification cases "
                                    "reach (pitch amplitude, rate and acceleration, frequency, "
                                    "heave), each the tighter of this table's and the data's")
    # an actuator's bandwidth: the highest harmonic of the flapping frequency a delivered
    # motion may contain (mfflap.optimisation.bandwidth); the vortex polish holds it
    bandwidth_harmonics: int = bounded(11, low=1, high=100_000, unit="1",
                                       doc="the highest harmonic of the flapping frequency "
                                           "a polished motion may contain (an actuator's "
                                           "bandwidth)")

    def __post_init__(self) -> None:
        check_fields(self, prefix="optimisation.")
        if self.min_period >= self.max_period:
            raise ConfigError(
                f"min_period {self.min_period} s must be smaller than max_period "
                f"{self.max_period} s: the bounds exclude every period",
                key="optimisation.min_period",
            )

    @property
    def fix_phase(self) -> bool:
        """Whether the optimisers keep the optimised motions' phase (``phase = "fixed"``,
        :mod:`mfflap.optimisation.phase`)."""
        return self.phase == "fixed"

    def pitch_envelope(self) -> dict[str, float]:
        """The FlappingProblem keywords of the pitch envelope's limits (rad, rad/s,
        rad/s^2; inf where no limit is given)."""
        return {"max_pitch": (np.inf if self.max_pitch_deg is None
                              else float(np.radians(self.max_pitch_deg))),
                "max_pitch_rate": (np.inf if self.max_pitch_rate is None
                                   else float(self.max_pitch_rate)),
                "max_pitch_acceleration": (np.inf if self.max_pitch_acceleration is None
                                           else float(self.max_pitch_acceleration))}


#: the decimals of each grid axis that a campaign case's id keeps
#: (:attr:`mfflap.campaign.cases.CfdCase.case_id`, e.g. ``f1p000_h0p300_phi090p0``): two
#: values of an axis equal to these decimals would name one case
CASE_ID_DECIMALS = {"frequencies": 3, "heave_amplitudes": 3, "phases_deg": 1}


@dataclass(frozen=True)
class IdentificationGrid:
    """The motion grid of the identification campaign (the paper's Table 1 by default)."""

    frequencies: tuple[float, ...] = bounded((0.1, 0.2, 0.5, 1.0, 2.0), low=0.0, low_open=True,
                                             high=100.0, unit="Hz", unique=True)
    heave_amplitudes: tuple[float, ...] = bounded((0.1, 0.2, 0.3, 0.4, 0.5), low=0.0,
                                                  high=10.0, unit="m", unique=True)
    phases_deg: tuple[float, ...] = bounded((45.0, 67.5, 90.0, 112.5, 135.0), low=-360.0,
                                            high=360.0, unit="deg", unique=True,
                                            period=360.0)
    pitch_ramp_rate_deg: float = bounded(10.0, low=0.0, high=1000.0, unit="deg/s",
                                         doc="theta_kamp")
    n_cycles: float = bounded(3.0, low=0.5, high=1000.0, unit="1", doc="cycles simulated")
    max_duration: float = bounded(30.0, low=0.1, high=1.0e5, unit="s",
                                  doc="cap on simulated time per case (n_cycles periods at "
                                      "0.1 Hz by default)")
    max_ramp_pitch_deg: float = bounded(
        60.0, low=0.0, low_open=True, high=89.0, unit="deg",
        doc="largest pitch amplitude theta_kamp t reaches at the end of a case: a case that "
            "runs longer than max_ramp_pitch_deg / theta_kamp ramps at that rate instead, so "
            "that every frequency runs its n_cycles periods over the same range of pitch")
    discard_time: float = bounded(0.75, low=0.0, high=1.0e5, unit="s",
                                  doc="start-up transient left out of the fit")
    frequency_weights: tuple[float, ...] | None = bounded(None, low=0.0, unit="1",
                                                          doc="one weight per frequency")
    residual_scaling: str = bounded(
        "auto", choices=("auto", "grid", "case"), unit="",
        doc="residuals over each component's RMS across every case (grid), over its "
            "range in each case (case: the fit minimises the mean square NRMSE), or the one "
            "of the two that the model's errors ask for (auto)")

    def __post_init__(self) -> None:
        check_fields(self, prefix="identification.")
        self._check_case_ids()
        short = [f for f in self.frequencies if self.case_duration(f) <= self.case_ramp_time(f)]
        if short:
            f = short[0]
            raise ConfigError(
                f"value {self.max_duration} s leaves the f = {f:g} Hz cases no time after "
                f"their {self.case_ramp_time(f):g} s start-up ramp (a quarter period, at most "
                "0.5 s): the motion would never reach its amplitude", key="identification."
                "max_duration")
        w = self.frequency_weights
        if w is not None:
            if len(w) != len(self.frequencies) or sum(w) <= 0:
                raise ConfigError(
                    f"value {list(w)!r}: needs one weight >= 0 per frequency "
                    f"({len(self.frequencies)}) and a positive sum",
                    key="identification.frequency_weights",
                )

    def case_duration(self, frequency: float) -> float:
        """Simulated time of the grid's case at ``frequency``, s: n_cycles periods capped
        at max_duration."""
        return min(self.n_cycles / frequency, self.max_duration)

    def case_pitch_ramp_rate_deg(self, frequency: float) -> float:
        """theta_kamp of the grid's case at ``frequency``, deg/s: ``pitch_ramp_rate_deg``,
        or the slower rate at which the ramp reaches ``max_ramp_pitch_deg`` at the end of
        the case.

        Examples
        --------
        >>> grid = IdentificationGrid()
        >>> grid.case_pitch_ramp_rate_deg(1.0), grid.case_pitch_ramp_rate_deg(0.1)
        (10.0, 2.0)
        """
        return min(self.pitch_ramp_rate_deg,
                   self.max_ramp_pitch_deg / self.case_duration(frequency))

    @staticmethod
    def case_ramp_time(frequency: float) -> float:
        """C^2 start-up ramp of the grid's case at ``frequency``, s: a quarter period, at
        most 0.5 s."""
        return min(0.25 / frequency, 0.5)

    def _check_case_ids(self) -> None:
        """Refuse two values of an axis that agree to the decimals the case ids keep: their
        cases would share an id, and so a record and a case folder."""
        for key, decimals in CASE_ID_DECIMALS.items():
            values = getattr(self, key)
            shown = [f"{v:.{decimals}f}" for v in values]
            for j, text in enumerate(shown):
                if text in shown[:j]:
                    i = shown.index(text)
                    raise ConfigError(
                        f"values {values[i]!r} and {values[j]!r} ({key}[{i}] and [{j}]) are "
                        f"one value to {decimals} decimal{'s' if decimals > 1 else ''}, as a "
                        f"campaign case's id keeps them ({text}): their cases would share an "
                        "id and a record; give values that differ there",
                        key=f"identification.{key}[{j}]")


@dataclass(frozen=True)
class CaseConfig:
    """A whole case file."""

    study: StudyInfo = field(default_factory=StudyInfo)
    fluid: Fluid = field(default_factory=Fluid)
    plate: Plate = field(default_factory=Plate)
    flow: FreeStream = field(default_factory=FreeStream)
    model: ModelSettings = field(default_factory=ModelSettings)
    coefficients: MorisonCoefficients = field(default_factory=MorisonCoefficients)
    vortex: VortexModelSettings = field(default_factory=VortexModelSettings)
    motion: MotionSpec = field(default_factory=MotionSpec)
    discretisation: Discretisation = field(default_factory=Discretisation)
    optimisation: OptimisationSettings = field(default_factory=OptimisationSettings)
    identification: IdentificationGrid = field(default_factory=IdentificationGrid)
    harmonic_set: HarmonicSet = field(default_factory=HarmonicSet)
    cfd: CfdSettings = field(default_factory=CfdSettings)
    backtest: BacktestSettings = field(default_factory=BacktestSettings)
    rounds: RoundsSettings = field(default_factory=RoundsSettings)
    source: str | None = field(default=None, compare=False)

    def __post_init__(self) -> None:
        r = self.rounds
        if r.count > 1 and not r.correct_outputs and self.optimisation.coefficients == "case":
            raise ConfigError(
                "rounds.count > 1 refits the model on each round's back-tests, which only "
                "identified coefficients take up; with optimisation.coefficients = \"case\" "
                "every round would optimise the same motions: give a weighting (uniform, low, "
                "high) or rounds.correct_outputs = true", source=self.source,
                key="rounds.count")

    def morison_model(self):
        """The Morison model this case describes."""
        return MorisonModel(self.plate, self.fluid, self.flow, self.coefficients,
                            self.model.strip_settings())

    def to_dict(self) -> dict[str, Any]:
        """Nested plain dict (the TOML tables)."""
        out = {}
        for f in dataclasses.fields(self):
            if f.name == "source":
                continue
            section = dataclasses.asdict(getattr(self, f.name))
            out[f.name] = {k: list(v) if isinstance(v, tuple) else v for k, v in section.items()}
        out["model"]["coefficients"] = out.pop("coefficients")
        return out

    def to_toml(self) -> str:
        """TOML text that :func:`load_case` reads back into an equal object."""
        return dumps(self.to_dict())


_SECTIONS: dict[str, type] = {
    "study": StudyInfo,
    "fluid": Fluid,
    "plate": Plate,
    "flow": FreeStream,
    "model": ModelSettings,
    "vortex": VortexModelSettings,
    "motion": MotionSpec,
    "discretisation": Discretisation,
    "optimisation": OptimisationSettings,
    "identification": IdentificationGrid,
    "harmonic_set": HarmonicSet,
    "cfd": CfdSettings,
    "backtest": BacktestSettings,
    "rounds": RoundsSettings,
}


def _build(cls: type, mapping: Any, source: str | None, key: str):
    try:
        return from_mapping(cls, mapping, source=source, prefix=key + ".")
    except ConfigError as exc:
        if exc.source is None:
            raise ConfigError(str(exc), source=source) from exc
        raise


def case_from_dict(data: dict[str, Any], source: str | None = None) -> CaseConfig:
    """Validate a parsed case mapping.

    Raises
    ------
    ConfigError
        Naming the file (``source``), the key, the value and the allowed range.
    """
    unknown = sorted(set(data) - set(_SECTIONS))
    if unknown:
        raise ConfigError(f"unknown table [{unknown[0]}]; allowed: {', '.join(_SECTIONS)}",
                          source=source, key=unknown[0])
    parts: dict[str, Any] = {}
    for name, cls in _SECTIONS.items():
        mapping = dict(data.get(name, {})) if isinstance(data.get(name, {}), dict) else data[name]
        if name == "model" and isinstance(mapping, dict):
            coeffs = mapping.pop("coefficients", {})
            parts["coefficients"] = _build(MorisonCoefficients, coeffs, source,
                                           "model.coefficients")
        parts[name] = _build(cls, mapping, source, name)
    return CaseConfig(**parts, source=source)


#: the keys a [motion] table must give, by kind, and those only the other kind reads
MOTION_KEYS = {"harmonic": ("frequency", "heave_amplitude", "pitch_amplitude_deg",
                            "phase_deg"),
               "ramp_harmonic": ("frequency", "heave_amplitude", "pitch_ramp_rate_deg",
                                 "phase_deg")}


class ConfigWarning(UserWarning):
    """A case file key that the rest of the file makes unused."""


def _check_motion_keys(table: dict[str, Any], kind: str, source: str | None) -> None:
    """Refuse a [motion] table that leaves out a key its kind needs (the default would be
    run as if given); warn of a key its kind does not read, naming it."""
    missing = [k for k in MOTION_KEYS[kind] if k not in table]
    if missing:
        raise ConfigError(f"a {kind} motion needs {', '.join(MOTION_KEYS[kind])}; "
                          f"{', '.join(missing)} missing", source=source,
                          key=f"motion.{missing[0]}")
    unused = sorted(k for other, keys in MOTION_KEYS.items() if other != kind
                    for k in keys if k in table and k not in MOTION_KEYS[kind])
    for key in unused:
        where = f"{source}: " if source else ""
        warnings.warn(ConfigWarning(f"{where}motion.{key} is not read by a {kind} motion"),
                      stacklevel=3)


def _setting_value(text: str) -> Any:
    """A ``--set`` value as TOML reads it (``3``, ``1e-4``, ``true``, ``[0, 0.5]``,
    ``"case"``); text that is not a TOML value is a string (``case``)."""
    try:
        return tomllib.loads(f"value = {text}")["value"]
    except tomllib.TOMLDecodeError:
        return text


def apply_settings(data: dict[str, Any], settings: Sequence[str]) -> dict[str, Any]:
    """The case mapping ``data`` with each ``table.key=value`` of ``settings`` set in it.

    Parameters
    ----------
    data
        A parsed case file (left unchanged).
    settings
        ``"table.key=value"`` texts; a value is read as TOML, and text that is not a TOML
        value as a string. ``model.coefficients.normal_drag=3`` reaches the nested table.

    Returns
    -------
    dict
        A new mapping, for :func:`case_from_dict` to check like the file.

    Raises
    ------
    ConfigError
        A setting without ``=`` or without a table and key, naming it.

    Examples
    --------
    >>> apply_settings({"rounds": {"count": 2}}, ["rounds.count=3", "optimisation.phase=free"])
    {'rounds': {'count': 3}, 'optimisation': {'phase': 'free'}}
    """
    out = copy.deepcopy(data)
    for text in settings:
        dotted, sep, value = text.partition("=")
        parts = dotted.strip().split(".")
        if not sep or len(parts) < 2 or not all(parts):
            raise ConfigError(f"{shown(text)} is not table.key=value (e.g. "
                              "optimisation.coefficients=case)", source="--set")
        table = out
        for name in parts[:-1]:
            inner = table.setdefault(name, {})
            if not isinstance(inner, dict):
                raise ConfigError(f"{'.'.join(parts[:-1])} is a value, not a table",
                                  source="--set", key=dotted.strip())
            table = inner
        table[parts[-1]] = _setting_value(value.strip())
    return out


def load_case(path: str | Path, settings: Sequence[str] = ()) -> CaseConfig:
    """Read and validate a TOML case file, with command-line settings applied.

    Beyond the ranges of each key, a [motion] table must give every key its kind reads
    (:data:`MOTION_KEYS`), and a key only the other kind reads is warned of
    (:class:`ConfigWarning`).

    Parameters
    ----------
    path
        The case file.
    settings
        ``table.key=value`` texts that override the file's keys (:func:`apply_settings`).

    Raises
    ------
    ConfigError
        Naming the file (with ``--set`` when a setting is at fault), the key, the value and
        what is allowed.

    Examples
    --------
    >>> import pathlib, tempfile
    >>> case = pathlib.Path(tempfile.mkdtemp()) / "case.toml"
    >>> _ = case.write_text('[study]\\nname = "demo"\\n')
    >>> load_case(case, ["optimisation.coefficients=case"]).optimisation.coefficients
    'case'
    """
    data = read_toml(path)
    if settings:
        data = apply_settings(data, settings)
        source = settings_source(path, settings)
    else:
        source = str(path)
    config = case_from_dict(data, source=source)
    if isinstance(data.get("motion"), dict):
        _check_motion_keys(data["motion"], config.motion.kind, source)
    return config


#: the most characters of one ``--set`` setting that a case file's name in an error repeats
SETTING_CHARS = 40


def settings_source(source: str | Path, settings: Sequence[str]) -> str:
    """Name a case file with the ``--set`` settings applied to it, each setting cut to
    :data:`SETTING_CHARS` characters so that an error (which repeats the offending value
    after this) stays one readable line.

    Examples
    --------
    >>> settings_source("case.toml", ["cfd.procs=2"])
    'case.toml with --set cfd.procs=2'
    >>> len(settings_source("case.toml", ["cfd.mesh=" + "z" * 5000])) < 100
    True
    """
    cut = [item if len(item) <= SETTING_CHARS else item[:SETTING_CHARS] + "..."
           for item in settings]
    return f"{source} with --set {' '.join(cut)}"


def loads_case(text: str, source: str = "<string>", settings: Sequence[str] = ()
               ) -> CaseConfig:
    """Validate case TOML given as text (e.g. the copy stored in a results file), with
    command-line ``settings`` applied as :func:`load_case` applies them.

    Examples
    --------
    >>> loads_case('[study]\\nname = "demo"\\n', settings=["cfd.procs=2"]).cfd.procs
    2
    """
    return _case_from_data(_parsed(text, source), source, settings)


def _parsed(text: str, source: str) -> dict[str, Any]:
    """Case TOML as a dict, a syntax error naming ``source``."""
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(f"TOML syntax error: {exc}", source=source) from exc


def _case_from_data(data: dict[str, Any], source: str, settings: Sequence[str]) -> CaseConfig:
    """The case of parsed TOML with command-line ``settings`` applied."""
    if settings:
        data = apply_settings(data, settings)
        source = settings_source(source, settings)
    return case_from_dict(data, source=source)


#: the spellings of [model.coefficients] keys that a case stored in a results file may hold
#: besides the model's term names (the ones a case file takes)
STORED_COEFFICIENT_SPELLINGS = {"drag_normal": "normal_drag",
                                "drag_tangential": "tangential_drag",
                                "added_mass_normal": "normal_added_mass",
                                "added_mass_tangential": "tangential_added_mass"}


def stored_case(text: str, source: str, settings: Sequence[str] = ()) -> CaseConfig:
    """The case stored beside a results file's numbers (its ``/inputs``), read as
    :func:`loads_case` reads a case, with the coefficient spellings of
    :data:`STORED_COEFFICIENT_SPELLINGS` taken as the term names they stand for, so that
    every results file mfflap wrote reads back.

    Examples
    --------
    >>> stored_case('[model.coefficients]\\ndrag_normal = 3.0\\n', "x.h5:/inputs"
    ...             ).coefficients.normal_drag
    3.0
    """
    data = _parsed(text, source)
    coefficients = data.get("model", {}).get("coefficients")
    if isinstance(coefficients, dict):
        for spelled, name in STORED_COEFFICIENT_SPELLINGS.items():
            if spelled in coefficients and name not in coefficients:
                coefficients[name] = coefficients.pop(spelled)
    return _case_from_data(data, source, settings)


def degrees(values) -> np.ndarray:
    """Convenience: degrees to radians as an array."""
    return np.deg2rad(np.asarray(values, dtype=float))
