"""compare_with_model, the library behind `mfflap cfd parse` (its CLI tests are in
test_case_inputs.py, test_fluent.py, test_motion_table.py and test_cli_cfd_gradcheck.py)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from mfflap.cfd.model_comparison import compare_with_model
from mfflap.errors import ConfigError

CASE = Path(__file__).resolve().parents[1] / "cases" / "paper2026.toml"


def _report(path: Path, t: np.ndarray, fx: np.ndarray) -> Path:
    from test_fluent import write_plate_report

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
