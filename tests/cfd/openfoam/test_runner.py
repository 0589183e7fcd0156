"""OpenFOAM adapter: writer, parser (three dialects), loads conversion, and a real run."""

import dataclasses
import re
import shutil
from pathlib import Path

import numpy as np
import pytest
from foamlib import FoamFile
from hypothesis import given, settings
from hypothesis import strategies as st

from mfflap.cfd.force_history import to_loads
from mfflap.cfd.imposed_motion import imposed_state
from mfflap.cfd.openfoam.forces import parse_table, read_forces
from mfflap.cfd.openfoam.runner import openfoam_available, run_case
from mfflap.cfd.openfoam.writer import format_motion_table, motion_table, write_case
from mfflap.errors import CfdRunError, ParseError
from mfflap.hydro import MorisonModel
from mfflap.kinematics import HarmonicMotion, RampHarmonicMotion
from mfflap.metrics import pearson

DATA = Path(__file__).parents[2] / "data" / "openfoam_v1912"
MOTION = HarmonicMotion(1.0, 0.3, np.deg2rad(20), np.pi / 2)


def copy_real_case(tmp_path, folder="0"):
    dest = tmp_path / "case" / "postProcessing" / "forces" / folder
    dest.mkdir(parents=True)
    for name in ("force.dat", "moment.dat"):
        shutil.copy(DATA / name, dest / name)
    return tmp_path / "case"


def test_real_v1912_force_file_parses():
    text = (DATA / "force.dat").read_text()
    arr, dialect = parse_table(text, "force.dat")
    assert dialect == "v1912"
    assert arr.shape[1] == 10
    # total = pressure + viscous, in the real solver output
    np.testing.assert_allclose(arr[:, 1:4], arr[:, 4:7] + arr[:, 7:10], rtol=1e-6, atol=1e-6)
    assert np.all(np.diff(arr[:, 0]) > 0)


def to_bare(text: str) -> str:
    return "\n".join(line if line.startswith("#") else line.replace("(", "").replace(")", "")
                     for line in text.splitlines()) + "\n"


def to_foundation(force_text: str, moment_text: str) -> str:
    f, _ = parse_table(force_text)
    m, _ = parse_table(moment_text)
    rows = ["# Time forces(pressure viscous) moment(pressure viscous)"]
    for a, b in zip(f, m, strict=True):
        rows.append(f"{a[0]:.10g} (({a[4]:.10g} {a[5]:.10g} {a[6]:.10g}) ({a[7]:.10g} "
                    f"{a[8]:.10g} {a[9]:.10g})) (({b[4]:.10g} {b[5]:.10g} {b[6]:.10g}) "
                    f"({b[7]:.10g} {b[8]:.10g} {b[9]:.10g}))")
    return "\n".join(rows) + "\n"


def test_three_dialects_give_the_same_totals(tmp_path):
    ref = read_forces(copy_real_case(tmp_path))
    bare = tmp_path / "bare" / "postProcessing" / "forces" / "0"
    bare.mkdir(parents=True)
    for name in ("force.dat", "moment.dat"):
        (bare / name).write_text(to_bare((DATA / name).read_text()))
    got = read_forces(tmp_path / "bare")
    assert got.dialect == "com-bare"
    np.testing.assert_allclose(got.force, ref.force)
    fnd = tmp_path / "fnd" / "postProcessing" / "forces" / "0"
    fnd.mkdir(parents=True)
    (fnd / "forces.dat").write_text(to_foundation((DATA / "force.dat").read_text(),
                                                  (DATA / "moment.dat").read_text()))
    got = read_forces(tmp_path / "fnd")
    assert got.dialect == "foundation"
    # the Foundation file's first triple is pressure only: the parser must add viscous
    np.testing.assert_allclose(got.force, ref.force, rtol=1e-6, atol=1e-8)
    np.testing.assert_allclose(got.moment, ref.moment, rtol=1e-6, atol=1e-8)


POROUS_FORCE = np.array([0.25, -0.5, 0.0])
POROUS_MOMENT = np.array([0.0, 0.0, 0.125])


def to_foundation_porous(force_text: str, moment_text: str) -> str:
    """Foundation rows with a third (porous) triple in the force and the moment."""
    f, _ = parse_table(force_text)
    m, _ = parse_table(moment_text)
    rows = ["# Time forces(pressure viscous porous) moment(pressure viscous porous)"]
    pf, pm = (" ".join(f"{v:.10g}" for v in x) for x in (POROUS_FORCE, POROUS_MOMENT))
    for a, b in zip(f, m, strict=True):
        rows.append(f"{a[0]:.10g} (({a[4]:.10g} {a[5]:.10g} {a[6]:.10g}) ({a[7]:.10g} "
                    f"{a[8]:.10g} {a[9]:.10g}) ({pf})) (({b[4]:.10g} {b[5]:.10g} "
                    f"{b[6]:.10g}) ({b[7]:.10g} {b[8]:.10g} {b[9]:.10g}) ({pm}))")
    return "\n".join(rows) + "\n"


def layout_files(layout: str) -> list[str]:
    """The texts a forces function object writes in ``layout``: one file holding forces
    and moments (Foundation), or a force file then a moment file (openfoam.com)."""
    force, moment = ((DATA / name).read_text() for name in ("force.dat", "moment.dat"))
    if layout == "v1912":
        return [force, moment]
    if layout == "com-bare":
        return [to_bare(force), to_bare(moment)]
    if layout == "foundation":
        return [to_foundation(force, moment)]
    if layout == "foundation-bare":
        return [to_bare(to_foundation(force, moment))]
    return [to_foundation_porous(force, moment)]


@pytest.mark.parametrize("layout", ["v1912", "com-bare", "foundation", "foundation-bare",
                                    "foundation-porous"])
@pytest.mark.parametrize("names", [("force.dat", "moment.dat"), ("forces.dat", "moments.dat"),
                                   ("a.dat", "b.dat")])
def test_every_layout_under_every_file_name_gives_the_totals(tmp_path, layout, names):
    """The layout is read from the rows and the quantity from the header, whatever the files
    are called: openfoam.com rows in forces.dat and Foundation rows (pressure and viscous,
    and porous) in force.dat give the real run's totals."""
    ref = read_forces(copy_real_case(tmp_path))
    folder = tmp_path / "user" / "postProcessing" / "forces" / "0"
    folder.mkdir(parents=True)
    for name, text in zip(names, layout_files(layout), strict=False):
        (folder / name).write_text(text)
    got = read_forces(tmp_path / "user")
    porous = layout == "foundation-porous"
    np.testing.assert_allclose(got.force, ref.force + (POROUS_FORCE if porous else 0.0),
                               rtol=1e-6, atol=1e-8)
    np.testing.assert_allclose(got.moment, ref.moment + (POROUS_MOMENT if porous else 0.0),
                               rtol=1e-6, atol=1e-8)
    assert got.dialect == layout.replace("-bare", "") if layout != "com-bare" else "com-bare"


def test_an_empty_force_file_is_named_by_its_path(tmp_path):
    folder = tmp_path / "case" / "postProcessing" / "forces" / "0"
    folder.mkdir(parents=True)
    (folder / "force.dat").write_text("")
    with pytest.raises(ParseError) as info:
        read_forces(tmp_path / "case")
    assert info.value.path == str(folder / "force.dat") and "empty" in str(info.value)


def test_a_row_of_no_known_layout_is_refused_naming_the_line(tmp_path):
    folder = tmp_path / "case" / "postProcessing" / "forces" / "0"
    folder.mkdir(parents=True)
    (folder / "force.dat").write_text("# Force\n0.1 (1 2 3) (4 5 6)\n")
    with pytest.raises(ParseError, match="a row of 6 numbers") as info:
        read_forces(tmp_path / "case")
    assert info.value.line == 2


def test_moments_about_the_header_s_cofr_give_the_loads_about_the_leading_edge(tmp_path):
    """A user's forces function object with its CofR at (0.05, 0.02, 0) m: the moments it
    writes are about that point; read with their header, they give the loads that the same
    run's moments about the origin give."""
    ref = read_forces(copy_real_case(tmp_path))
    centre = np.array([0.05, 0.02, 0.0])
    about_c = ref.moment - np.cross(centre, ref.force)
    folder = tmp_path / "user" / "postProcessing" / "forces" / "0"
    folder.mkdir(parents=True)
    cofr = f"# CofR          : ({centre[0]} {centre[1]} {centre[2]})"
    (folder / "force.dat").write_text((DATA / "force.dat").read_text().replace(
        "# CofR          : (0.00000000e+00 0.00000000e+00 0.00000000e+00)", cofr))
    moment = ["# Moment", cofr, "#", "# Time (total_x total_y total_z)"]
    moment += [f"{t!r} ({m[0]!r} {m[1]!r} {m[2]!r}) ({m[0]!r} {m[1]!r} {m[2]!r}) (0 0 0)"
               for t, m in zip(ref.time.tolist(), about_c.tolist(), strict=True)]
    (folder / "moment.dat").write_text("\n".join(moment) + "\n")
    got = read_forces(tmp_path / "user")
    np.testing.assert_array_equal(got.centre_of_rotation, centre)
    state = imposed_state(HarmonicMotion(1.0, 0.3, 0.3, np.pi / 2), ref.time, 0.25)
    expected = to_loads(ref, state, 0.18, 0.18, "ref")
    loads = to_loads(got, state, 0.18, 0.18, "user")
    np.testing.assert_allclose(loads.moment, expected.moment, rtol=1e-9,
                               atol=1e-9 * np.abs(expected.moment).max())


def test_restart_folders_are_merged(tmp_path):
    case = copy_real_case(tmp_path, "0")
    full = read_forces(case)
    t_restart = full.time[30]
    later = case / "postProcessing" / "forces" / f"{t_restart:.8g}"
    later.mkdir()
    for name in ("force.dat", "moment.dat"):
        lines = (DATA / name).read_text().splitlines()
        head = [ln for ln in lines if ln.startswith("#")]
        body = [ln for ln in lines if not ln.startswith("#")][30:]
        (later / name).write_text("\n".join(head + body) + "\n")
    merged = read_forces(case)
    np.testing.assert_allclose(merged.time, full.time)
    np.testing.assert_allclose(merged.force, full.force)


def test_truncated_last_line_of_killed_run_is_dropped(tmp_path):
    text = (DATA / "force.dat").read_text()
    cut = text[: len(text) - 40]  # cut inside the last row, no final newline
    arr, _ = parse_table(cut, "force.dat")
    full, _ = parse_table(text, "force.dat")
    assert len(arr) == len(full) - 1


@settings(max_examples=300, deadline=None)
@given(dialect=st.sampled_from(["v1912", "com-bare", "foundation", "foundation-bare",
                                "foundation-porous"]),
       name=st.sampled_from(["force.dat", "forces.dat", "moment.dat", "data.dat"]),
       keep=st.floats(0.0, 1.0))
@pytest.mark.slow
def test_a_cut_file_gives_a_prefix_of_the_whole_files_rows(dialect, name, keep):
    """Wherever a killed run cuts a file, in any layout and under any name, every row read
    is a row of the whole file: a last row cut inside a number is dropped, not read as
    another number."""
    text = layout_files(dialect)[0]
    whole, _ = parse_table(text, name)
    cut = text[:int(keep * len(text))]
    try:
        arr, _ = parse_table(cut, name)
    except ParseError as err:
        assert "no complete data rows" in str(err) or "no data rows" in str(err)
        return
    ended = cut[:cut.rfind("\n") + 1].splitlines()  # the rows written whole, with newline
    assert len(arr) >= sum(1 for ln in ended if ln.strip() and not ln.startswith("#"))
    np.testing.assert_array_equal(arr, whole[:len(arr)])


