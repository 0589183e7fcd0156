"""Optimisers: SQP with the adjoint vs IPOPT, non-convergence, artefact flags, storage, CLI."""

import json
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest
from click.testing import CliRunner

from mfflap.config import load_case
from mfflap.errors import ConfigError
from mfflap.kinematics.convert import harmonic_to_discrete
from mfflap.optimisation.optimise import assess, optimise_ipopt, optimise_sqp
from mfflap.optimisation.problem import FlappingProblem
from mfflap.optimisation.store import read_result, read_sweep, write_result
from mfflap.results import ResultsFile

#: one start and no IPOPT comparison or gain table unless asked: the quick optimisation
# with the case file's coefficients: no identification first (what these tests are not about)
ONE_START_NO_IPOPT = ("--set", "optimisation.starts=1", "--set", "optimisation.ipopt=false",
                      "--set", "optimisation.gain_table=false",
                      "--set", "optimisation.coefficients=case")
CASE = Path(__file__).parents[2] / "cases" / "paper2026.toml"
START = harmonic_to_discrete(2.1, 0.05, np.deg2rad(50), np.deg2rad(112.5), 30)


def problem(beta, **kw):
    c = load_case(CASE)
    o = c.optimisation
    args = {"max_power": o.max_power, "max_heave": o.max_heave, "penalty_power": o.penalty_power,
            "penalty_heave": o.penalty_heave, "smoothing_pitch": o.smoothing_pitch,
            "smoothing_heave": o.smoothing_heave, "scheme": "midpoint", **kw}
    return FlappingProblem(c.morison_model(), beta, **args)


def test_sqp_and_ipopt_reach_the_same_optimum():
    p = problem(0.5)
    sqp = optimise_sqp(p, START, min_period=0.2, max_period=20.0)
    ipo = optimise_ipopt(p, START, min_period=0.2, max_period=20.0)
    assert sqp.converged and ipo.converged
    assert sqp.objective < float(p.objective(START))  # improved on the start
    assert float(sqp.summary.mean_thrust) == pytest.approx(float(ipo.summary.mean_thrust),
                                                           rel=0.02)
    assert float(sqp.motion.period) == pytest.approx(float(ipo.motion.period), rel=0.05)
    # the hard constraints hold at the samples
    assert float(ipo.summary.max_power) <= p.max_power * (1 + 1e-6)
    # the penalty optimum violates P_max only slightly at sigma_P = 10
    assert float(sqp.summary.max_power) <= p.max_power * 1.02
    # the optimum is a stationary point of the penalised objective
    g = p.gradient(sqp.motion).flat()
    g0 = p.gradient(START).flat()
    assert np.linalg.norm(g[:-1]) < 1e-2 * np.linalg.norm(g0[:-1])


@pytest.mark.slow
def test_beta0_optimum_beats_the_starting_sinusoid_under_the_power_limit():
    p = problem(0.0)
    r = optimise_sqp(p, START, min_period=0.2, max_period=20.0)
    base = assess(p, START)[0]
    assert float(r.summary.mean_thrust) > 1.2 * float(base.mean_thrust)
    assert float(r.summary.max_power) < 1.02 * p.max_power
    assert np.all(np.diff(r.history[: 5]) <= 1e-9) or len(r.history) < 5


def test_non_convergence_is_reported_with_the_last_iterate():
    p = problem(0.0)
    r = optimise_sqp(p, START, min_period=0.2, max_period=20.0, max_iterations=2,
                     continuation=(1.0,))
    assert not r.converged
    assert "Iteration limit" in r.message or "iteration" in r.message.lower()
    assert r.motion.n_steps == START.n_steps and np.isfinite(r.objective)


def test_bad_continuation_and_period_bounds_are_refused():
    p = problem(0.0)
    with pytest.raises(ConfigError, match=r"ending at 1\.0"):
        optimise_sqp(p, START, min_period=0.2, max_period=20.0, continuation=(0.1, 0.5))
    from mfflap.config import loads_case
    with pytest.raises(ConfigError, match="exclude every period"):
        loads_case("[optimisation]\nmin_period = 5.0\nmax_period = 1.0\n")


