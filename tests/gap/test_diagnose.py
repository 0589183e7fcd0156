"""Gap diagnosis: candidate library, Wagner lag, decomposition, selection, blind benchmark."""

import json
import re
from pathlib import Path

import h5py
import numpy as np
import pytest
from click.testing import CliRunner

from mfflap.errors import ConfigError, ParseError
from mfflap.gap.blindtest import NULL, blind_test, synthesize, trial_cases
from mfflap.gap.candidates import CandidateEffect, load_all, register
from mfflap.gap.candidates.base import _REGISTRY
from mfflap.gap.diagnose import CONFOUNDED_VIF, _predictions, default_candidates, diagnose
from mfflap.gap.external import read_csv_case
from mfflap.gap.system import GapSystem, group_folds
from mfflap.gap.where import correlation_ratio, decompose
from mfflap.hydro import MorisonModel
from mfflap.hydro.thin_aerofoil import JONES_WAGNER, wagner_filter
from mfflap.records.record import CfdRecord, write_record

CASE = Path(__file__).parents[2] / "cases" / "paper2026.toml"


def test_library_has_the_required_effects_with_finite_regressors():
    names = set(load_all())
    assert {"circulatory_lift", "wake_lag", "pitch_rate_lift", "leading_edge_vortex",
            "added_mass_coupling", "turbulent_skin_friction"} <= names
    data = synthesize(np.random.default_rng(0), NULL, 0.0, n_cases=3)
    for name, effect in default_candidates().items():
        r = effect.regressor(data[0].state)
        assert all(np.all(np.isfinite(getattr(r, k))) for k in
                   ("normal_force", "tangential_force", "moment")), name
        assert effect.is_plausible(effect.typical), name


def test_wagner_step_response_is_jones_function():
    """A unit step after a long zero input: y(s) = 1 - sum A_i exp(-b_i s), s = 2 U t / c."""
    u, c = 0.3, 0.16
    t = np.linspace(-1.0, 20.0, 20001)
    x = (t >= 0).astype(float)
    y = wagner_filter(x, t, u, c, start="rest")
    s = 2 * u * t / c
    after = t > 0.01
    phi = 1 - sum(a * np.exp(-b * s[after]) for a, b in JONES_WAGNER)
    # zero-order hold of the input: a one-sample shift of the step, so compare at s +/- ds
    assert np.max(np.abs(y[after] - phi)) < 2e-3
    assert y[t < 0].max() == 0.0 and y[-1] == pytest.approx(1 - sum(
        a * np.exp(-b * s[-1]) for a, b in JONES_WAGNER), abs=1e-3)


def test_a_new_candidate_is_one_class_and_is_used_by_the_diagnosis():
    @register
    class ConstantNormalForce(CandidateEffect):
        """A constant normal force (a test candidate)."""

        name = "test_constant_normal_force"
        plausible = (0.0, 100.0)

        def regressor(self, state):
            return self.loads(state, normal=np.ones(state.shape))

    try:
        assert "test_constant_normal_force" in default_candidates()
        rng = np.random.default_rng(4)
        data = synthesize(rng, NULL, 0.0)
        for c in data:  # hide a constant 3 N offset in F_n
            c.cfd.normal_force[:] += 3.0
        diag = diagnose(data, MorisonModel())
        assert diag.chosen is not None
        assert diag.chosen.names[0] == "test_constant_normal_force"
        assert diag.chosen.coefficients["test_constant_normal_force"] == pytest.approx(3.0,
                                                                                      rel=0.2)
    finally:
        _REGISTRY.pop("test_constant_normal_force")


@pytest.mark.parametrize("withheld", ["circulatory_lift", "leading_edge_vortex",
                                      "added_mass_coupling"])
def test_a_withheld_effect_is_not_claimed_as_a_near_duplicate(withheld):
    """An effect hidden (SNR 3) and withheld from the candidates: the nearest candidate
    explains part of it, but not with a plausible, unconfounded coefficient, so nothing is
    claimed and the residual is called structured and unexplained."""
    from mfflap.gap.blindtest import default_candidates

    others = {k: v for k, v in default_candidates().items() if k != withheld}
    diag = diagnose(synthesize(np.random.default_rng(403), withheld, 3.0),
                    MorisonModel(), candidates=others)
    assert diag.chosen is None
    assert diag.verdict.startswith("structured, unexplained: no candidate explains it")
    assert diag.whiteness["within_noise"] is False


