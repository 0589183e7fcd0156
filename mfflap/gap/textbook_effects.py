"""Hidden effects written from their textbook forms, apart from the candidate library:
the blind test of the gap diagnosis that can show a form mismatch.

Each dataset is 36 pitch-ramp motions of the paper's plate whose "CFD" is the Morison
model with its four coefficients drawn within +-15 % of the paper's, plus one hidden effect
(or none) at its textbook strength, plus AR(1) noise (in proportion to each case's loads,
or of one size in every case) sized for the signal-to-noise ratio asked. The effects are
written here from their theory, not from :mod:`mfflap.gap.candidates`, so that a candidate
whose form differs from the physics it is named for is seen as such:

- in the library's reach: thin-aerofoil quasi-steady lift (incidence from the normal
  velocity at three-quarter chord, lift at the quarter chord); the same lift lagged by
  Wagner's function in the distance travelled at the relative flow speed; Polhamus' vortex
  normal force K_v sin^2(alpha) at mid-chord; laminar skin friction at the full relative
  speed (Blasius, 1.328 / sqrt(Re) with Re = |V| c / nu, the tangential share of
  |V| V, where the candidates take the tangential speed alone); a dynamic-stall lift
  deficit (the Beddoes-Leishman separation point's exponential curves, its lag in
  semichords, where the candidate has Goman and Khrabrov's logistic curve, delay and
  lag in convective times);
- outside it: the plate meeting its own wake (the normal velocity's lift delayed by the
  time the stream takes to travel a chord); a vortex-shedding force at a frequency of its
  own; the lift of a leading-edge vortex that builds while the incidence is past stall,
  rides down the chord and is shed at the trailing edge (the Beddoes-Leishman vortex-lift
  module);
- none.

A trial is scored by its verdict (:func:`outcome`): the effect claimed (an accepted
attribution, :data:`ACCEPTED`), "within noise", or "structured, unexplained". The goals:
at least 90 % of the in-library effects attributed, at most 5 % of the null datasets called
anything but noise, at least two thirds of the out-of-library effects called structured
and unexplained.
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Callable

import numpy as np

from mfflap.config import CaseConfig
from mfflap.errors import ConfigError
from mfflap.gap.blindtest import ar1_noise, trial_cases, unabsorbed_rms
from mfflap.gap.system import COMPONENTS
from mfflap.gap.workflow import diagnose_cases
from mfflap.hydro.loads import Loads
from mfflap.identification.data import CaseData

#: how a dataset's noise is sized, case by case
NOISE_MODELS = ("relative", "absolute")

#: the claims counted as the right attribution of each hidden effect (None: no effect
#: should be claimed; the verdict then decides)
ACCEPTED = {
    "thin_aerofoil_lift": {"circulatory_lift", "circulatory_lift + pitch_rate_lift",
                           "circulatory lift family"},
    "wagner_relative_flow": {"wake_lag", "circulatory lift family"},
    "polhamus_normal_force": {"leading_edge_vortex"},
    "laminar_friction": {"laminar_skin_friction", "turbulent_skin_friction",
                         "skin friction family"},
    "dynamic_stall": {"dynamic_stall"},
    "wake_encounter": None,
    "vortex_shedding": None,
    "vortex_lift_pulse": None,
    "none": None,
}
IN_LIBRARY = [k for k, v in ACCEPTED.items() if v is not None]
OUT_OF_LIBRARY = [k for k, v in ACCEPTED.items() if v is None and k != "none"]


def _velocities(state, velocity: float, x: float):
    """Normal velocity at x (m from the leading edge) and tangential velocity, m/s
    (v_n = hdot cos th + U sin th + thdot x, v_t = hdot sin th - U cos th)."""
    th, hd, thd = state.pitch_angle, state.heave_velocity, state.pitch_rate
    normal = hd * np.cos(th) + velocity * np.sin(th) + thd * x
    return normal, hd * np.sin(th) - velocity * np.cos(th)


def _distance_in_semichords(time, speed, chord):
    """s(t) = (2 / c) integral of the speed, trapezoidal."""
    steps = 0.5 * (speed[1:] + speed[:-1]) * np.diff(time)
    return 2.0 / chord * np.concatenate([[0.0], np.cumsum(steps)])


def _jones_wagner(forcing, s):
    """Duhamel response to ``forcing`` of Jones' Wagner function
    phi(s) = 1 - 0.165 exp(-0.0455 s) - 0.335 exp(-0.3 s), exact per step for a forcing
    held over it, from equilibrium with the first value (the motion ran before the first
    sample)."""
    out = np.empty_like(forcing)
    amplitude, rate = np.array([0.165, 0.335]), np.array([0.0455, 0.3])
    z = amplitude * forcing[0]
    for i, x in enumerate(forcing):
        if i:
            decay = np.exp(-rate * (s[i] - s[i - 1]))
            z = decay * z + amplitude * (1.0 - decay) * forcing[i - 1]
        out[i] = (1.0 - amplitude.sum()) * x + z.sum()
    return out


def _vortex_lift_pulse(state, velocity: float, chord: float, q_area: float) -> Loads:
    """Beddoes-Leishman's vortex lift (Leishman & Beddoes 1989, J. Am. Helicopter Soc.
    34(3)): while the incidence is past stall onset (15 deg) the vortex gathers the
    circulation the separated flow sheds, dC_v = d[2 pi sin(alpha) (1 - K_N)] with
    K_N = ((1 + sqrt f)/2)^2 and f the steady separation point, and decays over
    T_v = 6 semichords; once it has ridden T_vl = 8 semichords it leaves the trailing
    edge and its lift only decays. Its centre of pressure moves from c/4 towards the
    trailing edge as it rides."""
    t = np.asarray(state.time, dtype=float)
    vn34, vt = _velocities(state, velocity, 0.75 * chord)
    alpha = np.arctan2(vn34, np.abs(vt))
    speed2 = vn34**2 + vt**2
    mag, onset = np.abs(alpha), np.radians(15.0)
    f = np.where(mag < onset, 1.0 - 0.3 * np.exp((mag - onset) / np.radians(3.0)),
                 0.04 + 0.66 * np.exp((onset - mag) / np.radians(2.0)))
    feed = 2 * np.pi * np.sin(alpha) * (1.0 - ((1 + np.sqrt(f)) / 2) ** 2)
    s = _distance_in_semichords(t, np.sqrt(speed2), chord)
    ride, lift = np.zeros_like(t), np.zeros_like(t)
    for i in range(1, len(t)):
        ds = s[i] - s[i - 1]
        ride[i] = ride[i - 1] + ds if mag[i] > onset else 0.0
        lift[i] = lift[i - 1] * np.exp(-ds / 6.0)
        if 0.0 < ride[i] <= 8.0:
            lift[i] += (feed[i] - feed[i - 1]) * np.exp(-ds / 12.0)
    fn = -q_area * speed2 * lift
    centre = 0.25 + 0.5 * np.clip(ride / 8.0, 0.0, 1.0)
    return Loads(t, fn, np.zeros_like(t), fn * centre * chord)


def effect_loads(name: str, state, chord: float, span: float, density: float,
                 viscosity: float, velocity: float, rng: np.random.Generator) -> Loads:
    """The hidden effect's loads (N, N, N m about the leading edge) at unit strength."""
    t = np.asarray(state.time, dtype=float)
    zero = np.zeros_like(t)
    area = chord * span
    q_area = 0.5 * density * area
    if name == "thin_aerofoil_lift":
        vn34, vt = _velocities(state, velocity, 0.75 * chord)
        fn = -q_area * 2 * np.pi * np.abs(vt) * vn34
        return Loads(t, fn, zero, fn * 0.25 * chord)
    if name == "wagner_relative_flow":
        vn34, vt = _velocities(state, velocity, 0.75 * chord)
        quasi_steady = -q_area * 2 * np.pi * np.abs(vt) * vn34
        fn = _jones_wagner(quasi_steady, _distance_in_semichords(t, np.abs(vt), chord))
        return Loads(t, fn, zero, fn * 0.25 * chord)
    if name == "polhamus_normal_force":
        vn, vt = _velocities(state, velocity, 0.0)
        speed2 = vn**2 + vt**2
        sin_alpha = vn / np.sqrt(np.maximum(speed2, 1e-12))
        fn = -q_area * np.pi * speed2 * sin_alpha * np.abs(sin_alpha)
        return Loads(t, fn, zero, fn * 0.5 * chord)
    if name == "laminar_friction":
        vn, vt = _velocities(state, velocity, 0.5 * chord)
        speed = np.hypot(vn, vt)
        reynolds = np.maximum(speed * chord / viscosity, 1e3)
        ft = -0.5 * density * 2 * area * 1.328 / np.sqrt(reynolds) * speed * vt
        return Loads(t, zero, ft, zero)
    if name == "dynamic_stall":
        vn34, vt = _velocities(state, velocity, 0.75 * chord)
        alpha = np.arctan2(vn34, np.abs(vt))
        a1, s1, s2 = np.radians(15.0), np.radians(3.0), np.radians(2.0)
        mag = np.abs(alpha)
        f_steady = np.where(mag < a1, 1.0 - 0.3 * np.exp((mag - a1) / s1),
                            0.04 + 0.66 * np.exp((a1 - mag) / s2))
        s = _distance_in_semichords(t, np.sqrt(vn34**2 + vt**2), chord)
        f = np.empty_like(f_steady)
        f[0] = f_steady[0]
        for i in range(1, len(t)):  # first-order lag of 3 semichords
            decay = np.exp(-(s[i] - s[i - 1]) / 3.0)
            f[i] = decay * f[i - 1] + (1.0 - decay) * f_steady[i - 1]
        speed2 = vn34**2 + vt**2
        deficit = 2 * np.pi * np.sin(alpha) * (((1 + np.sqrt(f)) / 2) ** 2 - 1.0)
        fn = -q_area * speed2 * deficit
        return Loads(t, fn, zero, fn * (0.25 + 0.1 * (1.0 - f)) * chord)
    if name == "vortex_lift_pulse":
        return _vortex_lift_pulse(state, velocity, chord, q_area)
    if name == "wake_encounter":
        vn, vt = _velocities(state, velocity, 0.0)
        delay = chord / velocity
        late = np.interp(t - delay, t, vn, left=vn[0])
        fn = -q_area * 2 * np.pi * np.abs(vt) * late
        return Loads(t, fn, zero, fn * 0.25 * chord)
    if name == "vortex_shedding":
        frequency = 0.2 * velocity / (0.1 * chord)  # a wake Strouhal number of 0.2
        phase = rng.uniform(0.0, 2 * np.pi)
        fn = q_area * velocity**2 * np.sin(2 * np.pi * frequency * t + phase)
        return Loads(t, fn, zero, fn * 0.5 * chord)
    raise ValueError(name)


