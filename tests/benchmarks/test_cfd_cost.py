"""The pure logic of benchmarks/cfd_cost.py: windows, NRMSE, the time-step band, the verdict.

The benchmark's CFD runs take hours; what it computes from them is checked here on synthetic
force histories whose NRMSE follow by hand.
"""

from __future__ import annotations

import argparse
import shutil
import subprocess
import sys
import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from mfflap.cfd.openfoam.runner import run_case
from mfflap.cfd.openfoam.setups import setup
from mfflap.cfd.openfoam.writer import write_case

SCRIPT = Path(__file__).resolve().parents[2] / "benchmarks" / "cfd_cost.py"


@pytest.fixture(scope="module")
def bench(load_benchmark):
    return load_benchmark("cfd_cost.py")


def _run(bench, label, offset=0.0, cpu=100.0, time_s=None):
    """A run whose F_n, M and F_t are unit sines (range 2) plus ``offset``."""
    time_s = np.linspace(0.0, 2.0, 4001) if time_s is None else time_s
    wave = np.sin(2 * np.pi * time_s)
    loads = {k: wave + offset for k in bench.COMPONENTS}
    return bench.SetupRun(label, cpu, time_s=time_s, loads=loads)


def test_courant_list_parses_one_or_several_and_refuses_nonsense(bench):
    assert bench.courant_list("1") == [1.0]
    assert bench.courant_list("4,1,2.5") == [4.0, 1.0, 2.5]
    for bad, said in (("a", "not a comma-separated"), ("1,,2", "not a comma-separated"),
                      ("0", "positive"), ("-1", "positive"), ("nan", "positive"),
                      ("1,2,1", "twice")):
        with pytest.raises(argparse.ArgumentTypeError, match=said):
            bench.courant_list(bad)


def test_windows_are_each_cycle_after_the_ramp(bench):
    assert bench.windows(2.0) == {"cycle 1": (0.25, 1.0), "cycle 2": (1.0, 2.0)}
    assert bench.windows(1.5) == {"cycle 1": (0.25, 1.0), "cycle 2": (1.0, 1.5)}
    assert bench.windows(0.2) == {}  # nothing simulated after the ramp


def test_a_time_window_is_compared_after_the_cycles_and_named_by_its_times(bench):
    assert bench.windows(1.0, (0.25, 0.55)) == {"cycle 1": (0.25, 1.0),
                                                "t = 0.25-0.55 s": (0.25, 0.55)}
    assert bench.time_window("0.25:0.55") == (0.25, 0.55)
    for bad, said in (("0.25", "START:END"), ("a:b", "START:END"), ("1:2:3", "START:END"),
                      ("0.5:0.25", "START < END"), ("-1:1", "0 <= START"),
                      ("0:nan", "START < END")):
        with pytest.raises(argparse.ArgumentTypeError, match=said):
            bench.time_window(bad)


def test_nrmse_in_a_window_sees_only_the_forces_inside_it(bench):
    ref = _run(bench, "ref")
    # off by 0.1 from t = 0.6 s on only: nothing in the first stroke, 5 % in the rest
    late = bench.SetupRun("late", 100.0, time_s=ref.time_s,
                          loads={k: v + 0.1 * (ref.time_s >= 0.6) for k, v in ref.loads.items()})
    errors = bench.nrmse_percent(late, ref, 1.0, (0.25, 0.55))
    assert errors["t = 0.25-0.55 s"] == [0.0, 0.0, 0.0]
    # cycle 1 is 0.25-1 s: 0.1 off over 0.4 of its 0.75 s, range 2
    np.testing.assert_allclose(errors["cycle 1"], 100 * 0.1 * np.sqrt(0.4 / 0.75) / 2,
                               rtol=2e-2)
    said = bench.verdict(late, ref, None, float("nan"), 1.0, window=(0.25, 0.55))
    assert said.startswith("not within 2 % (F_n 3.65 %, M 3.65 %); over t = 0.25-0.55 s "
                           "within (F_n 0.00 %, M 0.00 %); cost met by")


def test_nrmse_percent_of_a_constant_offset_is_offset_over_range(bench):
    ref = _run(bench, "ref")
    assert all(e == [0.0, 0.0, 0.0] for e in bench.nrmse_percent(ref, ref, 2.0).values())
    shifted = _run(bench, "run", offset=0.04)
    # the sine has range 2 in every window of whole cycles (cycle 1: 0.25-1 s holds -1 and 1)
    for errors in bench.nrmse_percent(shifted, ref, 2.0).values():
        np.testing.assert_allclose(errors, 2.0, rtol=1e-3)


def test_ensemble_mean_averages_on_the_time_all_members_cover(bench):
    a = _run(bench, "a", offset=0.1, cpu=100.0)
    b = _run(bench, "b", offset=-0.3, cpu=300.0, time_s=np.linspace(0.0, 1.5, 777))
    mean = bench.ensemble_mean([a, b], "mean")
    assert mean.time_s[0] == 0.0 and mean.time_s[-1] == 1.5
    assert mean.cpu_per_cycle_s == 400.0 and mean.ok
    # off the members' own samples, the mean is of their linear interpolations
    wave = np.sin(2 * np.pi * mean.time_s)
    for k in bench.COMPONENTS:
        np.testing.assert_allclose(mean.loads[k], wave - 0.1, atol=2e-4)