def test_an_effect_no_candidate_has_is_called_structured_and_unexplained():
    """Skin friction hidden (SNR 3) and left out of the candidates: nothing is claimed, and
    the residual is not taken for noise."""
    from mfflap.gap.blindtest import default_candidates

    others = {k: v for k, v in default_candidates().items() if v.family != "skin friction"}
    diag = diagnose(synthesize(np.random.default_rng(7), "turbulent_skin_friction", 3.0),
                    MorisonModel(), candidates=others)
    assert diag.chosen is None
    assert diag.verdict.startswith("structured, unexplained: no candidate explains it (best: ")
    assert diag.whiteness["within_noise"] is False and diag.whiteness["p_value"] < 0.01
    # the headline a report and the command print says the finding once
    assert diag.headline().startswith("Structured, unexplained: no candidate explains it")
    assert diag.headline().lower().count("structured, unexplained") == 1


@pytest.mark.parametrize("effect", ["wake_lag", "circulatory_lift", "added_mass_coupling"])
def test_hidden_effect_is_found_and_the_gap_shrinks(effect):
    data = synthesize(np.random.default_rng(11), effect, 4.0)
    diag = diagnose(data, MorisonModel())
    assert diag.chosen is not None and diag.chosen.names[0] == effect
    assert diag.headline().startswith(f"Explained by {diag.chosen.label}: held-out error ")
    # what is left with it is noise: the claim is the whole gap
    assert diag.whiteness_after["within_noise"] is True
    assert "structured residual remains" not in diag.verdict
    before = diag.gap["before"]
    after = diag.gap["after"]
    shrink = {k: np.median(after[k]["nrmse"]) / np.median(before[k]["nrmse"])
              for k in ("normal_force", "tangential_force", "moment")}
    assert min(shrink.values()) < 0.8, shrink
    assert diag.validation["leave-one-frequency-out"]["gain"] > 0.1
    assert diag.validation["leave-one-frequency-out"]["claimed"] is True


def test_null_dataset_claims_nothing_and_says_it_is_noise():
    diag = diagnose(synthesize(np.random.default_rng(5), NULL, 0.0), MorisonModel())
    assert diag.chosen is None
    assert diag.verdict.startswith("within noise: Ljung-Box test of the held-out residual")
    assert diag.headline().startswith("Within noise: Ljung-Box test")
    assert diag.whiteness["within_noise"] is True and diag.whiteness["n_series"] == 60
    assert "after" not in diag.gap
    lofo = diag.validation["leave-one-frequency-out"]
    assert lofo["claimed"] is False and lofo["candidate"] == diag.scores[0].label


@pytest.mark.slow
def test_blind_benchmark_meets_its_targets_at_snr_3():
    """The issue's target: right effect first in >= 90 % of trials, no claim in >= 90 % of
    null trials (30 trials here; the benchmark script runs more)."""
    res = blind_test(n_trials=30, snr=3.0, seed=7)
    assert res.attribution_accuracy >= 0.9
    assert res.null_correct >= 0.9
    assert res.confusion().sum() == 30
    # the claimed effect's strength is recovered too (measured: 0.8 % median error)
    assert res.coefficient_error < 0.05
    assert all((h == 0.0) == (t == NULL) for t, h in zip(res.truth, res.hidden_coefficient,
                                                         strict=True))
    assert np.isfinite(res.fitted_coefficient).sum() == sum(
        t == c != NULL for t, c in zip(res.truth, res.claimed, strict=True))
    assert "no claim on null datasets : " in res.summary() and "nan" not in res.summary()


@pytest.mark.slow
def test_the_residual_scaling_that_wins_the_blind_benchmark_is_the_noise_model_s():
    """Weighted least squares is best with weights matching the noise: at SNR 1, noise of
    one size in every case is attributed far better with grid scaling, noise in proportion
    to each case's loads (as the model's errors against CFD are) with case scaling, whose
    refitted coefficient is then several times nearer the hidden one. "auto" chooses as
    well."""
    scores = {(noise, scaling): blind_test(n_trials=30, snr=1.0, seed=0, noise=noise,
                                           residual_scaling=scaling)
              for noise in ("absolute", "relative") for scaling in ("grid", "case")}
    absolute_grid, absolute_case = scores["absolute", "grid"], scores["absolute", "case"]
    relative_grid, relative_case = scores["relative", "grid"], scores["relative", "case"]
    # measured: 91 % against 82 % (the misses: friction forms named with a confounded
    # coefficient but not the hidden one)
    assert absolute_grid.attribution_accuracy > absolute_case.attribution_accuracy
    assert absolute_grid.attribution_accuracy >= 0.85
    assert relative_case.attribution_accuracy >= relative_grid.attribution_accuracy > 0.9
    assert relative_case.claimed_accuracy > relative_grid.claimed_accuracy
    assert relative_case.coefficient_error < 0.25 * relative_grid.coefficient_error
    assert absolute_grid.coefficient_error < absolute_case.coefficient_error
    for result in scores.values():
        assert result.null_correct == 1.0
    assert "(relative noise, residuals scaled by case)" in relative_case.summary()
    # "auto" lets the errors choose, and does as well as the better fixed choice
    for noise, better in (("absolute", absolute_grid), ("relative", relative_case)):
        auto = blind_test(n_trials=30, snr=1.0, seed=0, noise=noise, residual_scaling="auto")
        assert auto.attribution_accuracy >= better.attribution_accuracy - 0.05, noise
        assert auto.coefficient_error < 2 * better.coefficient_error, noise
    with pytest.raises(ConfigError, match="noise model 'gaussian': choose one of absolute, "
                                          "relative") as err:
        synthesize(np.random.default_rng(0), NULL, 1.0, noise="gaussian")
    assert err.value.key == "noise"