def dataset(name: str, seed: int, config, snr: float, n_cases: int = 36,
            noise_level: float = 0.05, noise: str = "relative") -> list[CaseData]:
    """One blind dataset: perturbed Morison + the hidden effect at its textbook strength +
    AR(1) noise, sized so that the effect's part no refit of the Morison coefficients
    absorbs is ``snr`` times the noise (``noise_level`` times each case's RMS without an
    effect with ``noise="relative"``, times each component's RMS over every case with
    ``"absolute"``).

    Raises
    ------
    ConfigError
        An effect not in :data:`ACCEPTED` (key ``effect``) or a noise model not in
        :data:`NOISE_MODELS` (key ``noise``).
    """
    if name not in ACCEPTED:
        raise ConfigError(f"hidden effect {name!r}: choose one of {', '.join(ACCEPTED)}",
                          key="effect")
    if noise not in NOISE_MODELS:
        raise ConfigError(f"noise model {noise!r}: choose one of {', '.join(NOISE_MODELS)}",
                          key="noise")
    rng = np.random.default_rng(seed)
    cases = trial_cases(rng, n_cases)
    paper = config.morison_model()
    base = paper.with_coefficients({k: v * rng.uniform(0.85, 1.15)
                                    for k, v in paper.coefficients.items()})
    clean = [base.loads(c.state) for c in cases]
    scale = {k: float(np.sqrt(np.mean(np.concatenate([getattr(ld, k) for ld in clean])**2)))
             for k in COMPONENTS}
    effects = None
    if name != "none":
        p, f = config.plate, config.fluid
        effects = [effect_loads(name, c.state, p.chord, p.span, f.density,
                                f.kinematic_viscosity, config.flow.velocity, rng)
                   for c in cases]
        noise_level = unabsorbed_rms(base, cases, effects, scale) / snr
    out = []
    for i, (c, ld) in enumerate(zip(cases, clean, strict=True)):
        comps = {}
        for k in COMPONENTS:
            y = getattr(ld, k).copy()
            if effects is not None:
                y += getattr(effects[i], k)
            size = (float(np.sqrt(np.mean(getattr(ld, k) ** 2))) if noise == "relative"
                    else scale[k])
            comps[k] = y + noise_level * size * ar1_noise(rng, len(y))
        out.append(CaseData(c.name, c.parameters, c.state,
                            Loads(c.state.time, comps["normal_force"],
                                  comps["tangential_force"], comps["moment"])))
    return out


