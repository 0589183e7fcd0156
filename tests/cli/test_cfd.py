import json
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from mfflap.cli.main import cli
from mfflap.optimisation import FlappingProblem
from mfflap.optimisation.problem import Gradient

CASE = Path(__file__).resolve().parents[2] / "cases" / "paper2026.toml"


@pytest.mark.openfoam
@pytest.mark.parametrize("options", [[], ["--set", 'cfd.far_field="freestream"',
                                          "--set", 'cfd.pressure_solver="GAMG"',
                                          "--set", 'cfd.turbulence_convection="upwind"']],
                         ids=["default", "freestream-GAMG-upwind"])
def test_cfd_write_run_parse_with_real_openfoam(tmp_path, options):
    runner = CliRunner()
    case_dir = tmp_path / "of"
    res = runner.invoke(cli, ["cfd", "write", str(CASE), str(case_dir), "--cycles", "0.05",
                              *options])
    assert res.exit_code == 0, res.output
    far = "freestreamVelocity" if options else "inletOutlet"  # the table1 set-up's
    assert f"type {far};" in (case_dir / "0" / "U").read_text()
    assert f"solver {'GAMG' if options else 'PCG'};" in (case_dir / "system/fvSolution"
                                                         ).read_text()
    res = runner.invoke(cli, ["cfd", "run", str(case_dir), "--timeout", "300", "--json"])
    assert res.exit_code == 0, res.output
    health = json.loads(res.stdout)
    assert health["openfoam_build"].startswith("OPENFOAM=")
    # the default set-up's wall treatment, valid at the plate's y+; said with or without
    # [cfd] y_plus
    assert health["wall_treatment"] == "all_y_plus"
    assert health["n_time_steps"] > 10 and health["cpu_time_s"] > 0
    assert health["n_steps_bounding_epsilon"] <= health["n_time_steps"]
    assert health["numerical_bursts"] == []  # the impulsive start's force impulse is real
    assert "y_plus_mean" not in health  # written without --y-plus: nothing to say
    schemes = (case_dir / "system" / "fvSchemes").read_text()
    if options:  # bounded upwind k and epsilon: nothing to clip
        assert "div(phi,k)      Gauss upwind;" in schemes
        assert health["n_steps_bounding_epsilon"] == 0
    else:  # the template's limitedLinear at max Co 2 clips epsilon in most steps
        assert "div(phi,k)      Gauss limitedLinear 1;" in schemes
        assert health["n_steps_bounding_epsilon"] > health["n_time_steps"] / 4
    # fields written at the end: running the finished case again adds no time step
    times = sorted(float(p.name) for p in case_dir.iterdir() if p.name[0].isdigit())
    # a write every quarter of the run (purgeWrite keeps the last two)
    assert times[-2:] == pytest.approx([0.0375, 0.05])
    _inject_burst(case_dir, 0.03)
    res = runner.invoke(cli, ["cfd", "run", str(case_dir), "--json"])
    assert res.exit_code == 0, res.output
    again = json.loads(res.stdout)
    assert again["n_time_steps"] == health["n_time_steps"]
    (burst,) = again["numerical_bursts"]
    assert 0.025 < float(burst.split()[2].split("-")[0]) <= 0.03
    res = runner.invoke(cli, ["cfd", "parse", str(case_dir), "--case-file", str(CASE), "--json",
                                 "--discard", "0.01"])
    assert res.exit_code == 0, res.output
    out = json.loads(res.stdout)
    assert out["dialect"] == "v1912" and out["n_samples"] > 50
    assert len(out["numerical_bursts"]) == 1  # bridged before the comparison
    assert out["forces_beyond_what_the_motion_can_drive"] == []  # the bridged burst is not
    assert out["pearson_normal_force"] > 0.5


def _inject_burst(case_dir, at_s):
    """Thirty nanosecond-long rows of 1 MN after the first row at or past ``at_s`` in the
    force and moment logs: a numerical burst as pimpleFoam would write it."""
    for name in ("force.dat", "moment.dat"):
        path = next(case_dir.glob(f"postProcessing/*/*/{name}"))
        lines = path.read_text().splitlines(keepends=True)
        i = next(j for j, line in enumerate(lines)
                 if line[0].isdigit() and float(line.split()[0]) >= at_s)
        t0 = float(lines[i].split()[0])
        lines[i + 1:i + 1] = [f"{t0 + 1e-9 * k:.12g}\t(1e6 1e6 1e6)\t(1e6 1e6 1e6)\t(0 0 0)\n"
                              for k in range(1, 31)]
        path.write_text("".join(lines))