@pytest.mark.slow
def test_a_blind_benchmark_without_null_trials_says_so_instead_of_nan():
    res = blind_test(n_trials=3, snr=3.0, seed=0)
    assert NULL not in res.truth and np.isnan(res.null_correct)
    text = res.summary()
    assert "no claim on null datasets : – (no null trial among these)" in text
    assert "nan" not in text
    weak = blind_test(n_trials=20, snr=0.2, seed=7)  # the test can fail: at SNR 0.2 it does
    assert weak.attribution_accuracy < 0.7


def _stacked(system, cols):
    """The fit's rows written out: each case's components scaled by their RMS over every
    case (grid) or their range in the case (case), and weighted by 1/sqrt(n_samples),
    stacked over all cases (what the Gram blocks summarise)."""
    a, y = [], []
    for c, case_cols in zip(system.cases, system.columns, strict=True):
        w = 1.0 / np.sqrt(c.n_samples)
        for k in case_cols:
            if system.residual_scaling == "case":
                scale = np.ptp(c.cfd_signal(k))
            else:
                scale = np.sqrt(np.mean(np.concatenate([d.cfd_signal(k)
                                                        for d in system.cases])**2))
            a.append(case_cols[k][:, cols] * w / scale)
            y.append(c.cfd_signal(k) * w / scale)
    return np.vstack(a), np.concatenate(y)


@pytest.mark.parametrize("residual_scaling", ["grid", "case"])
def test_held_fit_correlation_and_variance_inflation_equal_direct_least_squares(
        residual_scaling):
    """Computed from the Gram blocks; checked against least squares on the stacked rows,
    with the residuals scaled either way."""
    data = synthesize(np.random.default_rng(8), "wake_lag", 3.0, n_cases=6)
    model = MorisonModel()
    system = GapSystem.build(data, model.terms, list(default_candidates().values()),
                             residual_scaling=residual_scaling)
    assert system.residual_scaling == residual_scaling
    base, free = list(range(system.n_base)), [system.names.index("wake_lag"),
                                              system.names.index("pitch_rate_lift")]
    held_values = np.array([model.coefficients[n] for n in system.names[:system.n_base]])
    a_base, y = _stacked(system, base)
    a_free, _ = _stacked(system, free)
    direct = np.linalg.lstsq(a_free, y - a_base @ held_values, rcond=None)[0]
    got = system.fit_held(free, base, held_values, np.arange(len(data)))
    assert got == pytest.approx(direct, rel=1e-6)
    cols = base + free
    a, _ = _stacked(system, cols)
    cosine = (a.T @ a) / np.outer(np.linalg.norm(a, axis=0), np.linalg.norm(a, axis=0))
    assert system.correlation(cols) == pytest.approx(cosine, abs=1e-9)
    vif = system.variance_inflation(cols)
    for j in range(len(cols)):
        others = np.delete(a, j, axis=1)
        residual = a[:, j] - others @ np.linalg.lstsq(others, a[:, j], rcond=None)[0]
        assert vif[j] == pytest.approx(a[:, j] @ a[:, j] / (residual @ residual), rel=1e-6)
    # a column repeated exactly cannot be told apart from its copy
    assert np.isinf(system.variance_inflation([free[0], free[0]])).all()


