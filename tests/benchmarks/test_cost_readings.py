"""benchmarks/cost_readings.py: the cost target under every reading, from the cost studies.

The studies are written by cfd_cost.py's own writer from synthetic force histories whose NRMSE
follow by hand (a unit sine, range 2, offset by 0.02 is 1 % off); the shipped studies are read
as docs/findings/known_limits.md reads them.
"""

from __future__ import annotations

import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]
FIGURES = ROOT / "docs" / "figures"


@pytest.fixture(scope="module")
def bench(load_benchmark):
    return load_benchmark("cfd_cost.py")


@pytest.fixture(scope="module")
def readings(load_benchmark):
    return load_benchmark("cost_readings.py")


def _run(bench, label, offset, cpu):
    time_s = np.linspace(0.0, 1.0, 2001)
    wave = np.sin(2 * np.pi * time_s)
    return bench.SetupRun(label, cpu, time_s=time_s,
                          loads={k: wave + offset for k in bench.COMPONENTS})


def _write(bench, path, runs, named, floors, window=None, failed=(), yardstick="reference",
           settings="motion X"):
    """A one-cycle study against ``yardstick`` (openfoam_md's CPU 200 s: a cost ratio of 0.34
    is 68 s) written by cfd_cost.py's writer; the runs labelled in ``failed`` failed."""
    results = {yardstick: _run(bench, yardstick, 0.0, 300.0),
               "openfoam_md": _run(bench, "openfoam_md", 0.1, 200.0),
               **{label: _run(bench, label, offset, cpu) for label, (offset, cpu) in runs.items()},
               **{label: bench.SetupRun(label, None, failure="diverged") for label in failed}}
    study = bench.Study(results, results[yardstick], 1.0, named, floors,
                        dict.fromkeys(results, 1000), results["openfoam_md"], None, settings,
                        window)
    bench.write_study(study, path, ["cfd_cost.py"])


def test_the_nearest_set_up_within_the_cost_is_judged_by_its_worse_solver(bench, readings,
                                                                          tmp_path):
    # near: 1 % with GAMG but 3 % with PCG; steady: 1.6 % and 1.8 %; cheap but far: 5 %;
    # close but dear: 0.5 % at 0.5 of openfoam.md's set-up
    _write(bench, tmp_path / "cost_accuracy_pitch5.h5",
           {"near": (0.02, 50.0), "near-PCG": (0.06, 50.0),
            "steady": (0.032, 60.0), "steady-PCG": (0.036, 60.0),
            "far": (0.1, 40.0), "dear": (0.01, 100.0)},
           ["near", "steady", "far", "dear"], {"near": "near-PCG", "steady": "steady-PCG"})
    (reading,) = readings.study_readings(tmp_path / "cost_accuracy_pitch5.h5")
    assert (reading.pitch_deg, reading.yardstick, reading.window) == (
        5.0, "o_grid_time_step", "cycle 1")
    assert reading.setup == "steady" and reading.both_solvers
    assert reading.nrmse_percent == pytest.approx(1.8, rel=1e-3)
    assert reading.cost_ratio == pytest.approx(0.3)
    assert reading.baseline_nrmse_percent == pytest.approx(5.0, rel=1e-3)
    assert reading.met
    line = readings.describe(reading)
    assert "steady" in line and "1.8 %" in line and line.endswith(": met")


def test_a_reading_with_nothing_near_enough_or_cheap_enough_is_not_met(bench, readings,
                                                                       tmp_path):
    path = tmp_path / "cost_accuracy_pitch10_h_fine.h5"
    _write(bench, path, {"far": (0.1, 40.0)}, ["far"], {}, window=(0.25, 0.55),
           yardstick="openfoam_md@openfoam_md_fine")
    cycle, stroke = readings.study_readings(path)
    assert cycle.yardstick == "h_fine" and cycle.pitch_deg == 10.0
    assert stroke.window == "t = 0.25-0.55 s"
    assert cycle.setup == "far" and not cycle.both_solvers and not cycle.met
    _write(bench, path, {"dear": (0.0, 100.0)}, ["dear"], {})
    (reading,) = readings.study_readings(path)
    assert reading.setup is None and math.isnan(reading.nrmse_percent) and not reading.met
    assert readings.describe(reading).endswith("no set-up within the cost")
    # a failed rerun with the other solver leaves one solver; a failed baseline no scale
    _write(bench, path, {"near": (0.02, 50.0)}, ["near"], {"near": "near-PCG"},
           failed=("near-PCG", "openfoam_md"))
    (reading,) = readings.study_readings(path)
    assert reading.setup == "near" and not reading.both_solvers
    assert reading.nrmse_percent == pytest.approx(1.0, rel=1e-3)
    assert math.isnan(reading.baseline_nrmse_percent)