def test_artefact_flags():
    """A sinusoid whose sampled peak power is near P_max but whose true peak is far above."""
    coarse = harmonic_to_discrete(2.0, 0.3, np.deg2rad(30), np.deg2rad(90), 4)
    p = problem(0.0, scheme="paper", max_power=1e9)
    s, peak, _ = assess(p, coarse)
    p_tight = problem(0.0, scheme="paper", max_power=float(s.max_power))
    _, peak2, flags2 = assess(p_tight, coarse)
    assert peak2 == pytest.approx(peak)
    if peak > 1.05 * float(s.max_power):
        assert any("after resampling" in f for f in flags2)
    # the paper scheme's energy residual at N = 4 is a large share of the mean power
    assert any("energy residual" in f for f in flags2)
    fine = harmonic_to_discrete(0.5, 0.1, np.deg2rad(10), np.deg2rad(90), 200)
    assert assess(problem(0.0, max_power=1e9), fine)[2] == []


def test_result_round_trip(tmp_path):
    p = problem(0.5)
    r = optimise_sqp(p, START, min_period=0.2, max_period=20.0, max_iterations=5)
    with ResultsFile(tmp_path / "o.h5", "w", kind="optimisation") as rf:
        write_result(rf, "opt/beta_0.50", r, {"n_steps": 30, "scheme": "midpoint"})
    with ResultsFile(tmp_path / "o.h5") as rf:
        back = read_result(rf, "opt/beta_0.50")
        assert rf.h5["opt/beta_0.50"].attrs["setting_scheme"] == "midpoint"
    np.testing.assert_array_equal(back.motion.pitch_acceleration, r.motion.pitch_acceleration)
    assert back.converged == r.converged and back.flags == r.flags


@pytest.mark.slow
def test_optimise_cli_writes_results_and_report(tmp_path):
    out = tmp_path / "opt.h5"
    res = CliRunner().invoke(__import__("mfflap.cli.main", fromlist=["cli"]).cli,
                             ["optimise", str(CASE), "--betas", "0.5", *ONE_START_NO_IPOPT,
                              "--output", str(out), "--json"])
    assert res.exit_code == 0, res.output
    data = json.loads(res.output[res.output.index("{"):])
    assert data["optimised"]["0.5"]["converged"] is True
    # beta = 0 was not optimised: no "beta = 0 gain" from the beta = 0.5 motion
    assert data["thrust_gain_beta0"] is None and data["thrust_gain_beta0_refined"] is None
    assert data["thrust_gain_beta0_missing"] == "beta = 0 was not optimised"
    html = out.with_suffix(".html").read_text()
    assert html.count("<img") >= 3 and "Pareto" in html
    assert "not given: beta = 0 was not optimised" in html
    with ResultsFile(out) as rf:
        assert "optimisation/sqp/beta_0.50/motion" in rf.h5
        assert rf.h5["optimisation/sweep/mean_thrust"].attrs["units"] == "N"
        assert np.isnan(rf.h5["optimisation"].attrs["thrust_gain_beta0"])
        assert rf.h5["optimisation"].attrs["thrust_gain_beta0_missing"] == \
            "beta = 0 was not optimised"
        assert np.isnan(rf.h5["optimisation"].attrs["interrupted_beta"])  # ran to the end
        assert rf.h5["optimisation"].attrs["betas_not_optimised"].size == 0
    assert "Incomplete" not in html


def test_thrust_gain_is_not_a_ratio_to_a_drag():
    from mfflap.performance import thrust_gain

    assert thrust_gain(1.5, 1.0) == pytest.approx(0.5)
    assert thrust_gain(-0.01, 1.0) == pytest.approx(-1.01)
    for baseline in (0.0, -0.07, np.nan, np.inf):
        assert thrust_gain(-0.01, baseline) is None


