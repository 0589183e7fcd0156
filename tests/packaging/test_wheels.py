"""The two distributions built from the repository, installed in a new virtual environment
outside the checkout, run the commands a new user runs first."""

from __future__ import annotations

import subprocess
import sys
import venv
import zipfile
from pathlib import Path

import pytest

ROOT = Path(__file__).parents[2]
#: the largest the package's wheel may be, bytes (the CFD records are the data's)
MAX_WHEEL_BYTES = 20 * 1024 * 1024


def _run(args: list[str], cwd: Path, timeout: float = 900) -> str:
    done = subprocess.run(args, cwd=cwd, capture_output=True, text=True, timeout=timeout)
    assert done.returncode == 0, f"{args}\n{done.stdout[-2000:]}\n{done.stderr[-2000:]}"
    return done.stdout


@pytest.mark.slow
def test_the_wheels_installed_outside_the_checkout_write_cases_and_run_the_main_job(
        tmp_path):
    wheels = tmp_path / "wheels"
    _run([sys.executable, "-m", "pip", "wheel", "-q", "--no-deps", str(ROOT),
          str(ROOT / "data"), "-w", str(wheels)], cwd=tmp_path)
    package = next(wheels.glob("mfflap-*.whl"))
    assert next(wheels.glob("mfflap_data-*.whl"))
    assert package.stat().st_size <= MAX_WHEEL_BYTES
    names = zipfile.ZipFile(package).namelist()
    templates = sorted(n for n in names if n.startswith("mfflap/cfd_templates/"))
    shipped = sorted(p for p in (ROOT / "cfd_templates").rglob("*")
                     if p.is_file() and "__pycache__" not in p.parts)
    assert len(templates) == len(shipped)
    assert not any(n.endswith(".h5") for n in names)  # the records are the data's
    # the test's own dependencies are reused; mfflap itself must come from the wheel
    env_dir = tmp_path / "venv"
    venv.create(env_dir, system_site_packages=True, with_pip=True)
    python = env_dir / "bin" / "python"
    _run([str(python), "-m", "pip", "install", "-q", "--no-deps", *map(str, wheels.glob(
        "*.whl"))], cwd=tmp_path)
    work = tmp_path / "work"
    work.mkdir()
    where = _run([str(python), "-c", "import mfflap, mfflap_data; print(mfflap.__file__); "
                  "print(mfflap_data.__file__)"], cwd=work)
    assert all(line.startswith(str(env_dir)) for line in where.split()), where
    mfflap = str(env_dir / "bin" / "mfflap")
    _run([mfflap, "init", "study.toml"], cwd=work)
    _run([mfflap, "cfd", "write", "study.toml", "case", "--cycles", "1", "--ramp-time",
          "0.25"], cwd=work)
    assert (work / "case" / "constant" / "dynamicMeshDict").is_file()
    _run([mfflap, "cfd", "fluent", "study.toml", "udf", "--cycles", "1", "--ramp-time",
          "0.25"], cwd=work)
    assert (work / "udf" / "mfflap_motion.c").is_file()
    said = _run([mfflap, "run", "study.toml", "--out", "run"], cwd=work)
    assert "wrote run/report.html and run/results.h5" in said
    assert (work / "run" / "report.html").stat().st_size > 100_000
