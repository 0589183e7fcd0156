"""What OpenBLAS runs in this process: the CPU's feature flags, and the kernels and thread
count each OpenBLAS that numpy and scipy bundle has loaded. numpy is imported only when
OpenBLAS is asked, so tests/conftest.py can read the CPU's flags before numpy loads."""

import ctypes
from pathlib import Path

#: The kernels and OpenBLAS thread count the shipped series of rounds were computed with.
SHIPPED_KERNELS = "SkylakeX"
SHIPPED_THREADS = 2


def cpu_flags() -> set[str]:
    """The CPU's feature flags as /proc/cpuinfo lists them (none where it cannot be read)."""
    try:
        text = Path("/proc/cpuinfo").read_text(encoding="ascii", errors="replace")
    except OSError:
        return set()
    return set(next((line.split(":", 1)[1].split() for line in text.splitlines()
                     if line.startswith("flags")), []))


def has_avx512() -> bool:
    """Whether the CPU has the AVX-512 instructions OpenBLAS's SkylakeX kernels use."""
    return {"avx512f", "avx512cd", "avx512bw", "avx512dq", "avx512vl"} <= cpu_flags()


def openblas_answers(query: str, restype=ctypes.c_int) -> dict[str, object]:
    """What each OpenBLAS that numpy and scipy bundle answers to ``query`` (``get_corename``:
    the kernels it loaded; ``get_num_threads``), by library."""
    import numpy as np
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


def openblas_corenames() -> dict[str, str]:
    """The kernels each bundled OpenBLAS has loaded, by library."""
    return {lib: name.decode()
            for lib, name in openblas_answers("get_corename", ctypes.c_char_p).items()}


def unlike_the_shipped_series() -> str | None:
    """Why OpenBLAS here cannot replay the shipped series of rounds step for step (other
    kernels or another thread count than :data:`SHIPPED_KERNELS` on
    :data:`SHIPPED_THREADS` threads), or None when it runs what they were computed with."""
    kernels = sorted(set(openblas_corenames().values()))
    threads = sorted(set(openblas_answers("get_num_threads").values()))
    if kernels == [SHIPPED_KERNELS] and threads == [SHIPPED_THREADS]:
        return None
    return (f"replays the steps of a shipped series of rounds, which round-off steers "
            f"(docs/findings/known_limits.md): they were computed on OpenBLAS's {SHIPPED_KERNELS} "
            f"kernels with {SHIPPED_THREADS} threads, and OpenBLAS runs "
            f"{', '.join(kernels) or 'no kernels found'} with "
            f"{', '.join(map(str, threads)) or 'no'} thread(s) here")
