"""Run independent tasks on local cores or a Dask cluster, results in task order.

(Over 600 lines, one job: both executors behind :func:`run_tasks` share its chunking, its
fall-back to one task at a time and its delivery in task order; about half the lines are the
Dask path -- bundles, a quiet cluster, the waits that end -- and this docstring's measured
costs of it, which would move to a module of their own beside the pool when it grows.)

One entry point, :func:`run_tasks`, used by the runner, the stress test and the benchmarks::

    results = run_tasks(simulate_one, tasks)                       # all local cores
    results = run_tasks(simulate_one, tasks, workers=1)            # inline, no pool
    results = run_tasks(simulate_one, tasks, executor="dask")      # a LocalCluster for the run
    results = run_tasks(simulate_one, tasks, executor="dask", scheduler="tcp://host:8786")
    results = run_tasks(simulate_one, tasks, batch=simulate_many, group=engine_and_settings)

Determinism
    The results come back in the order of ``tasks`` whatever worker ran them or when it
    finished. Each call is independent (the engine adapters clear per-run state), so a
    task's result does not depend on which worker ran it nor on what it ran before: the
    local pool, inline execution and a Dask cluster give bit-identical results, and so do a
    ``batch`` call and one ``function`` call per task (the tests check this).

Chunks
    Tasks travel in chunks: one pool submission, one Dask future, and with ``batch`` one
    ``batch(chunk)`` call (the runner's :func:`harness.run.tasks.engine_chunk`, one
    ``Engine.run_many``) per chunk; ``group(task)`` keeps tasks of different keys (engine,
    settings) apart. Results are still delivered task by task (``on_result``) as each chunk
    finishes, so a kill loses at most the chunks under way. When ``batch`` raises, the
    chunk's tasks run one by one through ``function``: a task that raises or overruns costs
    only itself, and the exception of a task that raises there is re-raised once the chunk's
    other results are delivered.

    The size (:func:`chunk_size_for`): at least :data:`CHUNKS_PER_WORKER` chunks per worker,
    at most :data:`MAX_CHUNK` tasks. Measured on the 2-core machine (under load, medians of
    5): 1,000 pymunk engine tasks inline take 0.62 s one ``run`` each, 0.55 / 0.46 / 0.50 /
    0.36 / 0.37 / 0.36 / 0.44 s in chunks of 4 / 8 / 16 / 32 / 64 / 128 / 256 (pymunk puts 32
    impacts in a space); 2,000 mixed engine tasks (the four engines, both presets) show no
    difference between 8 and 128 within the noise (about ±30%).

Dask
    One graph of futures, each carrying a bundle of consecutive chunks (:class:`DaskChunk`,
    :func:`bundle_sizes`): the first futures large, the last ones single chunks. A local
    cluster's workers are forked on Linux from a fork server (not from this process, whose
    threads could hold a lock the child then waits for), which starts once in ~0.5 s; a
    worker then starts in ~0.16 s against ~0.7 s spawned, and a cluster started for the run stops
    in a background thread once every result is delivered: the caller builds and writes its
    records meanwhile (:func:`wait_for_shutdowns`). A kill loses the bundles under way.

    What a started cluster costs beyond the pool, measured inside one run of 2,000 engine
    tasks on the 2-core machine (under load; CPU seconds are steadier than wall ones there):
    the cluster's start, 0.16-0.43 s of wall time but 0.05-0.1 s of CPU (waiting for the
    forked workers to register); its shutdown, 0.1-0.3 s, after the run; then CPU taken from
    the cores the workers compute on. That was once 1.2-1.5 s of CPU more than the pool
    (3.1-3.6 s against 1.9-2.1 s): submitting 32 chunks one by one, 0.2-1.2 s, was Dask
    walking every task's scene for futures inside (a :class:`DaskChunk` is not walked:
    0.03-0.07 s now); each worker's event loop took 0.3 s of CPU beside 0.75 s of engine
    runs (a stack sampler every 10 ms, event-loop ticks every 20 ms in all five servers,
    /proc read every 0.5 s, a recursive size estimate of every result:
    :data:`QUIET_CLUSTER_CONFIG`, :func:`call_dask_chunk`). Then 0.3-0.45 s of CPU more than
    the pool (0.7-0.9 s on a machine loaded 20 by other jobs), most of it per future: each
    costs about 8 ms of CPU (4 ms in the main process's
    event loop, scheduler and client, 4 ms in a worker's), against 2-120 ms for a chunk of
    engine runs and 25 ms for a several-contact reference, a chunk of its own. One future
    per chunk, the run of the 114 files of ``bench --executors`` (32 chunks of engine runs,
    56 references) spent 0.66-0.74 s of CPU in the main process's event loop and 0.3 s in
    each worker's; bundled (16 futures), 0.30-0.31 s and 0.15 s. Shortening the clusters'
    other periodic work (memory monitors every second instead of 100 ms, no work stealing,
    no HTTP routes) changed nothing measurable. 2,000 engine tasks in one process, three
    alternations under load 20: Dask's CPU 1.40-1.46 times the pool's with a future per
    chunk, 1.18-1.35 bundled (``impact-harness bench --executors`` gives the wall-time
    ratios; README). Hence :data:`DASK_MIN_TASKS`: below it the local executor runs
    the tasks (``note`` says so). A fresh ``impact-harness run --executor dask`` pays also
    for importing dask.distributed (0.3 s of CPU, 0.3-0.5 s of wall time on a quiet
    machine), which the local pool never imports; a run kept on the pool does not import it
    (:func:`check_arguments` only looks it up).

Time limits and waits
    The local pool is a :class:`harness.processes.StoppablePool`: a chunk over its time
    limit (``time_limit``) is stopped by ending its worker process, a worker that dies costs
    its chunk only, and its workers end with this process. No wait has no end: the pool
    looks at its workers at least every second; a Dask run looks at its futures every
    :data:`DASK_POLL_S` and stops (:class:`DaskRunFailed`) when a cluster started for it has
    had no worker for :data:`NO_WORKER_TIMEOUT_S` or no result came for longer than the
    bundles' time limits allow (:data:`STALL_MARGIN_S` beyond them); closing a client or a
    cluster takes at most :data:`CLOSE_TIMEOUT_S` each.

``function`` and ``batch`` must be top-level (picklable) functions and each task picklable
(plain dicts, tuples, numbers, strings, dataclasses of those); on the local pool, forked,
``function`` is inherited rather than pickled.
"""

