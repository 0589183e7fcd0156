"""The timer the benchmark scripts share."""

from __future__ import annotations

import time


def best_of(fn, repeat=5, budget_s=0.5):
    """Fastest of at least ``repeat`` calls, repeated until ``budget_s`` is spent (the
    minimum is the least disturbed by other load on the machine)."""
    times = []
    start = time.perf_counter()
    while len(times) < repeat or time.perf_counter() - start < budget_s:
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return min(times)
