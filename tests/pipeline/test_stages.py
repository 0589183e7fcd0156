"""The main job's stages end typed: an mfflap error fails its stage and the run goes on
(the report says what is missing); any other exception is a fault and ends the run with its
traceback, from the Python API and from the command line alike."""

import json
from pathlib import Path

import h5py
import pytest
from click.testing import CliRunner

from mfflap.cli.main import cli
from mfflap.config import load_case
from mfflap.errors import MfflapError
from mfflap.pipeline import DONE, FAILED, RunOptions, run_study, write_results

CASE = Path(__file__).parents[2] / "cases" / "paper2026.toml"


def _quick() -> RunOptions:
    return RunOptions(n_starts=1, with_ipopt=False, sensitivity=False)


@pytest.mark.slow
def test_an_mfflap_error_fails_its_stage_and_the_run_goes_on(monkeypatch, tmp_path):
    import mfflap.pipeline as pipeline

    def refused(*args, **kwargs):
        raise MfflapError("the records are not readable")

    monkeypatch.setattr(pipeline, "load_cases", refused)
    outcome = run_study(load_case(CASE), _quick(), progress=lambda m: None)
    first = outcome.stages[0]
    assert (first.name, first.status, first.problem) == ("identification", FAILED,
                                                         "the records are not readable")
    assert "optimisation" in [s.name for s in outcome.stages if s.status == DONE]
    assert outcome.problems[0] == "identification: the records are not readable"
    write_results(load_case(CASE), outcome, tmp_path / "results.h5")
    with h5py.File(tmp_path / "results.h5") as h5:
        kept = json.loads(h5.attrs["stages"])
    assert kept[0]["status"] == FAILED and kept[0]["name"] == "identification"


def test_any_other_exception_ends_the_run_with_its_traceback(monkeypatch, tmp_path):
    import mfflap.pipeline as pipeline

    def broken(*args, **kwargs):
        raise TypeError("a fault in the code")

    monkeypatch.setattr(pipeline, "load_cases", broken)
    with pytest.raises(TypeError, match="a fault in the code"):
        run_study(load_case(CASE), _quick(), progress=lambda m: None)
    res = CliRunner().invoke(cli, ["run", str(CASE), "--out", str(tmp_path / "run")])
    assert res.exit_code == 1 and isinstance(res.exception, TypeError)


@pytest.mark.slow
def test_the_main_job_is_its_list_of_stages_in_order():
    """The stages a run reports are those of STAGES whose condition holds, in that order:
    without CFD records nothing but the optimisation, the back-test and the model ladder on
    what it found runs (the identification fails, and the stages that need its cases are
    not run)."""
    import mfflap.pipeline as pipeline

    names = [s.name for s in pipeline.STAGES if isinstance(s, pipeline.Stage)]
    assert names == ["identification", "identification coverage", "output correction",
                     "optimisation", "vortex polish", "gradient check", "gain table",
                     "motions against the identification data",
                     "back-test", "CFD baseline", "model ladder", "gap diagnosis",
                     "coefficient sensitivity",
                     "VTK export"]
    told: list[str] = []
    outcome = run_study(load_case(CASE), RunOptions(n_starts=1, with_ipopt=False,
                                                    gain_table=False, sensitivity=False,
                                                    fixtures=(Path("/nonexistent"),)),
                        progress=told.append)
    # the model ladder runs on the motions whose CFD the back-test found
    found = any(o.record is not None for o in outcome.backtests.values())
    assert [(s.name, s.status) for s in outcome.stages] == [
        ("identification", FAILED), ("optimisation", DONE), ("vortex polish", DONE),
        ("gradient check", DONE),
        ("back-test", DONE), ("CFD baseline", DONE)] + ([("model ladder", DONE)] if found
                                                        else [])
    assert set(outcome.ladder) == {label for label, o in outcome.backtests.items()
                                   if o.record is not None and o.comparison is not None}
    # the adjoint checked against complex step, controls and dt apart (Fig. 6)
    assert sorted(outcome.gradient_checks) == [0.0, 0.5, 1.0]
    assert all(max(c.controls_error_complex_step, c.time_step_error_complex_step) < 1e-10
               for c in outcome.gradient_checks.values())
    assert told.index("[optimisation] started") < told.index("[back-test] started")
    assert outcome.model is not None and outcome.optimised_with is None
    # every optimum polished; a polish that moved it is back-tested under its own label
    assert sorted(outcome.polished) == [0.0, 0.5, 1.0]
    for beta, polished in outcome.polished.items():
        moved = polished.moved_from(outcome.study.sqp[beta].motion)
        assert (f"β = {beta:g} polished" in outcome.backtest_motions) == moved
        assert polished.objective <= polished.start_objective
