"""The documentation site builds with warnings as errors, its generated pages hold what
the code says, and nothing outside the findings pages tells the project's history."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).parents[2]


@pytest.mark.slow
def test_the_site_builds_strictly_with_the_generated_references(tmp_path):
    site = tmp_path / "site"
    done = subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict", "-q", "-d",
                           str(site)], cwd=ROOT, capture_output=True, text=True,
                          env={**os.environ, "NO_MKDOCS_2_WARNING": "1"}, timeout=600)
    assert done.returncode == 0, done.stdout + done.stderr
    cli = (site / "reference" / "cli" / "index.html").read_text()
    for command in ("mfflap run", "mfflap cfd write", "mfflap campaign run", "mfflap init"):
        assert command in cli, command
    case_file = (site / "reference" / "case-file" / "index.html").read_text()
    assert "max_ramp_pitch_deg" in case_file and "heave_amplitude" in case_file
    api = (site / "reference" / "api" / "index.html").read_text()
    assert "load_case" in api
    assert "Unreleased" in (site / "changelog" / "index.html").read_text()
    # no click marker shown as a default, no raw Sphinx role, no table row split by a list
    assert "Sentinel" not in cli
    assert not re.search(r":(func|class|meth|mod|data|attr):<code>", api)
    assert re.search(r"<td>Mesh[^<]*, one of coarse, lean, medium,[^<]*</td>", cli)


#: what tells history: issue and session numbers, the person who asked, dates of work
HISTORY = re.compile("|".join([r"\bissue \d+", r"\bsession \d+", r"\bthe owner\b",
                               r"\b20\d\d-\d\d-\d\d\b", "earlier sess" "ions",
                               "this sess" "ion"]), re.IGNORECASE)


def _texts():
    yield ROOT / "README.md"
    yield from (p for p in (ROOT / "docs").rglob("*.md") if "findings" not in p.parts)
    for folder in ("mfflap", "tests", "benchmarks", "cfd_templates"):
        for p in (ROOT / folder).rglob("*"):
            if p.suffix in (".py", ".toml", ".j2", ".md") and p.is_file():
                yield p


def test_nothing_outside_the_findings_tells_the_project_s_history():
    found = [f"{p.relative_to(ROOT)}:{i}: {line.strip()[:100]}"
             for p in _texts() for i, line in enumerate(p.read_text().splitlines(), 1)
             if HISTORY.search(line)]
    assert not found, "\n".join(found)


def test_the_readme_is_short_and_opens_with_its_two_commands():
    text = (ROOT / "README.md").read_text()
    assert len(text.splitlines()) <= 150
    blocks = re.findall(r"```bash\n(.*?)```", text, re.S)
    assert blocks[0].startswith("pip install . ./data && mfflap run")
    assert blocks[1].strip() == "scripts/install-and-test.sh"


@pytest.mark.slow
def test_the_readme_s_python_example_runs(tmp_path):
    """The README's study in Python, as printed there, from the repository's root."""
    code = re.search(r"```python\n(.*?)```", (ROOT / "README.md").read_text(), re.S).group(1)
    assert len(code.strip().splitlines()) <= 10
    done = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True,
                          text=True, timeout=600)
    assert done.returncode == 0, done.stderr
    assert re.search(r"^\d+\.\d N at \d\.\d\d Hz$", done.stdout, re.M), done.stdout
    assert "normal_drag" in done.stdout


def test_ci_runs_the_readme_s_two_commands_in_order():
    """CI runs README command 1 (a non-editable install and the main job) before command 2
    (the editable install and the tests), as a new user would, reading both from the
    README."""
    script = (ROOT / ".ci" / "run").read_text()
    assert 'open("README.md"' in script and "blocks[:2]" in script
    assert "scripts/install-and-test.sh" not in script.split("PY\n)", 1)[1]
