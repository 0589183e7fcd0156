"""Named CFD set-ups (cfd_templates/openfoam/setups.toml): parsing, refusals, and the case a
set-up writes."""

import dataclasses
import re
from pathlib import Path

import pytest
from click.testing import CliRunner

from mfflap.cfd.openfoam.setups import named_setups, setup
from mfflap.cfd.openfoam.writer import mesh_specs
from mfflap.cli.main import cli
from mfflap.errors import ConfigError
from mfflap.toml_io import read_toml

CASE = Path(__file__).parents[3] / "cases" / "paper2026.toml"


def test_shipped_setups_name_real_meshes_and_valid_settings():
    setups = named_setups()
    assert {"reference", "affordable"} <= set(setups)
    affordable = setups["affordable"]
    assert affordable.mesh == mesh_specs()["graded"]
    assert (affordable.solver.n_outer_correctors, affordable.solver.n_correctors) == (1, 2)
    assert affordable.solver.velocity_convection == "LUST"
    assert affordable.solver.pressure_final_rel_tol == 0.01
    assert setups["reference"].solver.pressure_final_rel_tol == 0.0
    assert setups["reference"].mesh.name == "medium"
    assert affordable.description


def test_medium_piso_is_the_reference_with_affordables_pressure_velocity_coupling():
    """medium_piso changes the reference in what PISO 1x2 and the relaxed last corrector
    need and in nothing else (its measured distance rests on that)."""
    setups = named_setups()
    reference, piso, affordable = (setups[n].solver for n in
                                   ("reference", "medium_piso", "affordable"))
    assert setups["medium_piso"].mesh == setups["reference"].mesh
    coupling = ("n_outer_correctors", "n_correctors", "pressure_final_rel_tol")
    for field, value in dataclasses.asdict(piso).items():
        expected = getattr(affordable if field in coupling else reference, field)
        assert value == expected, field
    assert piso.velocity_convection == "linearUpwind" != affordable.velocity_convection
    co5 = setups["medium_piso_co5"]
    assert co5.mesh == setups["medium_piso"].mesh
    assert dataclasses.replace(co5.solver, max_courant=piso.max_courant) == piso
    assert co5.solver.max_courant == 5.0


def test_reference_all_y_plus_is_the_reference_but_for_its_wall_treatment():
    """Its measured distance from the reference is the wall treatment's and nothing else's."""
    setups = named_setups()
    reference, other = setups["reference"], setups["reference_all_y_plus"]
    assert other.mesh == reference.mesh
    assert reference.solver.wall_treatment == "log_law"
    assert dataclasses.replace(other.solver, wall_treatment="log_law") == reference.solver
    assert other.solver.wall_treatment == "all_y_plus"


def test_the_coarse_courant_set_ups_change_the_fixtures_set_up_in_what_they_say_alone():
    """coarse_co2, coarse_co1 and coarse_co05 are the shipped fixtures' set-up (the defaults
    on the coarse mesh) but for the Courant limit and, for the last two, the far field."""
    setups = named_setups()
    shipped = dataclasses.asdict(dataclasses.replace(setups["coarse_co2"].solver,
                                                     max_courant=4.0))
    for name, changes in (("coarse_co2", {"max_courant": 2.0}),
                          ("coarse_co1", {"max_courant": 1.0, "far_field": "inletOutlet"}),
                          ("coarse_co05", {"max_courant": 0.5, "far_field": "inletOutlet"})):
        assert setups[name].mesh == mesh_specs()["coarse"]
        solver = dataclasses.asdict(setups[name].solver)
        assert {k: v for k, v in solver.items() if shipped[k] != v} == changes, name


@pytest.mark.parametrize("body, key", [
    ('[a]\nmesh = "nowhere"\n', "a.mesh"),
    ('[a]\nmesh = "coarse"\nmax_courrant = 4.0\n', "a.max_courrant"),
    ('[a]\nmesh = "coarse"\nvelocity_convection = "upwind"\n', "a.velocity_convection"),
    ('[a]\nmesh = "coarse"\nmax_courant = "four"\n', "a"),
    ('a = 3\n', "a"),
])
def test_bad_setup_file_names_file_and_key(tmp_path, body, key):
    path = tmp_path / "setups.toml"
    path.write_text(body)
    with pytest.raises(ConfigError) as err:
        named_setups(path)
    assert err.value.key == key
    assert str(path) in str(err.value)


def test_unknown_setup_lists_the_known_ones():
    with pytest.raises(ConfigError, match="affordable"):
        setup("cheapest")


def test_cfd_write_with_a_setup_writes_its_mesh_and_solver(tmp_path):
    res = CliRunner().invoke(cli, ["cfd", "write", str(CASE), str(tmp_path / "c"),
                                   "--setup", "affordable", "--cycles", "0.1"])
    assert res.exit_code == 0, res.output
    case = tmp_path / "c"
    assert 'mesh = "graded"' in (case / "mfflap_case.toml").read_text()
    assert "Gauss LUST grad(U)" in (case / "system" / "fvSchemes").read_text()
    solution = (case / "system" / "fvSolution").read_text()
    assert "nOuterCorrectors 1;" in solution and "nCorrectors     2;" in solution
    assert "solver GAMG;" in solution
    assert "pFinal { $p; relTol 0.01; }" in solution
    assert not (case / "setups.toml").exists() and not (case / "meshes.toml").exists()