def test_case_scaling_makes_each_case_error_its_squared_nrmse_and_is_checked():
    """With residual_scaling="case" a case's scaled squared error is the sum over the
    components of its squared NRMSE (what the held-out errors and the significance test
    then compare); with grid scaling it is not, for cases of different size."""
    from mfflap.metrics import nrmse

    data = synthesize(np.random.default_rng(4), "wake_lag", 3.0, n_cases=6, noise="relative")
    model = MorisonModel()
    cols = list(range(len(model.terms)))
    x = np.array([model.coefficients[t.name] for t in model.terms])
    every = np.arange(len(data))
    expected = np.array([sum(float(nrmse(getattr(model.loads(c.state), k), c.cfd_signal(k)))**2
                             for k in ("normal_force", "tangential_force", "moment"))
                         for c in data])
    by_case = GapSystem.build(data, model.terms, [], residual_scaling="case")
    assert by_case.case_sse(cols, x, every) == pytest.approx(expected, rel=1e-9)
    on_grid = GapSystem.build(data, model.terms, [])
    assert not np.allclose(on_grid.case_sse(cols, x, every), expected, rtol=0.05)
    with pytest.raises(ConfigError, match="residual scaling 'rms': choose one of grid, "
                                          "case") as err:
        GapSystem.build(data, model.terms, [], residual_scaling="rms")
    assert err.value.key == "identification.residual_scaling"
    data = synthesize(np.random.default_rng(4), "wake_lag", 3.0, noise="relative")
    diag = diagnose(data, model, residual_scaling="case")
    assert diag.residual_scaling == "case" and diag.chosen.names == ("wake_lag",)


def test_a_hidden_effect_on_the_exact_base_model_has_its_coefficient_both_ways():
    """Loads = the configured model + 4.5 x the wake-lagged lift, no noise: fitted to the
    base model's residual, or refitted together with it, the coefficient is 4.5."""
    model = MorisonModel()
    wake = default_candidates()["wake_lag"]
    data = trial_cases(np.random.default_rng(9), n_cases=12)
    for c in data:
        exact, extra = model.loads(c.state), wake.regressor(c.state)
        for k in ("normal_force", "tangential_force", "moment"):
            getattr(c.cfd, k)[:] = getattr(exact, k) + 4.5 * getattr(extra, k)
    diag = diagnose(data, model)
    assert diag.chosen is not None and diag.chosen.names == ("wake_lag",), diag.verdict
    assert diag.chosen.held_coefficients["wake_lag"] == pytest.approx(4.5, rel=1e-6)
    assert diag.chosen.coefficients["wake_lag"] == pytest.approx(4.5, rel=1e-4)
    assert diag.chosen.variance_inflation["wake_lag"] < CONFOUNDED_VIF
    assert "confounded" not in diag.verdict


def test_an_effect_the_base_terms_can_mimic_is_named_and_not_claimed():
    """Skin friction, |v_t|^0.8 v_t Re-scaled, is nearly the tangential drag |v_t| v_t: the
    diagnosis finds a friction form explains the residual best, but its coefficient cannot
    be told from the drag's, so it is not claimed, and the verdict says which and why, and
    that the laminar and turbulent forms cannot be told apart."""
    data = synthesize(np.random.default_rng(11), "turbulent_skin_friction", 4.0)
    diag = diagnose(data, MorisonModel())
    assert diag.chosen is None
    best = diag.scores[0]
    (form,) = best.names
    assert form in {"turbulent_skin_friction", "laminar_skin_friction"}
    assert best.significant and not best.claimable
    name, r = best.confounded_with[form]
    assert name == "tangential_drag" and abs(r) > 0.95
    assert best.variance_inflation[form] > CONFOUNDED_VIF
    assert diag.verdict.startswith("structured, unexplained")
    assert (f"not claimed although they explain more: {form} ({form} is confounded with "
            "tangential_drag (variance inflation") in diag.verdict
    assert set(diag.not_claimed) >= {"turbulent_skin_friction", "laminar_skin_friction"}


def test_forms_of_one_effect_the_cases_cannot_tell_apart_are_named_as_their_family():
    """At SNR 1.5 the laminar and turbulent friction laws explain the hidden friction
    alike (their held-out errors within the signed-rank test): the verdict names the
    family and both forms, rather than one form picked by the noise."""
    diag = diagnose(synthesize(np.random.default_rng(11), "turbulent_skin_friction", 1.5),
                    MorisonModel())
    assert diag.family[0] == "skin friction"
    assert set(diag.family[1:]) == {"turbulent_skin_friction", "laminar_skin_friction"}
    said = diag.verdict[diag.verdict.index("skin friction: "):]
    assert "are forms of one effect that these cases cannot tell apart" in said
    assert "turbulent_skin_friction (" in said and "laminar_skin_friction (" in said


