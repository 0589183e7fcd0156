"""numba's compiled kernels are cached outside the installed package, so that uninstalling
mfflap (pip does not know the caches) leaves no folder behind to shadow a later install."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import mfflap

PACKAGE = Path(mfflap.__file__).parent

_RUN_A_KERNEL = """
import numpy as np
from mfflap.hydro.discrete_vortex import vortex_loads
from mfflap.kinematics.continuous import HarmonicMotion
state = HarmonicMotion(1.0, 0.05, 0.1).sample(np.arange(40) / 40)
vortex_loads(state)
import numba
print(numba.config.CACHE_DIR)
"""


def _cache_files(folder: Path) -> list[Path]:
    return [p for p in folder.rglob("*") if p.suffix in (".nbi", ".nbc")]


def test_kernels_compile_into_the_user_cache_not_the_package(tmp_path):
    before = set(_cache_files(PACKAGE))
    env = {k: v for k, v in os.environ.items() if k != "NUMBA_CACHE_DIR"}
    env["XDG_CACHE_HOME"] = str(tmp_path)
    done = subprocess.run([sys.executable, "-c", _RUN_A_KERNEL], env=env, check=True,
                          capture_output=True, text=True)
    assert Path(done.stdout.strip()) == tmp_path / "mfflap" / "numba"
    assert _cache_files(tmp_path / "mfflap" / "numba"), "the kernels were not cached at all"
    assert set(_cache_files(PACKAGE)) == before


def test_a_cache_folder_the_user_chose_is_kept(tmp_path):
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "mine"))
    done = subprocess.run([sys.executable, "-c", "import numba, mfflap\n"
                           "print(numba.config.CACHE_DIR)"], env=env, check=True,
                          capture_output=True, text=True)
    assert done.stdout.strip() == str(tmp_path / "mine")


def test_numba_imported_before_mfflap_still_caches_outside_the_package(tmp_path):
    env = {k: v for k, v in os.environ.items() if k != "NUMBA_CACHE_DIR"}
    env["XDG_CACHE_HOME"] = str(tmp_path)
    done = subprocess.run([sys.executable, "-c", "import numba\n" + _RUN_A_KERNEL], env=env,
                          check=True, capture_output=True, text=True)
    assert Path(done.stdout.strip()) == tmp_path / "mfflap" / "numba"
