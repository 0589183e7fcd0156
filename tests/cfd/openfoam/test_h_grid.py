"""The H-type mesh of shared/design/openfoam.md (mfflap.cfd.openfoam.h_grid): its graded
edges, its refusals, and the mesh blockMesh builds from it."""

import re

import numpy as np
import pytest

from mfflap.cfd.openfoam import writer
from mfflap.cfd.openfoam.h_grid import HGridSpec, expansion_ratio
from mfflap.cfd.openfoam.setups import setup
from mfflap.cfd.openfoam.writer import SolverSettings, mesh_specs, write_case
from mfflap.errors import ConfigError
from mfflap.kinematics import HarmonicMotion

MOTION = HarmonicMotion(1.0, 0.3, np.deg2rad(20), np.pi / 2)


def cell_lengths(length: float, n_cells: int, grading: float) -> np.ndarray:
    """The cells blockMesh puts on an edge of ``length`` with ``grading`` (last / first)."""
    ratio = grading ** (1 / (n_cells - 1))
    lengths = ratio ** np.arange(n_cells)
    return length * lengths / lengths.sum()


@pytest.mark.parametrize("length, n_cells, first_cell", [
    (1.5985, 40, 0.0005), (2.4, 80, 0.002), (1.6, 40, 0.002), (0.1, 10, 0.03), (3.0, 7, 0.9)])
def test_the_graded_edge_has_the_first_cell_asked_for_and_fills_the_edge(length, n_cells,
                                                                        first_cell):
    cells = cell_lengths(length, n_cells, expansion_ratio(length, n_cells, first_cell))
    assert cells[0] == pytest.approx(first_cell, rel=1e-9)
    assert cells.sum() == pytest.approx(length, rel=1e-12)
    # growing where the first cell is below the mean, shrinking where above
    assert np.all(np.diff(cells) > 0) == (first_cell < length / n_cells)


def test_a_uniform_edge_has_no_grading():
    assert expansion_ratio(1.0, 10, 0.1) == 1.0
    assert expansion_ratio(1.0, 1, 0.5) == 1.0


@pytest.mark.parametrize("n_cells, first_cell", [(5, 1.0), (5, 0.0), (0, 0.1), (5, -0.1)])
def test_an_impossible_graded_edge_is_refused(n_cells, first_cell):
    with pytest.raises(ConfigError, match="first_cell") as err:
        expansion_ratio(1.0, n_cells, first_cell)
    assert err.value.key == "first_cell_m"


@pytest.mark.parametrize("change, key", [
    ({"n_side": 0}, "n_side"), ({"n_thickness": 0}, "n_thickness"),
    ({"first_cell_m": 0.0}, "first_cell_m"), ({"first_cell_m": 0.02}, "first_cell_m"),
    ({"downstream_chords": 0.5}, "downstream_chords")])
def test_a_bad_h_grid_is_refused_naming_the_key(change, key):
    values = dict(name="h", n_chord=20, n_thickness=2, n_upstream=10, n_downstream=20,
                  n_side=10, first_cell_m=0.0005) | change
    with pytest.raises(ConfigError, match=key) as err:
        HGridSpec(**values)
    assert err.value.key == key


def test_the_shipped_h_grid_is_openfoam_md_s_mesh():
    """The far field 10 chords up, 15 down and 10 to each side, the first cell 0.5 mm off
    the plate, and the cell count within 0.5 % of that file's 16,442."""
    spec = mesh_specs()["openfoam_md"]
    assert isinstance(spec, HGridSpec)
    assert (spec.upstream_chords, spec.downstream_chords, spec.side_chords) == (10, 15, 10)
    assert spec.first_cell_m == 0.0005
    assert spec.n_cells == pytest.approx(16_442, rel=0.005)
    baseline = setup("openfoam_md")
    assert baseline.mesh == spec
    solver = baseline.solver
    assert (solver.max_courant, solver.n_outer_correctors, solver.n_correctors) == (2.0, 2, 1)
    assert (solver.pressure_solver, solver.velocity_convection, solver.far_field) == (
        "PCG", "linearUpwind", "freestream")


@pytest.mark.parametrize("coarser, finer, n_cells_there, rel", [
    ("openfoam_md", "openfoam_md_medium", 32_452, 0.005),
    ("openfoam_md_medium", "openfoam_md_fine", 67_320, 0.025)])
def test_the_finer_h_grids_are_openfoam_md_s_medium_and_fine_meshes(coarser, finer,
                                                                     n_cells_there, rel):
    """openfoam.md's cost table gives its medium and fine meshes only as 32,452 and 67,320
    cells: each shipped H-grid has the next coarser one's far field and first cell, is finer
    in every block row and column, and has about that many cells."""
    specs = mesh_specs()
    coarse, fine = specs[coarser], specs[finer]
    assert isinstance(fine, HGridSpec)
    assert fine.n_cells == pytest.approx(n_cells_there, rel=rel)
    for key in ("upstream_chords", "downstream_chords", "side_chords", "first_cell_m"):
        assert getattr(fine, key) == getattr(coarse, key)
    for key in ("n_chord", "n_thickness", "n_upstream", "n_downstream", "n_side"):
        assert 1.3 < getattr(fine, key) / getattr(coarse, key) < 1.6, key


