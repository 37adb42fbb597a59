"""Threads for independent compiled local searches.

The local search of ``symmetry._kernels`` releases the GIL (``numba.njit(nogil=True)``),
so independent searches (the starts of one phase of the witness search, the
candidates of a CNBS heat map, the maps refined over dense targets) run in parallel
threads of one process, sharing the distance matrix instead of copying it to worker
processes (``parallel`` is for whole shapes).

``thread_map(f, items)`` returns ``[f(x) for x in items]`` in input order, so a caller
that consumes the results in order gets the same answer with any number of threads; it
uses as many threads as numba may (``numba.get_num_threads()``: the cores of this
process, or its share when it is one of several workers of ``parallel``, which sets
``NUMBA_NUM_THREADS``).  A ``thread_map`` called from inside one of its own tasks runs
serially, so nested parallel code never oversubscribes the cores.

``one_blas_thread`` / ``single_blas_thread`` limit BLAS to one thread around the
small dense products of the searches and of ARPACK (threads only lose time
there, and a threaded product sums in another order, which greedy choices can
follow).
"""

from __future__ import annotations

import threading
from concurrent.futures import ThreadPoolExecutor

_local = threading.local()
_pools: dict[int, ThreadPoolExecutor] = {}
_lock = threading.Lock()


def n_threads() -> int:
    """Threads a ``thread_map`` called here would use (1 inside another ``thread_map``'s task)."""
    if getattr(_local, "inside", False):
        return 1
    import numba

    return max(1, int(numba.get_num_threads()))


def _pool(k: int) -> ThreadPoolExecutor:
    with _lock:
        if k not in _pools:
            _pools[k] = ThreadPoolExecutor(k, thread_name_prefix="shapecond")
        return _pools[k]


def _inside(f, x):
    _local.inside = True
    try:
        return f(x)
    finally:
        _local.inside = False


def thread_map(f, items) -> list:
    """``[f(x) for x in items]``, computed by up to ``n_threads()`` threads; exceptions propagate."""
    items = list(items)
    k = min(n_threads(), len(items))
    if k <= 1:
        return [f(x) for x in items]
    return list(_pool(k).map(lambda x: _inside(f, x), items))


def one_blas_thread():
    """Context manager limiting BLAS to one thread (threadpoolctl).

    The small dense products of the searches and of ARPACK lose time to BLAS
    threads, and thrash when the cores are shared (20x measured with ARPACK).
    """
    from threadpoolctl import threadpool_limits

    return threadpool_limits(limits=1, user_api="blas")


def single_blas_thread(f):
    """Decorator: run ``f`` with BLAS limited to one thread (``one_blas_thread``).

    Besides speed, this makes results independent of the thread count: a
    threaded matrix product sums in another order, and the greedy choices of
    CNBS follow near-ties of such sums (TOSCA wolf0, N = 400: the second CNBS
    landmark was sample 171 with one BLAS thread and 304 with two).
    """
    import functools

    @functools.wraps(f)
    def wrapped(*args, **kwargs):
        with one_blas_thread():
            return f(*args, **kwargs)

    return wrapped
