"""A study's results draw themselves, write themselves to HDF5, and come back from any
results file mfflap writes (mfflap.open_results) as the same objects with the same
numbers."""

from __future__ import annotations

import json
from pathlib import Path

import h5py
import numpy as np
import pytest
from click.testing import CliRunner

import mfflap
from mfflap.cli.main import cli
from mfflap.errors import MfflapError
from mfflap.study_results import (
    BacktestResult,
    CycleEvaluation,
    GapDiagnosis,
    IdentifiedCoefficients,
    OptimisedMotion,
)

CASE = Path(__file__).parents[2] / "cases" / "paper2026.toml"


def _labels_have_units(figure) -> None:
    """Every drawn axis names the quantity it measures with a unit in brackets (a bar
    chart's categories are on the other axis)."""
    labels = [(ax.get_xlabel(), ax.get_ylabel()) for ax in figure.axes if ax.has_data()]
    assert labels and all(any("[" in label and "]" in label for label in pair)
                          for pair in labels), labels


@pytest.mark.slow
def test_each_step_of_a_study_writes_and_reads_back_its_result(tmp_path):
    study = mfflap.Study.from_toml(CASE)
    fit = study.identify(bootstrap=10)
    optimum = study.optimise(beta=0.0)
    outcome = study.backtest(optimum)
    verdict = study.diagnose([outcome])
    evaluation = study.evaluate(optimum.motion)
    for result, cls, kind in ((fit, IdentifiedCoefficients, "identification"),
                              (optimum, OptimisedMotion, "optimisation"),
                              (outcome, BacktestResult, "backtest"),
                              (verdict, GapDiagnosis, "gap_diagnosis"),
                              (evaluation, CycleEvaluation, "evaluation")):
        assert isinstance(result, cls)
        path = result.to_hdf5(tmp_path / f"{kind}.h5")
        with h5py.File(path) as h5:
            assert h5.attrs["kind"] == kind and "[study]" in h5["inputs"].attrs["config_toml"]
        back = mfflap.open_results(path)
        assert back.kind == kind and back.config == study.config
        said = repr(result)  # a line a terminal shows whole: no arrays, no numpy types
        assert said.startswith(cls.__name__) and len(said) <= 400, said
        assert "array(" not in said and "np.float" not in said, said
        _labels_have_units(result.plot())
        _labels_have_units(back.plot())
    back = mfflap.open_results(tmp_path / "identification.h5").identification["uniform"]
    assert back.coefficients == pytest.approx(fit.coefficients)
    assert back.interval == pytest.approx(fit.interval)
    back = mfflap.open_results(tmp_path / "optimisation.h5").optima[0.0]
    assert back.summary.mean_thrust == pytest.approx(optimum.summary.mean_thrust)
    assert np.array_equal(back.motion.heave_acceleration, optimum.motion.heave_acceleration)
    # stored with the coefficients it was optimised with (the identified ones)
    assert back.model.coefficients == pytest.approx(fit.coefficients)
    back = mfflap.open_results(tmp_path / "backtest.h5").backtests[outcome.label]
    assert back.status == "back-tested"
    assert back.comparison.as_dict() == outcome.comparison.as_dict()  # stored as JSON
    back = mfflap.open_results(tmp_path / "gap_diagnosis.h5").gap
    assert back.verdict == verdict.verdict and back.case_names == verdict.case_names
    assert [s.label for s in back.scores] == [s.label for s in verdict.scores]
    for stored, computed in zip(back.scores, verdict.scores, strict=True):
        assert stored.gain == pytest.approx(computed.gain)
        assert stored.heldout_sse == pytest.approx(computed.heldout_sse)
        assert stored.plausible == computed.plausible
    assert back.gap["before"]["normal_force"]["nrmse"] == pytest.approx(
        verdict.gap["before"]["normal_force"]["nrmse"])
    assert back.where["ranking"] == json.loads(json.dumps(verdict.where["ranking"]))
    # written again from what was read: the same file's numbers
    again = mfflap.open_results(back.to_hdf5(tmp_path / "again.h5")).gap
    assert [s.p_value for s in again.scores] == pytest.approx([s.p_value for s in back.scores])
    back = mfflap.open_results(tmp_path / "evaluation.h5").evaluation
    assert back.thrust == pytest.approx(evaluation.thrust)
    assert back.period_s == pytest.approx(float(optimum.motion.period))
    # an optimum written by the API is what `mfflap backtest` takes
    res = CliRunner().invoke(cli, ["backtest", str(tmp_path / "optimisation.h5"), "--json"])
    assert res.exit_code == 0, res.output
    said = json.loads(res.stdout)
    assert said["motions"]["β = 0"]["status"] == "back-tested"