def test_an_implausible_best_candidate_is_not_claimed_nor_a_lesser_one_in_its_place():
    """A lift slope of -2 pi (the wrong sign) is implausible: nothing is claimed, the
    verdict names the candidate and its value, and no weaker candidate takes its place."""
    from mfflap.gap.blindtest import default_candidates

    rng = np.random.default_rng(12)
    data = synthesize(rng, NULL, 0.0)
    term = default_candidates()["circulatory_lift"]
    for c in data:
        effect = term.regressor(c.state)
        for k in ("normal_force", "tangential_force", "moment"):
            getattr(c.cfd, k)[:] -= 2 * np.pi * getattr(effect, k)
    diag = diagnose(data, MorisonModel())
    assert diag.scores[0].names[0] == "circulatory_lift"
    assert diag.chosen is None
    reasons = diag.not_claimed["circulatory_lift"]
    assert any(r.startswith("circulatory_lift = -") and r.endswith("is implausible")
               for r in reasons), reasons


def test_decomposition_finds_a_phase_locked_residual():
    rng = np.random.default_rng(2)
    data = synthesize(rng, NULL, 0.0)
    model = MorisonModel()
    for c in data:  # residual that is a pure function of the carrier phase
        f = c.parameters["frequency"]
        exact = model.loads(c.state)
        c.cfd.normal_force[:] = (exact.normal_force
                                 + 5 * np.sign(np.sin(2 * np.pi * f * c.state.time)))
        c.cfd.tangential_force[:] = exact.tangential_force
        c.cfd.moment[:] = exact.moment
    system = GapSystem.build(data, model.terms, [])
    pred = [{k: getattr(model.loads(c.state), k) for k in
             ("normal_force", "tangential_force", "moment")} for c in data]
    where = decompose(system, pred, 0.3, 0.16)
    assert where["by_state"]["phase in the cycle"] > 0.9
    assert where["by_component"]["normal_force"] > 0.99
    assert sum(where["by_component"].values()) == pytest.approx(1.0)
    assert correlation_ratio(np.arange(10.0), np.zeros(10)) == 0.0
    folds = group_folds(range(len(data)), 5)
    assert sorted(np.concatenate(folds).tolist()) == list(range(len(data)))
    assert _predictions(system, [0, 1, 2, 3], folds)[0]["moment"].shape == data[0].state.shape


def test_external_csv_case_and_its_errors(tmp_path):
    t = np.linspace(0, 2, 200)
    pitch, heave = 0.3 * np.sin(2 * np.pi * t), 0.2 * np.cos(2 * np.pi * t)
    rows = ["time,pitch_angle,heave_position,normal_force,tangential_force,moment"]
    rows += [f"{a},{b},{c},1.0,0.5,0.1" for a, b, c in zip(t, pitch, heave, strict=True)]
    good = tmp_path / "run.csv"
    good.write_text("\n".join(rows) + "\n")
    case = read_csv_case(good)
    # the splines' ends are left out (6 samples of 200 at each end)
    assert case.state.time[0] == t[6] and case.state.time[-1] == t[-7]
    assert case.state.heave_velocity[44] == pytest.approx(
        -0.4 * np.pi * np.sin(2 * np.pi * t[50]), rel=0.02)
    # a start-up left out: the rates are those of the whole record, the samples start later
    later = read_csv_case(good, discard_s=0.5)
    kept = (t >= 0.5) & (np.arange(t.size) < t.size - 6)
    assert later.state.time[0] == pytest.approx(t[kept][0])
    assert later.cfd.time.shape == later.state.heave_velocity.shape == (kept.sum(),)
    assert later.state.heave_velocity == pytest.approx(
        case.state.heave_velocity[(t >= 0.5)[6:-6]])
    with pytest.raises(ParseError, match=r"run: 0 samples after the first 5 s left out "
                                         r"\(identification\.discard_time\)"):
        read_csv_case(good, discard_s=5.0)
    bad = tmp_path / "bad.csv"
    bad.write_text("\n".join([*rows[:10], "0.5,0.1,oops,1,1,1", *rows[10:]]) + "\n")
    with pytest.raises(ParseError, match=r"bad\.csv.*line 11"):
        read_csv_case(bad)
    missing = tmp_path / "missing.csv"
    missing.write_text("time,pitch_angle\n0,0\n")
    with pytest.raises(ParseError, match="missing column"):
        read_csv_case(missing)
    # the motion's checks name the file too (they said "<text>")
    short = tmp_path / "short.csv"
    short.write_text("\n".join(rows[:3]) + "\n")
    with pytest.raises(ParseError, match=rf"^{re.escape(str(short))}: short: 2 samples; .* at "
                                         "least 8"):
        read_csv_case(short)
    back = tmp_path / "back.csv"
    back.write_text("\n".join([*rows[:6], rows[4], *rows[7:]]) + "\n")
    with pytest.raises(ParseError, match=rf"^{re.escape(str(back))}: back: time must increase: "
                                         r"sample 5 \(t = 0\.0301508 s\) is not after sample 4"):
        read_csv_case(back)
    # one CSV alone is too few cases; the message says why the fixtures were not pooled
    from mfflap.cli.main import cli

    res = CliRunner().invoke(cli, ["gap", "diagnose", str(CASE), "--csv", str(good),
                                   "--output", str(tmp_path / "g.h5")])
    assert res.exit_code == 2 and "1 case(s) from --csv; a diagnosis needs at least 3" \
        in res.output and "--fixtures DIR" in res.output


