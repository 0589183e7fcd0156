"""The tests run on the OpenBLAS kernels and thread count the shipped series of rounds were
computed with."""

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


def _openblas_answers(query: str, restype=ctypes.c_int) -> dict[str, object]:
    """What each OpenBLAS that numpy and scipy bundle answers to ``query`` (``get_corename``:
    the kernels it loaded; ``get_num_threads``), by library."""
    import scipy

    answers = {}
    for package in (np, scipy):
        libs = Path(package.__file__).parent.parent / f"{package.__name__}.libs"
        for lib in sorted(libs.glob("*openblas*.so*")):
            handle = ctypes.CDLL(str(lib))
            for symbol in (f"scipy_openblas_{query}64_", f"scipy_openblas_{query}",
                           f"openblas_{query}64_", f"openblas_{query}"):
                get = getattr(handle, symbol, None)
                if get is not None:
                    get.restype = restype
                    answers[lib.name] = get()
                    break
    return answers


def _openblas_corenames() -> dict[str, str]:
    """The kernels each bundled OpenBLAS has loaded, by library."""
    return {lib: name.decode()
            for lib, name in _openblas_answers("get_corename", ctypes.c_char_p).items()}


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


def test_openblas_runs_two_threads_where_there_are_two_cores_or_more():
    """tests/conftest.py pins OPENBLAS_NUM_THREADS to 2 before numpy loads: one thread
    instead of two moves beta = 1's least-power optimum of the shipped series elsewhere in
    its cycle, and OpenBLAS would otherwise take one thread per core."""
    assert os.environ["OPENBLAS_NUM_THREADS"] == "2"
    threads = _openblas_answers("get_num_threads")
    assert threads, "no bundled OpenBLAS found beside numpy or scipy"
    assert set(threads.values()) == {min(2, len(os.sched_getaffinity(0)))}, threads