def test_a_last_row_cut_inside_its_last_number_is_dropped():
    text = (DATA / "force.dat").read_text()
    whole, _ = parse_table(text, "force.dat")
    for dialect_text in (text, to_bare(text)):
        # "... 1.63633256e-15)" cut to "... 1.63633256e-1": still ten numbers, one wrong
        cut = dialect_text.rstrip("\n").rstrip(")")[:-1]
        arr, _ = parse_table(cut, "force.dat")
        np.testing.assert_array_equal(arr, whole[:-1])
    # a whole v1912 row without its newline is kept
    arr, _ = parse_table(text.rstrip("\n"), "force.dat")
    np.testing.assert_array_equal(arr, whole)


def test_a_folder_that_is_not_a_time_is_named(tmp_path):
    case = copy_real_case(tmp_path)
    (case / "postProcessing" / "forces" / "backup").mkdir()
    with pytest.raises(ParseError, match=r"backup.*not a time folder"):
        read_forces(case)


def _y_plus_case(tmp_path, text, folder="0"):
    out = tmp_path / "case" / "postProcessing" / "yPlus" / folder
    out.mkdir(parents=True)
    (out / "yPlus.dat").write_text(text)
    return tmp_path / "case"


def test_y_plus_rows_of_real_output_and_of_a_run_killed_mid_row(tmp_path):
    """tests/data/openfoam_v1912/yPlus.dat is v1912's own yPlus output (coarse mesh)."""
    from mfflap.cfd.openfoam.yplus import read_y_plus

    text = (DATA / "yPlus.dat").read_text()
    whole = read_y_plus(_y_plus_case(tmp_path / "a", text))
    assert len(whole.time) == 7 and np.all(np.diff(whole.time) > 0)
    assert np.all((whole.minimum < whole.average) & (whole.average < whole.maximum))
    assert whole.average[-1] == pytest.approx(5.70547206)
    cut = read_y_plus(_y_plus_case(tmp_path / "b", text.rstrip("\n")[:-3]))  # "...5.705472"
    np.testing.assert_array_equal(cut.average, whole.average[:-1])
    lines = text.splitlines()
    lines[-1] = lines[-1].rsplit(maxsplit=1)[0]  # a whole line, one column short
    with pytest.raises(ParseError, match=r"yPlus.dat, line 9: expected 5 columns"):
        read_y_plus(_y_plus_case(tmp_path / "c", "\n".join(lines) + "\n"))
    lines = text.splitlines()
    lines[5] = lines[5].replace(lines[5].split()[3], "nan")
    with pytest.raises(ParseError, match=r"yPlus.dat, line 6: non-finite value"):
        read_y_plus(_y_plus_case(tmp_path / "n", "\n".join(lines) + "\n"))
    case = _y_plus_case(tmp_path / "d", text)
    (case / "postProcessing" / "yPlus" / "old").mkdir()
    with pytest.raises(ParseError, match=r"old.*not a time folder"):
        read_y_plus(case)


def test_y_plus_summary_and_what_it_means_for_the_wall_functions(tmp_path):
    """Of v1912's real output (coarse mesh, average y+ about 5-6: below the log law) and of
    the same rows scaled into and past the 30-300 range."""
    from mfflap.cfd.openfoam.yplus import (
        YPlusHistory,
        read_y_plus,
        wall_function_note,
        y_plus_summary,
    )

    real = read_y_plus(_y_plus_case(tmp_path, (DATA / "yPlus.dat").read_text()))
    summary = y_plus_summary(real)
    assert summary["y_plus_mean"] == pytest.approx(np.mean(real.average))
    assert summary["y_plus_min"] == real.minimum.min()
    assert summary["y_plus_max"] == real.maximum.max()
    assert summary["y_plus_share_below_log_law"] == 1.0
    assert "below 30 for 100% of the output times" in wall_function_note(summary)

    def scaled(factor):
        return y_plus_summary(YPlusHistory(real.time, factor * real.minimum,
                                           factor * real.maximum, factor * real.average))

    inside = scaled(100.0 / real.average.min())  # the smallest average at y+ = 100
    assert inside["y_plus_share_below_log_law"] == 0 and wall_function_note(inside) is None
    half = np.sort(real.average)[3]  # four of the seven averages reach 300, three do not
    past = scaled(300.0001 / half)
    assert past["y_plus_share_above_log_law"] == pytest.approx(4 / 7)
    assert "above 300 for 57% of the output times" in wall_function_note(past)


@settings(max_examples=150, deadline=None)
@given(cut=st.integers(0, 600), junk=st.text(max_size=20), pos=st.integers(0, 600))
def test_y_plus_parser_fuzz_never_hangs_or_lies(tmp_path_factory, cut, junk, pos):
    """Cut and garbled yPlus output: an error naming the file, or rows of the whole file
    (junk may turn one number into another valid one; it stays finite and in its row)."""
    from mfflap.cfd.openfoam.yplus import read_y_plus

    text = (DATA / "yPlus.dat").read_text()
    broken = text[:pos] + junk + text[pos:]
    broken = broken[:cut] if cut < len(broken) else broken
    case = _y_plus_case(tmp_path_factory.mktemp("fuzz"), broken)
    whole = read_y_plus(_y_plus_case(tmp_path_factory.mktemp("whole"), text))
    try:
        got = read_y_plus(case)
    except ParseError as err:
        assert "yPlus" in str(err)
        return
    if not junk:  # only cut: a prefix of the whole file's rows
        n = len(got.time)
        np.testing.assert_array_equal(got.average, whole.average[:n])
        np.testing.assert_array_equal(got.time, whole.time[:n])
    assert len(got.time) <= len(whole.time) + 1
    assert all(np.all(np.isfinite(v)) for v in (got.time, got.minimum, got.maximum,
                                                 got.average))


def test_garbled_middle_line_names_file_and_line():
    lines = (DATA / "force.dat").read_text().splitlines()
    lines[10] = lines[10][:25] + " garbage " + lines[10][25:]
    with pytest.raises(ParseError, match=r"force.dat, line 11"):
        parse_table("\n".join(lines) + "\n", "force.dat")


def test_nan_row_is_reported_as_divergence():
    lines = (DATA / "force.dat").read_text().splitlines()
    lines[7] = lines[7].replace(lines[7].split()[1], "(nan", 1)
    with pytest.raises(ParseError, match="non-finite"):
        parse_table("\n".join(lines) + "\n", "force.dat")


@settings(max_examples=150, deadline=None)
@given(cut=st.integers(0, 4000), junk=st.text(max_size=30), pos=st.integers(0, 4000))
def test_parser_fuzz_never_hangs_or_lies(cut, junk, pos):
    text = (DATA / "force.dat").read_text()[:4000]
    text = text[:pos] + junk + text[pos:]
    text = text[:cut] if cut < len(text) else text
    try:
        arr, _ = parse_table(text, "force.dat")
    except ParseError:
        return
    assert np.all(np.isfinite(arr)) and np.all(np.diff(arr[:, 0]) > 0)
    assert arr.shape[1] in (10, 13)


def test_motion_table_starts_at_zero_and_runs_past_end():
    rows = motion_table(MOTION, end_time=2.0)
    assert rows[0, 0] == 0 and rows[-1, 0] > 2.0
    np.testing.assert_allclose(rows[0, 1:], 0.0, atol=1e-12)  # h(0) = 0.3 removed, theta(0)=0
    text = format_motion_table(rows)
    assert text.startswith(f"{len(rows)}\n(") and "((0 " in text


def test_ramp_state_derivatives_are_consistent():
    m = RampHarmonicMotion(1.0, 0.3, np.deg2rad(10), 0.8)
    t = np.linspace(0.01, 1.5, 200)
    s = imposed_state(m, t, ramp_time=0.5)
    dt = 1e-6
    sp, sm = imposed_state(m, t + dt, 0.5), imposed_state(m, t - dt, 0.5)
    np.testing.assert_allclose(s.heave_velocity,
                               (sp.heave_position - sm.heave_position) / (2 * dt), atol=1e-6)
    np.testing.assert_allclose(s.pitch_acceleration, (sp.pitch_rate - sm.pitch_rate) / (2 * dt),
                               atol=1e-5)


def test_written_case_has_everything(tmp_path):
    case = write_case(tmp_path / "c", MOTION, end_time=0.5, mesh="coarse", y_plus=True)
    for rel in ("system/blockMeshDict", "system/controlDict", "system/fvSchemes",
                "system/fvSolution", "constant/dynamicMeshDict", "constant/motion.dat",
                "constant/transportProperties", "constant/turbulenceProperties", "0/U", "0/p",
                "0/k", "0/epsilon", "0/nut"):
        assert (case / rel).is_file(), rel
    control = (case / "system/controlDict").read_text()
    assert "endTime         0.5;" in control and "yPlus" in control
    assert "{{" not in (case / "system/blockMeshDict").read_text()


def test_runner_without_mesh_reports_case_and_log(tmp_path):
    assert openfoam_available(), "OpenFOAM must be installed (.ci/run installs it)"
    case = write_case(tmp_path / "broken", MOTION, end_time=0.01)
    (case / "system" / "blockMeshDict").write_text("garbage\n")
    with pytest.raises(CfdRunError, match="broken") as info:
        run_case(case, timeout_s=60)
    assert "blockMesh" in str(info.value)


@pytest.mark.openfoam
def test_real_openfoam_run_end_to_end(tmp_path):
    """Write, run (real pimpleFoam on the coarse O-grid), parse, compare with the model."""
    assert openfoam_available(), "OpenFOAM must be installed (.ci/run installs it)"
    case = write_case(tmp_path / "run", MOTION, end_time=0.06, mesh="coarse")
    run_case(case, timeout_s=300)
    history = read_forces(case)
    assert history.dialect == "v1912" and history.time[-1] > 0.055  # last step may stop short
    state = imposed_state(MOTION, history.time)
    cfd = to_loads(history, state, span=0.18, depth=0.18, source=f"openfoam:{case}")
    model = MorisonModel().loads(state)
    after = history.time > 0.01  # skip the start-up spike
    # The plate accelerates into positive F_n; the added-mass dominated start agrees with CFD
    assert pearson(cfd.normal_force[after], model.normal_force[after]) > 0.9
    ratio = cfd.normal_force[after].mean() / model.normal_force[after].mean()
    assert 0.7 < ratio < 1.5
    # run again: it has run to its end time, so no solver starts and nothing is appended
    log = (case / "log.pimpleFoam").read_text()
    told: list[str] = []
    run_case(case, timeout_s=300, progress=told.append)
    assert told == [f"{case} has run to its end time (0.06 s) already: nothing to run"]
    assert (case / "log.pimpleFoam").read_text() == log


def _written_time(root: Path, initial: Path, name: str) -> None:
    """A time folder as a run writes it: every field of 0/, each ending with the divider."""
    (root / name).mkdir(parents=True)
    for field_file in initial.iterdir():
        (root / name / field_file.name).write_text(
            field_file.read_text() + "\n// " + "*" * 73 + " //\n")


