"""Run independent tasks on local cores or a Dask cluster, results in task order.

One entry point, :func:`run_tasks`, used by the runner, the stress test and the benchmarks::

    results = run_tasks(simulate_one, tasks)                       # all local cores
    results = run_tasks(simulate_one, tasks, workers=1)            # inline, no pool
    results = run_tasks(simulate_one, tasks, executor="dask")      # a LocalCluster for the run
    results = run_tasks(simulate_one, tasks, executor="dask", scheduler="tcp://host:8786")

Determinism
    ``function(task)`` is called exactly once per task and the results come back in the order
    of ``tasks`` whatever worker ran them or when it finished. Each call is independent (the
    engine adapters clear per-run state), so a task's result does not depend on which worker
    ran it nor on what it ran before: the local pool, inline execution and a Dask cluster give
    bit-identical results (the tests check this).

``function`` must be a top-level (picklable) function and each task picklable (plain dicts,
tuples, numbers, strings, dataclasses of those).
"""

from __future__ import annotations

import os
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from typing import Any, Callable, Iterable, Sequence

EXECUTORS: tuple[str, ...] = ("local", "dask")

DASK_INSTALL_HINT = 'pip install -e ".[dask]"'
#: Seconds to wait for a Dask scheduler before giving up with a one-line error.
CONNECT_TIMEOUT_S = 10.0


class DaskNotInstalled(ImportError):
    """``executor="dask"`` was asked for but dask.distributed cannot be imported."""


