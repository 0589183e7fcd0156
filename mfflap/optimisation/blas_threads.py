"""One BLAS thread around the optimisers.

SLSQP and IPOPT solve small dense systems (a few hundred unknowns) many times. On two
OpenBLAS threads each of those calls hands work to a second thread; when another process
(a CFD run) holds the other core, the hand-over waits for the scheduler, and one SQP
optimisation took 1.4-5.5 s instead of 0.04 s. On one thread it takes 0.033 s either way
(benchmarks/optimiser_and_identification.py measures both beside a busy core).

This holds whatever the environment sets (``OPENBLAS_NUM_THREADS=2`` and the like): such a
count is meant for the large algebra elsewhere, and with it and a CFD run on the other core
the main job's gain table ran for more than 12 minutes against 38 s for the whole job on one
thread. One thread also makes the optimisers' arithmetic the same whatever the count.
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager

from threadpoolctl import threadpool_limits

#: BLAS threads while an optimiser runs; None leaves the library's own count (what the
#: benchmark compares against)
OPTIMISER_BLAS_THREADS: int | None = 1


@contextmanager
def optimiser_blas_threads() -> Iterator[None]:
    """Limit the BLAS libraries loaded in this process to :data:`OPTIMISER_BLAS_THREADS`
    threads for the duration of the block, whatever the environment sets, and restore them
    after it.

    Examples
    --------
    >>> import numpy as np
    >>> with optimiser_blas_threads():
    ...     float(np.linalg.solve(np.eye(2), np.ones(2))[0])
    1.0
    """
    if OPTIMISER_BLAS_THREADS is None:
        yield
        return
    with threadpool_limits(limits=OPTIMISER_BLAS_THREADS, user_api="blas"):
        yield
