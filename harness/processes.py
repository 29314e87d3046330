"""Work on this machine's cores in forked processes: how many there are, a worker's BLAS
kept to one thread, and ``map`` over forked workers that inherit this process's memory.

Shared by the run side (the local executor's pool, the records built on forked workers), the
scenario checks, the survey and the report, which must not depend on each other for it.
"""

from __future__ import annotations

import functools
import multiprocessing
import os
from concurrent.futures import ProcessPoolExecutor
from typing import Any, Callable, Sequence


def default_workers() -> int:
    """Number of local cores this process may use."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # pragma: no cover - not Linux
        return max(1, os.cpu_count() or 1)


@functools.cache
def one_blas_thread() -> None:
    """Keep numpy's BLAS to one thread in a worker process (once per process; the main
    process is left alone). The local pools' initializer; tasks that may run on Dask
    workers call it too.

    Each worker is one of ``workers`` processes sharing the cores; a BLAS's own threads
    fight the other workers for them: several-contact references (many small linear-algebra
    calls) once ran no faster on two workers than on one, and twice as fast with one BLAS
    thread each.
    """
    if multiprocessing.parent_process() is None:
        return
    from threadpoolctl import threadpool_limits

    threadpool_limits(1, user_api="blas")


def map_forked(function: Callable[[Any], Any], items: Sequence, workers: int) -> list:
    """``[function(item) for item in items]`` in a pool of ``workers`` forked processes.

    The workers inherit this process's memory, so what ``function`` reads from module state
    set before the call (scenes, figure closures) is never pickled; only ``items`` and the
    results are. Runs inline with one worker, one item, or where fork is unavailable.
    """
    return start_forked(function, items, workers)()


def start_forked(function: Callable[[Any], Any], items: Sequence, workers: int, *,
                 in_background: bool = False) -> Callable[[], list]:
    """:func:`map_forked` started: the workers are forked and at work when this returns, and
    this process may go on; the function returned waits for them and gives the results (it
    runs ``function`` itself, then, where :func:`map_forked` would run inline).
    ``in_background``: fork even one worker for one item, so that this process can do other
    work meanwhile (inline only where fork is unavailable)."""
    items = list(items)
    workers = max(1, workers)
    alone = not in_background and (workers == 1 or len(items) <= 1)
    if alone or not items or "fork" not in multiprocessing.get_all_start_methods():
        return lambda: [function(item) for item in items]
    # With fork, every worker is forked at the first submit, before the pool's own thread
    # starts: what they inherit is this process as it is now.
    pool = ProcessPoolExecutor(max_workers=workers, mp_context=multiprocessing.get_context("fork"),
                               initializer=one_blas_thread)
    futures = [pool.submit(function, item) for item in items]

    def results() -> list:
        try:
            return [future.result() for future in futures]
        finally:
            pool.shutdown(cancel_futures=True)

    return results


__all__ = ["default_workers", "map_forked", "one_blas_thread", "start_forked"]
