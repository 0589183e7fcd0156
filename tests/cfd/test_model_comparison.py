"""compare_with_model, the library behind `mfflap cfd parse` (its CLI tests are in
test_case_inputs.py, test_fluent.py, test_motion_table.py and test_cli_cfd_gradcheck.py)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from mfflap.cfd.model_comparison import compare_with_model
from mfflap.errors import ConfigError

CASE = Path(__file__).resolve().parents[2] / "cases" / "paper2026.toml"


def _report(path: Path, t: np.ndarray, fx: np.ndarray) -> Path:
    from fluent_files import write_plate_report

    return write_plate_report(path, t, fx, 0 * t, 0 * t)


def test_a_constant_stream_wise_force_is_a_constant_thrust_and_its_mean(tmp_path):
    """F_x = -10 N per metre of depth on a 1 m deep 2D case, span 0.18 m: thrust is -F_x,
    1.8 N, at every sample whatever the pitch (global axes), so its time mean is 1.8 N."""
    t = np.linspace(0.01, 1.0, 200)
    out = compare_with_model(_report(tmp_path / "r.out", t, np.full_like(t, -10.0)), CASE)
    assert out["dialect"] == "fluent-report" and out["n_samples"] == 200
    assert out["cfd_mean_thrust"] == pytest.approx(1.8, rel=1e-9)
    assert out["numerical_bursts"] == []
    half = compare_with_model(tmp_path / "r.out", CASE, discard_s=0.5)
    assert half["cfd_mean_thrust"] == pytest.approx(1.8, rel=1e-9)
    assert half["model_mean_thrust"] != out["model_mean_thrust"]  # another window


def test_a_discard_past_the_run_names_the_file_and_its_end(tmp_path):
    t = np.linspace(0.01, 1.0, 50)
    report = _report(tmp_path / "r.out", t, np.sin(t))
    with pytest.raises(ConfigError, match=r"discard: --discard 2.0 s leaves fewer than two "
                                          r"samples of .*r\.out \(it ends at t = 1 s\)"):
        compare_with_model(report, CASE, discard_s=2.0)


def _beside_its_udf(tmp_path: Path) -> Path:
    """A Fluent report written where `cfd fluent` put its UDF: its inputs are kept."""
    from click.testing import CliRunner
    from fluent_files import write_plate_report

    from mfflap.cli.main import cli

    res = CliRunner().invoke(cli, ["cfd", "fluent", str(CASE), str(tmp_path / "fl"),
                                   "--cycles", "1", "--ramp-time", "0.25"])
    assert res.exit_code == 0, res.output
    t = np.linspace(0.01, 1.0, 300)
    return write_plate_report(tmp_path / "fl" / "plate-forces.out", t, 40 * np.sin(6 * t),
                              30 * np.cos(6 * t), 2 * np.sin(6 * t))


def test_a_comparison_round_trips_through_hdf5_with_its_inputs(tmp_path):
    from mfflap.cfd.model_comparison import (
        model_comparison,
        read_model_comparison,
        write_model_comparison,
    )
    from mfflap.results import ResultsFile

    report = _beside_its_udf(tmp_path)
    comparison = model_comparison(report, CASE, discard_s=0.3)
    path = write_model_comparison(tmp_path / "c.h5", comparison, CASE)
    back = read_model_comparison(path)
    assert back.summary == json.loads(json.dumps(comparison.summary))
    for name in ("cfd_loads", "model_loads"):
        for key in ("time", "normal_force", "tangential_force", "moment"):
            np.testing.assert_array_equal(getattr(getattr(back, name), key),
                                          getattr(getattr(comparison, name), key))
    for key in ("cfd_thrust_n", "cfd_power_w", "model_thrust_n", "model_power_w", "compared"):
        np.testing.assert_array_equal(getattr(back, key), getattr(comparison, key))
    assert back.compared.sum() == (comparison.cfd_loads.time >= 0.3).sum() < 300
    with ResultsFile(path) as stored:
        assert stored.config_toml == CASE.read_text()
        assert stored.units("performance")["cfd_power_w"] == "W"
        _, attrs = stored.read_group("summary")
    assert attrs["kept_inputs_toml"] == (report.parent / "mfflap_fluent.toml").read_text()


def test_the_figure_draws_both_series_on_the_compared_samples_scale(tmp_path):
    from mfflap.cfd.model_comparison import model_comparison
    from mfflap.plots import model_comparison_figure

    comparison = model_comparison(_beside_its_udf(tmp_path), CASE, discard_s=0.3)
    fig = model_comparison_figure(comparison)
    axes = fig.axes
    assert [ax.get_ylabel() for ax in axes] == ["F_n [N]", "F_t [N]", "M about LE [N m]",
                                                "thrust [N]", "input power [W]"]
    cfd_line, model_line = axes[0].get_lines()[:2]
    np.testing.assert_array_equal(cfd_line.get_ydata(), comparison.cfd_loads.normal_force)
    np.testing.assert_array_equal(model_line.get_ydata(), comparison.model_loads.normal_force)
    keep = comparison.compared
    low, high = axes[3].get_ylim()
    shown = np.concatenate([comparison.cfd_thrust_n[keep], comparison.model_thrust_n[keep]])
    assert low < shown.min() and shown.max() < high
    assert high - low <= 1.25 * np.ptp(shown)  # the compared samples fill the panel
    nrmse = 100 * comparison.summary["nrmse_moment"]
    assert f"NRMSE {nrmse:.1f} %" in axes[2].get_title(loc="right")


@pytest.mark.slow
def test_cfd_parse_writes_the_figure_and_the_hdf5_file(tmp_path):
    import matplotlib.image
    from click.testing import CliRunner

    from mfflap.cfd.model_comparison import read_model_comparison
    from mfflap.cli.main import cli

    report = _beside_its_udf(tmp_path)
    png, h5 = tmp_path / "figures" / "parse.png", tmp_path / "results" / "parse.h5"
    res = CliRunner().invoke(cli, ["cfd", "parse", str(report), "--case-file", str(CASE),
                                   "--plot", str(tmp_path / "parse.xyz")])
    assert res.exit_code == 2 and "--plot" in res.output and ".png, .pdf or .svg" in res.output
    res = CliRunner().invoke(cli, ["cfd", "parse", str(report), "--case-file", str(CASE),
                                   "--discard", "0.3", "--plot", str(png), "--save", str(h5),
                                   "--json"])
    assert res.exit_code == 0, res.output
    assert matplotlib.image.imread(png).shape[:2] == (1320, 960)
    assert read_model_comparison(h5).summary == json.loads(res.stdout)


def test_the_fluent_report_options_are_refused_for_an_openfoam_case(tmp_path):
    """--columns names a Fluent report's columns, and a case mfflap wrote keeps its
    depth: given with such a case they are refused, not ignored."""
    from click.testing import CliRunner

    from mfflap.cli.main import cli

    case = tmp_path / "case"
    assert CliRunner().invoke(cli, ["cfd", "write", str(CASE), str(case)]).exit_code == 0
    res = CliRunner().invoke(cli, ["cfd", "parse", str(case), "--case-file", str(CASE),
                                   "--columns", "a,b,c"])
    assert res.exit_code == 2
    assert f"--columns applies only to a Fluent report; {case} is an OpenFOAM case folder" in (
        res.output)
    res = CliRunner().invoke(cli, ["cfd", "parse", str(case), "--case-file", str(CASE),
                                   "--columns", "a,b"])
    assert res.exit_code == 2 and "give the three columns" in res.output
    res = CliRunner().invoke(cli, ["cfd", "parse", str(case), "--case-file", str(CASE),
                                   "--depth", "2"])
    assert res.exit_code == 2 and "keeps its depth (mfflap_case.toml)" in res.output


@pytest.mark.parametrize(("times", "end", "reached"), [
    (np.linspace(0.0, 1.0, 101), 1.0, True),  # lands on it
    (np.linspace(0.0, 0.996, 84), 1.0, True),  # stopped within half a step of it
    (np.r_[np.linspace(0.0, 0.99, 100), 0.995], 1.0, True),  # a last step shortened to it
    (np.linspace(0.0, 0.6, 61), 1.0, False),  # still going, or stopped early
    (np.linspace(0.0, 0.97, 98), 1.0, False),  # three steps short
    (np.array([0.5]), 1.0, False), (np.empty(0), 1.0, False)])
def test_a_history_reaches_its_end_time_within_its_last_steps(times, end, reached):
    from mfflap.cfd.model_comparison import reaches_end_time

    assert reaches_end_time(times, end) is reached


def test_forces_that_stop_short_of_the_end_time_are_flagged(tmp_path):
    """A Fluent report of 0.6 s beside a UDF written for 1 s: the summary says so, and
    `cfd parse` warns that its numbers cover only that; the whole second gives no warning."""
    from click.testing import CliRunner
    from fluent_files import write_plate_report

    from mfflap.cli.main import cli

    report = _beside_its_udf(tmp_path)
    whole = compare_with_model(report, CASE)
    assert whole["written_end_time"] == 1.0 and whole["forces_reach_end_time"] is True
    t = np.linspace(0.01, 0.6, 100)
    write_plate_report(report, t, 40 * np.sin(6 * t), 30 * np.cos(6 * t), 2 * np.sin(6 * t))
    short = compare_with_model(report, CASE)
    assert short["written_end_time"] == 1.0 and short["forces_reach_end_time"] is False
    res = CliRunner().invoke(cli, ["cfd", "parse", str(report), "--case-file", str(CASE)])
    assert res.exit_code == 0, res.output
    assert (f"warning: {report}: its forces end at t = 0.6 s, before the 1 s the run was "
            "written for (the run is still going or stopped there)") in res.stderr
    assert "warning" not in res.stdout


@pytest.mark.openfoam
def test_a_case_still_running_is_named_with_the_process_that_runs_it(tmp_path):
    """A real OpenFOAM case whose force log ends half-way, its run lock held (as while
    pimpleFoam runs in it): `cfd parse` says a run is still going and names the process."""
    import os

    from click.testing import CliRunner

    from mfflap.cfd.openfoam.case_lock import case_lock
    from mfflap.cfd.openfoam.runner import openfoam_available, run_case
    from mfflap.cfd.openfoam.writer import write_case
    from mfflap.cli.main import cli
    from mfflap.config import load_case

    assert openfoam_available(), "OpenFOAM must be installed (.ci/run installs it)"
    case_file = load_case(CASE)
    case = write_case(tmp_path / "run", case_file.motion.build(), end_time=0.004,
                      plate=case_file.plate, fluid=case_file.fluid, stream=case_file.flow)
    run_case(case, timeout_s=120)
    parse = ["cfd", "parse", str(case), "--case-file", str(CASE)]
    res = CliRunner().invoke(cli, parse)
    assert res.exit_code == 0 and "warning" not in res.stderr, res.output
    (force_file,) = case.glob("postProcessing/forces/*/force.dat")
    lines = force_file.read_text().splitlines()
    kept = [line for line in lines if line.startswith("#") or float(line.split()[0]) <= 0.002]
    assert len(kept) < len(lines)
    force_file.write_text("\n".join(kept) + "\n")
    with case_lock(case):
        res = CliRunner().invoke(cli, [*parse, "--json"])
    assert res.exit_code == 0, res.output
    assert json.loads(res.stdout)["forces_reach_end_time"] is False
    assert "before the 0.004 s the run was written for (a run is still going: pid " \
           f"{os.getpid()} since" in res.stderr


def test_cfd_parse_prints_numbers_with_units_and_warns_past_the_linear_theory(tmp_path):
    """The paper's motion reaches ~80 deg of effective incidence, far past where
    thin-aerofoil theory is a yardstick: `cfd parse --thin-aerofoil` says so. A motion of a
    few millimetres stays under the limit and gets no warning."""
    import re

    from click.testing import CliRunner
    from fluent_files import write_plate_report

    from mfflap.cli.main import cli
    from mfflap.hydro.thin_aerofoil import LINEAR_INCIDENCE_LIMIT_DEG

    runner = CliRunner()
    report = _beside_its_udf(tmp_path)
    res = runner.invoke(cli, ["cfd", "parse", str(report), "--case-file", str(CASE),
                              "--thin-aerofoil"])
    assert res.exit_code == 0, res.output
    incidence = float(re.search(r"max_effective_incidence_deg +([0-9.]+) deg",
                                res.stdout).group(1))
    assert incidence > LINEAR_INCIDENCE_LIMIT_DEG
    assert f"effective incidence reaches {incidence:.3g} deg" in res.stderr
    assert re.search(r"cfd_mean_thrust +-?[0-9.e+-]+ N\n", res.stdout)
    assert re.search(r"cfd_mean_power +-?[0-9.e+-]+ W\n", res.stdout)
    assert re.search(r"numerical_bursts +none\n", res.stdout)

    small = tmp_path / "small.toml"
    small.write_text(CASE.read_text().replace("heave_amplitude = 0.3", "heave_amplitude = 0.002")
                     .replace("pitch_amplitude_deg = 20.0", "pitch_amplitude_deg = 0.5"))
    res = runner.invoke(cli, ["cfd", "fluent", str(small), str(tmp_path / "small"),
                              "--cycles", "1", "--ramp-time", "0.25"])
    assert res.exit_code == 0, res.output
    t = np.linspace(0.01, 1.0, 300)
    report = write_plate_report(tmp_path / "small" / "plate-forces.out", t,
                                0.1 * np.sin(6 * t), 0.1 * np.cos(6 * t), 0.01 * np.sin(6 * t))
    res = runner.invoke(cli, ["cfd", "parse", str(report), "--case-file", str(small),
                              "--thin-aerofoil"])
    assert res.exit_code == 0, res.output
    assert "effective incidence reaches" not in res.stderr