def test_each_yardstick_is_sorted_into_its_kind_and_others_are_refused(readings):
    kind = readings.yardstick_kind
    assert kind("reference-co0.25") == kind("reference") == "o_grid_time_step"
    assert kind("mean of max Co 4, 3, 2, 1") == "o_grid_mean"
    assert kind("openfoam_md@openfoam_md_medium") == "h_medium"
    assert kind("openfoam_md@openfoam_md_fine") == kind("openfoam_md@openfoam_md_fine-co1") \
        == "h_fine"
    for other in ("affordable", "reference@graded", "openfoam_md", "reference-cox"):
        with pytest.raises(ValueError, match=f"'{other}' is none of"):
            kind(other)


def test_of_two_studies_at_two_time_steps_the_smaller_counts_and_other_twins_are_refused(
        bench, readings, tmp_path):
    # the same set-up 1 % from the medium mesh at max Co 1 and 3 % from it at max Co 0.5
    _write(bench, tmp_path / "cost_accuracy_pitch20_co1.h5", {"cheap": (0.02, 50.0)},
           ["cheap"], {}, yardstick="reference-co1")
    _write(bench, tmp_path / "cost_accuracy_pitch20_co0.5.h5", {"cheap": (0.06, 50.0)},
           ["cheap"], {}, yardstick="reference-co0.5")
    (reading,) = readings.all_readings(tmp_path)
    assert reading.yardstick_label == "reference-co0.5"
    assert reading.nrmse_percent == pytest.approx(3.0, rel=1e-3) and not reading.met
    # the H-type fine mesh at its own max Co 2 and at 1: the latter counts
    for name, label in (("cost_accuracy_pitch20_h_fine.h5", "openfoam_md@openfoam_md_fine"),
                        ("cost_accuracy_pitch20_h_fine_co1.h5",
                         "openfoam_md@openfoam_md_fine-co1")):
        _write(bench, tmp_path / name, {"cheap": (0.02, 50.0)}, ["cheap"], {},
               yardstick=label)
    assert [r.yardstick_label for r in readings.all_readings(tmp_path)] == [
        "reference-co0.5", "openfoam_md@openfoam_md_fine-co1"]
    for name in ("cost_accuracy_pitch20_h_medium.h5", "cost_accuracy_pitch20_h_medium2.h5"):
        _write(bench, tmp_path / name, {"cheap": (0.02, 50.0)}, ["cheap"], {},
               yardstick="openfoam_md@openfoam_md_medium")
    with pytest.raises(ValueError, match=r"a second study of 20 deg against openfoam\.md's "
                       r"H-type medium mesh"):
        readings.all_readings(tmp_path)


def test_a_study_run_with_the_all_y_plus_wall_treatment_is_a_yardstick_of_its_own(
        bench, readings, tmp_path):
    """The same motion against the O-grid medium mesh with each wall treatment: two
    readings, not a second study refused; the stamp cfd_cost.py writes is what is read."""
    stamp = bench.settings_stamp(bench.parsed_arguments(["--wall-treatment", "all_y_plus"]))
    assert readings.study_wall_treatment(stamp) == "all_y_plus"
    assert readings.study_wall_treatment(bench.settings_stamp(
        bench.parsed_arguments([]))) == "log_law"
    _write(bench, tmp_path / "cost_accuracy_pitch20.h5", {"cheap": (0.06, 50.0)}, ["cheap"],
           {})
    _write(bench, tmp_path / "cost_accuracy_pitch20_all_y_plus.h5", {"cheap": (0.02, 50.0)},
           ["cheap"], {}, settings=stamp)
    log_law, all_y_plus = readings.all_readings(tmp_path)
    assert (log_law.yardstick, log_law.met) == ("o_grid_time_step", False)
    assert (all_y_plus.yardstick, all_y_plus.met) == ("o_grid_time_step_all_y_plus", True)
    assert log_law.nrmse_percent == pytest.approx(3.0, rel=1e-3)
    assert readings.describe(all_y_plus).startswith(
        "20 deg, mfflap's O-grid medium mesh at its smallest time step run, all_y_plus wall "
        "treatment (reference), cycle 1: cheap")
    done = subprocess.run([sys.executable, str(ROOT / "benchmarks" / "cost_readings.py"),
                           "--studies", str(tmp_path)], capture_output=True, text=True,
                          check=True)
    assert done.stdout.splitlines()[-1] == ("1 of 2 readings met: 20 deg against reference "
                                            "with all_y_plus, cycle 1")
    _write(bench, tmp_path / "cost_accuracy_pitch20_x.h5", {"cheap": (0.06, 50.0)},
           ["cheap"], {}, settings="motion X; wall treatment lowRe")
    with pytest.raises(ValueError, match=r"pitch20_x\.h5: wall treatment 'lowRe' is none of"):
        readings.all_readings(tmp_path)


