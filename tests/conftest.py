from pathlib import Path

import numpy as np
import pytest

from mfflap.hydro import MorisonModel


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
    res = CliRunner().invoke(cli, ["optimise", str(case), "--betas", "0.5", "--starts", "1",
                                   "--no-ipopt", "--output", str(out)])
    assert res.exit_code == 0, res.output
    return out
