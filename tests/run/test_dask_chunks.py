"""The Dask path's own pieces: the opaque bundle of chunks, the bundles' sizes, the pickled
bundle result, a failure inside a bundle or of a worker, and the quiet settings of a started
cluster (the results themselves: test_executor.py)."""

from __future__ import annotations

import os
import pickle
import sys

import pytest

from harness.run.executor import (
    BUNDLE_DIVISOR,
    QUIET_CLUSTER_CONFIG,
    DaskChunk,
    bundle_sizes,
    call_chunk,
    call_dask_chunk,
    run_tasks,
    start_local_cluster,
    wait_for_shutdowns,
)

distributed = pytest.importorskip("distributed",
                                  reason='dask is not installed (pip install -e ".[dask]")')


def square_unless_three(task: int) -> int:
    if task == 3:
        raise RuntimeError("task 3 failed")
    return task * task


def square(task: int) -> int:
    return task * task


class LooksLikeAFuture:
    """What Dask's argument walk turns into a reference to another task's result."""

    __dask_future__ = True
    key = "another-task"


def test_dask_does_not_walk_into_a_chunk():
    from dask._task_spec import GraphNode, parse_input

    # A plain list of tasks is walked to the last item: a future inside is found ...
    assert isinstance(parse_input([{"scene": [LooksLikeAFuture()]}]), GraphNode)
    # ... a chunk is one opaque argument, handed over as it is.
    chunk = DaskChunk(square_unless_three, None, [[{"scene": [LooksLikeAFuture()]}]])
    assert parse_input(chunk) is chunk


def test_a_chunk_pickles_as_its_fields():
    chunk = pickle.loads(pickle.dumps(DaskChunk(square_unless_three, None, [[1, 2], [5]])))
    assert (chunk.function, chunk.batch, chunk.chunks) == (square_unless_three, None,
                                                           [[1, 2], [5]])


def test_the_pickled_bundle_result_is_call_chunk_of_each_chunk():
    from distributed.protocol.pickle import loads

    chunks = [[1, 2, 3, 4], [5, 6]]
    outcomes = loads(call_dask_chunk(DaskChunk(square_unless_three, None, chunks)))
    (results, failure), (other, no_failure) = outcomes
    expected, expected_failure = call_chunk(square_unless_three, None, chunks[0])
    assert results == expected == [1, 4, None, 16]
    assert failure[0] == expected_failure[0] == 2
    assert type(failure[1]) is RuntimeError and str(failure[1]) == "task 3 failed"
    assert other == [25, 36] and no_failure is None