@pytest.mark.openfoam
def test_a_run_does_not_switch_layout_part_way(tmp_path):
    """decomposePar and reconstructPar (1912) do not carry the moving mesh's points: a case
    run serial to t > 0 is not decomposed (the parallel run began again at t = 0), and one
    run on 2 processes is not continued serial (the solver stopped on a missing field) or
    on 3; each is refused naming how to continue, before anything runs."""
    from mfflap.cfd.openfoam.time_folders import latest_solution_time

    serial = write_case(tmp_path / "serial", MOTION, end_time=1.0)
    _written_time(serial, serial / "0", "0.25")
    with pytest.raises(CfdRunError, match=r"run serial to t = 0\.25 s; decomposed on 2 "
                                          r"processes it would start again from t = 0 s.*"
                                          r"continue it serial \(without --procs\)"):
        run_case(serial, n_procs=2)
    assert not (serial / "processor0").exists() and not (serial / "log.blockMesh").exists()

    decomposed = write_case(tmp_path / "decomposed", MOTION, end_time=1.0)
    for rank in (0, 1):
        for name in ("0", "0.3"):
            _written_time(decomposed / f"processor{rank}", decomposed / "0", name)
    assert latest_solution_time(decomposed, "serial") == "0"
    assert latest_solution_time(decomposed, "decomposed") == "0.3"
    assert latest_solution_time(decomposed) == "0.3"  # where the next run resumes
    for n_procs, layout in ((1, "serial"), (3, "on 3 processes")):
        with pytest.raises(CfdRunError, match=rf"run decomposed on 2 processes to t = 0\.3 s; "
                                              rf"{layout} it cannot resume there .* continue "
                                              r"it with --procs 2"):
            run_case(decomposed, n_procs=n_procs)
    assert not (decomposed / "log.blockMesh").exists()


def test_running_a_folder_that_is_not_a_case_says_so_and_writes_nothing(tmp_path):
    (tmp_path / "empty").mkdir()
    with pytest.raises(CfdRunError, match=r"empty: not an OpenFOAM case: no "
                                          r"system/controlDict or system/blockMeshDict"):
        run_case(tmp_path / "empty")
    assert not any((tmp_path / "empty").iterdir())


@pytest.mark.parametrize("ramp_time", [-0.5, float("nan"), float("inf")])
def test_an_impossible_start_up_ramp_is_refused_not_read_as_none(tmp_path, ramp_time):
    from mfflap.cfd.openfoam.writer import SolverSettings
    from mfflap.errors import ConfigError

    for frame in ("inertial", "plate"):
        solver = SolverSettings(frame=frame, far_field="inletOutlet")
        with pytest.raises(ConfigError, match="start-up ramp must be a finite time") as err:
            write_case(tmp_path / "c", MOTION, end_time=1.0, ramp_time=ramp_time, solver=solver)
        assert err.value.key == "ramp_time"
        assert not (tmp_path / "c").exists()  # refused before anything was written


def test_parsing_a_case_that_has_not_run_says_so(tmp_path):
    from mfflap.cfd.openfoam.forces import read_forces
    from mfflap.errors import ParseError

    case = write_case(tmp_path / "c", MOTION, end_time=1.0)
    with pytest.raises(ParseError, match=r"no forces output folder: the case has not run "
                                         r"yet \(mfflap cfd run .*c\)"):
        read_forces(case)
    (case / "log.pimpleFoam").write_text("crashed before the first time step\n")
    with pytest.raises(ParseError, match=r"no forces output folder$"):
        read_forces(case)


def test_a_start_up_ramp_as_long_as_the_run_is_refused(tmp_path):
    """The motion would never reach its amplitude; a ramp just shorter is written."""
    from mfflap.errors import ConfigError

    for ramp_time in (1.0, 10.0):
        with pytest.raises(ConfigError, match=rf"ramp \({ramp_time:g} s\) lasts the whole "
                                              r"run \(1 s\)") as err:
            write_case(tmp_path / "c", MOTION, end_time=1.0, ramp_time=ramp_time)
        assert err.value.key == "ramp_time" and not (tmp_path / "c").exists()
    assert write_case(tmp_path / "c", MOTION, end_time=1.0, ramp_time=0.99).is_dir()
    # a mesh study refuses it before its first run, not after it started
    from mfflap.campaign.convergence import run_convergence

    with pytest.raises(ConfigError, match="lasts the whole run"):
        run_convergence(tmp_path / "study", MOTION, 0.2, meshes=["coarse"], ramp_time=0.25)
    assert not (tmp_path / "study").exists()


def test_an_impossible_end_time_or_depth_writes_nothing(tmp_path):
    from mfflap.errors import ConfigError, MotionError

    with pytest.raises(MotionError, match="end_time must be a finite time > 0"):
        write_case(tmp_path / "c", MOTION, end_time=-1.0)
    with pytest.raises(ConfigError, match="depth must be > 0") as err:
        write_case(tmp_path / "c", MOTION, end_time=1.0, depth=0.0)
    assert err.value.key == "depth" and not (tmp_path / "c").exists()


def test_divergence_signatures():
    from mfflap.cfd.openfoam.solver_log import DIVERGED as _DIVERGED

    assert not _DIVERGED.search("trapFpe: Floating point exception trapping enabled (FOAM_SIGFPE).")
    assert not _DIVERGED.search("Solving for Ux, Initial residual = 0.004, No Iterations 1")
    assert _DIVERGED.search("Solving for p, Initial residual = nan, Final residual = nan")
    assert _DIVERGED.search("#1  Foam::sigFpe::sigHandler(int) at ??")
    assert _DIVERGED.search("--> FOAM FATAL ERROR:")


def test_a_failure_is_told_by_its_cause_not_by_its_exit_code_alone():
    from mfflap.cfd.openfoam.solver_log import FATAL_TEXT_CHARS, failure_reason

    fatal = ("--> FOAM FATAL ERROR: (openfoam-1912)\nCannot find file \"points\" in "
             "directory \"polyMesh\"\n\n    From function Foam::polyMesh::polyMesh\n    in "
             "file meshes/polyMesh/polyMesh.C at line 326.\n\nFOAM exiting\n")
    assert failure_reason(fatal, 1) == ('FOAM FATAL ERROR: Cannot find file "points" in '
                                        'directory "polyMesh"')
    long = "--> FOAM FATAL IO ERROR: \n" + "word " * 200 + "\n\nFOAM exiting\n"
    reason = failure_reason(long, 1)
    assert reason.startswith("FOAM FATAL IO ERROR: word word")
    assert len(reason) == len("FOAM FATAL IO ERROR: ") + FATAL_TEXT_CHARS
    assert reason.endswith("...")
    assert failure_reason("#1  Foam::sigFpe::sigHandler(int) at ??", -8) == (
        "a floating point exception: the solution diverged")
    assert failure_reason("Solving for p, Initial residual = nan", 0) == (
        "NaN in the solution: it diverged")
    assert failure_reason("Time = 0.1\n", -9) == "killed by SIGKILL (the out-of-memory killer?)"
    assert failure_reason("Time = 0.1\n", -15) == "killed by SIGTERM"
    assert failure_reason("Time = 0.1\n", 3) == "exit code 3"


@pytest.mark.openfoam
@pytest.mark.parametrize(("broken", "old", "new", "said"), [
    ("system/blockMeshDict", "vertices", "vertixes",
     "blockMesh failed (exit code 1): FOAM FATAL IO ERROR: Entry 'vertices' not found in "
     "dictionary"),
    ("system/fvSchemes", "linearUpwind", "linearUpwindd",
     "pimpleFoam failed (exit code 1): FOAM FATAL IO ERROR: Unknown discretisation type "
     "linearUpwindd"),
])
def test_a_case_openfoam_refuses_is_reported_with_openfoam_s_own_words(tmp_path, broken, old,
                                                                        new, said):
    """Real blockMesh and pimpleFoam on a case with a typo: the error says what OpenFOAM
    said, not only its exit code (it used to read "failed (exit code 1, diverged or
    crashed)")."""
    case = tmp_path / "case"
    write_case(case, MOTION, end_time=0.01)
    path = case / broken
    path.write_text(path.read_text().replace(old, new, 1))
    with pytest.raises(CfdRunError) as err:
        run_case(case)
    assert said in str(err.value).splitlines()[0]
    assert "diverged" not in str(err.value).splitlines()[0]


@pytest.mark.openfoam
def test_a_mesh_checkmesh_fails_starts_no_solver_however_it_was_made(tmp_path):
    """A mesh made without mfflap (here blockMesh's, mirrored by transformPoints so that
    every cell is inside out) used to go to pimpleFoam unchecked, as did a mesh whose
    check had failed once: the rerun saw its points and skipped checkMesh."""
    from mfflap.cfd.openfoam.runner import mesh_checked, run_application

    case = tmp_path / "case"
    write_case(case, MOTION, end_time=0.01)
    run_application(case, "blockMesh", timeout_s=120)
    run_application(case, "transformPoints", timeout_s=120, extra_args=("-scale", "(1 -1 1)"))
    assert not mesh_checked(case)
    for _ in range(2):  # the rerun checks it again
        with pytest.raises(CfdRunError) as err:
            run_case(case)
        first = str(err.value).splitlines()[0]
        assert "checkMesh did not report 'Mesh OK': Zero or negative cell volume detected" in first
        assert first.endswith("pimpleFoam is not started on this mesh (a rerun checks it again)")
        assert first.count("negative cell volume") == 1  # the last check's words only
        assert not (case / "log.pimpleFoam").exists()
    shutil.rmtree(case / "constant" / "polyMesh")  # meshed again by blockMesh: it passes
    run_case(case)
    assert mesh_checked(case) and (case / "log.pimpleFoam").is_file()


def test_courant_numbers_with_exponents_are_read(tmp_path):
    """Regression: values like 1.2e+02 (an exploding run) were dropped by the old filter."""
    from mfflap.cfd.openfoam.time_step_watch import TimeStepWatch

    log = tmp_path / "log.pimpleFoam"
    log.write_text("Time = 0.1\nCourant Number mean: 0.01 max: 3.9\n"
                   "Time = 0.2\nCourant Number mean: 0.5 max: 1.2e+02\n"
                   "Time = 0.3\nCourant Number mean: 0.02 max: 4.5e-01\n")
    watch = TimeStepWatch(log, 1e-7)
    watch.read()
    assert watch.largest_courant == (120.0, 0.2)
    log.write_text("no courant lines\n")
    watch = TimeStepWatch(log, 1e-7)
    watch.read()
    assert watch.largest_courant[0] == 0.0


@pytest.mark.openfoam
def test_a_courant_number_beyond_the_limit_stops_the_run_at_the_next_look(tmp_path):
    """A real run whose Courant number passes a limit of 2 (it climbs to its maxCo of 4 in
    the first tenth of a second) is stopped while it runs, the message giving the first
    Courant number beyond the limit in the log and the time its step began at."""
    from mfflap.cfd.openfoam.runner import run_application

    case = write_case(tmp_path / "co", MOTION, end_time=1.0, mesh="coarse")
    run_application(case, "blockMesh", timeout_s=120)
    from mfflap.errors import COURANT_EXPLODED, SolverDiverged

    with pytest.raises(SolverDiverged, match="Courant number exploded to") as info:
        run_application(case, "pimpleFoam", timeout_s=300, max_courant_abort=2.0)
    assert info.value.kind == COURANT_EXPLODED and 0.0 <= info.value.time_s < 1.0
    text = (case / "log.pimpleFoam").read_text()
    assert not re.search(r"^End$", text, re.M)  # stopped before its end
    steps, began = [], None  # (the time a step began at, its Courant number), in log order
    for time_s, courant in re.findall(r"^Time = (\S+)$|^Courant Number mean: \S+ max: (\S+)$",
                                      text, re.M):
        if time_s:
            began = float(time_s)
        else:
            steps.append((began, float(courant)))
    found = re.search(r"exploded to (\S+) in the step from t = (\S+) s", str(info.value))
    reported = (float(found[2]), float(found[1]))
    first = next(step for step in steps if step[1] > 2.0)
    assert reported in [(pytest.approx(t, rel=1e-6), pytest.approx(c, rel=1e-5))
                        for t, c in steps[steps.index(first):]]
    assert reported[1] >= first[1] > 2.0 and first[0] < 0.1


