"""The identification report reads the model's NRMSE beside CFD's own: each periodic case's
cycle-to-cycle NRMSE, its mesh and time-step NRMSE where a refined run exists, and why the
fit does not weigh the cases by it (the inverse-variance weights it would give, computed
from the same figures)."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from mfflap.cli.main import cli
from mfflap.records.record import read_record
from mfflap.reports.identification import uncertainty_weighting_said

ROOT = Path(__file__).parents[2]
CASE = str(ROOT / "cases" / "paper2026.toml")


def test_the_weights_said_are_the_inverse_variance_weights_of_the_figures_given():
    model = [0.10, 0.15, 0.20, 0.30]
    cfd = [0.005, 0.02, 0.09, 0.01]
    said = uncertainty_weighting_said(model, cfd)
    e = np.median(model)
    w = 1 / (e**2 + np.square(cfd))
    w /= w.mean()
    low, high = map(float, re.search(r"would range ([\d.]+)-([\d.]+)", said).groups())
    assert low == pytest.approx(w.min(), abs=0.006) and high == pytest.approx(w.max(), abs=0.006)
    assert f"({100 * e:.1f} %)" in said


@pytest.mark.slow
def test_the_report_of_harmonic_cases_gives_cfds_repeat_and_the_weighting(tmp_path):
    """Six real harmonic-set records identified and reported: the table of CFD's own
    cycle-to-cycle NRMSE and the weighting sentence are in the HTML."""
    folder = tmp_path / "records"
    folder.mkdir()
    shipped = sorted((ROOT / "campaigns" / "harmonic_set").glob("harmonic_f1p*.h5"))[:6]
    for p in shipped:
        (folder / p.name).symlink_to(p.resolve())
    out = tmp_path / "id.h5"
    res = CliRunner().invoke(cli, ["identify", CASE, "--fixtures", str(folder),
                                   "--output", str(out)])
    assert res.exit_code == 0, res.output
    res = CliRunner().invoke(cli, ["report", "identification", str(out), "--fixtures",
                                   str(folder)])
    assert res.exit_code == 0, res.output
    html = out.with_suffix(".html").read_text()
    assert "CFD cycle-to-cycle NRMSE of F_n [%]" in html
    assert "inverse-variance" in html and "would range" in html
    refined = [read_record(p) for p in shipped if read_record(p).refinement]
    assert refined, "a shipped record of these has a refined run (campaigns/uncertainty_*)"
    for record in refined:
        for kind, change in record.refinement.items():
            assert f"CFD {kind.replace('_', '-')} NRMSE of F_n [%]" in html
            assert f"<td>{100 * change.normal_force_nrmse:.4g}</td>" in html
