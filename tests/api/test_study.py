"""The study facade: identify, optimise, back-test and diagnose in a few lines, each step
returning the typed result the rest of mfflap uses."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import mfflap
from mfflap.errors import ConfigError

CASE = Path(__file__).parents[2] / "cases" / "paper2026.toml"


@pytest.mark.slow
def test_identify_optimise_backtest_diagnose_in_ten_lines():
    study = mfflap.Study.from_toml(CASE)
    fit = study.identify(bootstrap=20)
    optimum = study.optimise(beta=0.0)
    outcome = study.backtest(optimum)
    verdict = study.diagnose([outcome])
    # the identified coefficients are the study's model from then on
    assert 3.0 < fit.coefficients["normal_drag"] < 8.0
    assert study.model.coefficients["normal_drag"] == fit.coefficients["normal_drag"]
    assert optimum.beta == 0.0 and optimum.summary.mean_thrust > 0
    # the same optimum as the main job's (identified coefficients, the phase fixed): its
    # shipped OpenFOAM run is found
    from mfflap.records.record import fixture_dir

    assert outcome.status == "back-tested"
    assert (fixture_dir("backtest_main_job") / outcome.source.removeprefix("fixture ")).is_file()
    assert verdict.verdict


@pytest.mark.slow
def test_the_paper_s_optimum_is_back_tested_on_its_shipped_cfd():
    study = mfflap.Study.from_toml(CASE)  # the case file's coefficients
    optimum = study.optimise(beta=0.0)
    outcome = study.backtest(optimum)
    assert outcome.status == "back-tested" and outcome.record is not None
    assert outcome.record.provenance["openfoam_build"].startswith("OPENFOAM=")
    evaluation = study.evaluate(optimum.motion)
    assert np.mean(evaluation.thrust) == pytest.approx(optimum.summary.mean_thrust, rel=1e-6)


def test_a_weighting_that_does_not_exist_is_refused_by_name():
    with pytest.raises(ConfigError) as info:
        mfflap.Study.from_toml(CASE).identify(weighting="medium")
    assert info.value.key == "weighting"


def test_import_mfflap_does_not_load_the_layers_the_facade_needs(tmp_path):
    import subprocess
    import sys

    code = "import sys, mfflap; print('mfflap.pipeline' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True).stdout
    assert out.strip() == "False"
    assert "Study" in mfflap.__all__ and mfflap.Study.__module__ == "mfflap.api"