@pytest.mark.openfoam
def test_decomposed_run_matches_the_serial_run(tmp_path):
    """pimpleFoam on 2 ranks (decomposePar, method simple) gives the serial forces."""
    serial = write_case(tmp_path / "serial", MOTION, end_time=0.03, mesh="coarse")
    parallel = write_case(tmp_path / "parallel", MOTION, end_time=0.03, mesh="coarse")
    run_case(serial, timeout_s=300)
    run_case(parallel, timeout_s=300, n_procs=2)
    assert (parallel / "processor1").is_dir()
    assert "Finalising parallel run" in (parallel / "log.pimpleFoam").read_text()
    a, b = read_forces(serial), read_forces(parallel)
    assert abs(len(a.time) - len(b.time)) <= 2  # adaptive steps differ in the last digits
    late = a.time > 0.015  # after the start-up transient
    fy = np.interp(a.time[late], b.time, b.force[:, 1])
    span = np.ptp(a.force[late, 1])
    assert np.max(np.abs(fy - a.force[late, 1])) < 0.02 * span + 1e-6


@pytest.mark.openfoam
def test_convergence_command_on_three_meshes_and_two_courant_limits(tmp_path):
    """Real runs on coarse/medium/fine and a second Courant limit; y+ history; resumable."""
    import json

    from click.testing import CliRunner

    from mfflap.cli.main import cli

    case = Path(__file__).parents[3] / "cases" / "paper2026.toml"
    out = tmp_path / "conv"
    args = ["cfd", "convergence", str(case), str(out), "--cycles", "0.02", "--ramp-time",
            "0.005", "--json"]
    res = CliRunner().invoke(cli, args)
    assert res.exit_code == 0, res.output
    data = json.loads(res.output[res.output.index("{"):])
    assert data["reference"] == "fine_co4"
    assert set(data["runs"]) == {"coarse_co4", "medium_co4", "fine_co4", "coarse_co2"}
    for label in data["runs"]:  # each run's own progress, named (stderr)
        assert f"{label}: meshing " in res.stderr and f"{label}: pimpleFoam started" in res.stderr
    assert data["runs"]["fine_co4"]["n_cells"] > data["runs"]["coarse_co4"]["n_cells"]
    for key in ("coarse_co4 vs fine_co4", "medium_co4 vs fine_co4", "coarse_co4 vs coarse_co2"):
        assert 0 <= data["nrmse"][key]["normal_force"] < 1.0
    assert data["runs"]["coarse_co4"]["y_plus_mean"] > 0
    for run in data["runs"].values():  # the first 0.02 s of a ramped motion: y+ of a few,
        # where the default all_y_plus wall treatment holds
        assert run["y_plus_mean"] < 30 and run["wall_function_note"] is None
    for run in data["runs"].values():  # the records' own clipping counts, as a fraction
        assert 0 <= run["epsilon_clipped_step_fraction"] <= 1
    assert (out / "convergence.html").read_text().count("<img") == 1
    assert "log-law range (30-300)" not in (out / "convergence.html").read_text()
    assert "steps with epsilon clipped" in (out / "convergence.html").read_text()
    # the grid convergence index is computed from the three meshes' own records
    from mfflap.campaign.convergence import mesh_gci
    from mfflap.records.record import read_record
    assert data["gci_meshes"] == ["coarse_co4", "medium_co4", "fine_co4"]
    gci = mesh_gci([read_record(out / f"{m}.h5") for m in data["gci_meshes"]], 0.005)
    assert set(data["gci"]) == set(gci) == {"mean_thrust_N", "mean_input_power_W",
                                             "peak_normal_force_N", "rms_moment_Nm"}
    for k, g in gci.items():
        assert data["gci"][k]["values"] == pytest.approx(list(g.values))
        assert data["gci"][k]["cell_counts"] == [data["runs"][f"{m}_co4"]["n_cells"]
                                                 for m in ("fine", "medium", "coarse")]
        assert data["gci"][k]["behaviour"] == g.behaviour
    assert "Grid convergence index" in (out / "convergence.html").read_text()
    # a second call finds every run finished and reruns nothing
    mtime = (out / "fine_co4.h5").stat().st_mtime_ns
    res = CliRunner().invoke(cli, args)
    assert res.exit_code == 0 and "already finished" in res.output
    assert (out / "fine_co4.h5").stat().st_mtime_ns == mtime
    # nor does it take them for the runs of another motion or plate (it did before)
    text = case.read_text()
    for old, new, said in (
            ("pitch_amplitude_deg = 20.0", "pitch_amplitude_deg = 10.0",
             "coarse_co4.h5: motion: this run imposed another motion"),
            ("chord = 0.16 ", "chord = 0.12 ",
             "coarse_co4.h5: plate.chord: this run was made for plate.chord = 0.16, the "
             "study asks for 0.12")):
        other = tmp_path / "other.toml"
        other.write_text(text.replace(old, new))
        res = CliRunner().invoke(cli, ["cfd", "convergence", str(other), *args[3:]])
        assert res.exit_code == 2 and said in " ".join(res.output.split()), res.output
    res = CliRunner().invoke(cli, [*args, "--set", 'cfd.far_field="inletOutlet"'])
    assert res.exit_code == 2 and ("coarse_co4.h5: far_field: this run was made with "
                                   "far_field = 'freestream', the study asks for "
                                   "'inletOutlet'") in " ".join(res.output.split()), res.output
    res = CliRunner().invoke(cli, [*args, "--set", 'cfd.wall_treatment="log_law"'])
    assert res.exit_code == 2 and ("coarse_co4.h5: wall_treatment: this run was made with "
                                   "wall_treatment = 'all_y_plus', the study asks for "
                                   "'log_law'") in " ".join(res.output.split()), res.output
    for key, option in (("mesh", "--meshes"), ("max_courant", "--courant")):
        res = CliRunner().invoke(cli, [*args, "--set", f"cfd.{key}=2"])
        assert res.exit_code == 2 and (f"--set cfd.{key} applies only to single runs; a "
                                       f"study's are its {option}") in res.output, res.output
    assert (out / "fine_co4.h5").stat().st_mtime_ns == mtime
    # the text output and the report say what every run was made with
    import html

    settings = ("the meshes' runs: PIMPLE 2x1, PCG; every run, named set-ups included: "
                "freestream far field, limitedLinear k and epsilon convection, all_y_plus "
                "wall treatment")
    res = CliRunner().invoke(cli, args[:-1])
    assert res.exit_code == 0 and settings in res.output, res.output
    assert settings in html.unescape((out / "convergence.html").read_text())


def test_collapsed_time_step_is_recognised_from_a_real_log_excerpt():
    """The tail of a real v1912 run whose k-epsilon blew up: dt went to 1e-26 s while the
    Courant number stayed below 6, so the run would never have ended."""
    from mfflap.cfd.openfoam.time_step_watch import TimeStepWatch

    dt, t = TimeStepWatch(DATA / "collapsed_dt.log", 1e-9).read(to_end=True)
    assert dt == pytest.approx(7.3628536e-26) and t == pytest.approx(1.3821858)
    assert TimeStepWatch(DATA / "collapsed_dt.log", 1e-30).read(to_end=True) is None


@pytest.mark.openfoam
def test_runner_stops_a_run_whose_time_step_collapses(tmp_path):
    """A watchdog threshold above the run's real time step must stop it within seconds."""
    case = write_case(tmp_path / "run", MOTION, end_time=5.0, mesh="coarse")
    with pytest.raises(CfdRunError, match="time step collapsed") as info:
        run_case(case, timeout_s=120, min_time_step=1.0)
    assert "run" in str(info.value)


def _steps_s(log: Path) -> list[float]:
    return [float(s) for s in re.findall(r"^deltaT = (\S+)$", log.read_text(), re.M)]


@pytest.mark.openfoam
def test_a_time_step_below_the_limit_for_one_step_only_stops_the_run(tmp_path):
    """The first time step of a real run (1.2 times the case's 1e-4 s) is below a limit of
    1.3e-4 s and every later one above it: a moment long over when the runner first looks,
    2 s after the start. The runner reads every step and stops the run all the same."""
    from mfflap.cfd.openfoam.runner import run_application

    case = write_case(tmp_path / "brief", MOTION, end_time=0.3, mesh="coarse")
    run_application(case, "blockMesh", timeout_s=120)
    from mfflap.errors import TIME_STEP_COLLAPSED, SolverDiverged

    with pytest.raises(SolverDiverged, match=r"time step collapsed to 0.00012 s at "
                                             r"t = 0.00012\d* s") as info:
        run_application(case, "pimpleFoam", timeout_s=300, min_time_step=1.3e-4)
    assert info.value.kind == TIME_STEP_COLLAPSED
    assert info.value.time_s == pytest.approx(1.2e-4, rel=0.1)
    steps = _steps_s(case / "log.pimpleFoam")
    assert steps[0] < 1.3e-4 and all(step >= 1.3e-4 for step in steps[1:])
    assert "brief" in str(info.value)
    assert not re.search(r"^End$", (case / "log.pimpleFoam").read_text(), re.M)  # stopped


@pytest.mark.openfoam
def test_a_collapse_in_the_seconds_before_the_solver_exits_fails_the_run(tmp_path):
    """A real run short enough to end before the runner's first look (its poll made longer
    than the run) is judged on every step after it exits: the finished run fails."""
    from mfflap.cfd.openfoam.runner import run_application

    case = write_case(tmp_path / "short", MOTION, end_time=0.01, mesh="coarse")
    run_application(case, "blockMesh", timeout_s=120)
    with pytest.raises(CfdRunError, match=r"collapsed to 0.00012 s at t = 0.00012\d* s .*; the "
                       r"solver ran on past it to its end, .* \(its time folders 0.01\): "
                       r".*`mfflap cfd run --rewind-before 0.00012\d*`"):
        run_application(case, "pimpleFoam", timeout_s=300, min_time_step=1.3e-4, poll_s=600)
    assert re.search(r"^End$", (case / "log.pimpleFoam").read_text(), re.M)  # ran to its end
    assert len(_steps_s(case / "log.pimpleFoam")) > 5
    run_application(case, "pimpleFoam", timeout_s=300, poll_s=600)  # the default limit: no error


@pytest.mark.openfoam
def test_a_finished_run_that_diverged_is_not_taken_as_done_on_a_rerun(tmp_path):
    """A real run that reached its end time with a time step below the limit in its log (as
    one judged by the old runner, or whose caller was killed as it ended, would have) is not
    'run to its end already' on the next call: the call fails as the run would have, naming
    the time folders written past it. Rewound to before it (`--rewind-before`), the case
    runs again, and then it has run to its end."""
    from click.testing import CliRunner

    from mfflap.cfd.openfoam.writer import SolverSettings
    from mfflap.cli.main import cli

    case = write_case(tmp_path / "c", MOTION, end_time=0.04, mesh="coarse",
                      solver=SolverSettings(write_interval=0.01))
    run_case(case, timeout_s=300)
    log = case / "log.pimpleFoam"
    text = log.read_text()
    step = next(m for m in re.finditer(r"^deltaT = (\S+)\nTime = (\S+)$", text, re.M)
                if float(m[2]) > 0.035)
    log.write_text(f"{text[:step.start(1)]}1e-09{text[step.end(1):]}")
    with pytest.raises(CfdRunError, match=rf"collapsed to 1e-09 s at t = {step[2]} s .*its time "
                       r"folders 0.04\): .*--rewind-before"):
        run_case(case, timeout_s=300)
    res = CliRunner().invoke(cli, ["cfd", "run", str(case), "--rewind-before", step[2],
                                   "--progress-every", "0"])
    assert res.exit_code == 0, res.output
    assert "rewound to t = 0.03 s" in res.stderr
    told = []
    run_case(case, timeout_s=300, progress=told.append)
    assert any("has run to its end time (0.04 s) already" in m for m in told)