def test_time_step_band_is_the_furthest_member_from_the_mean(bench):
    members = [_run(bench, "a", 0.02), _run(bench, "b", -0.06), _run(bench, "c", 0.04)]
    mean = bench.ensemble_mean(members, "mean")  # offset 0: b is 0.06 / 2 = 3 % away
    np.testing.assert_allclose(bench.time_step_band(members, mean, 2.0), (3.0, 3.0),
                               rtol=1e-3)


def test_verdict_reads_the_accuracy_the_band_and_the_three_costs(bench):
    ref = _run(bench, "ref")
    baseline = _run(bench, "openfoam_md", cpu=300.0)
    near = _run(bench, "near", offset=0.03, cpu=80.0)  # 1.5 %, 0.27 of the baseline
    said = bench.verdict(near, ref, baseline, speed_factor=2.0, cycles=2.0)
    assert said.startswith("within 2 % (F_n 1.50 %, M 1.50 %)")
    assert ("this machine's seconds: yes, ratio to openfoam.md's set-up: yes, "
            "openfoam.md's speed: no") in said  # 80 s x 2 = 160 s > 90 s
    assert "band" not in said
    far = _run(bench, "far", offset=0.05, cpu=120.0)  # 2.5 %, 0.4 of the baseline
    said = bench.verdict(far, ref, baseline, 0.5, 2.0, band=(3.0, 2.4))
    assert said.startswith("not within 2 % (F_n 2.50 %, M 2.50 %); outside the medium "
                           "mesh's time-step band (F_n 3.00 %, M 2.40 %)")
    assert ("this machine's seconds: no, ratio to openfoam.md's set-up: no, "
            "openfoam.md's speed: yes") in said
    said = bench.verdict(far, ref, None, float("nan"), 2.0, band=(3.0, 2.6))
    assert "inside the medium mesh's time-step band" in said
    assert said.endswith("cost met by this machine's seconds: no")  # no baseline, one reading


def test_verdict_with_the_twin_says_when_the_pass_turns_on_round_off(bench):
    ref = _run(bench, "ref")
    baseline = _run(bench, "openfoam_md", cpu=300.0)
    run = _run(bench, "run", offset=0.038, cpu=80.0)  # 1.9 %
    near_twin = _run(bench, "run-PCG", offset=0.036)  # 1.8 %
    far_twin = _run(bench, "run-PCG", offset=0.052)  # 2.6 %
    said = bench.verdict(run, ref, baseline, 1.0, 2.0, twin=near_twin)
    assert said.startswith("within 2 % (F_n 1.90 %, M 1.90 %); with the other pressure "
                           "solver within (F_n 1.80 %, M 1.80 %); cost met by")
    assert "round-off" not in said
    said = bench.verdict(run, ref, baseline, 1.0, 2.0, twin=far_twin)
    assert said.startswith("within 2 % (F_n 1.90 %, M 1.90 %); with the other pressure "
                           "solver not within (F_n 2.60 %, M 2.60 %): the verdict turns on "
                           "round-off; cost met by")
    said = bench.verdict(far_twin, ref, baseline, 1.0, 2.0, band=(3.0, 3.0), twin=run)
    assert said.startswith("not within 2 % (F_n 2.60 %, M 2.60 %); with the other pressure "
                           "solver within (F_n 1.90 %, M 1.90 %): the verdict turns on "
                           "round-off; inside the medium mesh's time-step band")
    failed = bench.SetupRun("run-PCG", None, failure="diverged")
    assert "pressure solver" not in bench.verdict(run, ref, baseline, 1.0, 2.0, twin=failed)


def test_other_solver_swaps_gamg_and_pcg_and_labels_the_rerun(bench):
    ref = setup("reference")
    job = bench.Job("reference-co0.25", ref.mesh, replace(ref.solver, pressure_solver="GAMG"))
    rerun = bench.other_solver(job)
    assert rerun.label == "reference-co0.25-PCG" and rerun.solver.pressure_solver == "PCG"
    back = bench.other_solver(rerun)
    assert back.label == "reference-co0.25-PCG-GAMG" and back.solver.pressure_solver == "GAMG"
    assert rerun.solver.max_courant == job.solver.max_courant


def test_yardstick_jobs_are_the_reference_at_each_max_courant(bench):
    ref = setup("reference")
    reference = bench.Job("reference", ref.mesh, ref.solver)
    own = ref.solver.max_courant
    assert bench.yardstick_jobs(reference, None) == [reference]
    jobs = bench.yardstick_jobs(reference, [own, 0.25])
    assert [j.label for j in jobs] == ["reference", "reference-co0.25"]
    assert jobs[0] is reference and jobs[1].solver.max_courant == 0.25
    assert jobs[1].solver.pressure_solver == ref.solver.pressure_solver