@pytest.mark.slow
def test_no_gain_is_given_when_the_best_sinusoid_makes_drag(tmp_path):
    """With P_max = 1 mW every feasible sinusoid makes drag: the ratio of beta = 0's thrust
    to it (-85 % for a drag cut from 0.075 N to 0.011 N) is no gain and is not given."""
    case = tmp_path / "tiny_power.toml"
    case.write_text(CASE.read_text().replace("max_power = 50.0", "max_power = 0.001"))
    out = tmp_path / "opt.h5"
    runner = CliRunner()
    cli = __import__("mfflap.cli.main", fromlist=["cli"]).cli
    res = runner.invoke(cli, ["optimise", str(case), "--betas", "0", *ONE_START_NO_IPOPT,
                              "--output", str(out)])
    assert res.exit_code == 0, res.output
    assert "beta = 0 thrust gain: not given: the best feasible sinusoid makes no thrust" \
        in res.output
    # why the optimum is flagged (and, if so, not converged) is said under its line
    with ResultsFile(out) as rf:
        result = read_result(rf, "optimisation/sqp/beta_0.00")
    assert result.flags and all(f"    flagged: {flag}" in res.output for flag in result.flags)
    if not result.converged:
        assert f"    not converged after {result.n_iterations} iterations: " \
               f"{result.message}" in res.output
    with ResultsFile(out) as rf:
        sweep, best = read_sweep(rf, "optimisation/sweep")
        assert sweep.mean_thrust[best] < 0
        assert np.isnan(rf.h5["optimisation"].attrs["thrust_gain_beta0"])
    html = out.with_suffix(".html").read_text()
    assert ("thrust gain over the best feasible sinusoid: not given: the best feasible "
            "sinusoid makes no thrust") in html


@pytest.mark.slow
def test_a_gain_from_a_flagged_beta_0_optimum_says_so(tmp_path):
    """N = 2 steps per half cycle: the beta = 0 optimum is flagged (the scheme's energy
    error, peaks between the steps); its gain is still given, with the doubt beside it in
    the text, the JSON, the HDF5 file and the report (it was given as if sound)."""
    case = tmp_path / "n2.toml"
    case.write_text(CASE.read_text().replace("n_steps = 50", "n_steps = 2"))
    out = tmp_path / "opt.h5"
    cli = __import__("mfflap.cli.main", fromlist=["cli"]).cli
    args = ["optimise", str(case), "--betas", "0", *ONE_START_NO_IPOPT, "--output",
            str(out)]
    res = CliRunner().invoke(cli, args)
    assert res.exit_code == 0, res.output
    with ResultsFile(out) as rf:
        result = read_result(rf, "optimisation/sqp/beta_0.00")
        caveat = rf.h5["optimisation"].attrs["thrust_gain_beta0_caveat"]
        assert np.isfinite(rf.h5["optimisation"].attrs["thrust_gain_beta0"])
    n = len(result.flags)
    assert n >= 1 and caveat == (f"the beta = 0 optimum it is computed from is flagged ({n} "
                                 f"flag{'s' if n > 1 else ''}): the gain inherits that doubt")
    assert f"; caution: {caveat}" in res.output
    assert f"Caution: {caveat}." in out.with_suffix(".html").read_text()
    data = json.loads(CliRunner().invoke(cli, [*args, "--json"]).stdout)
    assert data["thrust_gain_beta0"] is not None and data["thrust_gain_beta0_caveat"] == caveat


def test_a_sound_beta_0_optimum_gives_its_gain_without_a_caveat():
    from mfflap.optimisation.study import BetaStudy

    sound = SimpleNamespace(converged=True, flags=[],
                            summary=SimpleNamespace(mean_thrust=3.0))
    study = BetaStudy(sweep=SimpleNamespace(mean_thrust=np.array([2.0])), best_sinusoid=0,
                      sqp={0.0: sound}, sqp_all={})
    assert study.thrust_gain == pytest.approx(0.5) and study.thrust_gain_caveat is None
    study.sqp[0.0] = SimpleNamespace(converged=False, flags=["a", "b"],
                                     summary=SimpleNamespace(mean_thrust=3.0))
    assert study.thrust_gain_caveat == ("the beta = 0 optimum it is computed from did not "
                                        "converge and is flagged (2 flags): the gain inherits "
                                        "that doubt")
    study.sweep = SimpleNamespace(mean_thrust=np.array([-1.0]))  # no gain: nothing to doubt
    assert study.thrust_gain is None and study.thrust_gain_caveat is None


