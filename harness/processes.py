"""Work on this machine's cores in forked processes: how many there are, a worker's BLAS
kept to one thread, workers that end when their parent dies, ``map`` over forked workers that
inherit this process's memory, and a pool whose jobs have time limits that hold
(:class:`StoppablePool`: a job over its limit is stopped by ending its worker).

Shared by the run side (the local executor's pool, the records built on forked workers), the
scenario checks, the survey and the report, which must not depend on each other for it.
"""

from __future__ import annotations

import collections
import ctypes
import functools
import multiprocessing
import multiprocessing.connection
import os
import signal
import sys
import threading
import time
from concurrent.futures import ProcessPoolExecutor
from typing import Any, Callable, Iterator, Sequence


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


#: Linux's ``prctl`` option asking for a signal when the parent dies (``<linux/prctl.h>``).
PR_SET_PDEATHSIG = 1
#: How often (s) a worker's watchdog checks that its parent still lives, where the kernel
#: cannot be asked to end it (not Linux) or the request failed.
PARENT_WATCH_S = 0.5


def end_with_parent() -> None:
    """End this worker process when its parent dies (a ``run`` or ``survey`` killed with
    SIGKILL leaves no worker behind, computing for nobody).

    On Linux the kernel sends the worker SIGKILL when the parent dies
    (``prctl(PR_SET_PDEATHSIG)``); everywhere a daemon thread also checks every
    :data:`PARENT_WATCH_S` s that the parent is still this process's parent and ends the
    worker otherwise (the fallback, and the case of a parent dead before the request). A
    no-op in a process that is not a multiprocessing child."""
    parent = multiprocessing.parent_process()
    if parent is None or parent.pid is None:
        return
    if sys.platform.startswith("linux"):
        try:
            libc = ctypes.CDLL(None, use_errno=True)
            libc.prctl(PR_SET_PDEATHSIG, signal.SIGKILL, 0, 0, 0)
        except (OSError, AttributeError):  # pragma: no cover - the watchdog below remains
            pass
    if os.getppid() != parent.pid:  # died before the request took effect
        os._exit(1)

    def watch(parent_pid: int) -> None:
        while True:
            time.sleep(PARENT_WATCH_S)
            if os.getppid() != parent_pid:
                os._exit(1)

    threading.Thread(target=watch, args=(parent.pid,), name="parent-watch", daemon=True).start()


def start_worker() -> None:
    """The initializer of every worker process of the harness's pools: ends with its parent
    (:func:`end_with_parent`), one BLAS thread (:func:`one_blas_thread`)."""
    end_with_parent()
    one_blas_thread.cache_clear()  # a parent's call (a no-op there) is inherited by a fork
    one_blas_thread()


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
                               initializer=start_worker)
    futures = [pool.submit(function, item) for item in items]

    def results() -> list:
        try:
            return [future.result() for future in futures]
        finally:
            pool.shutdown(cancel_futures=True)

    return results


class JobStopped(Exception):
    """A job of a :class:`StoppablePool` did not finish: over its time limit, or its worker
    died; ``reason`` says which (``"time limit: stopped after 5 s"``)."""

    def __init__(self, reason: str) -> None:
        super().__init__(reason)
        self.reason = reason


#: Longest single wait (s) of :meth:`StoppablePool.run` for a message, between checks of
#: the deadlines and of the workers' lives.
POLL_S = 1.0


