"""What the tests know of OpenBLAS: the kernels and thread count it runs, read from the
libraries numpy and scipy bundle, and why a replay of a shipped series is skipped where
they differ from those the series was computed with."""

import os
import subprocess
import sys
from pathlib import Path

from openblas_kernels import (
    SHIPPED_KERNELS,
    has_avx512,
    openblas_answers,
    openblas_corenames,
)


def _started_with(name: str) -> str | None:
    """``name`` in the environment this process started with (/proc/self/environ: what
    OpenBLAS read as it loaded, whatever a library set in os.environ since, as dask's
    nanny does for its workers)."""
    for item in Path("/proc/self/environ").read_bytes().split(b"\0"):
        key, _, value = item.decode(errors="replace").partition("=")
        if key == name:
            return value
    return None


def test_the_tests_leave_openblas_its_own_kernels_and_threads():
    """Nothing in the suite sets OpenBLAS's kernels or thread count: what it runs is what
    it picks here, or what the environment the tests started in asked for."""
    names = openblas_corenames()
    assert names, "no bundled OpenBLAS found beside numpy or scipy"
    threads = openblas_answers("get_num_threads")
    asked = _started_with("OPENBLAS_NUM_THREADS")
    if asked:
        assert set(threads.values()) == {min(int(asked), os.cpu_count() or 1)}, threads
    else:
        assert all(t >= 1 for t in threads.values()), threads


def test_replays_of_the_shipped_series_say_why_they_cannot_on_other_kernels():
    """A test marked ``shipped_kernels`` is skipped, with the kernels and threads named,
    where OpenBLAS runs other kernels or another thread count than the shipped series:
    Haswell's kernels, or one thread."""
    here = str(Path(__file__).parent)
    ask = "import openblas_kernels as k; print(k.unlike_the_shipped_series())"
    for kernels, threads, said in (("Haswell", "2", "runs Haswell with "),
                                   (SHIPPED_KERNELS, "1", f"runs {SHIPPED_KERNELS} with 1")):
        if kernels == SHIPPED_KERNELS and not has_avx512():
            continue  # those kernels would not load
        env = {**os.environ, "OPENBLAS_CORETYPE": kernels, "OPENBLAS_NUM_THREADS": threads,
               "PYTHONPATH": here}
        out = subprocess.run([sys.executable, "-c", ask], env=env, capture_output=True,
                             text=True, check=True).stdout
        assert said in out and "docs/findings/known_limits.md" in out, out