from __future__ import annotations

import functools
import logging
import math
import re
import sys
import threading
from typing import Any, Callable, Hashable, Iterable, Sequence

from harness.processes import JobStopped, StoppablePool, default_workers, one_blas_thread

EXECUTORS: tuple[str, ...] = ("local", "dask")

DASK_INSTALL_HINT = 'pip install -e ".[dask]"'
#: Seconds to wait for a Dask scheduler before giving up with a one-line error.
CONNECT_TIMEOUT_S = 10.0
#: Fewest tasks :func:`run_tasks` sends to Dask; fewer run on the local pool (or inline): a
#: started cluster costs CPU beyond the pool's whatever the number of tasks (its start, its
#: loops, ~8 ms per future): 1.5 times the pool's CPU at 1,000 engine tasks and 1.4 at 2,000
#: with a future per chunk; bundled, 1.2-1.35 at 2,000 (under load; the module doc). Two
#: runs at 1,000 (0.94 and 1.02) are too few, on a machine that loaded, to lower it.
DASK_MIN_TASKS = 2000


#: Seconds a Dask cluster may have no worker before the run stops (its workers died and
#: were not restarted: the futures would wait for one forever).
NO_WORKER_TIMEOUT_S = 60.0
#: Seconds beyond a bundle's own time limits (the sum of its chunks') that the run waits
#: for any result before it stops: room for a worker's restart and the cluster's queue.
STALL_MARGIN_S = 60.0
#: Seconds between two looks at a Dask run's finished futures and at its cluster's health.
DASK_POLL_S = 0.02
#: Seconds a client's or a started cluster's close may take.
CLOSE_TIMEOUT_S = 30.0


class DaskNotInstalled(ImportError):
    """``executor="dask"`` was asked for but dask.distributed cannot be imported."""


class DaskRunFailed(ConnectionError):
    """A Dask run stopped waiting: its cluster has no worker left, or no result came for
    longer than any bundle's time limits allow (one line: what, and how long)."""


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
    if scheduler is not None and not _SCHEDULER_ADDRESS.fullmatch(scheduler):
        raise ValueError(f"--scheduler {scheduler[:100]!r}: not a scheduler's address; "
                         "allowed: [tcp://|tls://]HOST:PORT, e.g. tcp://host:8786")
    if scheduler is not None and not 1 <= int(scheduler.rpartition(":")[2]) <= 65535:
        raise ValueError(f"--scheduler {scheduler!r}: the port is not 1 to 65535")
    if executor == "dask":
        _require_distributed()