def test_job_variant_changes_the_solver_and_labels_the_copy(bench):
    ref = setup("reference")
    job = bench.Job("reference", ref.mesh, ref.solver)
    co1 = job.variant("co1", max_courant=1.0)
    assert co1.label == "reference-co1" and co1.solver.max_courant == 1.0
    assert job.solver.max_courant == ref.solver.max_courant and co1.mesh is job.mesh


def test_a_run_is_read_only_when_it_reached_its_end_time(bench, tmp_path):
    """Regression: a run stopped early by the write-and-stop signal also ends its log in
    "End"; read as finished, its 0.3 s of 1 s gave 51 % NRMSE and a CPU per cycle of a
    third of a cycle. Only a log that reached endTime is read; the rest resume."""
    write_case(tmp_path, bench.benchmark_motion(), end_time=1.0)
    assert not bench.ran_to_end(tmp_path)
    log = tmp_path / "log.pimpleFoam"
    log.write_text("deltaT = 0.001\nTime = 0.5\nExecutionTime = 12 s\n")
    assert not bench.ran_to_end(tmp_path)  # killed mid-run: rerun, not read
    log.write_text("deltaT = 0.001\nTime = 0.297\nExecutionTime = 12 s\n\nEnd\n\n")
    assert not bench.ran_to_end(tmp_path)  # written and stopped at 0.297 s: resumed
    log.write_text("deltaT = 0.001\nTime = 1\nExecutionTime = 24 s\n\nEnd\n\n")
    assert bench.ran_to_end(tmp_path)


@pytest.mark.openfoam
def test_a_run_stopped_part_way_resumes_and_its_redone_steps_are_not_timed(bench, tmp_path):
    """Real pimpleFoam on a tiny mesh, 0.3 s of the benchmark motion written every 0.05 s:
    a run stopped at 0.2 s whose last write was lost resumes from 0.15 s when the benchmark
    runs again; the steps it takes twice count once in its steps per cycle, which then
    match an uninterrupted run's."""
    from dataclasses import replace

    from mfflap.cfd.openfoam.solver_log import solver_provenance
    from mfflap.cfd.openfoam.writer import MeshSpec

    spec = MeshSpec("tiny", n_chord=20, n_edge=4, n_radial=20, radial_expansion=100.0,
                    radius_chords=8.0)
    solver = replace(setup("reference").solver, write_interval=0.05)
    motion, cycles = bench.benchmark_motion(), 0.3
    for label in ("stopped", "whole"):
        write_case(tmp_path / label, motion, end_time=cycles, mesh=spec,
                   ramp_time=bench.RAMP_S, solver=solver)
    stopped = tmp_path / "stopped"
    control = stopped / "system" / "controlDict"
    text = control.read_text()
    assert "endTime         0.3;" in text
    control.write_text(text.replace("endTime         0.3;", "endTime         0.2;"))
    run_case(stopped, timeout_s=300)
    control.write_text(text)
    assert not bench.ran_to_end(stopped)  # its log ends in End, 0.1 s short of endTime
    shutil.rmtree(stopped / "0.2")  # the write a kill cut short (latest_solution_time)
    log = stopped / "log.pimpleFoam"
    log.write_text(log.read_text().rstrip().removesuffix("End"))  # a killed run's log
    assert not bench.ran_to_end(stopped)

    resumed = bench.run_setup(bench.Job("stopped", spec, solver), cycles, str(tmp_path), 20.0)
    whole = bench.run_setup(bench.Job("whole", spec, solver), cycles, str(tmp_path), 20.0)
    assert resumed.ok and whole.ok, (resumed.failure, whole.failure)
    assert log.read_text().count("Starting time loop") == 2
    provenance = solver_provenance(stopped)
    assert provenance["n_time_steps_redone"] > 0
    assert provenance["n_time_steps"] > whole.steps_per_cycle * cycles + 1
    assert resumed.steps_per_cycle * cycles == pytest.approx(whole.steps_per_cycle * cycles,
                                                             abs=1)
    assert resumed.cpu_per_cycle_s < provenance["cpu_time_s"] / cycles
    assert resumed.time_s[-1] == pytest.approx(cycles, abs=1e-3)


def _script(*args):
    return subprocess.run([sys.executable, str(SCRIPT), *args], capture_output=True,
                          text=True, timeout=120)


def test_a_work_dir_of_other_settings_is_refused_before_anything_runs(tmp_path):
    stamp = tmp_path / "benchmark_settings.txt"
    stamp.write_text("motion HarmonicMotion(...); cycles 1.0; far field inletOutlet\n")
    done = _script("--work-dir", str(tmp_path), "--cycles", "2")
    assert done.returncode != 0
    assert "holds runs of other settings" in done.stderr and str(stamp) in done.stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == ["benchmark_settings.txt"]
    assert "cycles 1.0" in stamp.read_text()  # the stamp of the runs there is kept


