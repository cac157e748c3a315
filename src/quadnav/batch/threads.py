"""How many numba threads a worker process runs: decided here, for every executor (the
local workers of ``batch`` and ``tune``, and Ray's).

The compiled kernels that test many points at once (``prange`` loops of
:mod:`quadnav.world`) run on numba's threads, one per CPU by default. When several worker
processes share the machine, each starting a thread per CPU only makes them wait for each
other (numba's OpenMP threads spin while they wait): each worker then runs one thread. A
single local worker has the machine to itself and keeps numba's threads. A Ray task takes
one CPU of a node that other tasks share: one thread. The rows are the same either way
(each ``prange`` iteration writes its own element; no sum depends on the thread count).
"""

from __future__ import annotations

import numba


def numba_threads(workers: int, ray: bool = False) -> int:
    """Numba threads of each of ``workers`` worker processes: numba's own count
    (``NUMBA_NUM_THREADS``, one per CPU unless set) for a single local worker, else 1."""
    return numba.config.NUMBA_NUM_THREADS if workers == 1 and not ray else 1


def use_numba_threads(count: int) -> None:
    """Run this thread's numba kernels on ``count`` threads (at most numba's own count).
    Call it in the worker, on the thread that runs the jobs, before the first job."""
    numba.set_num_threads(min(count, numba.config.NUMBA_NUM_THREADS))

