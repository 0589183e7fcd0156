"""Shared fixtures and the test tiers: fast (the default), full (``--full``: also real
OpenFOAM and the slow tests) and the replays of shipped series (``--replays``).

OpenBLAS runs whatever kernels and thread count it picks on the machine: no test depends
on them. The replays that follow a path round-off steers say so with the
``shipped_kernels`` marker and are skipped, saying why, where OpenBLAS runs otherwise.
"""

import importlib.util
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path
from types import ModuleType

import numpy as np
import pytest
from openblas_kernels import unlike_the_shipped_series

from mfflap.hydro import MorisonModel


def pytest_addoption(parser: pytest.Parser) -> None:
    parser.addoption("--full", action="store_true",
                     help="the full tier: also the tests marked openfoam (real OpenFOAM runs) "
                          "and slow; without it, the fast tier runs")
    parser.addoption("--replays", action="store_true",
                     help="the replays of the shipped series of rounds (marked replay, "
                          "2-6 minutes each), which no other tier runs")


#: the markers of the tests only the full tier runs
FULL_TIER_MARKERS = ("openfoam", "slow")


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    """The fast tier (the default) deselects the tests marked openfoam or slow; ``--full``
    runs them all. A ``-m`` expression given on the command line chooses instead. The
    replays (marked replay) run with ``--replays`` only, alone."""
    replays = config.getoption("--replays")
    every_tier = bool(config.getoption("--full") or config.getoption("-m"))
    kept, dropped = [], []
    for item in items:
        replay = item.get_closest_marker("replay") is not None
        full = any(item.get_closest_marker(m) is not None for m in FULL_TIER_MARKERS)
        keep = replay if replays else not replay and (every_tier or not full)
        (kept if keep else dropped).append(item)
    if dropped:
        config.hook.pytest_deselected(items=dropped)
        items[:] = kept


def pytest_runtest_setup(item: pytest.Item) -> None:
    """Skip a test marked ``shipped_kernels`` where OpenBLAS runs other kernels or another
    thread count than the shipped series of rounds were computed with, saying which: there
    the series take other steps from round 2 on, as docs/findings/known_limits.md say, and
    the test's assertions are those steps."""
    if item.get_closest_marker("shipped_kernels") is not None:
        why = unlike_the_shipped_series()
        if why is not None:
            pytest.skip(why)


@pytest.fixture()
def model() -> MorisonModel:
    return MorisonModel()


@pytest.fixture()
def rng() -> np.random.Generator:
    return np.random.default_rng(12345)


@pytest.fixture(scope="session")
def optimisation_file(tmp_path_factory) -> Path:
    """A real optimisation of cases/paper2026.toml (β = 0.5, one SQP start, about 8 s)."""
    from click.testing import CliRunner

    from mfflap.cli.main import cli

    case = Path(__file__).parents[1] / "cases" / "paper2026.toml"
    out = tmp_path_factory.mktemp("opt") / "opt.h5"
    res = CliRunner().invoke(cli, ["optimise", str(case), "--betas", "0.5", "--set",
                                   "optimisation.starts=1", "--set", "optimisation.ipopt=false",
                                   "--set", "optimisation.coefficients=case",
                                   "--set", "optimisation.gain_table=false", "--set",
                                   "optimisation.phase=free", "--output", str(out)])
    assert res.exit_code == 0, res.output
    return out


@pytest.fixture(scope="session")
def load_benchmark():
    """A loader of the scripts in benchmarks/ (not a package) by file name, each loaded once
    per session and registered in sys.modules (dataclasses look their module up by name)
    until the session ends."""
    loaded: dict[str, ModuleType] = {}

    def load(script: str) -> ModuleType:
        if script not in loaded:
            name = f"benchmarks_{Path(script).stem}"
            path = Path(__file__).resolve().parents[1] / "benchmarks" / script
            spec = importlib.util.spec_from_file_location(name, path)
            module = importlib.util.module_from_spec(spec)
            sys.modules[name] = module
            spec.loader.exec_module(module)
            loaded[script] = module
        return loaded[script]

    yield load
    for module in loaded.values():
        sys.modules.pop(module.__name__, None)


@pytest.fixture()
def solvers_left() -> Callable[..., str]:
    """A function of a ``pgrep -f`` pattern: the command lines of the processes matching it
    that still run after waiting up to ``wait_s`` for them to end ("" if none). A signalled
    solver takes a moment to write its fields and stop, longer on a loaded machine, so a
    test that a stop left no solver behind polls instead of sleeping a fixed time."""

    def left(pattern: str, wait_s: float = 60.0) -> str:
        deadline = time.monotonic() + wait_s
        while True:
            found = subprocess.run(["pgrep", "-a", "-f", pattern], capture_output=True,
                                   text=True).stdout
            if not found or time.monotonic() >= deadline:
                return found
            time.sleep(0.2)

    return left


@pytest.fixture()
def sigterm_before(monkeypatch) -> Callable[..., None]:
    """``sigterm_before(module, name, beta)``: wrap ``module.name`` (an optimiser taking a
    problem first) so that this process is sent a real SIGTERM as it starts on the problem
    of that beta, then runs it; the stop lands at a known place in a study."""
    import os
    import signal

    def wrap(module, name: str, beta: float) -> None:
        real = getattr(module, name)

        def stopped_at_beta(problem, *args, **kwargs):
            if problem.beta == beta:
                os.kill(os.getpid(), signal.SIGTERM)
            return real(problem, *args, **kwargs)

        monkeypatch.setattr(module, name, stopped_at_beta)

    return wrap