def test_refined_sinusoid_is_feasible_and_no_worse_than_the_grid():
    from mfflap.optimisation.refine import refine_best_sinusoid
    from mfflap.sweep import sinusoid_sweep

    c = load_case(CASE)
    model = c.morison_model()
    sweep = sinusoid_sweep(model, np.linspace(0.5, 2.5, 6), np.linspace(0.05, 0.3, 4),
                           np.deg2rad(np.linspace(10, 50, 5)), np.deg2rad([60, 90, 120]),
                           n_steps=30, max_power=50.0)
    r = refine_best_sinusoid(model, sweep, 30, 50.0, 0.5, 0.2, 20.0)
    assert r.max_power <= 50.0 * (1 + 1e-6)
    assert r.mean_thrust >= r.grid_thrust
    assert r.mean_thrust > 1.01 * r.grid_thrust  # a coarse grid leaves room to improve
    # SLSQP converges (the limit at every sample has no kink) and ends on the limit
    assert r.success, r.message
    assert r.max_power == pytest.approx(50.0, rel=1e-4)


def test_gain_table_entries_say_which_optimum_is_in_doubt():
    """Each (N, smoothing) entry: the gain over the best feasible sinusoid, and its progress
    line says when its beta = 0 optimum is flagged or did not converge (every entry of the
    paper's case is flagged, and the lines read as sound)."""
    from mfflap.optimisation.study import gain_table

    config = load_case(CASE)
    lines: list[str] = []
    table = gain_table(config, n_steps=(2, 25), smoothing_factors=(1.0,),
                       progress=lines.append)
    lines = [line for line in lines if line.startswith("gain table")]  # not the sweep's
    assert table["gain"].shape == (2, 1) and len(lines) == 2
    np.testing.assert_allclose(table["gain"][:, 0],
                               table["thrust"][:, 0] / float(table["baseline_thrust"]) - 1.0)
    assert table["flagged"][0, 0]  # N = 2: the scheme's energy error carries it
    for line, flagged in zip(lines, table["flagged"][:, 0], strict=True):
        assert ("flagged" in line) == bool(flagged), line


@pytest.fixture
def ctrl_c_raises():
    """SIGINT raises KeyboardInterrupt, as in an interactive Python: a process started in
    the background (CI's, with nohup) inherits SIGINT ignored, and Python then leaves it
    so."""
    import signal

    before = signal.signal(signal.SIGINT, signal.default_int_handler)
    yield
    signal.signal(signal.SIGINT, before)


def _sigint_at_iteration(k: int):
    """A CasADi iteration callback that sends this process SIGINT (a Ctrl-C) at IPOPT's
    iteration ``k``: deterministically inside the solve."""
    import os
    import signal

    import casadi as ca

    class SendSigint(ca.Callback):
        def __init__(self, nx: int, ng: int):
            ca.Callback.__init__(self)
            self.nx, self.ng, self.calls = nx, ng, 0
            self.construct("send_sigint", {})

        def get_n_in(self):
            return ca.nlpsol_n_out()

        def get_n_out(self):
            return 1

        def get_name_in(self, i):
            return ca.nlpsol_out(i)

        def get_name_out(self, i):
            return "ret"

        def get_sparsity_in(self, i):
            name = ca.nlpsol_out(i)
            if name in ("f",):
                return ca.Sparsity.scalar()
            if name in ("x", "lam_x"):
                return ca.Sparsity.dense(self.nx)
            if name in ("g", "lam_g"):
                return ca.Sparsity.dense(self.ng)
            return ca.Sparsity(0, 0)

        def eval(self, arg):
            self.calls += 1
            if self.calls == k:
                os.kill(os.getpid(), signal.SIGINT)
            return [0]

    return SendSigint