@pytest.mark.openfoam
def test_cfd_run_rewinds_a_finished_case_to_before_a_time_and_reruns_it(tmp_path):
    """`mfflap cfd run --rewind-before T` (what a collapse read after the solver exited tells
    the user to run): the case goes back to its last write before T, drops the later fields
    and force output, and pimpleFoam runs from there to the end again."""
    from click.testing import CliRunner

    from mfflap.cfd.openfoam.writer import SolverSettings
    from mfflap.cli.main import cli

    case = write_case(tmp_path / "c", MOTION, end_time=0.04, mesh="coarse",
                      solver=SolverSettings(write_interval=0.01))
    run_case(case, timeout_s=300)
    first = read_forces(case)
    res = CliRunner().invoke(cli, ["cfd", "run", str(case), "--rewind-before", "0.035",
                                   "--progress-every", "0"])
    assert res.exit_code == 0, res.output
    assert "rewound to t = 0.03 s, the last time written before 0.035 s" in res.stderr
    log = (case / "log.pimpleFoam").read_text()
    assert log.count("Starting time loop") == 2
    assert re.search(r"^Time = 0.03\d*$", log.split("Starting time loop")[2], re.M)
    again = read_forces(case)
    assert np.all(np.diff(again.time) > 0) and again.time[-1] == pytest.approx(0.04)
    # the rerun's forces are the first run's: the same case from the same written fields
    np.testing.assert_allclose(again.force, first.force, rtol=1e-5, atol=1e-6)
    res = CliRunner().invoke(cli, ["cfd", "run", str(case), "--rewind-before", "-1"])
    assert res.exit_code != 0 and "--rewind-before" in res.output


@pytest.mark.openfoam
def test_an_earlier_runs_divergence_in_the_same_log_does_not_fail_a_rerun(tmp_path):
    """The log is appended to: a rerun after a collapsed, crashed run is judged on its own
    lines, not stopped at once by the collapse or the fatal error above them."""
    case = write_case(tmp_path / "rerun", MOTION, end_time=0.02, mesh="coarse")
    earlier = (DATA / "collapsed_dt.log").read_text() + "\n--> FOAM FATAL ERROR:\nnan\n"
    (case / "log.pimpleFoam").write_text(earlier)
    run_case(case, timeout_s=300)
    log = (case / "log.pimpleFoam").read_text()
    assert log.startswith(earlier) and log.rstrip().endswith("End")
    assert read_forces(case).time[-1] == pytest.approx(0.02, abs=1e-3)


def test_restart_into_the_same_time_folder_supersedes_a_collapsed_segment(tmp_path):
    """v1912 writes force_0.dat beside force.dat when a run restarts from the same time. The
    first segment may end in a collapsed run whose times repeat at the written precision
    (seen on a real back-test): the later segment wins and the merge is clean."""
    case = copy_real_case(tmp_path)
    folder = case / "postProcessing" / "forces" / "0"
    for name in ("force", "moment"):
        text = (DATA / f"{name}.dat").read_text()
        rows = [ln for ln in text.splitlines() if ln and not ln.startswith("#")]
        last = rows[-1].split(None, 1)[1]
        collapsed = "\n".join(f"0.3441266 {last}" for _ in range(3))  # repeated times
        (folder / f"{name}.dat").write_text(text + collapsed + "\n")
        shutil.copy(DATA / f"{name}.dat", folder / f"{name}_0.dat")
    with pytest.raises(ParseError, match="time does not increase"):
        parse_table((folder / "force.dat").read_text(), "force.dat")
    merged = read_forces(case)
    reference = read_forces(copy_real_case(tmp_path / "ref"))
    np.testing.assert_array_equal(merged.time, reference.time)
    np.testing.assert_array_equal(merged.force, reference.force)


@pytest.mark.openfoam
def test_pressure_solver_settings_change_cost_not_forces_on_a_custom_mesh(tmp_path):
    """A MeshSpec not in meshes.toml runs; GAMG instead of PCG, and the last pressure
    corrector stopped at a relative tolerance of 1 %, change the iterations, not the forces."""
    import re
    from dataclasses import replace

    from mfflap.cfd.openfoam.writer import MeshSpec, SolverSettings

    spec = MeshSpec("tiny", n_chord=20, n_edge=4, n_radial=20, radial_expansion=100.0,
                    radius_chords=8.0)
    variants = {"PCG": {"pressure_solver": "PCG"}, "GAMG": {"pressure_solver": "GAMG"},
                "GAMG-final-1%": {"pressure_solver": "GAMG", "pressure_final_rel_tol": 0.01}}
    forces, final_p_iterations = {}, {}
    for name, changes in variants.items():
        settings = replace(SolverSettings(n_outer_correctors=1, n_correctors=2), **changes)
        case = write_case(tmp_path / name, MOTION, end_time=0.03, mesh=spec, solver=settings)
        assert f"solver {changes['pressure_solver']};" in (case / "system/fvSolution").read_text()
        assert 'mesh = "tiny"' in (case / "mfflap_case.toml").read_text()
        run_case(case, timeout_s=300)
        forces[name] = read_forces(case)
        log = (case / "log.pimpleFoam").read_text()
        # every second p solve of a time step is the final corrector's
        iterations = [int(n) for n in re.findall(r"Solving for p,.*No Iterations (\d+)", log)]
        final_p_iterations[name] = np.mean(iterations[1::2])
    a = forces["PCG"]
    t = np.linspace(0.005, 0.03, 50)
    fa = np.interp(t, a.time, a.force[:, 0])
    for name, tol in (("GAMG", 1e-3), ("GAMG-final-1%", 1e-2)):
        b = forces[name]
        assert b.time[-1] >= 0.03 - 1e-9
        fb = np.interp(t, b.time, b.force[:, 0])
        assert np.max(np.abs(fa - fb)) <= tol * np.max(np.abs(fa)), name
    assert final_p_iterations["GAMG-final-1%"] < 0.6 * final_p_iterations["GAMG"]


@pytest.mark.parametrize("changes, key", [
    ({"pressure_solver": "ILU"}, "pressure_solver"),
    ({"max_courant": 0.0}, "max_courant"),
    ({"n_outer_correctors": 0}, "n_outer_correctors"),
    ({"pressure_tolerance": -1.0}, "pressure_tolerance"),
    ({"velocity_convection": "upwind"}, "velocity_convection"),
    ({"turbulence_convection": "linearUpwind"}, "turbulence_convection"),
    ({"pressure_final_rel_tol": 1.0}, "pressure_final_rel_tol"),
    ({"pressure_final_rel_tol": -0.01}, "pressure_final_rel_tol"),
])
def test_impossible_solver_settings_are_refused_by_name(changes, key):
    from mfflap.cfd.openfoam.writer import SolverSettings
    from mfflap.errors import ConfigError

    with pytest.raises(ConfigError, match=key):
        SolverSettings(**changes)


def test_velocity_convection_scheme_reaches_fv_schemes(tmp_path):
    """The U convection scheme of the settings is the one the case's fvSchemes names."""
    from mfflap.cfd.openfoam.writer import SolverSettings

    for scheme in ("linearUpwind", "LUST"):
        case = write_case(tmp_path / scheme, MOTION, end_time=0.1,
                          solver=SolverSettings(velocity_convection=scheme))
        schemes = (case / "system" / "fvSchemes").read_text()
        assert f"div(phi,U)      Gauss {scheme} grad(U);" in schemes
        assert schemes.count("div(phi,U)") == 1


def test_bounding_summary_counts_clipped_solves_and_the_worst_relative_value(tmp_path):
    from mfflap.cfd.openfoam.solver_log import bounding_summary, solver_provenance

    # two time steps of a real v1912 log (the medium mesh at t = 3-4 ms)
    summary = bounding_summary((DATA / "log.pimpleFoam.bounding").read_text())
    assert summary["n_steps_bounding_epsilon"] == 2
    assert summary["n_steps_bounding_k"] == 2
    assert summary["worst_bounding_epsilon"] == pytest.approx(-0.010048885 / 0.46637612)
    assert summary["worst_bounding_k"] == pytest.approx(-3.9241005e-05 / 0.0026761405)
    case = tmp_path / "case"
    case.mkdir()
    shutil.copy(DATA / "log.pimpleFoam.bounding", case / "log.pimpleFoam")
    provenance = solver_provenance(case)
    assert provenance["n_time_steps"] == 3  # the excerpt starts three time steps
    assert provenance["n_steps_bounding_epsilon"] == 2
    clean = bounding_summary("Time = 1\nsmoothSolver:  Solving for epsilon\n")
    assert clean == {"n_steps_bounding_k": 0, "n_steps_bounding_epsilon": 0,
                     "worst_bounding_k": 0.0, "worst_bounding_epsilon": 0.0}


@settings(max_examples=300, deadline=None)
@given(st.lists(st.sampled_from([
    "bounding epsilon, min: -0.5 max: 2 average: 0.1", "bounding k, min: - max: e",
    "bounding epsilon, min: -1e999 max: 1e999", "bounding epsilon, min: -3 max: 0",
    "bounding nut, min: -1 max: 1", "Time = 0.1", "ExecutionTime = . s  ClockTime = 1 s",
    "ExecutionTime = 1.5 s  ClockTime = 2 s", "Create time", "bounding epsilon, min: nan max: 1",
    "deltaT = 0.1", "Time = 0.05", "Time = 1e999", "ExecutionTime = 1e999 s  ClockTime = 1 s",
    "ExecutionTime = 0.5 s  ClockTime = 1 s", "deltaT = -1",
]) | st.text(max_size=40), max_size=30))
@pytest.mark.slow
def test_log_summary_never_fails_on_garbled_lines(tmp_path_factory, lines):
    """A garbled, truncated or diverged log gives counts and finite ratios, never an error."""
    import math

    from mfflap.cfd.openfoam.solver_log import solver_provenance

    case = tmp_path_factory.mktemp("log")
    (case / "log.pimpleFoam").write_text("\n".join(lines))
    summary = solver_provenance(case)
    for field in ("k", "epsilon"):
        assert summary[f"n_steps_bounding_{field}"] <= sum(
            ln.startswith(f"bounding {field},") for ln in lines)
        assert math.isfinite(summary[f"worst_bounding_{field}"])
        assert summary[f"worst_bounding_{field}"] <= 0
    assert summary["cpu_time_s"] >= 0 and summary["n_time_steps"] <= len(lines)
    assert 0 <= summary["n_time_steps_redone"] <= summary["n_time_steps"]
    assert math.isfinite(summary["cpu_time_redone_s"]) and summary["cpu_time_redone_s"] >= 0


def _log_segment(steps: list[tuple[float, float, float | None]]) -> str:
    """A run's part of a pimpleFoam log: (deltaT, Time, ExecutionTime or None) per step."""
    lines = ["Create time", "", "Starting time loop", ""]
    for delta_t, time_s, cpu_s in steps:
        lines += [f"deltaT = {delta_t:.8g}", f"Time = {time_s:.8g}", "",
                  "smoothSolver:  Solving for Ux, Initial residual = 1e-3"]
        if cpu_s is not None:
            lines += [f"ExecutionTime = {cpu_s:.4g} s  ClockTime = {cpu_s:.0f} s", ""]
    return "\n".join(lines) + "\n"


