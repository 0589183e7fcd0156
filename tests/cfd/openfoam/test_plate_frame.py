"""The plate's frame (SolverSettings.frame = "plate"): static mesh, MRF pitch, heave as inflow
and body force; checked against the frame formulas and against the moving-mesh case."""

from dataclasses import replace

import numpy as np
import pytest

from mfflap.cfd.force_history import ForceHistory, to_loads
from mfflap.cfd.frames import (
    plate_frame_acceleration,
    plate_frame_inflow,
)
from mfflap.cfd.imposed_motion import imposed_state
from mfflap.cfd.openfoam.forces import read_forces
from mfflap.cfd.openfoam.plate_frame import plate_frame_tables
from mfflap.cfd.openfoam.runner import openfoam_available, run_case
from mfflap.cfd.openfoam.solver_log import solver_provenance
from mfflap.cfd.openfoam.writer import SolverSettings, table_times, write_case
from mfflap.errors import ConfigError
from mfflap.kinematics import HarmonicMotion
from mfflap.metrics import nrmse

MOTION = HarmonicMotion(1.0, 0.3, np.deg2rad(20), np.pi / 2)
PLATE = SolverSettings(frame="plate", far_field="inletOutlet")


def rotation(theta: np.ndarray) -> np.ndarray:
    """R(theta) in the case's (x, y), shape (n, 2, 2)."""
    c, s = np.cos(theta), np.sin(theta)
    return np.stack([np.stack([c, -s], -1), np.stack([s, c], -1)], -2)


def test_plate_frame_inflow_and_acceleration_turn_back_into_the_case_frame():
    rng = np.random.default_rng(1)
    theta, hd, hdd = rng.uniform(-1.2, 1.2, 50), rng.normal(0, 2, 50), rng.normal(0, 10, 50)
    r = rotation(theta)
    w = plate_frame_inflow(theta, hd, 0.3)
    a = plate_frame_acceleration(theta, hdd)
    assert np.all(w[:, 2] == 0) and np.all(a[:, 2] == 0)
    # the plate's axes turned by theta give back the stream minus the heave velocity ...
    np.testing.assert_allclose(np.einsum("nij,nj->ni", r, w[:, :2]),
                               np.column_stack([np.full(50, 0.3), -hd]), atol=1e-12)
    # ... and the heave acceleration
    np.testing.assert_allclose(np.einsum("nij,nj->ni", r, a[:, :2]),
                               np.column_stack([np.zeros(50), hdd]), atol=1e-12)


def test_plate_frame_loads_equal_the_inertial_loads_of_the_same_force():
    """One force and moment about the leading edge, given as a moving-mesh case reports it
    (case axes, moment about the origin) and as a plate-frame case does (plate axes, moment
    about the leading edge): the same F_n, F_t and M."""
    time = np.linspace(0, 1, 40)
    state = imposed_state(MOTION, time, 0.25)
    rng = np.random.default_rng(2)
    f_plate = rng.normal(0, 50, (40, 3))
    m_le = rng.normal(0, 5, 40)
    f_case = np.einsum("nij,nj->ni", rotation(state.pitch_angle), f_plate[:, :2])
    f_case = np.column_stack([f_case, f_plate[:, 2]])
    y_le = state.heave_position
    m_origin = m_le - y_le * f_case[:, 0]  # r_LE x F about the origin, r_LE = (0, h)
    zeros = np.zeros(40)
    inertial = to_loads(ForceHistory(time, f_case, np.column_stack([zeros, zeros, m_origin]),
                                     "v1912"), state, 0.18, 0.18, "inertial")
    plate = to_loads(ForceHistory(time, f_plate, np.column_stack([zeros, zeros, m_le]),
                                  "v1912"), state, 0.18, 0.18, "plate", frame="plate")
    for key in ("normal_force", "tangential_force", "moment"):
        np.testing.assert_allclose(getattr(plate, key), getattr(inertial, key), atol=1e-9)
    with pytest.raises(ConfigError, match="frame"):
        to_loads(ForceHistory(time, f_plate, f_plate, "v1912"), state, 0.18, 0.18, "x",
                 frame="body")


def test_plate_frame_needs_the_inlet_outlet_far_field_and_a_known_frame():
    with pytest.raises(ConfigError, match="far_field") as info:
        SolverSettings(frame="plate")
    assert info.value.key == "far_field"
    with pytest.raises(ConfigError, match="frame") as info:
        SolverSettings(frame="body", far_field="inletOutlet")
    assert info.value.key == "frame"