def _rosenbrock_solver(iteration_callback):
    import casadi as ca

    n = 40
    x = ca.SX.sym("x", n)
    f = ca.sum1(100 * (x[1:] - x[:-1] ** 2) ** 2 + (1 - x[:-1]) ** 2)
    callback = iteration_callback(n, 0)
    solver = ca.nlpsol("r", "ipopt", {"x": x, "f": f},
                       {"ipopt.print_level": 0, "print_time": False, "ipopt.sb": "yes",
                        "iteration_callback": callback})
    solver.callback = callback  # CasADi keeps no reference of its own
    return solver, np.full(n, -1.2)


def test_casadi_swallows_a_ctrl_c_in_ipopt_and_interrupts_kept_raises_it_again(ctrl_c_raises):
    """The premise, on real IPOPT: a SIGINT at iteration 3 makes CasADi return a stopped
    solve (User_Requested_Stop from a callback, NonIpopt_Exception_Thrown from IPOPT's own
    iterations, as in optimise_ipopt) instead of raising; within interrupts_kept the
    KeyboardInterrupt reaches the caller. A SIGTERM handled by mfflap's commands
    (StopRequested) likewise."""
    import signal

    from mfflap.cli.stop_signals import StopRequested, stop_signals_as_interrupt
    from mfflap.optimisation.interrupts import interrupts_kept

    solver, x0 = _rosenbrock_solver(_sigint_at_iteration(3))
    solver(x0=x0)  # returns: the interrupt is swallowed, the solve said stopped
    assert solver.stats()["return_status"] in ("User_Requested_Stop",
                                               "NonIpopt_Exception_Thrown")
    solver, x0 = _rosenbrock_solver(_sigint_at_iteration(3))
    with pytest.raises(KeyboardInterrupt), interrupts_kept():
        solver(x0=x0)
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler  # restored
    with interrupts_kept():  # nothing raised, nothing kept: the solve's result stands
        solved, x0 = _rosenbrock_solver(_sigint_at_iteration(10**9))
        solved(x0=x0)
    assert solved.stats()["success"]

    def sigterm_at_iteration(nx, ng):
        import os

        class SendSigterm(_sigint_at_iteration(3)):
            def eval(self, arg):
                self.calls += 1
                if self.calls == 3:
                    os.kill(os.getpid(), signal.SIGTERM)
                return [0]

        return SendSigterm(nx, ng)

    solver, x0 = _rosenbrock_solver(sigterm_at_iteration)
    with pytest.raises(StopRequested, match="SIGTERM"), stop_signals_as_interrupt(), \
            interrupts_kept():
        solver(x0=x0)


@pytest.mark.slow
def test_ctrl_c_during_optimise_ipopt_stops_it(capfd, ctrl_c_raises):
    """A SIGINT while IPOPT iterates in optimise_ipopt (its NLP built beforehand, so the
    signal lands in the solve: CasADi's warning says so) raises KeyboardInterrupt instead of
    returning a half-solved motion."""
    import os
    import signal
    import threading

    from mfflap.optimisation.optimise import _ipopt_solver

    p = problem(0.5)
    n = 120  # about 1.5 s of IPOPT here
    _ipopt_solver(p, n, 100000, 1e-14)
    start = harmonic_to_discrete(2.1, 0.05, np.deg2rad(50), np.deg2rad(112.5), n)
    timer = threading.Timer(0.3, lambda: os.kill(os.getpid(), signal.SIGINT))
    timer.start()
    try:
        with pytest.raises(KeyboardInterrupt):
            optimise_ipopt(p, start, min_period=0.2, max_period=20.0, max_iterations=100000,
                           tolerance=1e-14)
    finally:
        timer.cancel()
    assert "KeyboardInterruptException" in capfd.readouterr().err