@pytest.mark.parametrize("body, key", [
    ('[m]\ntopology = "C"\nn_chord = 5\n', "m.topology"),
    ('[m]\ntopology = "H"\nn_chord = 5\nn_radial = 5\n', "m"),
    ('[m]\nn_chord = 5\nn_thickness = 4\n', "m"),
    # a value the resolution refuses: blockMesh cannot make 2.5 cells, nor true of them
    ('[m]\nn_chord = 2.5\nn_edge = 2\nn_radial = 5\nradial_expansion = 10.0\n'
     'radius_chords = 5.0\n', "m.n_chord"),
    ('[m]\ntopology = "H"\nn_chord = 5\nn_thickness = 2\nn_upstream = 5\n'
     'n_downstream = 5\nn_side = true\nfirst_cell_m = 0.001\n', "m.n_side"),
])
def test_a_bad_mesh_table_names_the_file_and_key(tmp_path, monkeypatch, body, key):
    (tmp_path / "meshes.toml").write_text(body)
    monkeypatch.setattr(writer, "template_dir", lambda: tmp_path)
    with pytest.raises(ConfigError) as err:
        mesh_specs()
    assert err.value.key == key
    assert str(tmp_path / "meshes.toml") in str(err.value)


def test_the_h_grid_case_has_its_own_block_mesh_and_the_plate_frame_zone(tmp_path):
    spec = mesh_specs()["openfoam_md"]
    case = write_case(tmp_path / "h", MOTION, end_time=0.01, mesh="openfoam_md")
    text = (case / "system" / "blockMeshDict").read_text()
    assert "H-type" in text and "arc" not in text
    blocks = re.findall(r"hex \(([\d ]+)\)\s+(\w+ )?\((\d+) (\d+) 1\)", text)
    assert len(blocks) == 8
    assert sum(int(b[2]) * int(b[3]) for b in blocks) == spec.n_cells
    assert "n_cells = 16480" in (case / "mfflap_case.toml").read_text()
    plate = write_case(tmp_path / "p", MOTION, end_time=0.01, mesh="openfoam_md",
                       solver=SolverSettings(frame="plate", far_field="inletOutlet"))
    zones = re.findall(r"hex \([\d ]+\) plateFrame \(", (plate / "system" /
                                                          "blockMeshDict").read_text())
    assert len(zones) == 8


def _meshed_and_checked(spec: HGridSpec, tmp_path):
    """A case of ``spec`` with the openfoam_md set-up's solver, meshed by blockMesh; checkMesh
    passes it and counts the spec's cells."""
    from mfflap.cfd.openfoam.runner import run_application

    case = write_case(tmp_path / "h", MOTION, end_time=0.004, mesh=spec,
                      solver=setup("openfoam_md").solver)
    run_application(case, "blockMesh", timeout_s=120)
    log = run_application(case, "checkMesh", timeout_s=120).read_text()
    assert "Mesh OK" in log
    assert int(re.search(r"cells:\s+(\d+)", log).group(1)) == spec.n_cells
    return case


@pytest.mark.openfoam
def test_the_h_grid_builds_passes_checkmesh_and_runs(tmp_path):
    """blockMesh builds the spec's cells inside the stated far field, with the first cell
    0.5 mm off the plate's faces and the plate's chordwise cells carried up- and downstream;
    a few time steps of the openfoam_md set-up run and give finite forces."""
    import pyvista as pv

    from mfflap.cfd.openfoam.forces import read_forces
    from mfflap.cfd.openfoam.runner import run_case

    spec = mesh_specs()["openfoam_md"]
    case = _meshed_and_checked(spec, tmp_path)
    (case / "case.foam").touch()
    reader = pv.POpenFOAMReader(str(case / "case.foam"))
    reader.enable_all_patch_arrays()
    data = reader.read()
    points = np.asarray(data["internalMesh"].points)
    chord = 0.16
    assert points[:, 0].min() == pytest.approx(-10 * chord)
    assert points[:, 0].max() == pytest.approx(16 * chord)
    assert np.abs(points[:, 1]).max() == pytest.approx(10 * chord)
    plate = np.asarray(data["boundary"]["plate"].points)
    assert data["boundary"]["plate"].n_cells == 2 * spec.n_chord + 2 * spec.n_thickness
    front = points[np.abs(points[:, 2]) < 1e-9]
    above_mid_chord = np.sort(front[np.abs(front[:, 0] - chord / 2) < 1e-4][:, 1])
    above_mid_chord = above_mid_chord[above_mid_chord > 0.0015 - 1e-9]
    assert above_mid_chord[1] - above_mid_chord[0] == pytest.approx(spec.first_cell_m, rel=1e-3)
    # the trailing edge's cells continue downstream at a chordwise cell's length
    wake_line = np.unique(np.round(front[np.abs(front[:, 1] - 0.0015) < 1e-9][:, 0], 9))
    at_te = np.searchsorted(wake_line, chord - 1e-6)  # float32 points
    assert wake_line[at_te + 1] - wake_line[at_te] == pytest.approx(chord / spec.n_chord,
                                                                   rel=1e-3)
    assert plate[:, 0].min() == pytest.approx(0.0) and plate[:, 0].max() == pytest.approx(chord)
    run_case(case, timeout_s=300)
    history = read_forces(case)
    assert history.time[-1] == pytest.approx(0.004, abs=5e-4)
    assert np.all(np.isfinite(history.force))


@pytest.mark.openfoam
@pytest.mark.parametrize("name", ["openfoam_md_medium", "openfoam_md_fine"])
def test_the_finer_h_grids_build_and_pass_checkmesh(tmp_path, name):
    _meshed_and_checked(mesh_specs()[name], tmp_path)