def outcome(diag) -> str:
    """A diagnosis's verdict in a word: the claimed effect when it leaves a white residual,
    "partly X" when a structured residual remains with the claim X, "noise", "structured",
    or "structured, X not claimed" when the best candidate X explains it but its
    coefficient is implausible or confounded. X is "F family" when the verdict says that
    the cases cannot tell the forms of family F apart."""
    family = f"{diag.family[0]} family" if diag.family else None
    if diag.chosen is not None:
        label = family or diag.chosen.label
        return label if diag.finding.startswith("explained") else f"partly {label}"
    if diag.verdict.startswith("within noise"):
        return "noise"
    named = family or next(iter(diag.not_claimed), None)
    return f"structured, {named} not claimed" if named else "structured"


def right(name: str, said: str) -> bool:
    """Whether a trial of hidden effect ``name`` got the right verdict: an accepted claim
    (whole, or partly: a textbook form is not the candidate's, and a structured residual
    may remain with it), or the accepted effect named and not claimed for its coefficient
    (the diagnosis found the form and said why its strength cannot be told from the base
    model's terms); no claim of an effect outside the library, and no structure in
    none."""
    accepted = ACCEPTED[name]
    if accepted is not None:
        return (said in accepted or said in {f"partly {a}" for a in accepted}
                or said in {f"structured, {a} not claimed" for a in accepted})
    if name == "none":
        return said == "noise"
    return said.startswith("structured")