@pytest.mark.slow
def test_the_main_job_s_results_file_reads_back_whole(tmp_path):
    out = tmp_path / "run"
    res = CliRunner().invoke(cli, ["run", str(CASE), "--out", str(out), "--json"])
    assert res.exit_code == 0, res.output
    said = json.loads(res.stdout)
    back = mfflap.open_results(out / "results.h5")
    assert back.kind == "run" and back.config.study.name == "paper2026"
    assert set(back.identification) == {"uniform", "low", "high"}
    assert set(back.optima) == {0.0, 0.5, 1.0}
    assert back.sweep is not None and back.sweep.feasible[back.best_sinusoid]
    assert {"β = 0", "best sinusoid"} <= set(back.backtests)
    assert back.gap is not None and back.gap.verdict
    for beta, optimum in back.optima.items():
        assert optimum.beta == beta and np.isfinite(optimum.summary.mean_power)
    for shown in (*back.identification.values(), *back.optima.values(),
                  *back.backtests.values(), back.gap):  # short, plain figures
        said = repr(shown)
        assert len(said) <= 400 and "array(" not in said and "np.float" not in said, said
    assert back.optima[0.0].summary.mean_thrust > 0
    figure = back.plot()  # Fig. 4a,b
    assert figure.axes[0].get_xlabel().endswith("[W]")
    assert said  # the job's own summary came out too


def test_a_file_mfflap_did_not_write_or_cannot_read_is_refused_naming_it(tmp_path):
    other = tmp_path / "other.h5"
    with h5py.File(other, "w") as h5:
        h5["x"] = np.arange(3)
    with pytest.raises(MfflapError, match=r"other\.h5"):
        mfflap.open_results(other)
    text = tmp_path / "notes.h5"
    text.write_text("not HDF5")
    with pytest.raises(MfflapError, match=r"notes\.h5"):
        mfflap.open_results(text)
    from mfflap.results import ResultsFile

    with ResultsFile(tmp_path / "cmp.h5", "w", kind="campaign_comparison", config_toml=""):
        pass
    with pytest.raises(MfflapError, match=r"cmp\.h5: holds 'campaign_comparison' results, "
                                          "which open_results does not read"):
        mfflap.open_results(tmp_path / "cmp.h5")


def test_a_cfd_record_reads_back_as_the_record(tmp_path):
    from mfflap.records.record import fixture_dir, read_record

    path = sorted(fixture_dir("backtest").glob("*.h5"))[0]
    back = mfflap.open_results(path)
    assert back.kind == "cfd_record" and back.config is None
    assert np.array_equal(back.record.loads.normal_force, read_record(path).loads.normal_force)


def test_rounds_read_back_in_order_with_their_numbers(tmp_path):
    from mfflap.config import load_case
    from mfflap.rounds.checks import MotionCheck
    from mfflap.rounds.output import write_rounds_results
    from mfflap.rounds.summary import LoopResult, RoundSummary

    def check(thrust: float) -> MotionCheck:
        return MotionCheck(label="β = 0", key="k", cfd_mean_thrust=thrust,
                           model_mean_thrust=1.1 * thrust, cfd_mean_power=20.0,
                           model_mean_power=18.0, thrust_error=0.1, power_error=-0.1,
                           thrust_counted=True, in_fit=False)

    rounds = [RoundSummary(index=k, out_dir=tmp_path / f"round_{k}", n_cases=43,
                           loop_records_in_fit=k - 1, coefficients={"normal_drag": 5.0},
                           checks={"β = 0": check(10.0 + k)}) for k in (1, 2, 3)]
    loop = LoopResult(rounds=rounds, tolerance=0.1, converged=False, stopped_because="x")
    write_rounds_results(loop, load_case(CASE), tmp_path)
    back = mfflap.open_results(tmp_path / "rounds.h5")
    assert back.kind == "rounds" and [r.index for r in back.rounds] == [1, 2, 3]
    assert [float(r.values["cfd_mean_thrust"][0]) for r in back.rounds] == [11.0, 12.0, 13.0]
    assert back.rounds[0].labels == ["β = 0"] and back.rounds[0].summary["n_cases"] == 43