@pytest.mark.slow
def test_a_stop_signal_between_betas_keeps_the_betas_optimised_before_it():
    """A SIGTERM (SLURM's stop; a Ctrl-C alike) while beta = 0.75 is optimised: the study
    raises StudyInterrupted, a KeyboardInterrupt, holding beta = 0.5 and the sweep; the
    stopped beta is dropped, though one of its starts had finished."""
    import os
    import signal

    from mfflap.cli.stop_signals import stop_signals_as_interrupt
    from mfflap.optimisation.study import StudyInterrupted, beta_study
    from mfflap.sweep import sinusoid_sweep

    config = load_case(CASE)
    model = config.morison_model()
    o = config.optimisation
    sweep = sinusoid_sweep(model, np.linspace(0.5, 2.5, 5), np.linspace(0.05, 0.3, 3),
                           np.deg2rad([20, 40]), np.deg2rad([90]), n_steps=o.n_steps,
                           max_power=o.max_power)

    def progress(message: str) -> None:
        if message.startswith("beta 0.75 from"):  # inside the beta's multistart
            os.kill(os.getpid(), signal.SIGTERM)

    with pytest.raises(StudyInterrupted) as caught, stop_signals_as_interrupt():
        beta_study(config, [0.5, 0.75, 1.0], n_starts=1, with_ipopt=False, model=model,
                   sweep=sweep, progress=progress)
    assert isinstance(caught.value, KeyboardInterrupt)
    study = caught.value.study
    assert list(study.sqp) == [0.5] and list(study.sqp_all) == [0.5] and study.ipopt == {}
    assert study.sqp[0.5].converged and study.sweep is sweep
    assert study.interrupted_beta == 0.75 and study.betas_not_optimised == (0.75, 1.0)
    assert study.interruption == ("interrupted during beta = 0.75: beta 0.75, 1 not "
                                  "optimised (optimised: 0.5)")
    assert str(caught.value) == study.interruption


@pytest.mark.slow
def test_an_interrupted_optimise_writes_the_betas_optimised_before_it(tmp_path,
                                                                     sigterm_before):
    """`mfflap optimise` stopped by SIGTERM during beta = 0.75 (sent as its optimisation
    starts): exit 1, the message says what was left out, and the results file and the
    report hold beta = 0.5 and say the study is incomplete (before, nothing was written)."""
    import mfflap.optimisation.study as study_module

    sigterm_before(study_module, "multistart", 0.75)
    out = tmp_path / "opt.h5"
    res = CliRunner().invoke(__import__("mfflap.cli.main", fromlist=["cli"]).cli,
                             ["optimise", str(CASE), "--betas", "0.5,0.75,1", *ONE_START_NO_IPOPT,
                              "--output", str(out)])
    assert res.exit_code == 1, res.output
    html = out.with_suffix(".html")
    assert (f"interrupted during beta = 0.75: beta 0.75, 1 not optimised (optimised: 0.5); "
            f"wrote those optimised to {out} and {html}") in res.output
    with ResultsFile(out) as rf:
        assert list(rf.h5["optimisation/sqp"]) == ["beta_0.50"]
        assert rf.h5["optimisation"].attrs["interrupted_beta"] == 0.75
        np.testing.assert_array_equal(rf.h5["optimisation"].attrs["betas_not_optimised"],
                                      [0.75, 1.0])
        assert "optimisation/sweep/mean_thrust" in rf.h5
    assert ("Incomplete: interrupted during beta = 0.75: beta 0.75, 1 not optimised "
            "(optimised: 0.5).") in html.read_text()