def test_a_bad_yardstick_courant_is_a_usage_error():
    done = _script("--yardstick-courant", "1,0")
    assert done.returncode == 2
    assert "--yardstick-courant" in done.stderr and "positive" in done.stderr


def test_collect_reports_each_run_as_it_finishes_and_the_simulated_time_of_the_others(
        bench, tmp_path, capsys):
    (tmp_path / "slow").mkdir()
    (tmp_path / "slow" / "log.pimpleFoam").write_text("Courant Number mean: 0.1 max: 2\n"
                                                       "deltaT = 0.001\nTime = 0.5\n")

    def slow():
        time.sleep(0.6)
        return _run(bench, "slow", cpu=250.0)

    # finished before (its end time reached): read, not run, whatever its future says
    (tmp_path / "read" / "system").mkdir(parents=True)
    (tmp_path / "read" / "system" / "controlDict").write_text("endTime         2;\n")
    (tmp_path / "read" / "log.pimpleFoam").write_text("deltaT = 0.001\nTime = 2\n\nEnd\n")

    def read():
        time.sleep(0.6)
        return _run(bench, "read", cpu=90.0)

    with ThreadPoolExecutor(3) as pool:
        futures = {pool.submit(lambda: bench.SetupRun("broken", None, failure="diverged")):
                   "broken", pool.submit(slow): "slow", pool.submit(read): "read"}
        results = bench.collect(futures, str(tmp_path), 2.0, every_s=0.1)
    assert set(results) == {"broken", "slow", "read"}
    assert results["slow"].cpu_per_cycle_s == 250.0
    err = capsys.readouterr().err
    assert "[1/3] broken: failed: diverged" in err
    assert "running: slow t = 0.500 of 2 s\n" in err  # not the finished run's t = 2
    assert "[3/3]" in err.splitlines()[-1] and "slow: 250.0 s" in err


def test_setup_labels_name_a_set_up_its_mesh_and_a_max_courant(bench):
    assert bench.setup_label("affordable") == ("affordable", "", None)
    assert bench.setup_label("medium_piso@graded") == ("medium_piso", "graded", None)
    assert bench.setup_label("medium_piso@graded-co3") == ("medium_piso", "graded", 3.0)
    assert bench.setup_label("medium_piso-co0.25") == ("medium_piso", "", 0.25)
    for bad in ("a@b@c", "a-co", "a-co0", "a-co1e999", "a-cox", "a b", "-co3", "a@-co3"):
        with pytest.raises(argparse.ArgumentTypeError, match="SETUP, SETUP@MESH or either"):
            bench.setup_label(bad)


def test_a_labelled_job_is_its_set_up_on_its_mesh_at_its_max_courant(bench):
    baseline = setup("openfoam_md")
    job = bench.labelled_job("openfoam_md@openfoam_md_medium")
    assert job.label == "openfoam_md@openfoam_md_medium"
    assert job.solver == baseline.solver and job.mesh.n_cells == 32_368
    assert job.mesh != baseline.mesh
    faster = bench.labelled_job("openfoam_md@openfoam_md_medium", max_courant=3.0)
    assert faster.label == "openfoam_md@openfoam_md_medium-co3"
    assert faster.solver == replace(baseline.solver, max_courant=3.0)
    own = bench.labelled_job("medium_piso-co6", max_courant=3.0)  # the label's -coX wins
    assert own.label == "medium_piso-co6" and own.solver.max_courant == 6.0
    assert own.mesh == setup("medium_piso").mesh


def test_two_yardsticks_are_a_usage_error():
    done = _script("--yardstick", "openfoam_md@openfoam_md_medium", "--yardstick-courant", "1")
    assert done.returncode == 2
    assert "--yardstick and --yardstick-courant" in done.stderr


@pytest.mark.slow
def test_a_window_past_the_simulated_time_or_malformed_is_a_usage_error():
    done = _script("--cycles", "1", "--window", "0.25:1.5")
    assert done.returncode == 2
    assert "--window ends at 1.5 s, after the 1 s simulated" in done.stderr
    done = _script("--window", "0.55:0.25")
    assert done.returncode == 2 and "--window" in done.stderr and "START < END" in done.stderr


def test_a_bad_setup_label_is_a_usage_error():
    done = _script("medium_piso@graded-cox")
    assert done.returncode == 2 and "'medium_piso@graded-cox'" in done.stderr


def _labels(plan):
    return [j.label for j in plan.jobs]


def test_the_plan_runs_the_reference_its_floors_the_baseline_and_each_set_up_with_its_twin(
        bench):
    plan = bench.plan_runs(bench.parsed_arguments(["medium_piso", "affordable-co3"]))
    assert sorted(_labels(plan)) == sorted([
        "reference", "reference-PCG", "reference-co3", "openfoam_md", "medium_piso",
        "medium_piso-PCG", "affordable-co3", "affordable-co3-PCG"])
    assert plan.members == ["reference"] and plan.named == ["medium_piso", "affordable-co3"]
    assert plan.floors == {"medium_piso": "medium_piso-PCG",
                           "affordable-co3": "affordable-co3-PCG"}
    assert plan.yardstick_floors == {} and plan.moving == set()
    jobs = {j.label: j for j in plan.jobs}
    assert jobs["affordable-co3"].solver.max_courant == 3.0
    assert jobs["medium_piso-PCG"].solver.pressure_solver == "PCG"
    # the longest first: cells over max Co never rises along the list
    cost = [j.mesh.n_cells / j.solver.max_courant for j in plan.jobs]
    assert cost == sorted(cost, reverse=True)