def default_workers() -> int:
    """Number of local cores this process may use."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # pragma: no cover - not Linux
        return max(1, os.cpu_count() or 1)


def check_arguments(executor: str = "local", workers: int | None = None,
                    scheduler: str | None = None) -> None:
    """Raise ``ValueError`` (or :class:`DaskNotInstalled`) for options :func:`run_tasks` refuses.

    Cheap, and called by the command line before any scenario is read, so a wrong option
    costs a one-line message and no work.
    """
    if executor not in EXECUTORS:
        raise ValueError(f"--executor {executor!r}: unknown; allowed: {', '.join(EXECUTORS)}")
    if workers is not None and (isinstance(workers, bool) or int(workers) != workers
                                or workers < 1):
        raise ValueError(f"--workers {workers!r}: must be a positive integer")
    if scheduler is not None and executor != "dask":
        raise ValueError(f"--scheduler {scheduler!r}: needs --executor dask")
    if executor == "dask":
        _import_distributed()


def run_tasks(
    function: Callable[[Any], Any],
    tasks: Iterable[Any],
    executor: str = "local",
    workers: int | None = None,
    scheduler: str | None = None,
    progress: Callable[[int, int], None] | None = None,
    on_result: Callable[[int, Any], None] | None = None,
) -> list:
    """``[function(task) for task in tasks]``, spread over processes; results in task order.

    Parameters
    ----------
    function
        A top-level, picklable function of one task.
    tasks
        The tasks (picklable).
    executor
        ``"local"``: a process pool over ``workers`` local cores (default: all); runs inline,
        without a pool, when ``workers == 1`` or there is at most one task.
        ``"dask"``: a ``dask.distributed.Client`` connected to ``scheduler`` or, without one, to
        a ``LocalCluster`` of ``workers`` single-threaded worker processes on loopback,
        started for the run and shut down afterwards.
    workers
        Local worker processes (``None``: all local cores). Ignored with ``scheduler``.
    scheduler
        Address of a running Dask scheduler (``"tcp://host:8786"``); only with ``"dask"``.
    progress
        Called as ``progress(done, total)`` after each finished task (and once with
        ``(0, total)`` at the start).
    on_result
        Called as ``on_result(index, result)`` in this process as soon as task ``index``
        finishes (the runner stores it in the cache then, so a kill loses only unfinished
        tasks).

    Raises
    ------
    ValueError
        Unknown executor, ``workers < 1``, or a scheduler given to the local executor.
    ConnectionError
        The Dask scheduler cannot be reached.
    DaskNotInstalled
        ``executor="dask"`` without dask.distributed installed.
    Exception
        An exception raised by ``function`` is re-raised (remaining tasks are cancelled).
    """
    if executor not in EXECUTORS:
        raise ValueError(f"unknown executor {executor!r}; allowed: {list(EXECUTORS)}")
    if workers is not None and (
        isinstance(workers, bool) or int(workers) != workers or workers < 1
    ):
        raise ValueError(f"workers must be a positive integer or None, got {workers!r}")
    if scheduler is not None and executor != "dask":
        raise ValueError("a scheduler address needs executor='dask'")
    task_list = list(tasks)
    total = len(task_list)
    if progress is not None:
        progress(0, total)
    if executor == "dask":
        return _run_dask(function, task_list, workers, scheduler, progress, on_result)
    n_workers = min(workers or default_workers(), max(total, 1))
    if n_workers == 1 or total <= 1:
        return _run_inline(function, task_list, progress, on_result)
    return _run_pool(function, task_list, n_workers, progress, on_result)


def _run_inline(function, tasks: Sequence, progress, on_result=None) -> list:
    results = []
    for index, task in enumerate(tasks):
        results.append(function(task))
        if on_result is not None:
            on_result(index, results[-1])
        if progress is not None:
            progress(index + 1, len(tasks))
    return results


def _chunksize(total: int, workers: int) -> int:
    # A few chunks per worker: amortises pickling of tiny tasks, still balances the load.
    return max(1, total // (workers * 8))


def _call_chunk(function, chunk: Sequence) -> list:
    return [function(task) for task in chunk]


def _run_pool(function, tasks: Sequence, workers: int, progress, on_result=None) -> list:
    total = len(tasks)
    size = _chunksize(total, workers)
    chunks = [tasks[start : start + size] for start in range(0, total, size)]
    results: list[list | None] = [None] * len(chunks)
    done = 0
    with ProcessPoolExecutor(max_workers=workers) as pool:
        futures = {pool.submit(_call_chunk, function, chunk): index
                   for index, chunk in enumerate(chunks)}
        pending = set(futures)
        try:
            while pending:
                finished, pending = wait(pending, return_when=FIRST_COMPLETED)
                for future in finished:
                    index = futures[future]
                    results[index] = future.result()  # re-raises the task's exception
                    if on_result is not None:
                        first = index * size
                        for offset, result in enumerate(results[index]):
                            on_result(first + offset, result)
                    done += len(chunks[index])
                    if progress is not None:
                        progress(done, total)
        except BaseException:
            for future in pending:
                future.cancel()
            raise
    return [result for chunk in results for result in chunk]  # type: ignore[union-attr]


def _import_distributed():
    try:
        import distributed  # noqa: F401
        from distributed import Client, LocalCluster, as_completed
    except ImportError as error:
        raise DaskNotInstalled(
            f"executor 'dask' needs dask.distributed ({error}); "
            f"install it with `{DASK_INSTALL_HINT}`"
        ) from error
    return Client, LocalCluster, as_completed


def _run_dask(function, tasks: Sequence, workers, scheduler, progress, on_result=None) -> list:
    Client, LocalCluster, as_completed = _import_distributed()
    cluster = None
    if scheduler is None:
        cluster = LocalCluster(
            n_workers=workers or default_workers(),
            threads_per_worker=1,
            processes=True,
            host="127.0.0.1",
            dashboard_address=None,
        )
        client = Client(cluster)
    else:
        try:
            client = Client(scheduler, timeout=CONNECT_TIMEOUT_S)
        except (OSError, TimeoutError) as error:
            raise ConnectionError(f"cannot reach the Dask scheduler {scheduler!r} within "
                                  f"{CONNECT_TIMEOUT_S:g} s: {error}") from None
    try:
        total = len(tasks)
        if total == 0:
            return []
        # pure=False: every task is its own key even when two tasks are equal.
        futures = client.map(function, tasks, pure=False)
        index_of = {future.key: index for index, future in enumerate(futures)}
        results: list[Any] = [None] * total
        done = 0
        for future in as_completed(futures):
            index = index_of[future.key]
            results[index] = future.result()
            if on_result is not None:
                on_result(index, results[index])
            done += 1
            if progress is not None:
                progress(done, total)
        return results
    finally:
        client.close()
        if cluster is not None:
            cluster.close()


def progress_printer(label: str, every_s: float = 2.0, stream=None) -> Callable[[int, int], None]:
    """A ``progress`` callback printing ``label: done/total`` at most every ``every_s`` seconds."""
    import sys
    import time

    out = stream or sys.stderr
    last = [0.0]

    def report(done: int, total: int) -> None:
        now = time.monotonic()
        if done == total or now - last[0] >= every_s:
            last[0] = now
            print(f"{label}: {done}/{total}", file=out, flush=True)

    return report


__all__ = ["CONNECT_TIMEOUT_S", "EXECUTORS", "DaskNotInstalled", "check_arguments",
           "default_workers", "progress_printer", "run_tasks"]
