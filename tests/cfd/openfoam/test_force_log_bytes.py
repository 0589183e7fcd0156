"""A force log with bytes that are not text, or with a huge token, is a clean error naming
the file and line, never a traceback or the token echoed whole."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest
from click.testing import CliRunner

from mfflap.cfd.openfoam.forces import read_forces
from mfflap.cli.main import cli
from mfflap.errors import ParseError

REAL_LOG = Path(__file__).parents[2] / "data" / "openfoam_v1912" / "force.dat"
CASE = Path(__file__).parents[3] / "cases" / "paper2026.toml"


def _case_with_log(tmp_path: Path, edit) -> Path:
    folder = tmp_path / "case" / "postProcessing" / "forces" / "0"
    folder.mkdir(parents=True)
    log = folder / "force.dat"
    shutil.copyfile(REAL_LOG, log)
    lines = log.read_bytes().splitlines(keepends=True)
    row = next(i for i, line in enumerate(lines) if line[:1].isdigit()) + 3
    lines[row] = edit(lines[row])
    log.write_bytes(b"".join(lines))
    return tmp_path / "case", row + 1


def test_a_byte_that_is_not_text_names_the_file_and_line(tmp_path):
    case, line = _case_with_log(tmp_path, lambda row: row[:5] + b"\xff" + row[6:])
    with pytest.raises(ParseError) as refused:
        read_forces(case)
    assert refused.value.line == line and refused.value.path.endswith("force.dat")
    assert "0xff" in str(refused.value)
    res = CliRunner().invoke(cli, ["cfd", "parse", str(case), "--case-file", str(CASE)])
    assert res.exit_code == 2 and "Traceback" not in res.output
    assert f"force.dat, line {line}" in " ".join(res.output.split())


def test_a_megabyte_token_is_cut_short_in_the_error(tmp_path):
    case, _ = _case_with_log(tmp_path, lambda row: b"x" * 1_000_000 + b"\n")
    with pytest.raises(ParseError) as refused:
        read_forces(case)
    assert len(str(refused.value)) < 500 and "xxx..." in str(refused.value)


@pytest.mark.parametrize("header, rows_from", [
    ("# Forces\n# Time forces(pressure viscous) moment(pressure viscous)\n", "force.dat"),
    ("# Force\n# Time (total_x total_y total_z) (pressure_x pressure_y pressure_z) "
     "(viscous_x viscous_y viscous_z)\n", "foundation"),
])
def test_a_header_and_rows_of_two_layouts_are_an_error_naming_the_file(tmp_path, header,
                                                                        rows_from):
    """openfoam.com rows under the Foundation's column line (in forces.dat), or Foundation
    rows under openfoam.com's: which numbers are forces would be a guess."""
    from tests.cfd.openfoam.test_runner import to_foundation

    data = REAL_LOG.parent
    if rows_from == "foundation":
        body = to_foundation((data / "force.dat").read_text(), (data / "moment.dat").read_text())
    else:
        body = (data / "force.dat").read_text()
    rows = "".join(line + "\n" for line in body.splitlines() if not line.startswith("#"))
    folder = tmp_path / "case" / "postProcessing" / "forces" / "0"
    folder.mkdir(parents=True)
    (folder / "forces.dat").write_text(header + rows)
    with pytest.raises(ParseError, match=r"forces\.dat: its header says the rows hold .* "
                                         r"the header and the rows disagree"):
        read_forces(tmp_path / "case")
