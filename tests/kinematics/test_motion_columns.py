"""Motion tables by what their columns hold: aliases, units in the header, rates and
accelerations used as given, and headers that cannot be a motion refused by line."""

from pathlib import Path

import numpy as np
import pytest

from mfflap.errors import ParseError
from mfflap.kinematics.table_file import read_motion_table

T = np.linspace(0.0, 2.0, 41)
W = 2 * np.pi * 0.75
PITCH_RAD = np.radians(20.0) * np.sin(W * T)
HEAVE_M = 0.05 * np.cos(W * T)


def _table(path: Path, header: list[str], columns: list[np.ndarray]) -> Path:
    rows = "\n".join(",".join(f"{v:.15g}" for v in row) for row in np.column_stack(columns))
    path.write_text("# a user's table\n" + ",".join(header) + "\n" + rows + "\n")
    return path


@pytest.mark.parametrize("header, scale", [
    (["time", "pitch_angle", "heave_position"], (1.0, 1.0)),
    (["t", "theta", "h"], (1.0, 1.0)),
    (["t [s]", "pitch [deg]", "heave (mm)"], (np.degrees(1.0), 1e3)),
    (["Time", "pitch_angle_deg", "h_mm"], (np.degrees(1.0), 1e3)),
    (["T (ms)", "Theta [rad]", "H [cm]"], (1.0, 1e2)),
])
def test_the_same_motion_whatever_the_header_calls_its_columns(tmp_path, header, scale):
    time_scale = 1e3 if "(ms)" in header[0] else 1.0
    path = _table(tmp_path / "m.csv", header,
                  [T * time_scale, PITCH_RAD * scale[0], HEAVE_M * scale[1]])
    state = read_motion_table(path).sample(T)
    assert state.pitch_angle == pytest.approx(PITCH_RAD, abs=1e-12)
    assert state.heave_position == pytest.approx(HEAVE_M, abs=1e-12)


def test_rates_and_accelerations_are_used_as_given_at_the_rows(tmp_path):
    """Rates given exactly: the sampled rates and accelerations at the rows are those
    numbers (a spline through the positions alone gets them only approximately, worst at
    the ends, where it knows nothing of the slope)."""
    rate = np.radians(20.0) * W * np.cos(W * T)
    acc = -np.radians(20.0) * W**2 * np.sin(W * T)
    h_dot, h_ddot = -0.05 * W * np.sin(W * T), -0.05 * W**2 * np.cos(W * T)
    path = _table(tmp_path / "m.csv", ["t", "theta", "h", "theta_dot [deg/s]",
                                       "theta_ddot", "h_dot", "h_ddot"],
                  [T, PITCH_RAD, HEAVE_M, np.degrees(rate), acc, h_dot, h_ddot])
    given = read_motion_table(path).sample(T)
    assert given.pitch_rate == pytest.approx(rate, abs=1e-12)
    assert given.pitch_acceleration == pytest.approx(acc, abs=1e-12)
    assert given.heave_velocity == pytest.approx(h_dot, abs=1e-12)
    assert given.heave_acceleration == pytest.approx(h_ddot, abs=1e-12)
    positions_only = read_motion_table(
        _table(tmp_path / "p.csv", ["t", "theta", "h"], [T, PITCH_RAD, HEAVE_M])).sample(T)
    assert np.abs(positions_only.pitch_acceleration - acc).max() > 1e-3
    between = read_motion_table(path).sample(T[:-1] + 0.025)  # halfway between rows
    exact = np.radians(20.0) * np.sin(W * (T[:-1] + 0.025))
    assert between.pitch_angle == pytest.approx(exact, abs=1e-5)  # cubic Hermite: h^4 f""/384


@pytest.mark.parametrize("header, message", [
    (["t", "theta", "pitch_angle_deg", "h"], "'theta' and 'pitch_angle_deg' both hold"),
    (["t", "theta [furlongs]", "h"], "pitch_angle cannot be in 'furlongs'"),
    (["t", "h"], r"missing column\(s\) for pitch_angle"),
    (["t", "theta [rad]", "h [m]", "theta_ddot"], "pitch_acceleration is used with pitch_rate"),
])
def test_a_header_that_is_not_a_motion_is_refused_naming_the_file(tmp_path, header, message):
    path = _table(tmp_path / "m.csv", header, [T] * len(header))
    with pytest.raises(ParseError, match=message) as caught:
        read_motion_table(path)
    assert caught.value.path == str(path)
