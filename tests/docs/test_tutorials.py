"""Every tutorial's shell blocks run, in order, in an empty folder, as a reader would
type them; a page that needs OpenFOAM says so with a ``<!-- needs: openfoam -->`` line."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

TUTORIALS = sorted((Path(__file__).parents[2] / "docs" / "tutorials").glob("*.md"))
BLOCK = re.compile(r"^```bash\n(.*?)^```", re.S | re.M)


def shell_blocks(page: Path) -> list[str]:
    return BLOCK.findall(page.read_text())


def _marks(page: Path):
    return [pytest.mark.openfoam] if "<!-- needs: openfoam -->" in page.read_text() else []


@pytest.mark.slow
@pytest.mark.parametrize("page", [pytest.param(p, marks=_marks(p), id=p.stem)
                                  for p in TUTORIALS])
def test_every_tutorial_runs_as_written(tmp_path, page):
    blocks = shell_blocks(page)
    assert blocks, f"{page.name} has no ```bash block to run"
    env = {**os.environ, "PATH": f"{Path(sys.executable).parent}{os.pathsep}"
                                 f"{os.environ['PATH']}", "MPLBACKEND": "Agg"}
    for block in blocks:
        done = subprocess.run(["bash", "-euo", "pipefail", "-c", block], cwd=tmp_path,
                              env=env, capture_output=True, text=True, timeout=900)
        assert done.returncode == 0, (f"{page.name}:\n{block}\n--- stdout ---\n"
                                      f"{done.stdout[-3000:]}\n--- stderr ---\n"
                                      f"{done.stderr[-3000:]}")


def test_every_tutorial_is_in_the_site_s_navigation():
    nav = (Path(__file__).parents[2] / "mkdocs.yml").read_text()
    assert TUTORIALS and all(f"tutorials/{p.name}" in nav for p in TUTORIALS)
