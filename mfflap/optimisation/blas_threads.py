"""One BLAS thread around the optimisers.

SLSQP and IPOPT solve small dense systems (a few hundred unknowns) many times. On two
OpenBLAS threads each of those calls hands work to a second thread; when another process
(a CFD run) holds the other core, the hand-over waits for the scheduler, and one SQP
optimisation took 1.4-5.5 s instead of 0.04 s. On one thread it takes 0.033 s either way
(benchmarks/optimiser_and_identification.py measures both beside a busy core).

A thread count set in the environment (``OPENBLAS_NUM_THREADS``, ``OMP_NUM_THREADS``,
``MKL_NUM_THREADS``) is the user's choice and is left as it is.
"""

from __future__ import annotations

import os
from collections.abc import Iterator
from contextlib import contextmanager

from threadpoolctl import threadpool_limits

#: BLAS threads while an optimiser runs; None leaves the library's own count (what the
#: benchmark compares against)
OPTIMISER_BLAS_THREADS: int | None = 1
#: environment variables whose thread count, when set, is kept
THREAD_COUNT_VARIABLES = ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS")


@contextmanager
def optimiser_blas_threads() -> Iterator[None]:
    """Limit the BLAS libraries loaded in this process to :data:`OPTIMISER_BLAS_THREADS`
    threads for the duration of the block, and restore them after it; unless the
    environment sets a thread count (:data:`THREAD_COUNT_VARIABLES`).

    Examples
    --------
    >>> import numpy as np
    >>> with optimiser_blas_threads():
    ...     float(np.linalg.solve(np.eye(2), np.ones(2))[0])
    1.0
    """
    if OPTIMISER_BLAS_THREADS is None or any(os.environ.get(v)
                                             for v in THREAD_COUNT_VARIABLES):
        yield
        return
    with threadpool_limits(limits=OPTIMISER_BLAS_THREADS, user_api="blas"):
        yield