@pytest.mark.slow
def test_gap_cli_on_a_record_folder(tmp_path):
    from mfflap.cli.main import cli

    data = synthesize(np.random.default_rng(3), "circulatory_lift", 4.0)
    folder = tmp_path / "records"
    for c in data:
        write_record(folder / f"{c.name}.h5", CfdRecord(c.name, c.state, c.cfd, c.parameters))
    out = tmp_path / "gap.h5"
    res = CliRunner().invoke(cli, ["gap", "diagnose", str(CASE), "--fixtures", str(folder),
                                   "--output", str(out), "--json"])
    assert res.exit_code == 0, res.output
    data_out = json.loads(res.output[res.output.index("{"):])
    assert data_out["chosen"] == "circulatory_lift"
    chosen = next(c for c in data_out["candidates"] if c["label"] == "circulatory_lift")
    assert set(chosen["held_coefficients"]) == set(chosen["variance_inflation"]) == {
        "circulatory_lift"}
    assert chosen["significant"] is True and chosen["variance_inflation"]["circulatory_lift"] >= 1
    html = out.with_suffix(".html").read_text()
    assert "Which unmodelled effect" in html and "coefficients, base terms held" in html
    assert "what it is" in html and "Claimed circulatory_lift, quasi-steady" in html
    # as text: the verdict, then the five largest shares under a heading that says what
    # the numbers are
    res = CliRunner().invoke(cli, ["gap", "diagnose", str(CASE), "--fixtures", str(folder),
                                   "--output", str(out)])
    assert res.exit_code == 0, res.output
    lines = res.output.splitlines()
    heading = next(i for i, line in enumerate(lines) if line.startswith("where the model"))
    assert "share of the squared residual" in lines[heading] and "eta^2" in lines[heading]
    shares = [float(line.rsplit(":", 1)[1]) for line in lines[heading + 1:heading + 6]]
    assert shares == sorted(shares, reverse=True) and all(0 <= v <= 1 for v in shares)
    assert "residuals scaled each component by its RMS over every case" in res.output
    # the claim in words: what the effect is, what its coefficient means, both values
    claim = next(line for line in lines if line.startswith("claimed "))
    assert claim.startswith("claimed circulatory_lift, quasi-steady circulatory lift: lift "
                            "slope a = dC_L/dalpha (thin-aerofoil theory: 2 pi) = ")
    assert f"{chosen['held_coefficients']['circulatory_lift']:.3g} fitted to the residual" in (
        claim)
    assert chosen["physical_names"] == ["quasi-steady circulatory lift"]
    with h5py.File(out) as h5:
        scores = h5["gap/scores"].attrs
        labels = json.loads(scores["labels"])
        held = json.loads(scores["held_coefficients"])[labels.index("circulatory_lift")]
        assert h5["gap"].attrs["residual_scaling"] == "grid"
        assert json.loads(h5["gap"].attrs["descriptions"])["wake_lag"]["physical_name"] == (
            "wake-lagged circulatory lift (Wagner function, Jones approximation)")
    assert held == pytest.approx(chosen["held_coefficients"])
    # the residuals scaled per case: said on screen, in the JSON, the file and the report
    res = CliRunner().invoke(cli, ["gap", "diagnose", str(CASE), "--fixtures", str(folder),
                                   "--output", str(out), "--set",
                                   'identification.residual_scaling="case"'])
    assert res.exit_code == 0, res.output
    assert "residuals scaled each component of each case by its range" in res.output
    with h5py.File(out) as h5:
        assert h5["gap"].attrs["residual_scaling"] == "case"
    assert 'residual_scaling = "case"' in out.with_suffix(".html").read_text().replace(
        "&quot;", '"')
    again = tmp_path / "again"
    write_record(again / f"{data[0].name}.h5",
                 CfdRecord(data[0].name, data[0].state, data[0].cfd, data[0].parameters))
    res = CliRunner().invoke(cli, ["gap", "diagnose", str(CASE), "--fixtures", str(folder),
                                   "--fixtures", str(again), "--output", str(out)])
    assert res.exit_code != 0
    assert f"case {data[0].name} has a record in {folder} and in {again}" in res.output