def read_table(path) -> np.ndarray:
    """Rows of a Function1 table file or tabulatedAccelerationSource table as numbers."""
    text = path.read_text()
    body = text[text.index("("):]
    rows = []
    for line in body.splitlines()[1:-1]:
        rows.append([float(v) for v in line.replace("(", " ").replace(")", " ").split()])
    return np.array(rows)


def test_plate_frame_case_holds_the_frame_tables_and_no_mesh_motion(tmp_path):
    case = write_case(tmp_path / "c", MOTION, end_time=0.5, mesh="coarse", ramp_time=0.1,
                      solver=PLATE)
    constant = case / "constant"
    assert not (constant / "motion.dat").exists()
    assert "staticFvMesh" in (constant / "dynamicMeshDict").read_text()
    mrf = (constant / "MRFProperties").read_text()
    assert "cellZone            plateFrame;" in mrf and "nonRotatingPatches  (farfield);" in mrf
    assert "tabulatedAccelerationSource" in (constant / "fvOptions").read_text()
    assert (case / "system/blockMeshDict").read_text().count("plateFrame (") == 4
    u = (case / "0/U").read_text()
    assert "uniformInletOutlet" in u and "movingWallVelocity" not in u
    assert 'frame = "plate"' in (case / "mfflap_case.toml").read_text()

    tables = plate_frame_tables(MOTION, table_times(0.5), 0.3, ramp_time=0.1)
    rate = read_table(constant / "pitchRate.dat")
    inflow = read_table(constant / "farFieldVelocity.dat")
    accel = read_table(constant / "acceleration.dat")
    t = rate[:, 0]
    assert t[0] == 0 and t[-1] > 0.5  # past the end time
    state = imposed_state(MOTION, t, 0.1)
    # (the times are written to 9 digits)
    np.testing.assert_allclose(rate[:, 1], state.pitch_rate, rtol=1e-6, atol=1e-9)
    np.testing.assert_allclose(inflow[:, 1:], tables["inflow"][:, 1:], rtol=1e-8, atol=1e-12)
    np.testing.assert_allclose(accel[:, 1:4], tables["acceleration"][:, 1:], rtol=1e-8,
                               atol=1e-12)
    assert np.all(accel[:, 4:] == 0)  # the MRF zone turns the frame, not this source
    # the pitch rate (rad/s) is the derivative of the pitch a moving-mesh case would impose
    dtheta = np.diff(imposed_state(MOTION, t, 0.1).pitch_angle) / np.diff(t)
    np.testing.assert_allclose((rate[1:, 1] + rate[:-1, 1]) / 2, dtheta, rtol=0.01, atol=5e-3)

    inertial = write_case(tmp_path / "i", MOTION, end_time=0.5, mesh="coarse")
    assert (inertial / "constant/motion.dat").exists()
    assert not (inertial / "constant/MRFProperties").exists()
    assert "plateFrame" not in (inertial / "system/blockMeshDict").read_text()


@pytest.mark.openfoam
def test_plate_frame_run_gives_the_moving_mesh_forces(tmp_path):
    """The same motion on the coarse mesh, moving mesh and plate frame (both with the
    inletOutlet far field), through the start-up ramp and the first stroke: the same loads.
    A sign error in the frame's rotation, inflow or acceleration would not come close."""
    assert openfoam_available(), "OpenFOAM must be installed (.ci/run installs it)"
    end, ramp = 0.3, 0.2
    loads, steps = {}, {}
    for frame in ("inertial", "plate"):
        case = write_case(tmp_path / frame, MOTION, end_time=end, mesh="coarse",
                          ramp_time=ramp, solver=replace(PLATE, frame=frame))
        run_case(case, timeout_s=600)
        history = read_forces(case)
        assert history.time[-1] > end - 0.005
        loads[frame] = to_loads(history, imposed_state(MOTION, history.time, ramp), 0.18,
                                0.18, frame, frame=frame)
        steps[frame] = solver_provenance(case)["n_time_steps"]
    log = (tmp_path / "plate" / "log.pimpleFoam").read_text()
    assert "creating MRF zone: plateFrame" in log and "tabulatedAccelerationSource" in log
    # one time step per "Time = t" line, not counting the acceleration source's lines
    assert steps["plate"] == log.count("\nTime = ") - log.count(" accelerations: ")
    t = np.linspace(0.05, end - 0.005, 200)
    a, b = loads["inertial"], loads["plate"]
    for key in ("normal_force", "moment"):
        x, y = np.interp(t, b.time, getattr(b, key)), np.interp(t, a.time, getattr(a, key))
        assert nrmse(x, y) < 0.03, key
    fn = np.interp(t, a.time, a.normal_force)
    assert np.ptp(fn) > 50  # the stroke loads the plate: the comparison is not of zeros