def test_the_plan_runs_each_label_once_and_skips_what_the_options_skip(bench):
    # the reference's max Co 3 run named as a set-up, and again as a member of the yardstick
    args = bench.parsed_arguments(["reference-co3", "medium_piso", "--yardstick-courant",
                                   "4,3,1", "--no-solver-floor", "--no-baseline"])
    plan = bench.plan_runs(args)
    labels = _labels(plan)
    assert len(labels) == len(set(labels))
    assert sorted(labels) == sorted(["reference", "reference-PCG", "reference-co3",
                                     "reference-co1", "medium_piso"])
    assert plan.members == ["reference", "reference-co3", "reference-co1"]
    assert plan.named == ["medium_piso"] and plan.floors == {}


def test_the_plan_reruns_a_yardstick_with_the_other_solver_and_moves_set_ups_to_the_plate(
        bench):
    args = bench.parsed_arguments(["medium_piso", "--yardstick",
                                   "openfoam_md@openfoam_md_medium", "--yardstick-floor",
                                   "--no-time-step-floor", "--no-solver-floor",
                                   "--plate-frame", "--far-field", "inletOutlet",
                                   "--meshes", "coarse"])
    plan = bench.plan_runs(args)
    assert plan.members == ["openfoam_md@openfoam_md_medium"]
    # openfoam.md's settings are PCG: the yardstick's twin runs GAMG
    assert plan.yardstick_floors == {
        "openfoam_md@openfoam_md_medium": "openfoam_md@openfoam_md_medium-GAMG"}
    assert plan.moving == {"reference", "medium_piso"}
    jobs = {j.label: j for j in plan.jobs}
    assert {"reference-plate", "medium_piso-plate", "coarse-mesh"} <= set(jobs)
    assert "reference-co3" not in jobs
    assert jobs["medium_piso-plate"].solver.frame == "plate"
    assert all(j.solver.far_field == "inletOutlet" for j in plan.jobs)


def test_the_wall_treatment_asked_for_is_every_runs_and_stamps_the_work_folder(bench, tmp_path):
    """--wall-treatment all_y_plus: the reference, its reruns, the baseline, the named
    set-ups and their twins all run it; the work folder's stamp says so, so a folder of
    earlier (stamp without it, each set-up's own) runs is refused, and without the option
    the stamp reads as before."""
    args = bench.parsed_arguments(["medium_piso", "--wall-treatment", "all_y_plus"])
    plan = bench.plan_runs(args)
    assert {"reference", "reference-co3", "openfoam_md", "medium_piso-PCG"} <= set(
        _labels(plan))
    assert {j.solver.wall_treatment for j in plan.jobs} == {"all_y_plus"}
    own = bench.parsed_arguments(["medium_piso"])
    assert {j.solver.wall_treatment for j in bench.plan_runs(own).jobs} == {"log_law"}
    assert "wall treatment" not in bench.settings_stamp(own)
    assert bench.settings_stamp(args) == bench.settings_stamp(own).replace(
        "\n", "; wall treatment all_y_plus\n")
    bench.claim_work_dir(tmp_path, bench.settings_stamp(own))
    with pytest.raises(SystemExit, match="holds runs of other settings"):
        bench.claim_work_dir(tmp_path, bench.settings_stamp(args))


def test_without_the_solver_floor_a_twin_that_finished_before_is_still_read(bench, tmp_path):
    """--no-solver-floor runs no new reruns, but a set-up's rerun with the other pressure
    solver that finished in the work folder costs nothing and is read, so the set-up is
    still judged by both solvers; one stopped part-way is not resumed."""
    args = bench.parsed_arguments(["medium_piso", "affordable", "--no-solver-floor"])
    assert bench.plan_runs(args, tmp_path).floors == {}
    for label, reached in (("medium_piso-PCG", 1.0), ("affordable-PCG", 0.5)):
        write_case(tmp_path / label, bench.benchmark_motion(), end_time=1.0)
        (tmp_path / label / "log.pimpleFoam").write_text(
            f"deltaT = 0.001\nTime = {reached:g}\nExecutionTime = 24 s\n\nEnd\n\n")
    plan = bench.plan_runs(args, tmp_path)
    assert plan.floors == {"medium_piso": "medium_piso-PCG"}
    assert "medium_piso-PCG" in _labels(plan) and "affordable-PCG" not in _labels(plan)
    assert bench.plan_runs(args).floors == {}  # no work folder: nothing to read


