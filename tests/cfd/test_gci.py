"""Grid convergence index against Celik et al. (2008) and against solutions built by hand."""

import json

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from mfflap.cfd.gci import grid_convergence
from mfflap.errors import ConfigError


def test_celik_2008_worked_example():
    # Celik et al. (2008), Table 1, column phi = 1: N = 18000, 8000, 4500;
    # phi = 6.063, 5.972, 5.863 -> p = 1.53, phi_ext = 6.1685, e_a = 1.5 %, e_ext = 1.7 %,
    # GCI_fine = 2.2 % (the table's rounding)
    g = grid_convergence([6.063, 5.972, 5.863], [18000, 8000, 4500])
    assert g.refinement_ratios == pytest.approx((1.5, 4 / 3))
    assert g.behaviour == "monotone"
    assert g.apparent_order == pytest.approx(1.53, abs=0.005)
    assert g.extrapolated == pytest.approx(6.1685, abs=5e-4)
    assert g.relative_error_fine == pytest.approx(0.015, abs=5e-4)
    assert g.extrapolated_relative_error == pytest.approx(0.017, abs=5e-4)
    assert g.gci_fine == pytest.approx(0.022, abs=5e-4)


@pytest.mark.parametrize("order", [0.7, 1.0, 2.0, 3.2])
@pytest.mark.parametrize("cells", [(27200, 12880, 5800), (4000, 1000, 250), (9000, 5000, 2000)])
def test_recovers_a_power_law_exactly(order, cells):
    # phi(h) = phi_exact + C h^p with h = N^(-1/2): the order and the limit come back exactly
    # whatever the (non-uniform) refinement ratios
    phi_exact, c = 17.25, -40.0
    h = np.asarray(cells, float) ** -0.5
    g = grid_convergence(phi_exact + c * h**order, cells)
    assert g.behaviour == "monotone"
    assert g.apparent_order == pytest.approx(order, rel=1e-9)
    assert g.extrapolated == pytest.approx(phi_exact, rel=1e-9)
    r21 = h[1] / h[0]
    phi1, phi2 = phi_exact + c * h[:2] ** order
    assert g.gci_fine == pytest.approx(1.25 * abs((phi2 - phi1) / phi1) / (r21**order - 1))
    assert g.uncertainty_fine == pytest.approx(1.25 * abs(phi1 - phi_exact), rel=1e-9)
    # in the asymptotic range the two absolute bands differ by exactly r21^p, so the
    # relative indices by r21^p phi2 / phi1
    assert g.uncertainty_medium == pytest.approx(r21**order * g.uncertainty_fine, rel=1e-9)
    assert g.asymptotic_ratio == pytest.approx(phi1 / phi2, rel=1e-9)


def test_unequal_ratios_converge_although_the_error_ratio_exceeds_one():
    # r21 = 2, r32 = 1.25, first order: eps21 / eps32 = 2, which the equal-ratio test
    # |R| < 1 would call divergent
    cells = (10000, 2500, 1600)
    h = np.asarray(cells, float) ** -0.5
    g = grid_convergence(3.0 + h, cells)
    assert g.convergence_ratio == pytest.approx(2.0)
    assert g.behaviour == "monotone"
    assert g.apparent_order == pytest.approx(1.0)
    assert g.extrapolated == pytest.approx(3.0)


def test_order_of_the_inputs_does_not_matter():
    a = grid_convergence([6.063, 5.972, 5.863], [18000, 8000, 4500])
    b = grid_convergence([5.863, 6.063, 5.972], [4500, 18000, 8000])
    assert a == b


def test_three_dimensional_cell_size():
    # N = 8000, 1000, 125 in 3D is r = 2 per level; errors 1/4 then 1/16: p = 2
    g = grid_convergence([1 + 1 / 16, 1 + 1 / 4, 2.0], [8000, 1000, 125], dims=3)
    assert g.refinement_ratios == pytest.approx((2.0, 2.0))
    assert g.apparent_order == pytest.approx(2.0)
    assert g.extrapolated == pytest.approx(1.0)