def test_cfd_parse_of_a_folder_that_holds_no_case_is_a_clear_error(tmp_path):
    res = CliRunner().invoke(cli, ["cfd", "parse", str(tmp_path), "--case-file", str(CASE)])
    assert res.exit_code == 2
    assert (f"{tmp_path / 'postProcessing'}: no forces output") in " ".join(res.output.split())
    assert "Traceback" not in res.output


def test_gradcheck_cli_writes_its_figure_and_numbers_into_its_folder(tmp_path):
    out_dir = tmp_path / "check"
    res = CliRunner().invoke(cli, ["gradcheck", str(CASE), "--n-steps", "12", "--json",
                                   "--out", str(out_dir)])
    assert res.exit_code == 0, res.output
    out = json.loads(res.stdout)
    assert json.loads((out_dir / "gradcheck.json").read_text()) == {
        k: v for k, v in out.items() if k != "figure"}
    for beta in ("0.0", "0.5", "1.0"):
        for method in ("complex_step", "casadi"):
            assert out[beta][f"controls_error_{method}"] <= 1e-10
            assert out[beta][f"time_step_error_{method}"] <= 1e-10
        assert out[beta]["cosine_similarity_controls_fd"] > 0.999
        assert out[beta]["penalty_share"] <= 0.1
    assert (out_dir / "gradcheck.png").stat().st_size > 10_000


class _OffByOnePercent(FlappingProblem):
    """A problem whose gradient is 1 % wrong in its largest pitch control."""

    def gradient(self, motion):
        g = super().gradient(motion)
        pitch = g.pitch_acceleration.copy()
        pitch[np.argmax(np.abs(pitch))] *= 1.01
        return Gradient(pitch, g.heave_acceleration, g.time_step)


def test_a_one_percent_error_in_one_control_shows_although_dt_dwarfs_the_controls():
    """|dJ/d(dt)| is orders of magnitude above the controls' components, so a ratio over the
    whole vector would put this error near 1e-6; the controls' own ratio shows it whole."""
    from mfflap.config import load_case
    from mfflap.kinematics import to_discrete
    from mfflap.optimisation.gradcheck import check_gradient

    case = load_case(CASE)
    motion = to_discrete(case.motion.build(), 1 / case.motion.frequency, 10)
    check = check_gradient(_OffByOnePercent(case.morison_model(), 0.5), motion)
    whole = np.max(np.abs(check.adjoint - check.complex_step)) / np.max(
        np.abs(check.complex_step))
    assert whole < 1e-3
    assert check.controls_error_complex_step > 1e-3 > whole
    assert check.time_step_error_complex_step < 1e-10


def test_the_check_point_is_scaled_until_the_penalties_make_a_tenth_of_j():
    """A motion far past P_max, where the power penalty makes nearly all of J, is scaled
    down until it makes at most a tenth for every beta."""
    from mfflap.config import load_case
    from mfflap.kinematics import HarmonicMotion, to_discrete
    from mfflap.optimisation.gradcheck import check_point, penalty_share

    case = load_case(CASE)
    violent = to_discrete(HarmonicMotion(2.0, 0.5, 0.8, np.pi / 2), 0.5, 12)
    problems = [FlappingProblem(case.morison_model(), beta) for beta in (0.0, 0.5, 1.0)]
    assert max(penalty_share(p, violent) for p in problems) > 0.5
    point = check_point(problems, violent)
    assert max(penalty_share(p, point) for p in problems) <= 0.1
    assert np.abs(point.pitch_acceleration).max() < np.abs(violent.pitch_acceleration).max()


def test_gradcheck_reports_each_component_as_it_goes():
    """The check's work grows as N^2: it says how far it is, once per component."""
    from mfflap.config import load_case
    from mfflap.kinematics import to_discrete
    from mfflap.optimisation import FlappingProblem
    from mfflap.optimisation.gradcheck import check_gradient

    case = load_case(CASE)
    motion = to_discrete(case.motion.build(), 1 / case.motion.frequency, 10)
    seen = []
    check = check_gradient(FlappingProblem(case.morison_model(), 0.5), motion,
                           progress=lambda done, total: seen.append((done, total)))
    assert seen == [(i, 21) for i in range(1, 22)]
    assert check.controls_error_complex_step <= 1e-10
    assert check.time_step_error_complex_step <= 1e-10
    res = CliRunner().invoke(cli, ["gradcheck", str(CASE), "--n-steps", "10"])
    assert res.exit_code == 0, res.output
    assert "gradient components" in res.stderr and "/63 " in res.stderr  # 3 betas x 21
