"""The tests run on the OpenBLAS kernels the shipped series of rounds were computed with."""

import ctypes
import os
from pathlib import Path

import numpy as np


def _has_avx512() -> bool:
    try:
        text = Path("/proc/cpuinfo").read_text(errors="replace")
    except OSError:
        return False
    flags = next((line.split(":", 1)[1].split() for line in text.splitlines()
                  if line.startswith("flags")), [])
    return {"avx512f", "avx512cd", "avx512bw", "avx512dq", "avx512vl"} <= set(flags)


def _openblas_corenames() -> dict[str, str]:
    """The kernels each OpenBLAS that numpy and scipy bundle has loaded, by library."""
    import scipy

    names = {}
    for package in (np, scipy):
        libs = Path(package.__file__).parent.parent / f"{package.__name__}.libs"
        for lib in sorted(libs.glob("*openblas*.so*")):
            handle = ctypes.CDLL(str(lib))
            for symbol in ("scipy_openblas_get_corename64_", "scipy_openblas_get_corename",
                           "openblas_get_corename64_", "openblas_get_corename"):
                get = getattr(handle, symbol, None)
                if get is not None:
                    get.restype = ctypes.c_char_p
                    names[lib.name] = get().decode()
                    break
    return names


def test_openblas_runs_its_skylakex_kernels_where_the_cpu_has_avx512():
    """tests/conftest.py pins OPENBLAS_CORETYPE before numpy loads, in this process too:
    a plugin that loaded numpy first would leave the pin unread, and the rounds' series
    would take other steps (README, Known limits)."""
    if not _has_avx512():  # the kernels would not run: the environment's choice is kept
        assert "MFFLAP_TESTS_OPENBLAS_CORETYPE_WAS" not in os.environ
        return
    assert os.environ["OPENBLAS_CORETYPE"] == "SkylakeX"
    names = _openblas_corenames()
    assert names, "no bundled OpenBLAS found beside numpy or scipy"
    assert set(names.values()) == {"SkylakeX"}, names
