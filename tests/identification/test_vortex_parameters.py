"""The discrete-vortex model's critical LESP and core radius identified from real CFD
records (mfflap.identification.vortex_parameters): the grid is searched whole, the pair
kept is the grid's best, and bad input is refused naming the key."""

from __future__ import annotations

import numpy as np
import pytest

from mfflap.errors import ConfigError, MfflapError
from mfflap.hydro.discrete_vortex import VortexModelSettings
from mfflap.identification.vortex_parameters import (
    identify_vortex_parameters,
    record_nrmse,
)
from mfflap.records.record import fixture_dir, read_records


@pytest.fixture(scope="module")
def runs():
    """Two real back-tests of the main job: the beta = 0 optimum, which sheds from its
    leading edge, and the best sinusoid."""
    every = read_records(fixture_dir("backtest_main_job"))
    return [r for r in every if r.parameters.get("label") in ("β = 0", "best sinusoid")
            and r.provenance["solver_max_courant"] == 2.0]  # the table1 set-up's


@pytest.mark.slow
def test_the_pair_kept_is_the_best_of_the_whole_grid(runs):
    assert len(runs) == 2
    fit = identify_vortex_parameters(runs, critical_lesp=(0.1, 0.3, float("inf")),
                                     core_radius_chords=(0.02, 0.05))
    assert len(fit.grid) == 6
    assert fit.score == min(row[2] for row in fit.grid)
    best = next(row for row in fit.grid if row[:2] == (fit.critical_lesp,
                                                      fit.core_radius_chords))
    assert best[2] == fit.score
    # the score is the RMS of the records' NRMSE at the pair kept
    assert fit.score == pytest.approx(np.sqrt(np.mean(np.square(
        list(fit.record_nrmse.values())))))
    again = record_nrmse(runs[0], fit.settings())
    assert again == pytest.approx(fit.record_nrmse[runs[0].name])
    # the grid is not flat on a motion that sheds: leading-edge shedding changes F_n
    scores = [row[2] for row in fit.grid]
    assert max(scores) > 1.05 * min(scores)


def test_an_empty_grid_or_no_record_is_refused_naming_the_key(runs):
    with pytest.raises(ConfigError) as err:
        identify_vortex_parameters([])
    assert err.value.key == "records"
    with pytest.raises(ConfigError) as err:
        identify_vortex_parameters(runs, critical_lesp=())
    assert err.value.key == "critical_lesp"
    with pytest.raises(ConfigError) as err:
        identify_vortex_parameters(runs, core_radius_chords=(0.02, -1.0))
    assert err.value.key == "core_radius_chords"


def test_a_record_shorter_than_the_periods_compared_is_refused_naming_it(runs):
    with pytest.raises(MfflapError, match=runs[0].name):
        record_nrmse(runs[0], VortexModelSettings(), periods=100.0)