def run(trials: int = 3, snr: float = 3.0, config: CaseConfig | None = None, seed: int = 0,
        noise: str = "relative", residual_scaling: str | None = None,
        progress: Callable[[str], None] | None = None) -> dict[str, list[str]]:
    """Every effect's verdicts over ``trials`` datasets each, diagnosed as
    :func:`~mfflap.gap.workflow.diagnose_cases` does with ``config`` (default: the paper's
    case; its residual scaling unless ``residual_scaling`` is given)."""
    config = config or CaseConfig()
    said: dict[str, list[str]] = {}
    for k, name in enumerate(ACCEPTED):
        said[name] = []
        for trial in range(trials):
            cases = dataset(name, 100_000 * seed + 1000 * k + trial, config, snr,
                            noise=noise)
            diag, _, _ = diagnose_cases(config, cases, residual_scaling=residual_scaling)
            said[name].append(outcome(diag))
            if progress is not None:
                progress(f"{name} trial {trial + 1}/{trials}: {said[name][-1]}")
    return said


def scores(said: dict[str, list[str]]) -> dict[str, float]:
    """The three goal figures: in-library attribution, null false alarms, out-of-library
    effects called structured and unexplained."""
    def share(names, test):
        hits = [test(n, s) for n in names for s in said.get(n, [])]
        return float(np.mean(hits)) if hits else float("nan")

    return {"in_library_attributed": share(IN_LIBRARY, right),
            "null_false_alarms": share(["none"], lambda n, s: s != "noise"),
            "out_of_library_structured": share(OUT_OF_LIBRARY, right),
            "out_of_library_overclaimed": share(OUT_OF_LIBRARY, lambda n, s: is_claim(s))}


def is_claim(said: str) -> bool:
    """Whether an :func:`outcome` claims an effect (whole or partly)."""
    return not (said == "noise" or said.startswith("structured"))


def predicted(said: str) -> str:
    """The column of an :func:`outcome` in the confusion matrix: the effect claimed
    (whole or partly), "X (not claimed)", "structured" or "noise".

    Examples
    --------
    >>> predicted("partly wake_lag"), predicted("structured, skin friction family not claimed")
    ('wake_lag', 'skin friction family (not claimed)')
    """
    if said.startswith("structured, ") and said.endswith(" not claimed"):
        return f"{said[len('structured, '):-len(' not claimed')]} (not claimed)"
    return said.removeprefix("partly ")


def confusion(said: dict[str, list[str]]) -> dict[str, dict[str, int]]:
    """Hidden effect -> predicted column (:func:`predicted`) -> trials.

    Examples
    --------
    >>> confusion({"none": ["noise", "noise", "structured"]})
    {'none': {'noise': 2, 'structured': 1}}
    """
    return {name: dict(Counter(predicted(s) for s in verdicts).most_common())
            for name, verdicts in said.items()}


def recall(said: dict[str, list[str]]) -> dict[str, float]:
    """Each hidden effect's share of right verdicts (:func:`right`)."""
    return {name: float(np.mean([right(name, s) for s in verdicts]))
            for name, verdicts in said.items() if verdicts}


def summary(said: dict[str, list[str]]) -> str:
    """Each effect's recall and row of the confusion matrix, the three goal figures and the
    out-of-library over-claims, as lines of text."""
    lines = ["hidden effect            right   verdicts (confusion matrix row)"]
    for name, row in confusion(said).items():
        hits = sum(right(name, s) for s in said[name])
        shown = ", ".join(f"{k} x{n}" for k, n in row.items())
        lines.append(f"{name:24s} {hits:3d}/{len(said[name]):<3d} {shown}")
    s = scores(said)
    lines += [f"in-library effects attributed      {s['in_library_attributed']:.0%} (goal >= 90 %)",
              f"null datasets not called noise     {s['null_false_alarms']:.0%} (goal <= 5 %)",
              f"out-of-library called unexplained  {s['out_of_library_structured']:.0%} "
              "(goal >= 67 %)",
              f"out-of-library claimed as an effect {s['out_of_library_overclaimed']:.0%}"]
    return "\n".join(lines)


__all__ = ["ACCEPTED", "IN_LIBRARY", "NOISE_MODELS", "OUT_OF_LIBRARY", "confusion", "dataset",
           "effect_loads", "is_claim", "outcome", "predicted", "recall", "right", "run",
           "scores", "summary"]
