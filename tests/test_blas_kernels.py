"""The tests run on the OpenBLAS kernels and thread count the shipped series of rounds were
computed with."""

import os
import subprocess
import sys
from pathlib import Path

from openblas_kernels import (
    has_avx512,
    openblas_answers,
    openblas_corenames,
    unlike_the_shipped_series,
)


def test_openblas_runs_its_skylakex_kernels_where_the_cpu_has_avx512():
    """tests/conftest.py pins OPENBLAS_CORETYPE before numpy loads, in this process too:
    a plugin that loaded numpy first would leave the pin unread, and the rounds' series
    would take other steps (docs/findings/known_limits.md)."""
    if not has_avx512():  # the kernels would not run: the environment's choice is kept
        assert "MFFLAP_TESTS_OPENBLAS_CORETYPE_WAS" not in os.environ
        return
    assert os.environ["OPENBLAS_CORETYPE"] == "SkylakeX"
    names = openblas_corenames()
    assert names, "no bundled OpenBLAS found beside numpy or scipy"
    assert set(names.values()) == {"SkylakeX"}, names


def test_openblas_runs_two_threads_where_there_are_two_cores_or_more():
    """tests/conftest.py pins OPENBLAS_NUM_THREADS to 2 before numpy loads: one thread
    instead of two moves beta = 1's least-power optimum of the shipped series elsewhere in
    its cycle, and OpenBLAS would otherwise take one thread per core."""
    assert os.environ["OPENBLAS_NUM_THREADS"] == "2"
    threads = openblas_answers("get_num_threads")
    assert threads, "no bundled OpenBLAS found beside numpy or scipy"
    assert set(threads.values()) == {min(2, len(os.sched_getaffinity(0)))}, threads


def test_tests_that_replay_the_shipped_series_say_why_they_cannot_on_other_kernels():
    """The tests marked ``shipped_kernels`` run here (SkylakeX kernels where the CPU has
    AVX-512, two threads) and are skipped, with the kernels and threads named, where
    OpenBLAS runs others: Haswell's kernels, one thread."""
    from openblas_kernels import SHIPPED_KERNELS, SHIPPED_THREADS

    if has_avx512() and len(os.sched_getaffinity(0)) >= SHIPPED_THREADS:
        assert unlike_the_shipped_series() is None
    here = str(Path(__file__).parent)
    ask = "import openblas_kernels as k; print(k.unlike_the_shipped_series())"
    for kernels, threads, said in (("Haswell", "2", "runs Haswell with 2 thread(s)"),
                                   (SHIPPED_KERNELS, "1", f"runs {SHIPPED_KERNELS} with 1")):
        if kernels == SHIPPED_KERNELS and not has_avx512():
            continue  # those kernels would not load
        env = {**os.environ, "OPENBLAS_CORETYPE": kernels, "OPENBLAS_NUM_THREADS": threads,
               "PYTHONPATH": here}
        out = subprocess.run([sys.executable, "-c", ask], env=env, capture_output=True,
                             text=True, check=True).stdout
        assert said in out and "docs/findings/known_limits.md" in out, out