def test_the_yardstick_is_one_run_or_the_mean_of_several_with_their_band(bench):
    args = bench.parsed_arguments(["--yardstick-courant", "4,1", "--no-baseline"])
    plan = bench.plan_runs(args)
    results = {"reference": _run(bench, "reference", 0.1),
               "reference-co1": _run(bench, "reference-co1", -0.1)}
    mean, band = bench.yardstick_of(results, plan, args.yardstick_courant, 1.0)
    assert mean.label == "mean of max Co 4, 1"
    for k in bench.COMPONENTS:  # the offsets cancel, off the samples too (interpolation)
        np.testing.assert_allclose(mean.loads[k], np.sin(2 * np.pi * mean.time_s), atol=2e-4)
    # each member is 0.1 off the mean, whose range is 2: 5 %
    np.testing.assert_allclose(band, (5.0, 5.0), rtol=1e-3)
    one = bench.parsed_arguments(["--no-baseline"])
    run, band = bench.yardstick_of(results, bench.plan_runs(one), None, 1.0)
    assert run is results["reference"] and band is None


def test_a_failed_yardstick_run_stops_the_study_with_its_reason(bench):
    args = bench.parsed_arguments(["--yardstick-courant", "4,1"])
    plan = bench.plan_runs(args)
    results = {"reference": _run(bench, "reference"),
               "reference-co1": bench.SetupRun("reference-co1", None,
                                               failure="pimpleFoam diverged at t = 0.4")}
    with pytest.raises(SystemExit, match="the reference-co1 run failed: pimpleFoam diverged"):
        bench.yardstick_of(results, plan, args.yardstick_courant, 1.0)


def _study(bench, tmp_path):
    """A study whose NRMSE against the reference follow by hand: a unit sine (range 2)
    offset by 0.02 is 1 % off, by 0.06 3 %."""
    results = {"reference": _run(bench, "reference", cpu=300.0),
               "openfoam_md": _run(bench, "openfoam_md", offset=0.1, cpu=200.0),
               "cheap": _run(bench, "cheap", offset=0.02, cpu=50.0),
               "cheap-PCG": _run(bench, "cheap-PCG", offset=0.06, cpu=52.0),
               "broken": bench.SetupRun("broken", None, failure="diverged")}
    cells = dict.fromkeys(results, 1000)
    return bench.Study(results, results["reference"], 2.0, ["cheap", "broken"],
                       {"cheap": "cheap-PCG"}, cells, results["openfoam_md"], None,
                       "motion X; cycles 2.0")


def test_the_study_file_keeps_every_run_with_the_inputs(bench, tmp_path):
    import h5py

    study = _study(bench, tmp_path)
    bench.write_study(study, tmp_path / "s.h5", ["cfd_cost.py", "cheap"])
    with h5py.File(tmp_path / "s.h5") as h5:
        assert h5.attrs["command"] == "cfd_cost.py cheap"
        assert h5.attrs["settings"] == "motion X; cycles 2.0"
        assert h5.attrs["yardstick"] == "reference" and h5.attrs["cost_ratio_to"] == "openfoam_md"
        assert list(h5.attrs["windows"]) == ["cycle 1", "cycle 2"]
        cheap = h5["cheap"]
        assert cheap.attrs["cost_ratio"] == pytest.approx(0.25)
        assert cheap.attrs["other_pressure_solver_run"] == "cheap-PCG" and cheap.attrs["named"]
        np.testing.assert_allclose(cheap["nrmse_percent"][()], 1.0, rtol=1e-4)
        np.testing.assert_allclose(h5["cheap-PCG/nrmse_percent"][()], 3.0, rtol=1e-4)
        broken = h5["broken"].attrs
        assert broken["failure"] == "diverged" and "cost_ratio" not in broken


def test_the_study_file_keeps_the_window_beside_the_cycles(bench, tmp_path):
    import h5py

    study = replace(_study(bench, tmp_path), window=(0.25, 0.55))
    bench.write_study(study, tmp_path / "s.h5", ["cfd_cost.py", "--window", "0.25:0.55"])
    with h5py.File(tmp_path / "s.h5") as h5:
        assert list(h5.attrs["windows"]) == ["cycle 1", "cycle 2", "t = 0.25-0.55 s"]
        # a constant offset is the same NRMSE in any window holding the sine's range; the
        # first stroke holds only part of it (sin from 0.25 to 0.55 s: 1 down to -0.31)
        errors = h5["cheap/nrmse_percent"][()]
        np.testing.assert_allclose(errors[:2], 1.0, rtol=1e-4)
        span = 1 - np.sin(2 * np.pi * 0.55)
        np.testing.assert_allclose(errors[2], 100 * 0.02 / span, rtol=1e-3)