@pytest.mark.openfoam
def test_vorticity_at_the_largest_residual_from_real_openfoam_fields(tmp_path):
    """A real run that writes fields; the diagnosis report shows the flow at the residual peak."""
    from mfflap.cfd.openfoam.run_motion import run_motion
    from mfflap.cfd.openfoam.writer import SolverSettings
    from mfflap.cli.main import cli
    from mfflap.gap.flowfield import vorticity_field
    from mfflap.kinematics import HarmonicMotion

    records = tmp_path / "records"
    for c in synthesize(np.random.default_rng(1), NULL, 0.0, n_cases=3):
        write_record(records / f"{c.name}.h5", CfdRecord(c.name, c.state, c.cfd, c.parameters))
    motion = HarmonicMotion(1.0, 0.3, np.deg2rad(20), np.pi / 2)
    rec = run_motion(tmp_path / "of", motion, "live", {"frequency": 1.0}, 0.04,
                     solver=SolverSettings(write_interval=0.01))
    write_record(records / "live.h5", rec)
    xy, w, shown = vorticity_field(tmp_path / "of", 0.03)
    assert shown == pytest.approx(0.03, abs=1e-6) and xy.shape[0] == w.shape[0] > 1000
    # the strongest vorticity sits at the plate (within a chord of the leading edge)
    assert np.linalg.norm(xy[np.argmax(np.abs(w))]) < 0.2
    res = CliRunner().invoke(cli, ["gap", "diagnose", str(CASE), "--fixtures", str(records),
                                   "--flow", f"live={tmp_path / 'of'}", "--set",
                                   "identification.discard_time=0",
                                   "--output", str(tmp_path / "g.h5")])
    assert res.exit_code == 0, res.output
    assert "live: vorticity at t =" in (tmp_path / "g.html").read_text()
    # the flow of another run is refused: its vorticity would be of a motion the record
    # never had
    other = next(p.stem for p in sorted(records.glob("*.h5")) if p.stem != "live")
    res = CliRunner().invoke(cli, ["gap", "diagnose", str(CASE), "--fixtures", str(records),
                                   "--flow", f"{other}={tmp_path / 'of'}", "--set",
                                   "identification.discard_time=0",
                                   "--output", str(tmp_path / "g2.h5")])
    assert res.exit_code == 2
    assert f"{tmp_path / 'of'} is not the run of record {other}: it was written" in res.output
    assert not (tmp_path / "g2.h5").exists()


@pytest.mark.parametrize(("flow", "said"), [
    ("nocase", "'nocase': expected CASE=DIR, a record's case id and the OpenFOAM case folder"),
    ("=TMP", "'=TMP': expected CASE=DIR"),
    ("f1p000_h0p300_phi90p0=TMP", "no record 'f1p000_h0p300_phi90p0' among the 161 records; "
                                  "nearest: f1p000_h0p300_phi090p0,"),
    ("f1p000_h0p300_phi090p0=TMP/missing", "TMP/missing is not a folder"),
])
@pytest.mark.slow
def test_a_flow_folder_that_cannot_be_shown_is_refused_before_the_diagnosis(tmp_path, flow,
                                                                           said):
    """--flow is checked before the diagnosis runs (it was checked after it, and a case id
    mistyped got no hint), naming what is wrong."""
    from mfflap.cli.main import cli

    flow = flow.replace("TMP", str(tmp_path))
    res = CliRunner().invoke(cli, ["gap", "diagnose", str(CASE), "--flow", flow, "--output",
                                   str(tmp_path / "g.h5")])
    assert res.exit_code == 2, res.output
    assert "Invalid value for --flow" in res.output
    assert said.replace("TMP", str(tmp_path)) in " ".join(res.output.split())
    assert not (tmp_path / "g.h5").exists()


