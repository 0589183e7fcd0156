"""The case-file tables of CFD runs, the second identification set, back-tests and CFD in
the loop.

``[cfd]`` says how every OpenFOAM run of a case is set up and kept (mesh, set-up, solver
details, ranks, time limit, retries, record precision), for every command that runs or
writes one; ``[harmonic_set]`` is the second identification set, harmonic motions at the
large pitch and fast pitching of optimised motions (``mfflap campaign run --cases
harmonic``); ``[backtest]`` says how ``mfflap run`` and ``mfflap backtest`` check optima in
CFD; ``[rounds]`` holds the settings that only studies of the method use (rounds of CFD in
the loop, the output correction, the trust region, first-order corrections, CFD's
repeatability). Each table refuses a combination that cannot run, naming the key, so that
what a case file says is what runs.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass, fields

from mfflap.errors import ConfigError
from mfflap.validation import bounded, check_fields

#: the largest trust-region radius, as a fraction of the centre motion's accelerations and
#: time step
MAX_TRUST_RADIUS = 2.0

#: the [rounds] keys that act from round 2 on: given for one round, they are refused
LATER_ROUNDS_KEYS = ("refit", "correct_outputs", "trust_radius", "first_order",
                     "cfd_repeatability")


#: the plate's wall conditions a run can have (their templates:
#: :data:`mfflap.cfd.openfoam.writer.WALL_TREATMENTS`)
WALL_TREATMENT_NAMES = ("log_law", "all_y_plus")
#: where the mesh moves: with the plate (inertial) or not at all (the plate's frame)
FRAME_NAMES = ("inertial", "plate")
#: far-field conditions of the outer boundary
FAR_FIELD_NAMES = ("freestream", "inletOutlet")
#: linear solvers of the pressure equation
PRESSURE_SOLVER_NAMES = ("PCG", "GAMG")
#: convection schemes of U
VELOCITY_CONVECTION_NAMES = ("linearUpwind", "LUST")
#: convection schemes of k and epsilon
TURBULENCE_CONVECTION_NAMES = ("limitedLinear", "upwind")

#: the [cfd] keys that override a set-up's solver settings, with the
#: :class:`~mfflap.cfd.openfoam.writer.SolverSettings` field each sets
SOLVER_KEYS = {"wall_treatment": "wall_treatment", "frame": "frame",
               "far_field": "far_field", "pressure_solver": "pressure_solver",
               "velocity_convection": "velocity_convection",
               "turbulence_convection": "turbulence_convection",
               "max_courant": "max_courant", "outer_correctors": "n_outer_correctors",
               "correctors": "n_correctors"}


@dataclass(frozen=True)
class CfdSettings:
    """How a case's OpenFOAM runs are set up and kept: ``mfflap cfd write``, ``cfd run``,
    ``cfd convergence``, ``cfd linear-check``, ``campaign run``, ``backtest --live`` and
    ``run --live`` read it.

    ``setup`` names a mesh with the solver settings it was measured with
    (``cfd_templates/openfoam/setups.toml``); ``mesh`` puts those settings on another mesh;
    the solver keys left out keep the set-up's values (or the defaults without one).

    Examples
    --------
    >>> CfdSettings().retries_from_start, CfdSettings().single_precision
    (True, True)
    >>> CfdSettings(setup="table1", max_courant=2.0).solver_overrides()
    {'max_courant': 2.0}
    >>> CfdSettings(frame="plate").solver_overrides()  # the plate's frame needs inletOutlet
    {'frame': 'plate', 'far_field': 'inletOutlet'}
    >>> CfdSettings(far_field="outlet")  # doctest: +IGNORE_EXCEPTION_DETAIL
    Traceback (most recent call last):
    mfflap.errors.ConfigError: cfd.far_field: value 'outlet' is not allowed
    """

    setup: str | None = bounded("table1", unit="",
                                doc="a named set-up of cfd_templates/openfoam/setups.toml "
                                    "(table1: the one the shipped identification records "
                                    "ran on, so that a back-test is run as the data the "
                                    "model was fitted to)")
    mesh: str | None = bounded(None, unit="",
                               doc="a mesh of cfd_templates/openfoam/meshes.toml (left out: "
                                   "the set-up's, else coarse)")
    wall_treatment: str | None = bounded(
        None, choices=WALL_TREATMENT_NAMES, unit="",
        doc="the plate's wall conditions: log_law (k-epsilon wall functions, for a first "
            "cell at y+ 30-300) or all_y_plus (Spalding's law for nut and epsilon's low-Re "
            "correction: any y+, like Fluent's enhanced wall treatment); left out: the "
            "set-up's, else log_law")
    frame: str | None = bounded(
        None, choices=FRAME_NAMES, unit="",
        doc="inertial (the whole mesh moves with the plate) or plate (a static mesh in the "
            "plate's frame, about a third less CPU, with the inletOutlet far field); left "
            "out: the set-up's, else inertial")
    far_field: str | None = bounded(
        None, choices=FAR_FIELD_NAMES, unit="",
        doc="far-field conditions (inletOutlet for heaves much faster than the stream); "
            "left out: the set-up's, else freestream")
    pressure_solver: str | None = bounded(
        None, choices=PRESSURE_SOLVER_NAMES, unit="",
        doc="linear solver of the pressure equation; left out: the set-up's, else PCG")
    velocity_convection: str | None = bounded(
        None, choices=VELOCITY_CONVECTION_NAMES, unit="",
        doc="convection scheme of U; left out: the set-up's, else linearUpwind")
    turbulence_convection: str | None = bounded(
        None, choices=TURBULENCE_CONVECTION_NAMES, unit="",
        doc="convection scheme of k and epsilon (upwind: no clipping of negative epsilon); "
            "left out: the set-up's, else limitedLinear")
    max_courant: float | None = bounded(
        None, low=0.0, high=100.0, low_open=True, unit="1",
        doc="Courant limit of the adaptive time step; left out: the set-up's, else 4")
    outer_correctors: int | None = bounded(
        None, low=1, high=100, unit="1",
        doc="PIMPLE outer iterations per time step (1: PISO); left out: the set-up's, else 2")
    correctors: int | None = bounded(
        None, low=1, high=100, unit="1",
        doc="pressure correctors per outer iteration; left out: the set-up's, else 1")
    writes: int = bounded(4, low=1, high=100_000, unit="1",
                          doc="times a case written by cfd write writes its fields over the "
                              "run (a killed run restarts from the last one)")
    y_plus: bool = bounded(False, choices=(True, False), unit="",
                           doc="add the yPlus function object to a case written by cfd write")
    procs: int = bounded(1, low=1, high=4096, unit="1",
                         doc="MPI ranks of each run (above 1 the case is decomposed, method "
                             "simple, and pimpleFoam runs under mpirun)")
    timeout_s: float = bounded(6 * 3600.0, low=0.0, high=30 * 86400.0, low_open=True,
                               unit="s", doc="wall-clock limit of each solver run")
    retries_from_start: bool = bounded(
        True, choices=(True, False), unit="",
        doc="a retried run (its time step collapsed, or its forces left what the motion can "
            "drive) reruns from t = 0 s with the changed far field or Courant limit, so "
            "that every cycle ran one set-up (false: it resumes from its last written time, "
            "cheaper, but its cycles can straddle the change)")
    single_precision: bool = bounded(
        True, choices=(True, False), unit="",
        doc="campaign records store their time series in float32, like the shipped "
            "records (half the size; 7 significant digits, far below CFD's cycle-to-cycle "
            "scatter)")
    keep_case_dirs: bool = bounded(
        False, choices=(True, False), unit="",
        doc="keep a campaign's OpenFOAM case folders once their records are written "
            "(false: a finished case keeps only its record)")

    def __post_init__(self) -> None:
        check_fields(self, prefix="cfd.")

    def solver_overrides(self) -> dict[str, object]:
        """The solver settings this table gives, as
        :class:`~mfflap.cfd.openfoam.writer.SolverSettings` fields (the plate's frame with
        the inletOutlet far field unless ``far_field`` says otherwise)."""
        out = {field: getattr(self, key) for key, field in SOLVER_KEYS.items()
               if getattr(self, key) is not None}
        if self.frame == "plate" and self.far_field is None:
            out["far_field"] = "inletOutlet"
        return out


@dataclass(frozen=True)
class HarmonicSet:
    """The second identification set: harmonic motions, theta = theta_a sin(2 pi f t),
    h = h_a sin(2 pi f t + phi), at the pitch amplitudes and rates optimised motions reach
    (the Table 1 grid's pitch ramp never pitches faster than 3.3 rad/s; optima reach
    15 rad/s and 58 deg).

    Every (frequency, pitch amplitude) pair is run at every heave amplitude, and each of
    these meets the phases in turn (a Latin square over heave amplitude and phase), so
    that the set spans all four axes at a third of the full factorial's cost: 36 cases by
    default, each ``n_cycles`` periods long after a start-up ramp of a quarter period.

    Examples
    --------
    >>> cases = HarmonicSet().motions()
    >>> len(cases), cases[0]
    (36, (1.0, 0.05, 30.0, 60.0))
    >>> sorted({phi for _, _, _, phi in cases})
    [60.0, 90.0, 120.0]
    """

    frequencies: tuple[float, ...] = bounded((1.0, 1.5, 2.0, 2.5), low=0.0, low_open=True,
                                             high=100.0, unit="Hz", unique=True)
    heave_amplitudes: tuple[float, ...] = bounded((0.05, 0.15, 0.3), low=0.0, low_open=True,
                                                  high=10.0, unit="m", unique=True)
    pitch_amplitudes_deg: tuple[float, ...] = bounded((30.0, 45.0, 60.0), low=0.0,
                                                      low_open=True, high=89.0, unit="deg",
                                                      unique=True)
    phases_deg: tuple[float, ...] = bounded((60.0, 90.0, 120.0), low=-360.0, high=360.0,
                                            unit="deg", unique=True, period=360.0,
                                            doc="by which heave leads pitch")
    n_cycles: float = bounded(4.0, low=1.0, high=1000.0, unit="1",
                              doc="periods simulated, the start-up ramp's included")

    def __post_init__(self) -> None:
        check_fields(self, prefix="harmonic_set.")

    def motions(self) -> list[tuple[float, float, float, float]]:
        """The set's motions as (frequency Hz, heave amplitude m, pitch amplitude deg,
        phase deg), ordered so that the frequency varies fastest (a campaign stopped
        part-way still spans the frequencies)."""
        pairs = list(itertools.product(self.pitch_amplitudes_deg, self.frequencies))
        out = []
        for j, h in enumerate(self.heave_amplitudes):
            for i, (theta, f) in enumerate(pairs):
                out.append((f, h, theta, self.phases_deg[(i + j) % len(self.phases_deg)]))
        return out

    def duration(self, frequency: float) -> float:
        """Simulated time of the set's case at ``frequency``, s."""
        return self.n_cycles / frequency

    @staticmethod
    def ramp_time(frequency: float) -> float:
        """C^2 start-up ramp of the set's case at ``frequency``, s: a quarter period."""
        return 0.25 / frequency