@pytest.mark.slow
def test_a_stop_during_the_gain_table_writes_the_beta_study_without_it(tmp_path,
                                                                       sigterm_before):
    """SIGTERM as the gain table's first beta = 0 optimisation starts: the beta study
    (beta = 0.5, finished) is written whole, without a gain table, and the message says so."""
    import mfflap.optimisation.study as study_module

    # only the gain table's problems have beta = 0: the study's beta is 0.5
    sigterm_before(study_module, "optimise_sqp", 0.0)
    out = tmp_path / "opt.h5"
    res = CliRunner().invoke(__import__("mfflap.cli.main", fromlist=["cli"]).cli,
                             ["optimise", str(CASE), "--betas", "0.5", *ONE_START_NO_IPOPT,
                              "--set", "optimisation.gain_table=true", "--output", str(out)])
    assert res.exit_code == 1, res.output
    assert (f"interrupted during the gain table; wrote the beta study without it to {out}"
            in res.output)
    with ResultsFile(out) as rf:
        assert list(rf.h5["optimisation/sqp"]) == ["beta_0.50"]
        assert "optimisation/gain_table" not in rf.h5
        assert np.isnan(rf.h5["optimisation"].attrs["interrupted_beta"])


ENVELOPE = {"max_pitch": np.deg2rad(40.0), "max_pitch_rate": 3.0,
            "max_pitch_acceleration": 40.0}


def _pitch_peaks(p, motion):
    st = motion.states(p.scheme)
    return np.array([np.max(np.abs(st.pitch_angle)), np.max(np.abs(st.pitch_rate)),
                     np.max(np.abs(st.pitch_acceleration))])


def test_the_pitch_envelope_holds_the_optimum_within_it():
    """The start pitches at 50 deg and 2.1 Hz, beyond every limit; IPOPT keeps the optimum
    within them at every sample, the penalised SQP within 2 % (sigma_theta = 1e4), and
    without the envelope the optimum leaves it."""
    limits = np.array(list(ENVELOPE.values()))
    free = problem(0.0)
    held = problem(0.0, **ENVELOPE)
    assert np.all(_pitch_peaks(held, START) > limits)
    r_free = optimise_sqp(free, START, min_period=0.2, max_period=20.0)
    r_sqp = optimise_sqp(held, START, min_period=0.2, max_period=20.0)
    r_ipopt = optimise_ipopt(held, START, min_period=0.2, max_period=20.0)
    assert r_sqp.converged and r_ipopt.converged
    assert np.any(_pitch_peaks(free, r_free.motion) > 1.1 * limits)
    assert np.all(_pitch_peaks(held, r_sqp.motion) <= 1.02 * limits)
    assert np.all(_pitch_peaks(held, r_ipopt.motion) <= limits * (1 + 1e-6))
    # the envelope costs thrust, and the two optimisers agree on how much
    assert float(r_sqp.summary.mean_thrust) < float(r_free.summary.mean_thrust)
    assert float(r_sqp.summary.mean_thrust) == pytest.approx(
        float(r_ipopt.summary.mean_thrust), rel=0.05)


def test_the_sweep_and_the_refined_sinusoid_keep_within_the_pitch_envelope():
    from dataclasses import replace

    from mfflap.optimisation.refine import refine_best_sinusoid
    from mfflap.optimisation.study import default_sweep, within_pitch_envelope

    c = load_case(CASE)
    inside = within_pitch_envelope([0.8, 0.8, 2.0], np.deg2rad([30.0, 45.0, 30.0]),
                                   **ENVELOPE)
    # 45 deg exceeds the amplitude; at 2 Hz 30 deg pitches at 6.6 rad/s
    assert inside.tolist() == [True, False, False]
    o = replace(c.optimisation, max_pitch_deg=40.0, max_pitch_rate=3.0,
                max_pitch_acceleration=40.0)
    limited = replace(c, optimisation=o)
    sweep = default_sweep(limited)
    best = sweep.best_feasible()
    w = 2 * np.pi * sweep.frequency[best]
    a = sweep.pitch_amplitude[best]
    assert a <= np.deg2rad(40.0) and w * a <= 3.0 and w**2 * a <= 40.0
    assert sweep.feasible.sum() < default_sweep(c).feasible.sum()
    env = {k: v for k, v in o.pitch_envelope().items() if k != "penalty_pitch"}
    r = refine_best_sinusoid(c.morison_model(), sweep, 30, o.max_power, o.max_heave,
                             o.min_period, o.max_period, pitch_envelope=env)
    w = 2 * np.pi * r.frequency
    assert r.pitch_amplitude <= np.deg2rad(40.0) * (1 + 1e-6)
    assert w * r.pitch_amplitude <= 3.0 * (1 + 1e-6)
    assert r.mean_thrust >= r.grid_thrust