def test_cfd_write_runs_a_setups_solver_on_another_mesh(tmp_path):
    """--setup with --mesh: the set-up's solver settings on that mesh, to tell what its
    mesh does from what its solver settings do."""
    res = CliRunner().invoke(cli, ["cfd", "write", str(CASE), str(tmp_path / "c"),
                                   "--setup", "affordable", "--mesh", "medium",
                                   "--cycles", "0.1"])
    assert res.exit_code == 0, res.output
    case = tmp_path / "c"
    assert 'mesh = "medium"' in (case / "mfflap_case.toml").read_text()
    assert "Gauss LUST grad(U)" in (case / "system" / "fvSchemes").read_text()
    assert "nOuterCorrectors 1;" in (case / "system" / "fvSolution").read_text()
    medium = mesh_specs()["medium"]
    block_mesh = (case / "system" / "blockMeshDict").read_text()
    assert f"({medium.n_chord} {medium.n_radial} 1)" in block_mesh


def test_cfd_write_overrides_a_setups_velocity_convection(tmp_path):
    res = CliRunner().invoke(cli, ["cfd", "write", str(CASE), str(tmp_path / "c"),
                                   "--setup", "affordable", "--set",
                                   'cfd.velocity_convection="linearUpwind"', "--cycles", "0.1"])
    assert res.exit_code == 0, res.output
    schemes = (tmp_path / "c" / "system" / "fvSchemes").read_text()
    assert "Gauss linearUpwind grad(U)" in schemes and "LUST" not in schemes
    assert "nOuterCorrectors 1;" in (tmp_path / "c" / "system" / "fvSolution").read_text()


def test_every_mesh_and_scheme_is_named_in_the_options_and_the_case_file():
    from mfflap.cfd.openfoam.writer import VELOCITY_CONVECTION_SCHEMES
    from mfflap.cli.options import MESH_NAMES
    from mfflap.study_tables import VELOCITY_CONVECTION_NAMES

    assert MESH_NAMES.split(", ") == list(mesh_specs())
    assert VELOCITY_CONVECTION_NAMES == VELOCITY_CONVECTION_SCHEMES


def test_mesh_and_solver_of_a_command():
    from mfflap.cfd.openfoam.setups import mesh_and_solver, setup
    from mfflap.cfd.openfoam.writer import SolverSettings
    from mfflap.errors import ConfigError

    mesh, solver = mesh_and_solver()
    assert mesh.name == "coarse" and solver == SolverSettings()
    mesh, solver = mesh_and_solver(mesh="medium")
    assert mesh.name == "medium" and solver == SolverSettings()
    mesh, solver = mesh_and_solver(setup_name="affordable")
    assert (mesh, solver) == (setup("affordable").mesh, setup("affordable").solver)
    mesh, solver = mesh_and_solver(mesh="medium", setup_name="affordable")
    assert (mesh, solver) == (mesh_specs()["medium"], setup("affordable").solver)
    with pytest.raises(ConfigError, match="finest"):
        mesh_and_solver(mesh="finest", setup_name="affordable")
    with pytest.raises(ConfigError, match="cheapest"):
        mesh_and_solver(setup_name="cheapest")
    with pytest.raises(ConfigError, match="finest"):
        mesh_and_solver(mesh="finest")


def test_cfd_write_sets_the_courant_limit_and_the_correctors(tmp_path):
    """[cfd] max_courant, outer_correctors and correctors override the set-up's; an
    impossible value is refused naming its key, and no case is left behind."""
    res = CliRunner().invoke(cli, ["cfd", "write", str(CASE), str(tmp_path / "c"),
                                   "--setup", "affordable", "--cycles", "0.1",
                                   "--set", "cfd.max_courant=2.5",
                                   "--set", "cfd.outer_correctors=3",
                                   "--set", "cfd.correctors=2"])
    assert res.exit_code == 0, res.output
    case = tmp_path / "c"
    assert res.stdout.strip() == (f"wrote {case} (mesh graded, inertial frame, PIMPLE 3x2, "
                                  "max Co 2.5, GAMG, log_law wall treatment, end time 0.1 s)")
    assert "does not start at rest" in res.stderr  # no --ramp-time
    assert re.search(r"^maxCo\s+2.5;", (case / "system" / "controlDict").read_text(), re.M)
    solution = (case / "system" / "fvSolution").read_text()
    assert "nOuterCorrectors 3;" in solution and "nCorrectors     2;" in solution
    assert "Gauss LUST grad(U)" in (case / "system" / "fvSchemes").read_text()  # the rest kept
    kept = read_toml(case / "mfflap_case.toml")  # the settings asked for, beside the case
    assert kept["solver_max_courant"] == 2.5 and kept["solver_n_outer_correctors"] == 3
    assert kept["solver_velocity_convection"] == "LUST"
    res = CliRunner().invoke(cli, ["cfd", "write", str(CASE), str(tmp_path / "bad"),
                                   "--set", "cfd.max_courant=0"])
    assert res.exit_code == 2
    assert "cfd.max_courant: value 0 is out of range; allowed: (0, 100]" in res.output
    assert not (tmp_path / "bad").exists()
    res = CliRunner().invoke(cli, ["cfd", "write", str(CASE), str(tmp_path / "bad"),
                                   "--set", "cfd.correctors=0"])
    assert res.exit_code == 2 and "cfd.correctors" in res.output