def test_labels_that_would_overlap_are_placed_apart_and_others_left_alone(bench):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots()
    ax.set_xscale("log")
    ax.set_xlim(0.1, 10)
    ax.set_ylim(0, 10)
    # a long label reaching the next run's place, one at the same place, one far away
    labels = [ax.annotate(text, xy, textcoords="offset points", xytext=(5, -3), fontsize=7)
              for text, xy in (("medium_piso@openfoam_md", (0.29, 5.13)),
                               ("medium_piso", (0.53, 5.12)),
                               ("medium_piso-co8", (0.53, 5.12)),
                               ("affordable", (0.27, 1.0)))]
    renderer = fig.canvas.get_renderer()
    assert labels[0].get_window_extent(renderer).overlaps(labels[1].get_window_extent(renderer))
    twin = (0.3, 5.6)  # a point drawn without a label
    ax.plot(*twin, "o")
    bench.unstack_labels(fig, labels, [twin])
    boxes = [t.get_window_extent(renderer) for t in labels]
    assert not any(a.overlaps(b) for i, a in enumerate(boxes) for b in boxes[i + 1:])
    # no label covers a point: the long label clears the next run's, all clear the twin
    for xy in [t.xy for t in labels] + [twin]:
        x, y = ax.transData.transform(xy)
        assert not any(b.x0 <= x <= b.x1 and b.y0 <= y <= b.y1 for b in boxes), xy
    for text in labels:  # each stays within a few lines of its point
        assert abs(text.xyann[0]) == 5 and abs(text.xyann[1] + 3) <= 4 * 9
    assert labels[-1].xyann == (5, -3)  # nothing near it: where it was
    # a label moved off its point's line has a leader to that point
    moved = {t.xy for t in labels if t.xyann[1] != -3}
    leaders = [a for a in ax.texts if a not in labels]
    assert moved and {a.xy for a in leaders} == moved
    assert all(a.arrow_patch is not None and a.get_text() == "" for a in leaders)
    plt.close(fig)


def test_the_cost_accuracy_figure_draws_each_run_where_its_numbers_put_it(bench, tmp_path):
    import matplotlib.image

    study = _study(bench, tmp_path)
    drawn = bench.cost_accuracy_figure(study, tmp_path / "f.png")
    assert set(drawn) == {"openfoam_md", "cheap", "cheap-PCG"}  # not the yardstick, failures
    assert drawn["cheap"] == pytest.approx((0.25, 1.0), rel=1e-4)
    assert drawn["cheap-PCG"] == pytest.approx((0.26, 3.0), rel=1e-4)
    assert drawn["openfoam_md"] == pytest.approx((1.0, 5.0), rel=1e-4)
    image = matplotlib.image.imread(tmp_path / "f.png")
    assert image.shape[0] > 500 and image.shape[1] > 800
    study = replace(study, baseline=None, band=(2.5, 2.0))  # ratios to the reference
    drawn = bench.cost_accuracy_figure(study, tmp_path / "g.png", title="t")
    assert drawn["cheap"] == pytest.approx((50 / 300, 1.0), rel=1e-4)
    assert (tmp_path / "g.png").stat().st_size > 10_000


FIGURES = Path(__file__).resolve().parents[2] / "docs" / "figures"


def _in_target(group, attrs, window: int = 0) -> bool:
    """Within the cost, with F_n and M within the NRMSE target in that window (0: cycle 1)."""
    errors = group["nrmse_percent"][window]
    return bool(group.attrs["cost_ratio"] <= attrs["target_ratio"]
                and max(errors[:2]) <= attrs["target_nrmse_percent"])


@pytest.mark.parametrize("pitch", [5, 10, 20])
def test_the_shipped_cost_studies_say_what_readme_says_of_them(pitch):
    """docs/findings/known_limits.md reads the three studies behind docs/figures: no set-up has both
    of its runs (GAMG and PCG) in the target box; at 5 deg medium_piso@graded is in it with
    GAMG only; at 10 deg medium_piso with PCG is outside the time-step band on M."""
    import h5py

    with h5py.File(FIGURES / f"cost_accuracy_pitch{pitch}.h5") as h5:
        attrs = dict(h5.attrs)
        assert attrs["target_ratio"] == pytest.approx(90 / 264)
        assert attrs["cost_ratio_to"] == "openfoam_md"
        named = [name for name in h5 if h5[name].attrs["named"]]
        assert named
        for name in named:
            twin = h5[h5[name].attrs["other_pressure_solver_run"]]
            assert not (_in_target(h5[name], attrs) and _in_target(twin, attrs)), name
        if pitch == 5:
            assert attrs["yardstick"] == "reference-co0.25"
            assert _in_target(h5["medium_piso@graded"], attrs)
            assert not _in_target(h5["medium_piso@graded-PCG"], attrs)
        if pitch == 10:
            band_m = attrs["time_step_band_percent"][1]
            assert h5["medium_piso-PCG/nrmse_percent"][0][1] > band_m
            assert h5["medium_piso/nrmse_percent"][0][1] <= band_m


