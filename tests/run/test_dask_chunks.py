"""The Dask path's own pieces: the opaque chunk argument, the pickled chunk result and the
quiet settings of a started cluster (the results themselves: test_executor.py)."""

from __future__ import annotations

import pickle

import pytest

from harness.run.executor import (
    QUIET_CLUSTER_CONFIG,
    DaskChunk,
    call_chunk,
    call_dask_chunk,
    start_local_cluster,
)

distributed = pytest.importorskip("distributed",
                                  reason='dask is not installed (pip install -e ".[dask]")')


def square_unless_three(task: int) -> int:
    if task == 3:
        raise RuntimeError("task 3 failed")
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
    chunk = DaskChunk(square_unless_three, None, [{"scene": [LooksLikeAFuture()]}])
    assert parse_input(chunk) is chunk


def test_a_chunk_pickles_as_its_fields():
    chunk = pickle.loads(pickle.dumps(DaskChunk(square_unless_three, None, [1, 2])))
    assert (chunk.function, chunk.batch, chunk.tasks) == (square_unless_three, None, [1, 2])


def test_the_pickled_chunk_result_is_call_chunks():
    from distributed.protocol.pickle import loads

    tasks = [1, 2, 3, 4]
    results, failure = loads(call_dask_chunk(DaskChunk(square_unless_three, None, tasks)))
    expected, expected_failure = call_chunk(square_unless_three, None, tasks)
    assert results == expected == [1, 4, None, 16]
    assert failure[0] == expected_failure[0] == 2
    assert type(failure[1]) is RuntimeError and str(failure[1]) == "task 3 failed"


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