def test_a_file_that_is_not_a_study_is_refused_by_name(bench, readings, tmp_path):
    with pytest.raises(ValueError, match="not a cost study file"):
        readings.study_readings(tmp_path / "results.h5")
    import h5py

    with h5py.File(tmp_path / "cost_accuracy_pitch5.h5", "w") as h5:
        h5.attrs["yardstick"] = "reference"
    with pytest.raises(ValueError, match=r"cost_accuracy_pitch5\.h5: the study has no "
                       r"attribute 'target_ratio'"):
        readings.study_readings(tmp_path / "cost_accuracy_pitch5.h5")
    script = str(ROOT / "benchmarks" / "cost_readings.py")
    for folder, said in (("missing", "missing: no such folder"),
                         ("empty", "empty: no cost study")):
        if folder == "empty":
            (tmp_path / folder).mkdir()
        done = subprocess.run([sys.executable, script, "--studies", str(tmp_path / folder)],
                              capture_output=True, text=True, check=False)
        assert done.returncode == 1 and said in done.stderr


@pytest.mark.slow
def test_the_shipped_studies_meet_the_target_only_at_20_deg_against_the_o_grid_mean(readings,
                                                                              tmp_path):
    """The findings' verdict, read from the shipped studies: the readings met are against the
    mean of the O-grid medium mesh's time steps at 20 deg (medium_piso, with both pressure
    solvers, in cycle 1 and over the first stroke; with the all_y_plus wall treatment in
    every run, over the first stroke only at 20 deg and not at all at 5 or 10 deg); against that
    mesh's smallest time step run the nearest set-up within the cost is 2.5 % off at 5 deg
    (its worse solver) and 2.2 % at 20 deg; against openfoam.md's H-type meshes nothing
    within the cost comes within 2 %."""
    every = readings.all_readings(FIGURES)
    met = [(r.yardstick, r.pitch_deg, r.window) for r in every if r.met]
    assert met == [("o_grid_mean", 20.0, "cycle 1"), ("o_grid_mean", 20.0, "t = 0.25-0.55 s"),
                   ("o_grid_mean_all_y_plus", 20.0, "t = 0.25-0.55 s")]
    assert {r.setup for r in every if r.met} == {"medium_piso"}
    # with all_y_plus in every run the cycle-1 reading is missed, by round-off's doing too
    missed = next(r for r in every if (r.yardstick, r.pitch_deg, r.window)
                  == ("o_grid_mean_all_y_plus", 20.0, "cycle 1"))
    assert missed.setup == "medium_piso" and missed.both_solvers
    assert 4.0 < missed.nrmse_percent < 5.0
    assert all(r.both_solvers for r in every if r.met)
    five = next(r for r in every
                if (r.yardstick, r.pitch_deg, r.window) == ("o_grid_time_step", 5.0, "cycle 1"))
    assert five.yardstick_label == "reference-co0.25"
    assert 2.0 < five.nrmse_percent < 3.0
    # at 20 deg against the smallest time step run (max Co 0.5) medium_piso misses on M
    twenty = next(r for r in every if (r.yardstick, r.pitch_deg, r.window)
                  == ("o_grid_time_step", 20.0, "cycle 1"))
    assert twenty.yardstick_label == "reference-co0.5" and twenty.setup == "medium_piso"
    assert 2.0 < twenty.nrmse_percent < 2.5
    assert {(r.yardstick, r.pitch_deg) for r in every} == {
        ("o_grid_time_step", 5.0), ("o_grid_time_step", 10.0), ("o_grid_time_step", 20.0),
        ("o_grid_mean", 5.0), ("o_grid_mean", 10.0),
        ("o_grid_mean", 20.0), ("h_medium", 5.0), ("h_medium", 10.0), ("h_medium", 20.0),
        ("h_fine", 5.0), ("h_fine", 10.0), ("h_fine", 20.0), ("o_grid_mean_all_y_plus", 5.0),
        ("o_grid_mean_all_y_plus", 10.0), ("o_grid_mean_all_y_plus", 20.0)}
    # at 5 and 10 deg with all_y_plus nothing within the cost comes within 2 %, either window
    for pitch in (5.0, 10.0):
        low = [r for r in every
               if (r.yardstick, r.pitch_deg) == ("o_grid_mean_all_y_plus", pitch)]
        assert len(low) == 2 and all(r.nrmse_percent > 3.0 for r in low), pitch
    readme = " ".join((ROOT / "docs" / "findings" / "known_limits.md").read_text().split())
    assert f"{len(met)} of {len(every)} are met" in readme
    assert readings.readings_figure(every, tmp_path / "r.png") is not None
    import matplotlib.image

    image = matplotlib.image.imread(tmp_path / "r.png")
    assert image.shape[0] > 500 and image.shape[1] > 1200