@pytest.mark.parametrize("chunks,threads", [(1, 2), (7, 2), (32, 2), (88, 2), (88, 1), (2000, 8)])
def test_bundles_cover_every_chunk_largest_first_and_end_single(chunks, threads):
    sizes = bundle_sizes(chunks, threads)
    assert sum(sizes) == chunks and min(sizes) >= 1
    assert sizes == sorted(sizes, reverse=True)  # the largest go first, the small even out
    assert sizes[-1] == 1
    # each takes its share of what is left: never more than 1 / (divisor x threads) of it
    left = chunks
    for size in sizes:
        assert size == max(1, left // (BUNDLE_DIVISOR * threads))
        left -= size


def test_bundles_are_far_fewer_than_chunks_on_two_workers():
    # the bench's 114 files: 32 chunks of engine runs and 56 references, one chunk each
    assert len(bundle_sizes(88, 2)) <= 20
    assert len(bundle_sizes(32, 2)) <= 14


def test_a_task_raising_in_a_bundle_delivers_the_bundles_other_results_first():
    delivered = []
    with pytest.raises(RuntimeError, match="task 3"):
        run_tasks(square_unless_three, list(range(40)), executor="dask", workers=2,
                  chunk_size=1, dask_min_tasks=0,
                  on_result=lambda index, result: delivered.append((index, result)))
    wait_for_shutdowns()
    first_bundle = bundle_sizes(40, 2)[0]  # chunks of one task: tasks 0 .. first_bundle - 1
    assert {(i, i * i) for i in range(first_bundle) if i != 3} <= set(delivered)
    assert 3 not in [index for index, _ in delivered]


def test_a_running_cluster_of_ones_own_gives_the_local_pools_results():
    tasks = list(range(30))
    cluster = start_local_cluster(2)
    try:
        delivered = []
        results = run_tasks(square, tasks, executor="dask",
                            scheduler=cluster.scheduler_address, chunk_size=2, dask_min_tasks=0,
                            on_result=lambda index, _: delivered.append(index))
    finally:
        cluster.close()
    assert results == run_tasks(square, tasks, workers=2, chunk_size=2)
    assert sorted(delivered) == tasks


def on_which_worker(task: int) -> str:
    from distributed import get_worker

    return get_worker().address  # raises outside a Dask worker (the local pool, inline)


def test_a_named_scheduler_gets_every_run_however_few():
    cluster = start_local_cluster(2)
    notes = []
    try:
        addresses = run_tasks(on_which_worker, [1, 2, 3], executor="dask",
                              scheduler=cluster.scheduler_address, note=notes.append)
        workers = set(cluster.scheduler_info["workers"])
    finally:
        cluster.close()
    assert notes == []  # the default threshold (2,000 tasks) did not send them to the pool
    assert set(addresses) <= workers and len(addresses) == 3


def kill_the_worker_on_seven(task: int) -> int:
    if task == 7:
        import os

        os._exit(1)  # the worker process dies, as when an engine crashes
    return task * task


def test_a_worker_dying_fails_the_run_without_hanging_and_keeps_finished_results():
    """Dask retries a task whose worker died on another worker (``allowed-failures``, 3 by
    default), each retry killing a worker its nanny must fork again: that restart, a fork of
    a process running threads, now and then never came back, and with both workers gone the
    futures waited for one forever (2 runs in 6 hung). With no retry the first death fails
    the run at once; every wait of the run and of the cluster's close is bounded anyway
    (``NO_WORKER_TIMEOUT_S``, ``CLOSE_TIMEOUT_S``)."""
    import time

    import dask

    delivered = []
    begin = time.monotonic()
    with dask.config.set({"distributed.scheduler.allowed-failures": 0}), \
            pytest.raises(distributed.KilledWorker):
        run_tasks(kill_the_worker_on_seven, list(range(40)), executor="dask", workers=2,
                  chunk_size=1, dask_min_tasks=0,
                  on_result=lambda index, result: delivered.append((index, result)))
    wait_for_shutdowns()
    assert time.monotonic() - begin < 30
    assert all(result == index * index for index, result in delivered)
    assert 7 not in [index for index, _ in delivered]


def sleep_on_three(task: int) -> int:
    if task == 3:
        import time

        time.sleep(60)  # a task far over its limit: Dask workers are not stopped
    return task


def test_a_dask_run_without_any_result_for_longer_than_its_limits_allow_stops(monkeypatch):
    import time

    from harness.run import executor

    monkeypatch.setattr(executor, "STALL_MARGIN_S", 1.0)
    begin = time.monotonic()
    with pytest.raises(executor.DaskRunFailed, match="no result for 1.5 s"):
        run_tasks(sleep_on_three, list(range(4)), executor="dask", workers=1, chunk_size=4,
                  dask_min_tasks=0, time_limit=lambda task: 0.5)
    wait_for_shutdowns()
    assert time.monotonic() - begin < 45  # not the task's 60 s


def test_a_started_cluster_runs_without_the_dashboards_bookkeeping():
    from dask.utils import parse_timedelta

    cluster = start_local_cluster(1)
    try:
        with distributed.Client(cluster) as client:
            callbacks = next(iter(client.run(
                lambda dask_worker: sorted(dask_worker.periodic_callbacks)).values()))
            tick_ms = next(iter(client.run(
                lambda dask_worker: dask_worker.periodic_callbacks["tick"].callback_time
            ).values()))
    finally:
        cluster.close()
    assert "profile" not in callbacks  # the 10 ms stack sampler of the worker's loop
    assert "memory_monitor" in callbacks  # kept: it stops a worker running out of memory
    assert tick_ms == parse_timedelta(QUIET_CLUSTER_CONFIG["distributed.admin.tick.interval"],
                                      default="ms") * 1000


def worker_parent_and_filters() -> tuple[int, list[str]]:
    import logging
    import os

    return os.getppid(), [type(one).__name__
                          for one in logging.getLogger("distributed.worker").filters]


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="the fork server is Linux's")
def test_a_started_clusters_workers_come_from_the_fork_server_with_the_log_filter():
    # Not forked from this process, which has threads (Dask's event loop; in CI a worker
    # forked beside them never started): their parent is the fork server, and the heartbeat
    # filter reaches them through the preload hook, not through inherited memory.
    cluster = start_local_cluster(2)
    try:
        with distributed.Client(cluster) as client:
            seen = client.run(worker_parent_and_filters)
    finally:
        cluster.close()
    assert len(seen) == 2
    for parent, filters in seen.values():
        assert parent != os.getpid()
        assert "HeartbeatAfterClose" in filters