def test_redone_work_counts_what_later_runs_took_again():
    """Worked by hand: a run killed at 0.5 s (its last step printed no CPU time) resumed
    from its write at 0.3 s repeats its steps at 0.4 and 0.5 s (CPU 3 -> 4 s); a third run
    rewound to 0 repeats everything before it."""
    from mfflap.cfd.openfoam.solver_log import redone_work

    killed = _log_segment([(0.1, 0.1, 1.0), (0.1, 0.2, 2.0), (0.1, 0.3, 3.0),
                           (0.1, 0.4, 4.0), (0.1, 0.5, None)])
    resumed = _log_segment([(0.1, 0.4, 1.5), (0.1, 0.5, 3.0), (0.1, 0.6, 4.5)])
    assert redone_work(killed) == (0, 0.0)
    assert redone_work(killed + resumed) == (2, pytest.approx(1.0))
    rewound = _log_segment([(0.1, 0.1 * k, float(k)) for k in range(1, 11)])
    assert redone_work(killed + resumed + rewound) == (8, pytest.approx(4.0 + 4.5))
    # adaptive steps: the resumed run's first step is smaller than the killed run's last
    varied = _log_segment([(0.07, 0.07, 1.0), (0.09, 0.16, 2.0), (0.11, 0.27, 3.0)])
    after = _log_segment([(0.05, 0.21, 1.0), (0.06, 0.27, 2.0)])
    assert redone_work(varied + after) == (1, pytest.approx(1.0))


@pytest.mark.openfoam
def test_upwind_turbulence_convection_keeps_epsilon_positive(tmp_path):
    """With limitedLinear k and epsilon at max Co 4 OpenFOAM clips negative epsilon after
    most solves (the implicit TVD matrix is not an M-matrix above Co 1); bounded upwind
    convection needs no clipping. The count is read from the real log."""
    from mfflap.cfd.openfoam.solver_log import solver_provenance
    from mfflap.cfd.openfoam.writer import MeshSpec, SolverSettings

    spec = MeshSpec("tiny", n_chord=20, n_edge=4, n_radial=20, radial_expansion=100.0,
                    radius_chords=8.0)
    health = {}
    for scheme, entry in (("limitedLinear", "Gauss limitedLinear 1;"), ("upwind", "Gauss upwind;")):
        settings = SolverSettings(n_outer_correctors=1, n_correctors=2,
                                  turbulence_convection=scheme)
        case = write_case(tmp_path / scheme, MOTION, end_time=0.1, mesh=spec, solver=settings)
        schemes = (case / "system" / "fvSchemes").read_text()
        assert f"div(phi,k)      {entry}" in schemes
        assert f"div(phi,epsilon) {entry}" in schemes
        run_case(case, timeout_s=300)
        health[scheme] = solver_provenance(case)
    clipped = health["limitedLinear"]
    assert clipped["n_steps_bounding_epsilon"] > clipped["n_time_steps"] / 4
    assert clipped["worst_bounding_epsilon"] < -1e-3
    assert health["upwind"]["n_steps_bounding_epsilon"] == 0
    assert health["upwind"]["worst_bounding_epsilon"] == 0.0


def test_final_pressure_tolerance_reaches_fv_solution(tmp_path):
    """The last corrector's relative tolerance is pFinal's; 0 (the default) converges it."""
    from mfflap.cfd.openfoam.writer import SolverSettings

    for rel_tol in (0.0, 0.01):
        case = write_case(tmp_path / str(rel_tol), MOTION, end_time=0.1,
                          solver=SolverSettings(pressure_final_rel_tol=rel_tol))
        solution = (case / "system" / "fvSolution").read_text()
        assert f"pFinal {{ $p; relTol {rel_tol}; }}" in solution


def test_impossible_mesh_is_refused_by_name():
    from mfflap.cfd.openfoam.writer import MeshSpec
    from mfflap.errors import ConfigError

    with pytest.raises(ConfigError, match="n_radial"):
        MeshSpec("bad", n_chord=10, n_edge=2, n_radial=0, radial_expansion=10.0,
                 radius_chords=5.0)


@pytest.mark.openfoam
def test_convergence_floor_reruns_the_reference_with_the_other_pressure_solver(tmp_path):
    """--floor: the reference again with GAMG; its NRMSE is round-off small on a short run.
    --setups: a named set-up runs with its own mesh and solver and is compared too;
    the [cfd] table's far field and k and epsilon convection apply to all of them."""
    import json

    from click.testing import CliRunner

    from mfflap.cli.main import cli

    case = Path(__file__).parents[3] / "cases" / "paper2026.toml"
    args = ["cfd", "convergence", str(case), str(tmp_path / "c"), "--meshes", "coarse",
            "--courant", "4", "--cycles", "0.02", "--ramp-time", "0.005", "--floor",
            "--set", "cfd.correctors=2", "--setups", "affordable", "--set",
            'cfd.far_field="inletOutlet"', "--set", 'cfd.turbulence_convection="upwind"',
            "--json"]
    res = CliRunner().invoke(cli, args)
    assert res.exit_code == 0, res.output
    data = json.loads(res.output[res.output.index("{"):])
    assert set(data["runs"]) == {"coarse_co4", "coarse_co4_GAMG", "setup_affordable",
                                 "setup_affordable_PCG"}
    assert data["runs"]["setup_affordable"]["mesh"] == "graded"
    assert "setup_affordable vs coarse_co4" in data["nrmse"]
    affordable = tmp_path / "c" / "cases" / "setup_affordable"
    assert "Gauss LUST grad(U)" in (affordable / "system" / "fvSchemes").read_text()
    assert "nOuterCorrectors 1;" in (affordable / "system" / "fvSolution").read_text()
    # every run of the study, the set-up's too, has the far field and the k and epsilon
    # convection asked for; with upwind no solve needed clipping
    for run in data["runs"]:
        assert "inletOutlet" in (tmp_path / "c" / "cases" / run / "0" / "U").read_text()
        schemes = (tmp_path / "c" / "cases" / run / "system" / "fvSchemes").read_text()
        assert "div(phi,epsilon) Gauss upwind;" in schemes
        assert data["runs"][run]["epsilon_clipped_step_fraction"] == 0.0
    floor = data["nrmse"]["coarse_co4_GAMG vs coarse_co4 (round-off floor)"]
    assert 0 < floor["normal_force"] < 1e-3
    # the set-up (GAMG) has its own floor, a rerun with PCG compared with it, not with the
    # reference
    assert data["pairs"]["setup_affordable_PCG vs setup_affordable (round-off floor)"] == [
        "setup_affordable_PCG", "setup_affordable"]
    assert "setup_affordable_PCG vs coarse_co4" not in data["nrmse"]
    setup_floor = data["nrmse"]["setup_affordable_PCG vs setup_affordable (round-off floor)"]
    assert 0 < setup_floor["normal_force"] < 0.05
    assert "solver PCG;" in (tmp_path / "c" / "cases" / "setup_affordable_PCG" / "system" /
                             "fvSolution").read_text()
    # the same folder with other settings: refused by file and key, nothing rerun or lost
    record = tmp_path / "c" / "coarse_co4.h5"
    mtime = record.stat().st_mtime_ns
    for (was, now), key in ((("cfd.correctors=2", "cfd.correctors=1"), "n_correctors"),
                            (('cfd.far_field="inletOutlet"', 'cfd.far_field="freestream"'),
                             "far_field"),
                            (('cfd.turbulence_convection="upwind"',
                              'cfd.turbulence_convection="limitedLinear"'),
                             "turbulence_convection"),
                            (("0.02", "0.03"), "cycles")):
        changed = list(args)
        changed[changed.index(was)] = now
        res = CliRunner().invoke(cli, changed)
        assert res.exit_code != 0
        assert "coarse_co4.h5" in res.output and f": {key}:" in res.output, res.output
    assert record.stat().st_mtime_ns == mtime
    solver = (tmp_path / "c" / "cases" / "coarse_co4_GAMG" / "system" / "fvSolution").read_text()
    assert "solver GAMG;" in solver and "nCorrectors     2;" in solver


def test_mean_cycles_outside_the_run_or_of_no_period_are_refused_before_any_run(tmp_path):
    from mfflap.campaign.convergence import run_convergence
    from mfflap.errors import ConfigError

    for phase_from in (-0.1, 2.0):
        with pytest.raises(ConfigError) as err:
            run_convergence(tmp_path / "d", MOTION, 2.0, meshes=["coarse"], period=1.0,
                            phase_from=phase_from)
        assert err.value.key == "phase_from"
    with pytest.raises(ConfigError) as err:
        run_convergence(tmp_path / "d", MOTION, 2.0, meshes=["coarse"], period=0.0)
    assert err.value.key == "period"
    assert not (tmp_path / "d").exists()


@pytest.mark.openfoam
def test_convergence_compares_mean_cycles_of_a_periodic_motion(tmp_path):
    """A harmonic motion over three periods: the study also compares the mean cycles of the
    two Courant limits over the two periods after the first, as recomputed here from the
    stored records, and reports each run's cycle-to-cycle scatter."""
    import json

    from click.testing import CliRunner

    from mfflap.cli.main import cli
    from mfflap.metrics import nrmse
    from mfflap.records.record import read_record

    text = (Path(__file__).parents[3] / "cases" / "paper2026.toml").read_text()
    period_s = 0.025
    text = text.replace("frequency = 1.0 ", "frequency = 40.0 ").replace(
        "heave_amplitude = 0.3 ", "heave_amplitude = 0.0025 ").replace(
        "pitch_amplitude_deg = 20.0", "pitch_amplitude_deg = 1.0")
    case = tmp_path / "fast.toml"
    case.write_text(text)
    res = CliRunner().invoke(cli, ["cfd", "convergence", str(case), str(tmp_path / "c"),
                                   "--meshes", "coarse", "--courant", "4,3", "--cycles", "3",
                                   "--set", 'cfd.pressure_solver="GAMG"', "--json"])
    assert res.exit_code == 0, res.output
    data = json.loads(res.output[res.output.index("{"):])
    assert data["phase_cycles"] == 2
    assert set(data["cycle_scatter"]) == {"coarse_co4", "coarse_co3"}
    # the same pairs as the point-wise NRMSE
    assert set(data["phase_nrmse"]) == set(data["nrmse"]) == {"coarse_co3 vs coarse_co4",
                                                              "coarse_co4 vs coarse_co3"}
    key = "coarse_co4 vs coarse_co3"
    phase = np.arange(256) / 256
    means = {}
    for label in ("coarse_co4", "coarse_co3"):
        rec = read_record(tmp_path / "c" / f"{label}.h5")
        # the first period is left out
        cycles = [np.interp((1 + k + phase) * period_s, rec.time, rec.loads.normal_force)
                  for k in (0, 1)]
        means[label] = np.mean(cycles, axis=0)
        spread = np.std(cycles, axis=0, ddof=1)
        assert data["cycle_scatter"][label]["normal_force"] == pytest.approx(
            np.sqrt(np.mean(spread**2)) / np.ptp(means[label]), rel=1e-9)
    assert data["phase_nrmse"][key]["normal_force"] == pytest.approx(
        float(nrmse(means["coarse_co4"], means["coarse_co3"])), rel=1e-9)
    assert 0 < data["phase_nrmse"][key]["normal_force"] < 1
    assert "Mean cycles (2 periods per run)" in (tmp_path / "c" / "convergence.html").read_text()
    # two periods: one whole period after the first, too few, and the study says so
    res = CliRunner().invoke(cli, ["cfd", "convergence", str(case), str(tmp_path / "d"),
                                   "--meshes", "coarse", "--courant", "4", "--cycles", "2",
                                   "--set", 'cfd.pressure_solver="GAMG"', "--json"])
    assert res.exit_code == 0, res.output
    assert "no mean cycles compared" in res.output and "(0.025 s) after their first" in res.output
    assert json.loads(res.output[res.output.index("{"):])["phase_nrmse"] == {}


