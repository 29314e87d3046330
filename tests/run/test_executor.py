"""run_tasks: inline, local process pool and a Dask LocalCluster give bit-identical results."""

from __future__ import annotations

import logging
import multiprocessing
import sys

import numpy as np
import pytest

import planar_impact as pi
from harness.processes import start_forked
from harness.run.executor import (
    DaskNotInstalled,
    HeartbeatAfterClose,
    run_tasks,
    wait_for_shutdowns,
)
from harness.scene.random_problems import random_problems


def solve_chunk(task: dict) -> dict:
    """A real unit of work: one law over a slice of random contact-space problems."""
    problems = random_problems(task["count"], seed=task["seed"])
    result = pi.solve_batch(problems["mnn"], problems["mnt"], problems["mtt"], problems["vn"],
                            problems["vt"], problems["mu"], problems["e"], law=task["law"])
    return {"seed": task["seed"], "law": task["law"],
            "normal": result.normal_impulse.tobytes(),
            "tangential": result.tangential_impulse.tobytes(),
            "status": result.status.tobytes()}


def fail_on_three(task: int) -> int:
    if task == 3:
        raise RuntimeError("task 3 failed")
    return task * task


TASKS = [{"seed": seed, "law": law, "count": 200}
         for seed in range(6) for law in ("poisson", "stronge")]


def test_pool_equals_inline_bit_for_bit():
    inline = run_tasks(solve_chunk, TASKS, workers=1)
    pooled = run_tasks(solve_chunk, TASKS, workers=2)
    assert [r["seed"] for r in pooled] == [t["seed"] for t in TASKS]  # task order kept
    assert pooled == inline  # bytes of the float arrays: bit for bit


def test_progress_reports_every_task_and_ends_at_total():
    seen = []
    run_tasks(fail_on_three, [0, 1, 2], workers=2,
              progress=lambda done, total: seen.append((done, total)))
    assert seen[0] == (0, 3) and seen[-1] == (3, 3)
    assert [done for done, _ in seen] == sorted(done for done, _ in seen)


def test_errors_propagate_and_bad_arguments_fail():
    with pytest.raises(RuntimeError, match="task 3"):
        run_tasks(fail_on_three, range(6), workers=2)
    with pytest.raises(ValueError, match="unknown executor"):
        run_tasks(fail_on_three, [1], executor="ray")
    with pytest.raises(ValueError, match="workers"):
        run_tasks(fail_on_three, [1], workers=0)
    assert run_tasks(fail_on_three, []) == []
    assert run_tasks(fail_on_three, [2]) == [4]  # a single task runs inline


def test_missing_dask_names_the_install_command(monkeypatch):
    monkeypatch.setitem(sys.modules, "distributed", None)  # makes `import distributed` fail
    with pytest.raises(DaskNotInstalled, match=r'pip install -e "\.\[dask\]"'):
        run_tasks(fail_on_three, [1, 2], executor="dask")


def test_missing_dask_fails_the_argument_check(monkeypatch):
    from harness.run.executor import check_arguments

    monkeypatch.setitem(sys.modules, "distributed", None)
    with pytest.raises(DaskNotInstalled, match=r'pip install -e "\.\[dask\]"'):
        check_arguments("dask")


def test_dask_is_imported_only_for_a_run_that_goes_to_dask():
    pytest.importorskip("distributed", reason='dask is not installed (pip install -e ".[dask]")')
    import subprocess

    # A fresh interpreter: the argument check and a run kept on the local pool (below the
    # threshold) leave dask.distributed unimported; its import costs 0.3-0.5 s.
    code = ("import sys\n"
            "from harness.run.executor import check_arguments, run_tasks\n"
            "check_arguments('dask', 2)\n"
            "assert run_tasks(abs, [-1, -2], executor='dask', workers=2) == [1, 2]\n"
            "print('distributed' in sys.modules)\n")
    finished = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                              check=True)
    assert finished.stdout.strip() == "False"


def test_a_failing_import_inside_dask_is_not_called_missing_dask(monkeypatch):
    pytest.importorskip("distributed", reason='dask is not installed (pip install -e ".[dask]")')
    # A module named like a standard one in the working folder (a stray timeit.py) breaks
    # distributed's own imports: that error is shown as it is, not as "install dask".
    for name in [name for name in sys.modules if name.partition(".")[0] == "distributed"]:
        monkeypatch.delitem(sys.modules, name)  # imported afresh (restored after the test)
    monkeypatch.setitem(sys.modules, "timeit", None)  # `import timeit` fails
    with pytest.raises(ImportError) as caught:
        run_tasks(fail_on_three, [1, 2], executor="dask", dask_min_tasks=0)
    assert not isinstance(caught.value, DaskNotInstalled)
    assert caught.value.name == "timeit"


def test_dask_local_cluster_equals_local_executor_bit_for_bit():
    pytest.importorskip("distributed", reason='dask is not installed (pip install -e ".[dask]")')
    import cloudpickle

    # Dask workers are fresh processes: ship this test module's function by value.
    cloudpickle.register_pickle_by_value(sys.modules[__name__])
    try:
        local = run_tasks(solve_chunk, TASKS, workers=2)
        seen = []
        distributed = run_tasks(solve_chunk, TASKS, executor="dask", workers=2,
                                dask_min_tasks=0,  # a cluster, however few the tasks
                                progress=lambda done, total: seen.append(done))
    finally:
        cloudpickle.unregister_pickle_by_value(sys.modules[__name__])
    assert distributed == local
    assert seen[-1] == len(TASKS)
    # The cluster stops in the background; once waited for, none of its processes is left.
    wait_for_shutdowns()
    assert not [child for child in multiprocessing.active_children()
                if "Dask" in child.name or "worker" in child.name.lower()]
    # the arrays are real answers, not empty: some rows solved
    assert np.any(np.frombuffer(local[0]["status"], dtype=np.int8) == 0)


def _record(message: str, error: BaseException | None) -> logging.LogRecord:
    exc_info = (type(error), error, None) if error is not None else None
    return logging.LogRecord("distributed.worker", logging.ERROR, __file__, 1, message, None,
                             exc_info)


def test_heartbeat_filter_drops_only_the_shutdown_race_record():
    comm = pytest.importorskip("distributed.comm.core",
                               reason='dask is not installed (pip install -e ".[dask]")')
    race = HeartbeatAfterClose()
    closed = comm.CommClosedError("in <TCP (closed) ConnectionPool.heartbeat_worker>")
    assert not race.filter(_record(
        "Failed to communicate with scheduler during heartbeat.", closed))
    # the same words for any other failure, and any other message, still reach the log
    assert race.filter(_record("Failed to communicate with scheduler during heartbeat.",
                               OSError("connection refused")))
    assert race.filter(_record("Failed to communicate with scheduler during heartbeat.", None))
    assert race.filter(_record("Compute Failed", closed))


def _process_id(_item) -> int:
    import os

    return os.getpid()


@pytest.mark.skipif("fork" not in multiprocessing.get_all_start_methods(), reason="no fork")
def test_start_forked_runs_inline_or_in_the_background_as_asked():
    """One item (or one worker) runs inline when waited for; ``in_background`` forks it, so
    the caller works meanwhile; several items on several workers are forked either way."""
    import os

    here = os.getpid()
    assert start_forked(_process_id, [0], 2)() == [here]
    assert start_forked(_process_id, [0, 1], 1)() == [here, here]
    (lone,) = start_forked(_process_id, [0], 1, in_background=True)()
    assert lone != here
    assert here not in start_forked(_process_id, [0, 1, 2], 2)()
    assert start_forked(_process_id, [], 2, in_background=True)() == []