def test_oscillatory_convergence():
    # phi = 1 + (-1)^k 0.5^k on meshes refined by 2: eps alternate in sign, shrinking by 2
    g = grid_convergence([1 + 0.125, 1 - 0.25, 1 + 0.5], [64 * 64, 32 * 32, 16 * 16])
    assert g.behaviour == "oscillatory"
    assert g.convergence_ratio == pytest.approx(-0.5)
    assert g.converging
    assert g.apparent_order == pytest.approx(1.0)  # |eps32 / eps21| = 2 = r^p with r = 2
    assert np.isfinite(g.gci_fine) and g.gci_fine > 0


@pytest.mark.parametrize("values, behaviour", [([1.0, 1.1, 1.15], "divergent"),
                                               ([1.3, 1.1, 1.0], "divergent"),
                                               ([1.0, 1.2, 1.1], "oscillatory divergent"),
                                               ([1.0, 1.1, 1.1], "divergent")])
def test_divergence_has_no_index(values, behaviour):
    g = grid_convergence(values, [9000, 4000, 1000])
    assert g.behaviour == behaviour
    assert not g.converging
    assert np.isnan(g.apparent_order) and np.isnan(g.gci_fine) and np.isnan(g.extrapolated)
    out = g.as_dict()
    assert out["apparent_order"] is None and out["gci_fine"] is None
    assert out["values"] == list(g.values) and out["converging"] is False
    json.dumps(out, allow_nan=False)  # strict JSON


def test_exact_agreement_of_the_two_finer_meshes():
    g = grid_convergence([2.0, 2.0, 2.5], [9000, 4000, 1000])
    assert g.behaviour == "exact" and g.converging
    assert g.gci_fine == 0 and g.extrapolated == 2.0


@pytest.mark.parametrize("values, cells, key", [
    ([1.0, 2.0], [100, 50], "values"),
    ([1.0, float("nan"), 2.0], [400, 200, 100], "values"),
    ([1.0, 1.1, 1.3], [400, 400, 100], "cell_counts"),
    ([1.0, 1.1, 1.3], [400, 0, 100], "cell_counts"),
])
def test_impossible_inputs_name_the_key(values, cells, key):
    with pytest.raises(ConfigError) as err:
        grid_convergence(values, cells)
    assert err.value.key == key


def test_impossible_options_name_the_key():
    with pytest.raises(ConfigError, match="safety_factor"):
        grid_convergence([1.0, 1.1, 1.3], [400, 200, 100], safety_factor=0)
    with pytest.raises(ConfigError, match="dims"):
        grid_convergence([1.0, 1.1, 1.3], [400, 200, 100], dims=4)


@settings(max_examples=200, deadline=None)
@given(st.floats(0.3, 4.0), st.floats(1.2, 3.0), st.floats(1.2, 3.0),
       st.floats(-1e3, 1e3).filter(lambda v: abs(v) > 1e-3),
       st.floats(-1e3, 1e3).filter(lambda v: abs(v) > 1e-3))
def test_power_laws_of_any_order_and_ratio(order, r21, r32, phi_exact, c):
    # any monotone power law within double precision: order and limit recovered
    h1 = 1e-2
    h = np.array([h1, h1 * r21, h1 * r21 * r32])
    cells = np.rint(h**-2).astype(int)
    h = cells.astype(float) ** -0.5  # the cell size the counts really give
    assume(len(set(cells.tolist())) == 3)
    # the mesh-to-mesh differences must stand above round-off in phi
    assume(abs(c) * h[0] ** order > 1e-6 * max(1.0, abs(phi_exact)))
    g = grid_convergence(phi_exact + c * h**order, cells)
    assert g.behaviour == "monotone"
    assert g.apparent_order == pytest.approx(order, rel=1e-6, abs=1e-6)
    assert g.extrapolated == pytest.approx(phi_exact, rel=1e-6, abs=1e-6 * abs(c))