def first_radial_cell_m(spec, chord: float = 0.16) -> float:
    """Height of the first cell off the plate of a radially graded O-grid (geometric series
    over about the far-field radius), m."""
    ratio = spec.radial_expansion ** (1 / (spec.n_radial - 1))
    return spec.radius_chords * chord * (ratio - 1) / (ratio**spec.n_radial - 1)


def test_the_larger_domain_keeps_the_medium_mesh_near_the_plate():
    from mfflap.cfd.openfoam.writer import mesh_specs

    specs = mesh_specs()
    for near, far in (("medium", "medium_r20"), ("coarse", "coarse_r20")):
        medium, large = specs[near], specs[far]
        assert large.radius_chords == 2 * medium.radius_chords
        assert (large.n_chord, large.n_edge) == (medium.n_chord, medium.n_edge)
        assert first_radial_cell_m(large) == pytest.approx(first_radial_cell_m(medium),
                                                           rel=0.01)


def test_the_edge_study_meshes_change_only_the_cells_across_the_plates_ends():
    from mfflap.cfd.openfoam.writer import mesh_specs

    specs = mesh_specs()
    medium = dataclasses.asdict(specs["medium"])
    edges = [dataclasses.asdict(s) for name, s in specs.items() if name.startswith("medium_edge")]
    assert [e["n_edge"] for e in edges] == [10, 9, 6, 4]
    for edge in edges:
        assert edge["n_edge"] < medium["n_edge"]
        assert {k: v for k, v in edge.items() if k not in ("name", "n_edge")} == {
            k: v for k, v in medium.items() if k not in ("name", "n_edge")}


@pytest.mark.openfoam
@pytest.mark.parametrize("mesh", ["coarse", "lean", "graded", "medium", "medium_r20", "fine",
                                  "medium_edge6", "coarse_r20"])
def test_every_named_mesh_builds_and_passes_checkmesh(tmp_path, mesh):
    """blockMesh + checkMesh on each resolution of meshes.toml; the cell count is the spec's,
    and the lean mesh's chordwise cells really are crowded toward the plate's ends."""
    import re

    from mfflap.cfd.openfoam.runner import run_application
    from mfflap.cfd.openfoam.writer import mesh_specs

    spec = mesh_specs()[mesh]
    case = write_case(tmp_path / mesh, MOTION, end_time=0.01, mesh=mesh)
    run_application(case, "blockMesh", timeout_s=120)
    log = run_application(case, "checkMesh", timeout_s=120).read_text()
    assert "Mesh OK" in log
    assert int(re.search(r"cells:\s+(\d+)", log).group(1)) == spec.n_cells
    if spec.chord_grading != 1.0:
        import pyvista as pv

        (case / "case.foam").touch()
        reader = pv.POpenFOAMReader(str(case / "case.foam"))
        reader.enable_all_patch_arrays()
        plate = reader.read()["boundary"]["plate"]
        xyz = np.asarray(plate.points)
        face = xyz[(np.abs(xyz[:, 1] + 0.0015) < 1e-6) & (np.abs(xyz[:, 2]) < 1e-9)]
        x = np.unique(np.round(face[:, 0], 9))
        widths = np.diff(x)
        assert widths[len(widths) // 2] / widths[0] == pytest.approx(spec.chord_grading,
                                                                     rel=0.15)
    if mesh.startswith("medium_edge"):
        import pyvista as pv

        (case / "case.foam").touch()
        reader = pv.POpenFOAMReader(str(case / "case.foam"))
        reader.enable_all_patch_arrays()
        xyz = np.asarray(reader.read()["boundary"]["plate"].points)
        trailing_edge = xyz[(np.abs(xyz[:, 0] - 0.16) < 1e-6) & (np.abs(xyz[:, 2]) < 1e-9)]
        widths = np.diff(np.unique(np.round(trailing_edge[:, 1], 9)))
        assert len(widths) == spec.n_edge
        assert widths == pytest.approx(0.003 / spec.n_edge, rel=1e-3)


def assert_forces_match_the_uninterrupted_run(case: Path, whole: Path) -> None:
    """The merged forces of a restarted 0.03 s run end where the uninterrupted run's do,
    increase in time and match it within 1 % of its peak."""
    merged, reference = read_forces(case), read_forces(whole)
    assert merged.time[-1] == pytest.approx(reference.time[-1])
    assert np.all(np.diff(merged.time) > 0)
    t = np.linspace(0.002, 0.029, 60)
    for k in range(2):
        a = np.interp(t, merged.time, merged.force[:, k])
        b = np.interp(t, reference.time, reference.force[:, k])
        assert np.max(np.abs(a - b)) <= 1e-2 * np.max(np.abs(b))


@pytest.mark.openfoam
def test_second_restart_from_a_non_integer_time_is_read_from_its_suffixed_file(tmp_path):
    """A run restarted twice from t = 0.02 s: the first restart wrote forces/0.02/force.dat
    and was killed; v1912 writes the second restart's forces to force_0.02.dat beside it.
    The merged history runs to the end and matches an uninterrupted run (seen on a campaign
    case that resumed at 0.75 s, whose end was first read as the killed run's 1.263 s)."""
    from mfflap.cfd.openfoam.writer import MeshSpec, SolverSettings

    spec = MeshSpec("tiny", n_chord=20, n_edge=4, n_radial=20, radial_expansion=100.0,
                    radius_chords=8.0)
    settings = SolverSettings(write_interval=0.01)
    whole = write_case(tmp_path / "whole", MOTION, end_time=0.03, mesh=spec, solver=settings)
    run_case(whole, timeout_s=300)
    case = write_case(tmp_path / "restarted", MOTION, end_time=0.03, mesh=spec,
                      solver=settings)
    run_case(case, timeout_s=300)
    for restart in range(2):
        shutil.rmtree(case / "0.03")  # the fields are kept at 0.02 and 0.03 (purgeWrite 2)
        run_case(case, timeout_s=300)
        if restart == 0:  # the first restart was killed at 0.025 s
            for name in ("force", "moment"):
                path = case / "postProcessing" / "forces" / "0.02" / f"{name}.dat"
                lines = path.read_text().splitlines(keepends=True)
                path.write_text("".join(ln for ln in lines
                                        if ln.startswith("#") or float(ln.split()[0]) < 0.025))
    folder = case / "postProcessing" / "forces" / "0.02"
    assert (folder / "force_0.02.dat").is_file() and (folder / "moment_0.02.dat").is_file()
    assert_forces_match_the_uninterrupted_run(case, whole)


@pytest.mark.openfoam
def test_restart_skips_time_folders_that_hold_only_the_y_plus_field(tmp_path):
    """The yPlus function object writes its field into a time folder of its own every 20
    steps. A run killed after such a folder (here: its last full write removed) restarts
    from the last folder with every field, not from the y+ folder (where pimpleFoam stopped
    at once: cannot find p); forces and y+ of the restart replace the killed run's from the
    restart time on."""
    from mfflap.cfd.openfoam.time_folders import latest_solution_time
    from mfflap.cfd.openfoam.writer import MeshSpec, SolverSettings
    from mfflap.cfd.openfoam.yplus import read_y_plus

    spec = MeshSpec("tiny", n_chord=20, n_edge=4, n_radial=20, radial_expansion=100.0,
                    radius_chords=8.0)
    settings = SolverSettings(write_interval=0.01, max_time_step=2e-4)  # 150 steps
    whole = write_case(tmp_path / "whole", MOTION, end_time=0.03, mesh=spec, solver=settings,
                       y_plus=True)
    run_case(whole, timeout_s=300)
    case = write_case(tmp_path / "killed", MOTION, end_time=0.03, mesh=spec, solver=settings,
                      y_plus=True)
    run_case(case, timeout_s=300)
    shutil.rmtree(case / "0.03")
    y_plus_only = [p for p in case.iterdir() if p.name.replace(".", "").isdigit()
                   and 0.02 < float(p.name) and not (p / "p").exists()]
    assert y_plus_only, "no y+ folder after the last full write: the test needs one"
    assert latest_solution_time(case) == "0.02"
    run_case(case, timeout_s=300)
    assert FoamFile(case / "system" / "controlDict")["startTime"] == 0.02
    assert_forces_match_the_uninterrupted_run(case, whole)
    y_plus = read_y_plus(case)
    restart_rows = [float(ln.split()[0]) for ln in
                    (case / "postProcessing" / "yPlus" / "0.02" / "yPlus.dat").read_text()
                    .splitlines() if ln.strip() and not ln.startswith("#")]
    assert np.all(np.diff(y_plus.time) > 0)
    np.testing.assert_array_equal(y_plus.time[y_plus.time >= restart_rows[0]], restart_rows)
    assert y_plus.time[-1] == pytest.approx(read_y_plus(whole).time[-1])


@pytest.mark.openfoam
def test_a_restart_from_a_folder_named_past_the_time_precision_starts_there(tmp_path):
    """OpenFOAM raises its time precision while it runs, to tell two times apart, and does
    not write it down. At the case's precision (here 1) the restart time 0.015 s is named
    0.01: a folder of that name holding only y+ (as the yPlus function object writes one
    where the time steps have collapsed) made pimpleFoam start there and stop, cannot find
    0.01/p (seen on a back-test of the filtered rounds, restarting at 2.20850674 s with
    precision 8). The restart raises timePrecision to the folder's digits and runs from
    0.015 s to the end."""
    from mfflap.cfd.openfoam.writer import MeshSpec, SolverSettings

    spec = MeshSpec("tiny", n_chord=20, n_edge=4, n_radial=20, radial_expansion=100.0,
                    radius_chords=8.0)
    settings = SolverSettings(write_interval=0.015)
    case = write_case(tmp_path / "restarted", MOTION, end_time=0.03, mesh=spec,
                      solver=settings)
    control = case / "system" / "controlDict"
    FoamFile(control)["timePrecision"] = 1
    run_case(case, timeout_s=300)
    assert (case / "0.015" / "p").is_file()  # written with the precision raised to 2
    shutil.rmtree(case / "0.03")
    (case / "0.01").mkdir()
    (case / "0.01" / "yPlus").write_bytes((case / "0.015" / "p").read_bytes())
    run_case(case, timeout_s=300)
    assert (FoamFile(control)["startTime"], FoamFile(control)["timePrecision"]) == (0.015, 2)
    log = (case / "log.pimpleFoam").read_text()
    assert "Create time" in log and log.rstrip().endswith("End")
    assert "cannot find file" not in log
    assert (case / "0.03" / "p").is_file() and not (case / "0.01" / "p").exists()
    # (at precision 1 the forces' time column repeats itself: not compared here)


def test_the_start_time_carries_the_time_precision_that_names_it(tmp_path):
    from mfflap.cfd.openfoam.control_dict import set_start_time, significant_digits

    assert [significant_digits(n) for n in ("2.20850674", "0.015", "1e-05", "10", "0",
                                            "0.0001230", "3.5E+2")] == [9, 2, 1, 2, 1, 4, 2]
    case = write_case(tmp_path / "case", MOTION, end_time=0.1)
    control = case / "system" / "controlDict"
    original = control.read_text()
    precision = FoamFile(control)["timePrecision"]
    set_start_time(case, "0.05")  # fewer digits: the precision stays
    entries = FoamFile(control)
    assert (entries["startFrom"], entries["startTime"]) == ("startTime", 0.05)
    assert entries["timePrecision"] == precision
    set_start_time(case, "2.20850674123")
    entries = FoamFile(control)
    assert (entries["timePrecision"], entries["startTime"]) == (12, 2.20850674123)
    assert control.read_text().count("timePrecision") == 1
    set_start_time(case, "0.05")  # never lowered
    assert FoamFile(control)["timePrecision"] == 12
    # a controlDict without the entry (OpenFOAM's default 6) gets one where 6 would not do
    control.write_text(original)
    del FoamFile(control)["timePrecision"]
    set_start_time(case, "0.123456")
    assert "timePrecision" not in FoamFile(control)
    set_start_time(case, "0.1234567")
    assert FoamFile(control)["timePrecision"] == 7