def test_the_force_histories_show_the_yardstick_the_medium_mesh_and_the_named_set_ups(
        bench, tmp_path):
    import matplotlib.image

    study = _study(bench, tmp_path)
    drawn = bench.force_histories_figure(study, tmp_path / "h.png")
    # not the rerun with the other pressure solver, not the failed run; the yardstick first
    assert drawn == ["reference", "openfoam_md", "cheap"]
    image = matplotlib.image.imread(tmp_path / "h.png")
    assert image.shape[0] > 600 and image.shape[1] > 900
    other = bench.SetupRun("H-medium", 700.0, time_s=study.yardstick.time_s,
                           loads=study.yardstick.loads)
    drawn = bench.force_histories_figure(replace(study, yardstick=other), tmp_path / "i.png")
    assert drawn == ["H-medium", "reference", "openfoam_md", "cheap"]


@pytest.mark.parametrize("pitch", [5, 10, 20])
def test_the_shipped_studies_against_openfoam_md_s_medium_mesh_say_what_readme_says(pitch):
    """docs/findings/known_limits.md reads the studies against openfoam.md's own medium mesh: no run
    within the cost is within 2 % of it, openfoam.md's own set-up is not either (that file
    found 1-2 %), and medium_piso@openfoam_md meets the cost with both pressure solvers. The
    same holds over the first stroke alone (t = 0.25-0.55 s, before the shed vortex passes
    the plate), where the runs are closest."""
    import h5py

    with h5py.File(FIGURES / f"cost_accuracy_pitch{pitch}_h_medium.h5") as h5:
        attrs = dict(h5.attrs)
        assert attrs["yardstick"] == "openfoam_md@openfoam_md_medium"
        assert "--yardstick openfoam_md@openfoam_md_medium" in attrs["command"]
        assert f"{np.deg2rad(pitch)!r}" in attrs["settings"]
        assert not any(_in_target(h5[name], attrs) for name in h5 if "cost_ratio" in
                       h5[name].attrs)
        assert min(h5["openfoam_md/nrmse_percent"][0][:2]) > attrs["target_nrmse_percent"]
        for run in ("medium_piso@openfoam_md", "medium_piso@openfoam_md-PCG"):
            assert h5[run].attrs["cost_ratio"] <= attrs["target_ratio"]
            assert min(h5[run]["nrmse_percent"][0][:2]) > attrs["target_nrmse_percent"]
        stroke = list(attrs["windows"]).index("t = 0.25-0.55 s")
        assert "--window 0.25:0.55" in attrs["command"]
        assert not any(_in_target(h5[name], attrs, stroke) for name in h5 if "cost_ratio" in
                       h5[name].attrs)
        assert max(h5["openfoam_md/nrmse_percent"][stroke][:2]) > attrs["target_nrmse_percent"]


@pytest.mark.parametrize("pitch", [5, 10, 20])
def test_the_shipped_studies_against_openfoam_md_s_fine_mesh_say_what_readme_says(pitch):
    """docs/findings/known_limits.md reads the studies against openfoam.md's fine H-type mesh: a run
    of the H-type medium mesh (max Co 2 at 5°, 1 at 10°) is nearer it than any other mesh,
    the O-grid medium mesh is further, and no run within the cost is within 2 % of it, in
    cycle 1 or over the first stroke. At 5° the fine mesh itself at max Co 1 lies within 2 %
    of it in cycle 1 (1.8 / 1.6 %), nearer than any other run; at 10° it lies 5.8 / 8.9 %
    away, further than the medium mesh at either time step: there the fine mesh is not
    settled in time. At 20° (two cycles, the fine mesh at its own max Co only) the H-type
    medium mesh is 4.8 / 5.3 % from it, nearest of all, and the O-grid medium mesh 10 %."""
    import h5py

    with h5py.File(FIGURES / f"cost_accuracy_pitch{pitch}_h_fine.h5") as h5:
        attrs = dict(h5.attrs)
        assert attrs["yardstick"] == "openfoam_md@openfoam_md_fine"
        assert f"{np.deg2rad(pitch)!r}" in attrs["settings"]
        stroke = list(attrs["windows"]).index("t = 0.25-0.55 s")
        runs = [name for name in h5 if "cost_ratio" in h5[name].attrs
                and name != attrs["yardstick"]]
        for window in (0, stroke):
            assert not any(_in_target(h5[name], attrs, window) for name in runs)
        error = {name: max(h5[name]["nrmse_percent"][0][:2]) for name in runs}
        own_time_step = error.pop("openfoam_md@openfoam_md_fine-co1", None)
        assert (own_time_step is None) == (pitch == 20)
        if pitch == 5:
            assert own_time_step < 2.0
            assert own_time_step < min(error.values())
        elif pitch == 10:
            assert own_time_step > 5.0
            assert own_time_step > error["openfoam_md@openfoam_md_medium"]
        else:
            assert 4.0 < error["openfoam_md@openfoam_md_medium"] < 6.0
            assert error["reference"] > 9.0
        nearest = {5: "openfoam_md@openfoam_md_medium", 10: "openfoam_md@openfoam_md_medium-co1",
                   20: "openfoam_md@openfoam_md_medium"}
        assert min(error, key=error.get) == nearest[pitch]
        assert error["reference"] > error["openfoam_md@openfoam_md_medium"]