class StoppablePool:
    """Worker processes that run one job at a time each, where a job that outlives its time
    limit is stopped by ending its worker (SIGKILL) and a fresh worker takes the place.

    A time limit inside the worker (``SIGALRM``) is never seen while an engine runs its
    step in C; ending the process always works. Workers are forked where fork exists (they
    inherit the engines already imported, as the local pool's did), started by
    :func:`start_worker` (they end with this process), and ended when the pool closes::

        with StoppablePool(function, 2) as pool:
            for index, outcome in pool.run(arguments, limits):
                ...  # ("result", value), ("error", exception) or ("stopped", reason)

    Each argument and result must be picklable (plain data). With fork, ``function`` is
    inherited by the workers, never pickled (it may be a closure), as is what it reads.
    """

    def __init__(self, function: Callable[[Any], Any], workers: int) -> None:
        self.function = function
        self.size = max(1, int(workers))
        methods = multiprocessing.get_all_start_methods()
        self.context = multiprocessing.get_context("fork" if "fork" in methods else None)
        self.idle: list[tuple] = []  # (process, connection) waiting for a job
        self.all: list[tuple] = []

    def __enter__(self) -> StoppablePool:
        return self

    def __exit__(self, *exc_info) -> None:
        self.close()

    def _start(self) -> tuple:
        ours, theirs = self.context.Pipe(duplex=True)
        process = self.context.Process(target=_serve_jobs, args=(self.function, theirs),
                                       daemon=True,
                                       name="harness-worker")
        process.start()
        theirs.close()
        worker = (process, ours)
        self.all.append(worker)
        return worker

    def _end(self, worker: tuple) -> None:
        process, connection = worker
        if process.is_alive():
            process.kill()
        process.join(timeout=5)
        connection.close()
        if worker in self.all:
            self.all.remove(worker)

    def close(self) -> None:
        """End every worker (a job under way is lost)."""
        for worker in list(self.all):
            process, connection = worker
            try:
                connection.send(None)  # asks an idle worker to return
            except OSError:
                pass
        for worker in list(self.all):
            worker[0].join(timeout=0.5)
            self._end(worker)
        self.idle.clear()

    def run(self, arguments: Sequence,
            limits: Sequence[float | None] | None = None) -> Iterator[tuple[int, tuple]]:
        """``(index, outcome)`` of ``function(arguments[index])`` for every index, as each
        finishes: ``("result", value)``, ``("error", exception)`` (what it raised), or
        ``("stopped", reason)`` when it ran past ``limits[index]`` seconds (None: no limit)
        or its worker died. No wait is longer than :data:`POLL_S`."""
        waiting = collections.deque(range(len(arguments)))
        busy: dict[Any, tuple] = {}  # connection -> (worker, index, deadline)
        while waiting or busy:
            while waiting and (self.idle or len(self.all) < self.size):
                worker = self.idle.pop() if self.idle else self._start()
                index = waiting.popleft()
                limit = None if limits is None else limits[index]
                try:
                    worker[1].send((arguments[index],))
                except (OSError, ValueError) as error:  # died idle, or the job won't pickle
                    self._end(worker)
                    yield index, ("error", error)
                    continue
                deadline = None if limit is None else time.monotonic() + float(limit)
                busy[worker[1]] = (worker, index, deadline, limit)
            if not busy:
                continue
            now = time.monotonic()
            deadlines = [entry[2] for entry in busy.values() if entry[2] is not None]
            timeout = min([POLL_S] + [max(0.0, deadline - now) for deadline in deadlines])
            sentinels = {entry[0][0].sentinel: connection for connection, entry in busy.items()}
            ready = multiprocessing.connection.wait([*busy, *sentinels], timeout=timeout)
            finished = {one for one in ready if one in busy}
            finished |= {sentinels[one] for one in ready if one in sentinels}
            for connection in finished:
                worker, index, _, _ = busy.pop(connection)
                try:
                    outcome = connection.recv()
                except (EOFError, OSError):
                    worker[0].join(timeout=1)
                    code = worker[0].exitcode
                    self._end(worker)
                    yield index, ("stopped", f"worker died (exit code {code})")
                    continue
                self.idle.append(worker)
                yield index, outcome
            now = time.monotonic()
            for connection, (worker, index, deadline, limit) in list(busy.items()):
                if deadline is not None and now >= deadline:
                    del busy[connection]
                    self._end(worker)
                    yield index, ("stopped", f"time limit: stopped after {limit:g} s")


def _serve_jobs(function: Callable[[Any], Any], connection) -> None:
    """A :class:`StoppablePool` worker: ``(argument,)`` in, the outcome of
    ``function(argument)`` out, until ``None`` or the pool's end of the pipe closes."""
    start_worker()
    while True:
        try:
            job = connection.recv()
        except (EOFError, OSError):
            return
        if job is None:
            return
        (argument,) = job
        try:
            outcome = ("result", function(argument))
        except Exception as error:  # noqa: BLE001 - the caller decides
            outcome = ("error", error)
        try:
            connection.send(outcome)
        except Exception as error:  # noqa: BLE001 - a result or exception that won't pickle
            connection.send(("error", RuntimeError(f"{type(error).__name__}: {error}")))


__all__ = ["JobStopped", "StoppablePool", "default_workers", "end_with_parent", "map_forked",
           "one_blas_thread", "start_forked", "start_worker"]