@dataclass(frozen=True)
class BacktestSettings:
    """How ``mfflap run`` and ``mfflap backtest`` check optima in CFD: the periods a live
    run simulates and the whole cycles its means are taken over (how a live run is set up,
    retried and kept is the case's [cfd]).

    Examples
    --------
    >>> BacktestSettings().average_cycles
    2
    >>> BacktestSettings(cycles=1.0, average_cycles=2)  # doctest: +IGNORE_EXCEPTION_DETAIL
    Traceback (most recent call last):
    mfflap.errors.ConfigError: backtest.average_cycles: 2 whole cycles need cycles >= 2
    """

    cycles: float = bounded(3.0, low=1.0, high=100.0, unit="1",
                            doc="periods a live back-test runs after its start-up ramp of "
                                "half a period")
    average_cycles: int = bounded(2, low=1, high=100, unit="1",
                                  doc="the CFD and model means are taken over the last this "
                                      "many whole cycles, with CFD's cycle-to-cycle scatter")

    def __post_init__(self) -> None:
        check_fields(self, prefix="backtest.")
        if self.average_cycles > self.cycles:
            raise ConfigError(
                f"{self.average_cycles} whole cycles need cycles >= {self.average_cycles}; "
                f"a live back-test runs {self.cycles:g} after its start-up ramp",
                key="backtest.average_cycles")

    @property
    def simulated_periods(self) -> float:
        """The periods a live back-test simulates, its start-up ramp of half a period
        included.

        Examples
        --------
        >>> BacktestSettings().simulated_periods
        3.5
        """
        return self.cycles + 0.5