def test_the_pitch_envelope_is_read_from_the_case_file_and_checked():
    from mfflap.config import loads_case
    from mfflap.optimisation.study import problem_for

    text = CASE.read_text().replace("[optimisation]\n", "[optimisation]\nmax_pitch_deg = 40.0\n"
                                    "max_pitch_rate = 3.0\n", 1)
    c = loads_case(text)
    p = problem_for(c, 0.0)
    assert p.max_pitch == pytest.approx(np.deg2rad(40.0)) and p.max_pitch_rate == 3.0
    assert p.max_pitch_acceleration == np.inf  # left out: no limit
    assert problem_for(load_case(CASE), 0.0).max_pitch == np.inf
    bad = CASE.read_text().replace("[optimisation]\n", "[optimisation]\nmax_pitch_rate = -1\n",
                                   1)
    with pytest.raises(ConfigError, match=r"optimisation\.max_pitch_rate"):
        loads_case(bad)


def test_the_optimisers_run_on_one_blas_thread_whatever_the_environment_sets(monkeypatch):
    """Inside the block the BLAS libraries run one thread and get their count back after
    it, also where the environment asks for two (a count meant for other algebra: with it
    and a CFD run on the other core the gain table's SLSQP ran for minutes)."""
    from threadpoolctl import threadpool_info, threadpool_limits

    from mfflap.optimisation.blas_threads import optimiser_blas_threads

    def blas_threads():
        return [lib["num_threads"] for lib in threadpool_info() if lib["user_api"] == "blas"]

    with threadpool_limits(limits=2, user_api="blas"):
        before = blas_threads()
        for environment in ({}, {"OPENBLAS_NUM_THREADS": "2", "OMP_NUM_THREADS": "2"}):
            for name, value in environment.items():
                monkeypatch.setenv(name, value)
            with optimiser_blas_threads():
                assert blas_threads() and set(blas_threads()) == {1}
            assert blas_threads() == before


def test_optimise_uses_the_coefficients_run_uses_and_says_which_first(tmp_path):
    """By default both identify from the shipped CFD with the uniform weighting: the same
    model, so the same optimum from the same start; the first line says which."""
    from mfflap.api import Study

    cli = __import__("mfflap.cli.main", fromlist=["cli"]).cli
    out = tmp_path / "opt.h5"
    res = CliRunner().invoke(cli, ["optimise", str(CASE), "--betas", "0.5", "--set",
                                   "optimisation.starts=1", "--set", "optimisation.ipopt=false",
                                   "--set", "optimisation.gain_table=false", "--output",
                                   str(out), "--json"])
    assert res.exit_code == 0, res.output
    first = res.stderr.splitlines()[0]
    assert first.startswith("optimising with the coefficients identified from the shipped "
                            "CFD records with the uniform weighting")
    study = Study.from_toml(CASE)
    study.identify(bootstrap=0)
    for term, value in study.model.coefficients.items():
        assert f"{term} = {value:.4g}" in first
    with ResultsFile(out) as rf:
        stored = json.loads(rf.h5["optimisation"].attrs["model_coefficients"])
    assert stored == pytest.approx(dict(study.model.coefficients))
    case = CliRunner().invoke(cli, ["optimise", str(CASE), "--betas", "0.5", *ONE_START_NO_IPOPT,
                                    "--output", str(tmp_path / "case.h5")])
    assert case.stderr.splitlines()[0].startswith(
        "optimising with the case file's [model.coefficients]: ")