def test_cfd_write_frame_plate_takes_the_inlet_outlet_far_field(tmp_path):
    from pathlib import Path

    from click.testing import CliRunner

    from mfflap.cli.main import cli

    case_file = Path(__file__).parents[3] / "cases" / "paper2026.toml"
    res = CliRunner().invoke(cli, ["cfd", "write", str(case_file), str(tmp_path / "c"),
                                   "--setup", "affordable", "--set",
                                   'cfd.frame="plate"', "--cycles", "0.1"])
    assert res.exit_code == 0, res.output
    assert "plate frame" in res.output
    case = tmp_path / "c"
    assert 'mesh = "graded"' in (case / "mfflap_case.toml").read_text()
    assert "uniformInletOutlet" in (case / "0/U").read_text()
    assert "type fixedValue; value uniform 0;" in (case / "0/p").read_text()
    assert (case / "constant/MRFProperties").is_file()
    res = CliRunner().invoke(cli, ["cfd", "write", str(case_file), str(tmp_path / "d"),
                                   "--set", 'cfd.frame="plate"',
                                   "--set", 'cfd.far_field="freestream"'])
    assert res.exit_code == 2 and "cfd.far_field" in res.output and "inletOutlet" in res.output
    assert not (tmp_path / "d" / "constant").exists()


def test_convergence_refuses_a_plate_frame_set_up_in_a_freestream_study(tmp_path):
    from mfflap.campaign.convergence import run_convergence
    from mfflap.cfd.openfoam.setups import setup

    plate = setup("affordable")
    plate = replace(plate, name="plate", solver=replace(plate.solver, frame="plate",
                                                        far_field="inletOutlet"))
    with pytest.raises(ConfigError, match=r"'plate'.*inletOutlet") as err:
        run_convergence(tmp_path / "study", MOTION, 1.0, meshes=["coarse"], setups=[plate])
    assert err.value.key == "far_field"
    assert not (tmp_path / "study" / "cases").exists()


@pytest.mark.openfoam
def test_decomposed_plate_frame_run_matches_the_serial_run(tmp_path):
    """The MRF cell zone and the acceleration source survive decomposePar: 2 ranks give
    the serial forces."""
    serial = write_case(tmp_path / "serial", MOTION, end_time=0.03, mesh="coarse",
                        solver=PLATE)
    parallel = write_case(tmp_path / "parallel", MOTION, end_time=0.03, mesh="coarse",
                          solver=PLATE)
    run_case(serial, timeout_s=300)
    run_case(parallel, timeout_s=300, n_procs=2)
    assert "Finalising parallel run" in (parallel / "log.pimpleFoam").read_text()
    a, b = read_forces(serial), read_forces(parallel)
    late = a.time > 0.015
    fy = np.interp(a.time[late], b.time, b.force[:, 1])
    assert np.ptp(a.force[late, 1]) > 0
    assert np.max(np.abs(fy - a.force[late, 1])) < 0.02 * np.ptp(a.force[late, 1]) + 1e-6


@pytest.mark.openfoam
def test_campaign_record_of_a_plate_frame_run_carries_its_frame(tmp_path):
    """run_motion writes, runs and parses a plate-frame case: the record's loads are the
    plate-axes conversion and its provenance names the frame."""
    from mfflap.cfd.openfoam.run_motion import run_motion

    record = run_motion(tmp_path / "case", MOTION, "plate", {}, 0.03, mesh="coarse",
                        solver=replace(PLATE, write_interval=0.03))
    assert record.provenance["solver_frame"] == "plate"
    history = read_forces(tmp_path / "case")
    np.testing.assert_allclose(record.loads.normal_force, history.force[:, 1])
    np.testing.assert_allclose(record.loads.tangential_force, history.force[:, 0])
    np.testing.assert_allclose(record.loads.moment, history.moment[:, 2])