@dataclass(frozen=True)
class RoundsSettings:
    """CFD in the loop: the main job run up to ``count`` times, each round identifying the
    model with the back-test CFD of the rounds before, until the model predicts its
    back-tested motions' mean thrust and power within ``tolerance``.

    Examples
    --------
    >>> RoundsSettings().count
    1
    >>> RoundsSettings(count=3, trust_radius=0.25).trust_radius
    0.25
    >>> RoundsSettings(trust_radius=0.25)  # doctest: +IGNORE_EXCEPTION_DETAIL
    Traceback (most recent call last):
    mfflap.errors.ConfigError: rounds.trust_radius: needs rounds.count >= 2
    """

    count: int = bounded(1, low=1, high=100, unit="1",
                         doc="rounds of CFD in the loop (1: the main job once)")
    tolerance: float = bounded(0.1, low=0.0, high=1.0, low_open=True, high_open=True,
                               unit="1", doc="relative error of the model's mean thrust and "
                                             "power against CFD at which the rounds stop")
    refit: bool = bounded(True, choices=(True, False), unit="",
                          doc="refit the identified coefficients on the back-tests of the "
                              "rounds before (false: round 1's coefficients throughout)")
    correct_outputs: bool = bounded(False, choices=(True, False), unit="",
                                    doc="from round 2 on, optimise each beta with the model's "
                                        "thrust and power scaled to predict the CFD means of "
                                        "the previous round's optimum (output space mapping)")
    correction_gain: float = bounded(1.0, low=0.0, high=1.0, low_open=True, unit="1",
                                     doc="K of a first-order filter of the output scales "
                                         "(1: no filter)")
    trust_radius: float | None = bounded(None, low=0.0, high=MAX_TRUST_RADIUS, low_open=True,
                                         unit="1",
                                         doc="keep each beta's optimum within this fraction "
                                             "of the last confirmed optimum's accelerations "
                                             "and time step (trust-region modifier "
                                             "adaptation; left out: no trust region)")
    first_order: bool = bounded(False, choices=(True, False), unit="",
                                doc="give the corrected objective a secant slope too "
                                    "(needs correct_outputs and trust_radius)")
    cfd_repeatability: float | None = bounded(None, low=0.0, high=1.0, low_open=True,
                                              high_open=True, unit="1",
                                              doc="share by which two CFD runs of one motion "
                                                  "differ in their means; relaxes the trust "
                                                  "region's judgement of each step")

    def __post_init__(self) -> None:
        check_fields(self, prefix="rounds.")
        if self.count == 1:
            given = [f.name for f in fields(self) if f.name in LATER_ROUNDS_KEYS
                     and getattr(self, f.name) != f.default]
            if given:
                raise ConfigError("rounds of CFD in the loop take this from round 2 on; "
                                  "it needs rounds.count >= 2", key=f"rounds.{given[0]}")
        if self.count > 1 and not self.refit and not self.correct_outputs:
            raise ConfigError("refit = false keeps the coefficients of round 1, so without "
                              "correct_outputs every round would optimise the same motions",
                              key="rounds.refit")
        if self.correction_gain != 1.0 and not self.correct_outputs:
            raise ConfigError("the gain filters the output correction's scales; it needs "
                              "correct_outputs = true", key="rounds.correction_gain")
        if self.cfd_repeatability is not None and self.trust_radius is None:
            raise ConfigError("CFD's repeatability relaxes the trust region's judgement of "
                              "each step; it needs trust_radius", key="rounds.cfd_repeatability")
        if self.first_order:
            missing = [k for k, given in (("correct_outputs", self.correct_outputs),
                                          ("trust_radius", self.trust_radius is not None))
                       if not given]
            if missing:
                raise ConfigError("a slope on the corrected objective would lead the "
                                  "optimiser off along a secant without a trust region; it "
                                  f"needs {' and '.join(missing)}", key="rounds.first_order")
            if self.correction_gain != 1.0:
                raise ConfigError("first-order corrections meet CFD at the centre with the "
                                  f"measured scales; correction_gain {self.correction_gain:g} "
                                  "filters them", key="rounds.first_order")


__all__ = ["FAR_FIELD_NAMES", "FRAME_NAMES", "MAX_TRUST_RADIUS", "PRESSURE_SOLVER_NAMES",
           "SOLVER_KEYS", "TURBULENCE_CONVECTION_NAMES", "VELOCITY_CONVECTION_NAMES",
           "WALL_TREATMENT_NAMES", "BacktestSettings", "CfdSettings", "RoundsSettings"]