@pytest.mark.openfoam
def test_a_run_killed_while_writing_resumes_from_the_last_folder_written_whole(tmp_path):
    """A run killed while it wrote its last time folder (here: its pressure field and mesh
    points cut short) resumes from the folder before, where pimpleFoam would stop at once on
    the field it cannot read; the merged forces match an uninterrupted run."""
    from mfflap.cfd.openfoam.solver_log import solver_provenance
    from mfflap.cfd.openfoam.time_folders import latest_solution_time
    from mfflap.cfd.openfoam.writer import MeshSpec, SolverSettings

    spec = MeshSpec("tiny", n_chord=20, n_edge=4, n_radial=20, radial_expansion=100.0,
                    radius_chords=8.0)
    settings = SolverSettings(write_interval=0.01, max_time_step=2e-4)
    whole = write_case(tmp_path / "whole", MOTION, end_time=0.03, mesh=spec, solver=settings)
    run_case(whole, timeout_s=300)
    case = write_case(tmp_path / "killed", MOTION, end_time=0.03, mesh=spec, solver=settings)
    run_case(case, timeout_s=300)
    for cut in (case / "0.03" / "p", case / "0.03" / "polyMesh" / "points"):
        data = cut.read_bytes()
        cut.write_bytes(data[: len(data) // 2])
    assert latest_solution_time(case) == "0.02"
    run_case(case, timeout_s=300)
    assert FoamFile(case / "system" / "controlDict")["startTime"] == 0.02
    assert_forces_match_the_uninterrupted_run(case, whole)
    # the steps from 0.02 to 0.03 s were taken twice: once more than the uninterrupted run
    resumed, uninterrupted = solver_provenance(case), solver_provenance(whole)
    redone = resumed["n_time_steps_redone"]
    assert redone >= 0.01 / 2e-4 - 1 and resumed["cpu_time_redone_s"] > 0
    assert abs(resumed["n_time_steps"] - redone - uninterrupted["n_time_steps"]) <= 1


def test_latest_solution_time_needs_every_initial_field_written_whole(tmp_path):
    """The latest time folder with every field of 0/, each file ending with OpenFOAM's end
    divider (compressed or not; 0/ is mfflap's and has none), in every processor folder."""
    import gzip

    from mfflap.cfd.openfoam.control_dict import set_start_time
    from mfflap.cfd.openfoam.time_folders import latest_solution_time

    whole = b"FoamFile {}\n(1 2 3)\n\n// " + b"*" * 73 + b" //\n"
    assert latest_solution_time(tmp_path) is None
    roots = (tmp_path / "serial", tmp_path / "decomposed" / "processor0",
             tmp_path / "decomposed" / "processor1")
    for root in roots:
        for folder, names in (("0", "U p k epsilon nut"), ("0.5", "U p k epsilon nut phi"),
                              ("0.7", "yPlus"), ("0.8", "U p"), ("1e-3", "U p k epsilon nut"),
                              ("constant", "U p k epsilon nut")):
            (root / folder).mkdir(parents=True)
            for name in names.split():
                (root / folder / name).write_bytes(b"" if folder == "0" else whole)
        (root / "0.5" / "uniform").mkdir()
        (root / "0.5" / "uniform" / "time").write_bytes(whole)
        (root / "0.6").mkdir()
        for name in ("U.gz", "p.gz", "k.gz", "epsilon.gz", "nut.gz"):
            (root / "0.6" / name).write_bytes(gzip.compress(whole))
    assert latest_solution_time(tmp_path / "serial") == "0.6"
    assert latest_solution_time(tmp_path / "decomposed") == "0.6"
    cut = tmp_path / "decomposed" / "processor1" / "0.6" / "k.gz"
    cut.write_bytes(gzip.compress(whole)[:-12])  # a compressed write cut short
    assert latest_solution_time(tmp_path / "decomposed") == "0.5"
    shutil.rmtree(tmp_path / "serial" / "0.6")
    assert latest_solution_time(tmp_path / "serial") == "0.5"
    (tmp_path / "serial" / "0.5" / "uniform" / "time").write_bytes(whole[:-20])
    assert latest_solution_time(tmp_path / "serial") == "1e-3"
    (tmp_path / "serial" / "1e-3" / "p").write_bytes(whole[:30])
    assert latest_solution_time(tmp_path / "serial") == "0"
    case = write_case(tmp_path / "case", MOTION, end_time=0.1)
    set_start_time(case, "0.05")
    control = FoamFile(case / "system" / "controlDict")
    assert (control["startFrom"], control["startTime"]) == ("startTime", 0.05)
    del control["startTime"]
    with pytest.raises(CfdRunError, match="controlDict has no startFrom or startTime"):
        set_start_time(case, "0")


def test_far_field_switch_reaches_the_processor_folders(tmp_path):
    from mfflap.cfd.openfoam.retry_edits import use_inlet_outlet_far_field

    case = write_case(tmp_path / "case", MOTION, end_time=0.1)
    for proc in ("processor0", "processor1"):
        shutil.copytree(case / "0", case / proc / "0.05")
    assert "freestreamVelocity" in (case / "processor1" / "0.05" / "U").read_text()
    assert use_inlet_outlet_far_field(case)
    for folder in (case / "0", case / "processor0" / "0.05", case / "processor1" / "0.05"):
        assert "inletOutlet" in (folder / "U").read_text()
        assert "freestream" not in (folder / "U").read_text()
        assert "freestreamPressure" not in (folder / "p").read_text()


@pytest.mark.openfoam
def test_convergence_time_step_study_on_a_chosen_mesh(tmp_path):
    """--courant 4,2@MESH repeats that mesh (not the first) at the further Courant limits;
    with two meshes there is no grid convergence index."""
    import json

    from click.testing import CliRunner

    from mfflap.cli.main import cli

    case = Path(__file__).parents[3] / "cases" / "paper2026.toml"
    args = ["cfd", "convergence", str(case), str(tmp_path / "c"), "--meshes", "coarse,lean",
            "--cycles", "0.02", "--ramp-time", "0.005", "--json"]
    res = CliRunner().invoke(cli, [*args, "--courant", "4,2@medium"])
    assert res.exit_code == 2 and ("Invalid value for --courant: 'medium' is not one "
                                   "of the study's --meshes (coarse, lean)") in res.output
    res = CliRunner().invoke(cli, [*args, "--courant", "4,2@lean"])
    assert res.exit_code == 0, res.output
    data = json.loads(res.output[res.output.index("{"):])
    assert set(data["runs"]) == {"coarse_co4", "lean_co4", "lean_co2"}
    assert data["runs"]["lean_co2"]["max_courant"] == 2
    assert "lean_co4 vs lean_co2" in data["nrmse"]
    assert data["gci"] == {} and data["gci_meshes"] == []


@pytest.mark.parametrize(("meshes", "courants", "key", "said"), [
    (["coarse", "bogus"], [4.0], None, "unknown mesh 'bogus'"),
    (["coarse"], [4.0, -1.0], "max_courant", "max_courant must be > 0"),
    (["coarse", "coarse"], [4.0], "meshes/courants", "coarse_co4 twice"),
    (["coarse"], [4.0, 4.0], "meshes/courants", "coarse_co4 twice")])
def test_convergence_checks_every_run_before_the_first_starts(tmp_path, meshes, courants,
                                                              key, said):
    """A typo in the last mesh or Courant limit used to surface after the first runs had
    taken their CPU; now nothing is written or run."""
    from mfflap.campaign.convergence import run_convergence
    from mfflap.errors import ConfigError

    with pytest.raises(ConfigError, match=said) as err:
        run_convergence(tmp_path / "study", MOTION, 0.02, meshes=meshes, courants=courants)
    assert key is None or err.value.key == key
    assert not (tmp_path / "study").exists()


def test_a_run_resumed_between_writes_still_writes_at_its_end(tmp_path):
    """OpenFOAM counts write times from a run's start: resumed from a time off the write
    grid, the interval shrinks to the largest one that divides the time left (so the run
    writes at its end); from the case's own grid (even one that misses the end), or writing
    by time step, nothing changes; the function objects' own intervals are never touched."""
    from mfflap.cfd.openfoam.control_dict import align_writes_to_end
    from mfflap.cfd.openfoam.writer import SolverSettings

    write_case(tmp_path, MOTION, 1.0, solver=SolverSettings(write_interval=0.25))
    control = tmp_path / "system" / "controlDict"
    original = control.read_text()
    assert align_writes_to_end(tmp_path, 0.5) is None and control.read_text() == original
    assert align_writes_to_end(tmp_path, 1.0) is None  # nothing left to run
    before = FoamFile(control).as_dict()
    aligned = align_writes_to_end(tmp_path, 0.3)  # 0.7 left: 3 writes of 0.2333
    assert aligned == pytest.approx(0.7 / 3)
    after = FoamFile(control).as_dict()
    assert after["writeInterval"] == aligned
    assert {**after, "writeInterval": 0.25} == before  # only that entry, not the functions'
    assert align_writes_to_end(tmp_path, 0.3) is None  # aligned now: stays
    control.write_text(original.replace("writeInterval   0.25;", "writeInterval   0.3;"))
    assert align_writes_to_end(tmp_path, 0.0) is None  # the user's own grid, from the start
    assert align_writes_to_end(tmp_path, 0.6) is None  # and from one of its writes
    control.write_text(original.replace("writeControl    adjustableRunTime;",
                                        "writeControl    timeStep;"))
    assert align_writes_to_end(tmp_path, 0.3) is None


@pytest.mark.parametrize(("steps", "ending", "finished"), [
    ([(0.98, 0.01), (0.99, 0.01), (1.0, 0.01)], "End", True),
    ([(0.98, 0.012), (0.992, 0.012)], "End", True),  # within half a step: OpenFOAM stops
    ([(0.5, 0.01), (0.51, 0.01)], "End", False),  # ended early (a stop signal)
    ([(0.99, 0.01), (1.0, 0.01)], "PIMPLE: iteration 1", False),  # cut off, no End
    ([(0.99, None), (1.0, None)], "End", True),  # a fixed time step prints no deltaT
    ([(0.5, None), (0.51, None)], "End", False),
    ([(0.99, 0.01), (1.0, 0.01)], "End\n\nFinalising parallel run", True),
])
def test_ran_to_end_reads_the_log_against_the_end_time(tmp_path, steps, ending, finished):
    from mfflap.cfd.openfoam.runner import ran_to_end

    write_case(tmp_path, MOTION, 1.0)
    lines = []
    for time_s, step_s in steps:
        if step_s is not None:
            lines.append(f"Courant Number mean: 0.01 max: 0.9\ndeltaT = {step_s}")
        lines.append(f"Time = {time_s}\n\nPIMPLE: iteration 1\nExecutionTime = 1 s\n")
    (tmp_path / "log.pimpleFoam").write_text("\n".join(lines) + f"\n{ending}\n\n")
    assert ran_to_end(tmp_path) is finished
    (tmp_path / "log.pimpleFoam").unlink()
    assert ran_to_end(tmp_path) is False  # no log: not run