#: A Dask scheduler's address as --scheduler takes it: a protocol, a host name or address
#: (an IPv6 one in brackets) and a port.
_SCHEDULER_ADDRESS = re.compile(
    r"(?:(?:tcp|tls|ucx|ws|wss)://)?(?:\[[0-9A-Fa-f:.]+\]|[A-Za-z0-9][A-Za-z0-9.\-_]{0,252}):"
    r"[0-9]{1,5}")


def run_tasks(
    function: Callable[[Any], Any],
    tasks: Iterable[Any],
    executor: str = "local",
    workers: int | None = None,
    scheduler: str | None = None,
    progress: Callable[[int, int], None] | None = None,
    on_result: Callable[[int, Any], None] | None = None,
    *,
    batch: Callable[[list], list] | None = None,
    group: Callable[[Any], Hashable] | None = None,
    chunk_size: int | None = None,
    dask_min_tasks: int = DASK_MIN_TASKS,
    note: Callable[[str], None] | None = None,
    time_limit: Callable[[Any], float | None] | None = None,
    stopped: Callable[[Any, str], Any] | None = None,
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
        started for the run and shut down in the background once every result is delivered
        (:func:`wait_for_shutdowns`). Below ``dask_min_tasks`` tasks, without a
        ``scheduler``, the local executor runs them instead (``note`` says so); a named
        scheduler gets every run.
    workers
        Local worker processes (``None``: all local cores). Ignored with ``scheduler``.
    scheduler
        Address of a running Dask scheduler (``"tcp://host:8786"``); only with ``"dask"``.
    progress
        Called as ``progress(done, total)`` after each finished chunk (and once with
        ``(0, total)`` at the start).
    on_result
        Called as ``on_result(index, result)`` in this process for every task of a chunk as
        soon as the chunk finishes (the runner stores it in the cache then, so a kill loses
        only unfinished chunks).
    batch
        A top-level, picklable function of a list of tasks returning ``[function(task) for
        task in chunk]`` faster (the runner's :meth:`Engine.run_many`). Chunks are then
        dispatched whole: one ``batch`` call each, also inline. When ``batch`` raises, the
        chunk's tasks run one by one through ``function``, so one bad task costs only itself.
    group
        ``group(task)``: tasks with different keys never share a chunk (the runner: engine
        and settings, one ``run_many`` call per chunk). Called in this process only.
    chunk_size
        Tasks per chunk (default :func:`chunk_size_for`).
    dask_min_tasks
        Fewest tasks sent to Dask (default :data:`DASK_MIN_TASKS`).
    note
        Called with a one-line remark on how the tasks ran (the local pool in place of Dask).
    time_limit
        ``time_limit(task)``: the seconds a task may run (None: no limit); a chunk has its
        first task's limit as a whole (``group`` keeps tasks of different limits apart). On
        the local executor a chunk over its limit is stopped by ending its worker process
        (:class:`harness.processes.StoppablePool`; with a limit, even ``workers == 1`` runs
        in a child process, since a signal never interrupts an engine's step in C); its
        tasks then run again one per chunk, each with its own limit. Dask workers are not
        stopped.
    stopped
        ``stopped(task, reason)``: the result of a task stopped alone, over its limit
        (``reason``: ``"time limit: stopped after 5 s"``) or because its worker died; the
        run goes on. Without it such a task raises :class:`harness.processes.JobStopped`
        as a task that raises does.

    Raises
    ------
    ValueError
        Unknown executor, ``workers < 1``, or a scheduler given to the local executor.
    ConnectionError
        The Dask scheduler cannot be reached.
    DaskNotInstalled
        ``executor="dask"`` without dask.distributed installed.
    Exception
        An exception raised by ``function`` is re-raised once the rest of its chunk has run
        and been delivered to ``on_result`` (the other chunks are cancelled).
    """
    if executor not in EXECUTORS:
        raise ValueError(f"unknown executor {executor!r}; allowed: {list(EXECUTORS)}")
    if workers is not None and (
        isinstance(workers, bool) or int(workers) != workers or workers < 1
    ):
        raise ValueError(f"workers must be a positive integer or None, got {workers!r}")
    if scheduler is not None and executor != "dask":
        raise ValueError("a scheduler address needs executor='dask'")
    if chunk_size is not None and (isinstance(chunk_size, bool) or int(chunk_size) != chunk_size
                                   or chunk_size < 1):
        raise ValueError(f"chunk_size must be a positive integer or None, got {chunk_size!r}")
    task_list = list(tasks)
    total = len(task_list)
    if progress is not None:
        progress(0, total)
    if executor == "dask":
        _require_distributed()  # asked for: missing is an error even for a run kept local
    # The threshold weighs a cluster's start against the pool's: a running cluster the user
    # named (perhaps far larger than this machine) gets the runs whatever their number.
    if executor == "dask" and scheduler is None and total < dask_min_tasks:
        if note is not None:
            note(f"executor dask: {total} tasks, fewer than {dask_min_tasks}: run on the local "
                 "pool, whose start costs less than a cluster's")
        executor, scheduler = "local", None
    if executor == "dask":
        n_workers = workers or default_workers()
    else:
        n_workers = min(workers or default_workers(), max(total, 1))
        if total <= 1:
            n_workers = 1
    if n_workers == 1 and executor == "local" and batch is None:
        chunks = [[index] for index in range(total)]  # nothing to amortise: one at a time
    else:
        size = chunk_size or chunk_size_for(total, n_workers, batched=batch is not None)
        chunks = make_chunks(task_list, size, group)
    limited = time_limit is not None and any(time_limit(task) is not None for task in task_list)
    run = (functools.partial(_run_dask, limit_of=time_limit) if executor == "dask" else
           _run_inline if n_workers == 1 and not limited else
           functools.partial(_run_pool, limit_of=time_limit, stopped=stopped))
    results: list[Any] = [None] * total
    delivered = [0]

    def deliver(chunk: list[int], outputs: list, failure) -> None:
        for position, index in enumerate(chunk):
            if failure is not None and position == failure[0]:
                continue
            results[index] = outputs[position]
            if on_result is not None:
                on_result(index, outputs[position])
        delivered[0] += len(chunk)
        if progress is not None:
            progress(delivered[0], total)
        if failure is not None:
            raise failure[1]

    extra = (scheduler,) if executor == "dask" else ()
    run(function, batch, task_list, chunks, n_workers, deliver, *extra)
    return results


#: Most tasks in one chunk. A chunk is one ``Engine.run_many`` call (pymunk puts 32 ground
#: impacts in a space) and, for the pool or Dask, one round trip; beyond 32-64 the measured
#: wall time no longer falls (see the module doc) while a kill loses a larger chunk.
MAX_CHUNK = 64
#: Chunks per worker at least, when there are enough tasks: keeps both cores busy to the end.
CHUNKS_PER_WORKER = 4


def chunk_size_for(total: int, workers: int, batched: bool = True) -> int:
    """Tasks per chunk: :data:`CHUNKS_PER_WORKER` chunks per worker or more, at most
    :data:`MAX_CHUNK` tasks each (without ``batched``, the pool's former ``total // (8 ×
    workers)``, which only amortises pickling and so has no cap)."""
    if not batched:
        return max(1, total // (workers * 8))
    return max(1, min(MAX_CHUNK, math.ceil(total / (workers * CHUNKS_PER_WORKER))))


def make_chunks(tasks: Sequence, size: int,
                group: Callable[[Any], Hashable] | None = None) -> list[list[int]]:
    """Task indices in chunks of at most ``size``, tasks of one ``group`` key together (in
    order of first appearance), each chunk's indices increasing."""
    members: dict[Hashable, list[int]] = {}
    for index, task in enumerate(tasks):
        members.setdefault(None if group is None else group(task), []).append(index)
    return [indices[start:start + size] for indices in members.values()
            for start in range(0, len(indices), size)]


def call_chunk(function, batch, chunk: Sequence) -> tuple[list, tuple[int, Exception] | None]:
    """``(results, failure)`` of one chunk, in the process that runs it.

    ``batch(chunk)`` when given; when it raises, or without it, ``function`` of each task.
    ``failure`` is ``(position, exception)`` of the first task that raised (its result is
    ``None``); the chunk's other tasks still run, so their results are kept.
    """
    if batch is not None and len(chunk) > 1:
        try:
            results = batch(list(chunk))
        except Exception:  # noqa: BLE001 - one by one below names the failing task
            results = None
        if results is not None and len(results) == len(chunk):
            return list(results), None
    results, failure = [], None
    for position, task in enumerate(chunk):
        try:
            results.append(function(task))
        except Exception as error:  # noqa: BLE001 - re-raised in the caller's process
            results.append(None)
            if failure is None:
                failure = (position, error)
    return results, failure


def _run_inline(function, batch, tasks: Sequence, chunks, workers, deliver) -> None:
    for chunk in chunks:
        deliver(chunk, *call_chunk(function, batch, [tasks[index] for index in chunk]))


def _run_pool(function, batch, tasks: Sequence, chunks, workers: int, deliver, *,
              limit_of=None, stopped=None) -> None:
    """The chunks on a :class:`StoppablePool` of ``workers`` processes. A chunk of several
    tasks stopped (over its limit, or its worker died) runs again task by task, each with its
    own limit, so that only the task at fault is stopped; a task stopped alone gets
    ``stopped(task, reason)`` (or raises :class:`JobStopped`)."""
    job = functools.partial(call_chunk, function, batch)
    with StoppablePool(job, workers) as pool:
        round_chunks = list(chunks)
        while round_chunks:
            again: list[list[int]] = []
            limits = [None if limit_of is None else limit_of(tasks[chunk[0]])
                      for chunk in round_chunks]
            arguments = [[tasks[index] for index in chunk] for chunk in round_chunks]
            for position, (kind, value) in pool.run(arguments, limits):
                chunk = round_chunks[position]
                if kind == "result":
                    deliver(chunk, *value)
                elif kind == "error":  # not a task's own exception (call_chunk keeps those)
                    raise value
                elif len(chunk) > 1:
                    again += [[index] for index in chunk]
                elif stopped is not None:
                    deliver(chunk, [stopped(tasks[chunk[0]], value)], None)
                else:
                    deliver(chunk, [None], (0, JobStopped(value)))
            round_chunks = again


def _require_distributed() -> None:
    """Raise :class:`DaskNotInstalled` unless dask.distributed is installed, without importing
    it: the import costs 0.3-0.5 s of CPU (measured on the 2-core machine), which a command
    whose run stays on the local pool (fewer than :data:`DASK_MIN_TASKS` tasks) need not pay.
    A broken installation fails at the import, when a run goes to Dask."""
    import importlib.util

    for name in ("dask", "distributed"):
        if name in sys.modules:
            found = sys.modules[name] is not None  # None: an import known to fail
        else:
            found = importlib.util.find_spec(name) is not None
        if not found:
            raise DaskNotInstalled(f"executor 'dask' needs dask.distributed (no module named "
                                   f"{name!r}); install it with `{DASK_INSTALL_HINT}`")


def _import_distributed():
    try:
        import distributed  # noqa: F401
        from distributed import Client, LocalCluster, as_completed
    except ImportError as error:
        if (error.name or "").partition(".")[0] not in ("dask", "distributed"):
            raise  # installed, but something it imports fails: its own error says what
        raise DaskNotInstalled(
            f"executor 'dask' needs dask.distributed ({error}); "
            f"install it with `{DASK_INSTALL_HINT}`"
        ) from error
    return Client, LocalCluster, as_completed


class HeartbeatAfterClose(logging.Filter):
    """Drops the one log record of Dask's shutdown race, nothing else.

    A closing ``LocalCluster`` stops its scheduler first; a worker whose periodic heartbeat
    falls in the moment before its own close order arrives logs "Failed to communicate with
    scheduler during heartbeat" at ERROR, with a ``CommClosedError`` traceback (about one
    close in six on the 2-core machine; a known Dask race, not a fault of the run: every
    result was delivered by then). A scheduler lost in the middle of a run still fails the
    run through the client, so hiding this record hides no lost result.
    """

    MESSAGE = "Failed to communicate with scheduler during heartbeat"

    def filter(self, record: logging.LogRecord) -> bool:
        error = record.exc_info[1] if record.exc_info else None
        return not (record.getMessage().startswith(self.MESSAGE)
                    and type(error).__name__ == "CommClosedError")


def _quiet_heartbeat_race() -> None:
    """Install :class:`HeartbeatAfterClose` once on Dask's worker logger (here, and in each
    worker of a cluster started here, through :func:`dask_setup`)."""
    worker_log = logging.getLogger("distributed.worker")
    if not any(isinstance(one, HeartbeatAfterClose) for one in worker_log.filters):
        worker_log.addFilter(HeartbeatAfterClose())


#: Dask settings of a cluster :func:`start_local_cluster` starts: its periodic
#: bookkeeping, which feeds the dashboard (not started) and costs CPU for every second the
#: cluster runs, on the two cores its workers compute on. Each worker's event loop sampled
#: the computing thread's stack every 10 ms (the profiler) and every one of the five servers
#: (scheduler, two nannies, two workers) measured its loop every 20 ms and read /proc every
#: 0.5 s (the system monitor): measured on 2,000 engine tasks, each worker's event loop took
#: 0.3 s of CPU beside 0.75 s of engine runs. The memory monitor (which would stop a worker
#: running out of memory) is kept, and a loop blocked longer than Dask's limit (3 s) is still
#: reported.
QUIET_CLUSTER_CONFIG = {"distributed.worker.profile.enabled": False,
                        "distributed.admin.tick.interval": "500ms",
                        "distributed.admin.system-monitor.interval": "5s"}


def dask_setup(worker) -> None:
    """Dask's preload hook, run in each worker of a cluster :func:`start_local_cluster`
    starts (its ``preload`` names this module): the worker's logger gets the filter."""
    _quiet_heartbeat_race()


#: Seconds a local cluster's worker may take to start before the start fails with an error
#: (normally ~0.2 s); also how long a worker outlives a lost scheduler.
WORKER_START_TIMEOUT_S = 60.0

#: Modules the fork server imports once, so that each worker forked from it has them.
FORKSERVER_PRELOAD = ["distributed", "harness.run.executor"]


@functools.cache
def _forkserver_context():
    """Dask's multiprocessing context for ``forkserver``, its server told to import
    :data:`FORKSERVER_PRELOAD` (once per process: the server starts with the first worker)."""
    import dask
    from distributed.utils import get_mp_context

    with dask.config.set({"distributed.worker.multiprocessing-method": "forkserver"}):
        context = get_mp_context()
    context.set_forkserver_preload(FORKSERVER_PRELOAD)
    return context


def start_local_cluster(workers: int):
    """A ``LocalCluster`` of ``workers`` single-threaded worker processes on loopback, as
    :func:`run_tasks` starts for a run (the caller closes it)."""
    _, LocalCluster, _ = _import_distributed()
    import dask

    _quiet_heartbeat_race()

    # Workers forked from a fork server on Linux, not from this process: this process has
    # threads (Dask's event loop, a previous cluster still closing), and a child forked
    # while one of them held a lock may never start; in CI one of two workers never
    # registered, and the run waited until the test's 180 s limit. The server is a
    # single-threaded process started once (measured: the first cluster 0.7 s, later ones
    # 0.16 s, against 0.12-0.18 s forked and 0.6-0.9 s spawned).
    if sys.platform.startswith("linux"):
        _forkserver_context()
        method = "forkserver"
    else:
        method = dask.config.get("distributed.worker.multiprocessing-method")
    with dask.config.set({"distributed.worker.multiprocessing-method": method,
                          **QUIET_CLUSTER_CONFIG}):
        # No dashboard; the scheduler's HTTP routes (health, metrics) on a free port rather
        # than 8787, which another cluster may hold (Dask then warns). death_timeout: a
        # worker that does not start in time fails the start ("Nanny failed to start")
        # instead of leaving it waiting.
        return LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                            host="127.0.0.1", dashboard_address=None,
                            scheduler_kwargs={"dashboard_address": ":0"},
                            death_timeout=WORKER_START_TIMEOUT_S,
                            preload=[__name__])


class DaskChunk:
    """Chunks as one Dask task's single argument (a bundle, :func:`bundle_sizes`), their
    tasks kept opaque.

    Dask walks every list, tuple and dict argument of a submitted task, to the last number,
    looking for futures inside (``dask._task_spec.parse_input``): measured on 2,000 engine
    tasks (32 chunks of scenes and settings), 0.3-0.7 s of the main process before the
    last chunk was on its way, while the workers it competes with for the two cores ran
    the first ones. An object of this class is not walked; it pickles as its fields.
    """

    __slots__ = ("function", "batch", "chunks")

    def __init__(self, function, batch, chunks: list[list]) -> None:
        self.function, self.batch, self.chunks = function, batch, chunks

    def __reduce__(self):
        return DaskChunk, (self.function, self.batch, self.chunks)


#: A Dask future's first bundle holds 1 / (this × the cluster's threads) of the chunks (see
#: :func:`bundle_sizes`).
BUNDLE_DIVISOR = 2


def bundle_sizes(chunks: int, threads: int) -> list[int]:
    """How many consecutive chunks each Dask future carries: each takes ``1 / (BUNDLE_DIVISOR
    × threads)`` of the chunks not yet given out, at least one (guided self-scheduling), so
    the first futures are large and the last ones single chunks that even out the end.

    A future costs the cluster about 8 ms of CPU whatever it carries (measured on the 2-core
    machine under load: 4 ms in the scheduler's and client's event loop, 4 ms in the
    worker's), against 2-120 ms for a chunk of engine runs and about 25 ms for a
    several-contact reference: one future per chunk (88 for the 114 files of ``bench
    --executors``) cost 0.7 s of CPU; bundled, 16 futures.
    """
    sizes: list[int] = []
    left = chunks
    while left > 0:
        size = max(1, left // (BUNDLE_DIVISOR * max(1, threads)))
        sizes.append(size)
        left -= size
    return sizes


def call_dask_chunk(bundle: DaskChunk) -> bytes:
    """:func:`call_chunk` of each chunk of a :class:`DaskChunk` on a Dask worker (one BLAS
    thread, as the local pool's initializer gives its workers), the list of their ``(results,
    failure)`` pickled as Dask would pickle it.

    Pickled here, in the worker's computing thread: a result that is a list of dicts is
    walked by the worker's event loop to estimate its size (``dask.sizeof``, a recursive
    sample of every nested list and dict; about a tenth of a second per worker for 2,000
    engine outputs, on the two cores the workers compute on); the size of bytes is their
    length. The caller unpickles them (:func:`_unpickle_chunk_result`), as Dask would.
    """
    from distributed.protocol.pickle import dumps

    one_blas_thread()
    return dumps([call_chunk(bundle.function, bundle.batch, tasks) for tasks in bundle.chunks])


def _unpickle_chunk_result(blob: bytes) -> list[tuple[list, tuple[int, Exception] | None]]:
    from distributed.protocol.pickle import loads

    return loads(blob)


def _run_dask(function, batch, tasks: Sequence, chunks, workers, deliver, scheduler, *,
              limit_of=None) -> None:
    Client, _, as_completed = _import_distributed()
    cluster = None
    if scheduler is None:
        cluster = start_local_cluster(workers)
        # Results straight from the workers, not relayed by the scheduler.
        client = Client(cluster, direct_to_workers=True)
    else:
        try:
            client = Client(scheduler, timeout=CONNECT_TIMEOUT_S)
        except (OSError, TimeoutError) as error:
            raise ConnectionError(f"cannot reach the Dask scheduler {scheduler!r} within "
                                  f"{CONNECT_TIMEOUT_S:g} s: {error}") from None
    try:
        if chunks:
            # One future per bundle of chunks, all in one graph (one message to the
            # scheduler, run in the bundles' order: the largest first); pure=False: every
            # bundle is its own key even when two are equal.
            bundles, start = [], 0
            for size in bundle_sizes(len(chunks), _threads(client, workers, cluster)):
                bundles.append(chunks[start:start + size])
                start += size
            futures = client.map(call_dask_chunk, [
                DaskChunk(function, batch, [[tasks[i] for i in chunk] for chunk in bundle])
                for bundle in bundles], pure=False)
            bundle_of = {future.key: bundle for future, bundle in zip(futures, bundles)}
            stall_s = _stall_limit(bundles, tasks, limit_of)
            try:
                # with_results: each result is fetched as its bundle finishes, in the
                # client's event loop, rather than one blocking round trip per bundle.
                completed = as_completed(futures, with_results=True)
                for future, blob in _finished(completed, len(futures), client, cluster,
                                              stall_s):
                    _deliver_bundle(bundle_of[future.key], _unpickle_chunk_result(blob),
                                    deliver)
            except BaseException:
                client.cancel(futures)
                raise
    except BaseException:
        _close(client, cluster)
        raise
    _close_in_background(client, cluster)


def _stall_limit(bundles: list[list[list[int]]], tasks: Sequence, limit_of) -> float | None:
    """Seconds without any result after which a Dask run is stuck: the largest sum of a
    bundle's chunks' time limits (a thread runs a bundle's chunks one after the other) and
    :data:`STALL_MARGIN_S`; None when some chunk has no limit."""
    if limit_of is None:
        return None
    longest = 0.0
    for bundle in bundles:
        limits = [limit_of(tasks[chunk[0]]) for chunk in bundle]
        if any(limit is None for limit in limits):
            return None
        longest = max(longest, sum(limits))
    return longest + STALL_MARGIN_S


def _finished(completed, count: int, client, cluster, stall_s: float | None):
    """``(future, result)`` of each of ``count`` futures of ``completed`` (a Dask
    ``as_completed``), as each finishes, and never a wait without an end: every look waits
    at most :data:`DASK_POLL_S`; :class:`DaskRunFailed` when a cluster started here has had
    no worker for :data:`NO_WORKER_TIMEOUT_S` (its workers died, and their tasks would wait
    for one forever) or no result came for ``stall_s`` seconds (None: no such bound). A
    future that erred raises its error (``KilledWorker`` when its task killed the worker
    each time it ran)."""
    import time

    done = 0
    last_result = time.monotonic()
    workerless_since = None
    while done < count:
        if completed.has_ready():
            item = next(completed)  # ready: no wait; a future that erred raises here
            done += 1
            last_result = time.monotonic()
            yield item
            continue
        now = time.monotonic()
        if stall_s is not None and now - last_result > stall_s:
            raise DaskRunFailed(f"Dask: no result for {stall_s:g} s, longer than any "
                                f"bundle's time limits allow; {done} of {count} bundles "
                                "finished")
        if cluster is not None:
            if cluster.scheduler_info.get("workers"):
                workerless_since = None
            elif workerless_since is None:
                workerless_since = now
            elif now - workerless_since > NO_WORKER_TIMEOUT_S:
                raise DaskRunFailed(f"Dask: the cluster has had no worker for "
                                    f"{NO_WORKER_TIMEOUT_S:g} s; {done} of {count} bundles "
                                    "finished")
        time.sleep(DASK_POLL_S)


def _threads(client, workers: int, cluster) -> int:
    """Tasks the cluster runs at once: ``workers`` for a cluster started here (one thread
    each), else the sum of the connected workers' threads (``workers`` while none is
    connected yet)."""
    if cluster is not None:
        return workers
    return sum(client.nthreads().values()) or workers


def _deliver_bundle(bundle: list[list[int]], outcomes: list, deliver) -> None:
    """Every chunk's results of a finished bundle, then the first task exception among them
    (as :func:`run_tasks` re-raises a chunk's once its other results are delivered)."""
    first_error: BaseException | None = None
    for chunk, (outputs, failure) in zip(bundle, outcomes):
        try:
            deliver(chunk, outputs, failure)
        except Exception as error:  # noqa: BLE001 - re-raised once the bundle is delivered
            if first_error is None:
                first_error = error
    if first_error is not None:
        raise first_error


def _close(client, cluster) -> None:
    """Close the client and a cluster started for the run, each within
    :data:`CLOSE_TIMEOUT_S` (a close that overruns is given up, with a warning)."""
    for closing in (client, cluster):
        if closing is None:
            continue
        try:
            closing.close(timeout=CLOSE_TIMEOUT_S)
        except (TimeoutError, OSError) as error:
            logging.getLogger(__name__).warning("Dask: closing %s: %s", type(closing).__name__,
                                                error)


#: Clusters being shut down after their run delivered every result (see
#: :func:`_close_in_background`).
_CLOSING: list[threading.Thread] = []


def _close_in_background(client, cluster) -> None:
    """Shut a finished run's client (and the cluster started for it) down in a thread.

    Every result is delivered by then; a local cluster takes about 0.3 s to stop, which the
    caller spends building and writing its records instead of waiting. The thread is not a
    daemon: the interpreter waits for it before exiting, so no worker outlives the command.
    :func:`wait_for_shutdowns` waits for it sooner.
    """
    thread = threading.Thread(target=_close, args=(client, cluster), name="dask-shutdown")
    thread.start()
    _CLOSING.append(thread)


def wait_for_shutdowns() -> None:
    """Return once every cluster :func:`run_tasks` started has stopped (each close is
    bounded: :data:`CLOSE_TIMEOUT_S` for the client and for the cluster)."""
    while _CLOSING:
        _CLOSING.pop().join(timeout=3 * CLOSE_TIMEOUT_S)


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


__all__ = ["CONNECT_TIMEOUT_S", "DASK_MIN_TASKS", "EXECUTORS", "MAX_CHUNK", "DaskChunk",
           "DaskNotInstalled", "DaskRunFailed", "HeartbeatAfterClose", "call_chunk",
           "call_dask_chunk", "check_arguments", "chunk_size_for", "make_chunks",
           "progress_printer", "run_tasks", "start_local_cluster", "wait_for_shutdowns"]