def test_a_flow_folder_of_another_plate_is_refused(tmp_path):
    """The run of the record's motion, but written for another chord: its vorticity is not
    this case's flow. Refused by --flow before the diagnosis (only the motion was checked)."""
    from mfflap.campaign.cases import CfdCase
    from mfflap.cfd.openfoam.writer import write_case
    from mfflap.cli.main import cli
    from mfflap.parameters import Plate
    from mfflap.records.record import fixture_dir, read_record

    name = "f1p000_h0p300_phi090p0"
    p = read_record(fixture_dir("table1_coarse") / f"{name}.h5").parameters
    case = CfdCase(p["frequency"], p["heave_amplitude"], p["phase_deg"],
                   p["pitch_ramp_rate_deg"], duration=p["duration"], ramp_time=p["ramp_time"])
    folder = write_case(tmp_path / "of", case.motion(), case.duration,
                        ramp_time=case.ramp_time, plate=Plate(chord=0.2))
    res = CliRunner().invoke(cli, ["gap", "diagnose", str(CASE), "--flow", f"{name}={folder}",
                                   "--output", str(tmp_path / "g.h5")])
    assert res.exit_code == 2, res.output
    assert (f"Invalid value for --flow: '{name}={folder}': plate.chord: 0.16 in the case "
            f"file, but {folder} was written for 0.2") in " ".join(res.output.split())
    assert "its flow field is not this case's" in " ".join(res.output.split())
    assert not (tmp_path / "g.h5").exists()


def test_a_candidate_the_chosen_one_does_not_beat_is_named_as_indistinguishable():
    from mfflap.gap.diagnose import CandidateScore, indistinguishable_from

    rng = np.random.default_rng(0)
    errors = rng.uniform(1.0, 2.0, 30)

    def score(name: str, sse: np.ndarray, significant: bool = True) -> CandidateScore:
        return CandidateScore((name,), sse, 0.3, 1e-4, significant, {}, {}, {})

    chosen = score("a", errors)
    twin = score("b", errors * rng.uniform(0.98, 1.02, 30))  # as good, case by case
    worse = score("c", errors * 1.5)                          # worse in every case
    weak = score("d", errors, significant=False)
    assert [s.names for s in indistinguishable_from(chosen, [chosen, twin, worse, weak],
                                                    0.01)] == [("b",)]


def test_the_gap_is_shown_beside_cfd_s_own_nrmse_known_per_case(tmp_path):
    """CFD's own NRMSE of each diagnosed case: its cycles against its mean cycle where the
    motion repeats (not for a pitch ramp, whose cycles differ by design), its mesh NRMSE
    where the record holds a refined run; stored with the diagnosis and read into the
    report's table as a median over the cases that have it."""
    import dataclasses

    from mfflap.config import CaseConfig
    from mfflap.gap.store import read_diagnosis, write_diagnosis
    from mfflap.gap.workflow import diagnose_cases
    from mfflap.records.refinement import RefinementChange
    from mfflap.reports.gap import gap_report
    from mfflap.results import ResultsFile

    cases = synthesize(np.random.default_rng(4), "circulatory_lift", 4.0, n_cases=12)
    mesh = RefinementChange("mesh", "r.h5", "refined", "0" * 64, 1.49, 2, 0.071, 0.98,
                            (1.0, 1.1), (2.0, 2.1), (3.0, 3.1), 0.5, 0.3, 0.2)
    repeating = {c.name for c in cases if c.frequency * (c.state.time[-1] - c.state.time[0])
                 >= 2.0}
    assert len(repeating) >= 2
    cases = [dataclasses.replace(c, parameters={**c.parameters, "kind": "harmonic"},
                                 refinement={"mesh": mesh} if i == 0 else {})
             if c.name in repeating or i == 0 else c for i, c in enumerate(cases)]
    diag, where, _ = diagnose_cases(CaseConfig(), cases)
    cycle = diag.gap["cfd_cycle"]["normal_force"]["nrmse"]
    assert np.isfinite(cycle).sum() == len(repeating)
    assert all(np.isfinite(v) == (c.name in repeating) for v, c in zip(cycle, cases,
                                                                        strict=True))
    assert np.all(cycle[np.isfinite(cycle)] > 0)
    mesh_nrmse = diag.gap["cfd_mesh"]["normal_force"]["nrmse"]
    assert mesh_nrmse[0] == 0.071 and np.isnan(mesh_nrmse[1:]).all()
    assert np.isnan(diag.gap["cfd_time_step"]["normal_force"]["nrmse"]).all()
    with ResultsFile(tmp_path / "gap.h5", "w") as rf:
        write_diagnosis(rf, diag, where)
    with ResultsFile(tmp_path / "gap.h5") as rf:
        back, _ = read_diagnosis(rf)
    np.testing.assert_array_equal(back.gap["cfd_cycle"]["normal_force"]["nrmse"], cycle)
    np.testing.assert_array_equal(back.gap["cfd_mesh"]["normal_force"]["nrmse"], mesh_nrmse)
    html = Path(gap_report(tmp_path / "gap.html", back, where)).read_text()
    assert "CFD mesh NRMSE [%]" in html and f"7.1 (1 of {len(cases)})" in html
    median = 100 * float(np.median(cycle[np.isfinite(cycle)]))
    assert f"{median:.1f} ({len(repeating)} of {len(cases)})" in html