def _record(time, normal, tangential, moment, pitch_deg, heave_velocity, n_cells):
    from mfflap.hydro.loads import Loads
    from mfflap.kinematics.state import KinematicState
    from mfflap.records.record import CfdRecord

    zero = np.zeros_like(time)
    state = KinematicState(time=time, pitch_angle=np.full_like(time, np.deg2rad(pitch_deg)),
                           pitch_rate=zero, pitch_acceleration=zero, heave_position=zero,
                           heave_velocity=np.full_like(time, heave_velocity),
                           heave_acceleration=zero)
    full = np.ones_like(time)
    return CfdRecord("r", state, Loads(time, normal * full, tangential * full, moment),
                     {}, {"n_cells": n_cells})


def test_mesh_study_quantities_by_hand():
    from mfflap.campaign.convergence import integral_quantities

    t = np.linspace(0.0, 2.0, 4001)
    # theta = 30 deg, F_n = 10 N, F_t = 2 N, hdot = 0.5 m/s, M = 3 sin(2 pi t) N m
    rec = _record(t, 10.0, 2.0, 3 * np.sin(2 * np.pi * t), 30.0, 0.5, 100)
    q = integral_quantities(rec, 1.0)
    s, c = np.sin(np.pi / 6), np.cos(np.pi / 6)
    assert q["mean_thrust_N"] == pytest.approx(10 * s - 2 * c)
    assert q["mean_input_power_W"] == pytest.approx(-(10 * c + 2 * s) * 0.5)
    assert q["peak_normal_force_N"] == pytest.approx(10.0)
    assert q["rms_moment_Nm"] == pytest.approx(3 / np.sqrt(2), rel=1e-6)
    with pytest.raises(ValueError, match="fewer than two samples"):
        integral_quantities(rec, 2.5)


def test_mesh_gci_reads_cells_from_the_records():
    from mfflap.campaign.convergence import mesh_gci

    t = np.linspace(0.0, 1.0, 201)
    cells = (27200, 12880, 5800)
    # F_n = 100 + 50 h^2 on each mesh: the peak F_n extrapolates to 100 N with order 2
    recs = [_record(t, 100 + 5e4 * n**-1.0, 0.0, np.zeros_like(t), 10.0, 0.0, n)
            for n in cells]
    gci = mesh_gci(recs[::-1], 0.1)
    g = gci["peak_normal_force_N"]
    assert g.cell_counts == cells
    assert g.apparent_order == pytest.approx(2.0) and g.extrapolated == pytest.approx(100.0)
    assert gci["rms_moment_Nm"].behaviour == "exact"
    with pytest.raises(ValueError, match="three meshes"):
        mesh_gci(recs[:2], 0.1)


@pytest.mark.parametrize(("order", "ratio"), [(1.0, 2.0), (2.0, 1.49), (2.0, 2.0), (1.7, 1.3)])
def test_two_level_index_bounds_a_power_law_error_by_its_safety_factor(order, ratio):
    """phi(h) = phi0 + C h^p sampled at h and h / r: the band around the coarse value is
    exactly Fs times its error when the assumed order is the true one."""
    from mfflap.cfd.gci import two_level_index

    phi0, c, h = 3.0, -0.8, 0.4
    coarse, fine = phi0 + c * h**order, phi0 + c * (h / ratio) ** order
    ix = two_level_index(coarse, fine, ratio, order=order)
    assert ix.uncertainty_coarse == pytest.approx(3.0 * abs(coarse - phi0), rel=1e-12)
    assert ix.gci_coarse == pytest.approx(ix.uncertainty_coarse / abs(coarse), rel=1e-12)
    assert ix.relative_difference == pytest.approx((fine - coarse) / abs(coarse))
    # an order assumed higher than the true one under-states the error
    assert two_level_index(coarse, fine, ratio, order=order + 1).uncertainty_coarse < \
        ix.uncertainty_coarse


@pytest.mark.parametrize(("args", "key"), [((1.0, np.nan, 2.0), "values"),
                                           ((1.0, 2.0, 1.0), "refinement_ratio"),
                                           ((1.0, 2.0, 0.5), "refinement_ratio")])
def test_two_level_index_refuses_what_it_cannot_estimate(args, key):
    from mfflap.cfd.gci import two_level_index

    with pytest.raises(ConfigError) as err:
        two_level_index(*args)
    assert err.value.key == key
