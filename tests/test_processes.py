"""harness.processes: a pool whose jobs are stopped at their limit, and workers that end with
their parent (issue 23 items 4 and 8)."""

from __future__ import annotations

import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from harness.processes import StoppablePool

ROOT = Path(__file__).resolve().parents[1]
linux_only = pytest.mark.skipif(not Path("/proc/self/stat").exists(),
                                reason="reads the process table from /proc (Linux)")


def stuck_in_c(seconds: float) -> str:
    """Never returns to Python for hours (exponential backtracking in C) unless ``seconds``
    is 0: where no signal handler runs, as in an engine's step."""
    if seconds:
        re.match(r"(a+)+$", "a" * 60 + "b")
    return "done"


def test_a_job_over_its_limit_is_stopped_and_the_others_finish():
    begin = time.monotonic()
    with StoppablePool(stuck_in_c, 2) as pool:
        outcomes = dict(pool.run([0, 1, 0, 0], limits=[5.0, 0.5, 5.0, None]))
    assert time.monotonic() - begin < 10
    assert outcomes == {0: ("result", "done"), 1: ("stopped", "time limit: stopped after 0.5 s"),
                        2: ("result", "done"), 3: ("result", "done")}


def raises_or_dies(how: str) -> str:
    if how == "raise":
        raise ValueError("bad task")
    if how == "die":
        os._exit(3)
    return how


def test_a_job_that_raises_or_kills_its_worker_costs_itself_only():
    with StoppablePool(raises_or_dies, 1) as pool:
        outcomes = dict(pool.run(["a", "raise", "die", "b"]))
    kind, error = outcomes[1]
    assert kind == "error" and isinstance(error, ValueError) and str(error) == "bad task"
    assert outcomes[2] == ("stopped", "worker died (exit code 3)")
    assert outcomes[0] == ("result", "a") and outcomes[3] == ("result", "b")


# --------------------------------------------------------------------------------------------
# No worker outlives a killed command
# --------------------------------------------------------------------------------------------
def _parent_and_state(pid: int) -> tuple[int, str] | None:
    try:
        stat = Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        return None
    state, parent = stat.rpartition(")")[2].split()[:2]
    return int(parent), state


def children_of(pid: int) -> list[int]:
    found = []
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            info = _parent_and_state(int(entry.name))
            if info is not None and info[0] == pid and info[1] != "Z":
                found.append(int(entry.name))
    return found


def alive(pid: int) -> bool:
    info = _parent_and_state(pid)
    return info is not None and info[1] != "Z"  # a zombie has ended


KILLED_COMMANDS = {
    "run": ["run", ROOT / "scenarios" / "sweep-disk-alpha.toml", "--engines", "pymunk",
            "--workers", "2", "--no-cache", "--set", "pymunk.iterations=1000000000",
            "--task-time-limit", "300", "--json", "{tmp}/r.json"],
    "survey": ["survey", "disk-disk", "--samples", "400000", "--engines", "pymunk",
               "--workers", "2", "--no-figures", "--out", "{tmp}/survey"],
}


@linux_only
@pytest.mark.parametrize("command", sorted(KILLED_COMMANDS))
def test_no_worker_outlives_a_command_killed_with_sigkill(tmp_path, command):
    argv = [str(part).format(tmp=tmp_path) for part in KILLED_COMMANDS[command]]
    environment = dict(os.environ, PYTHONPATH=f"{ROOT / 'src'}{os.pathsep}{ROOT}",
                       IMPACT_HARNESS_MAX_SOLVER_ITERATIONS="1e10")  # a runaway engine
    process = subprocess.Popen([sys.executable, "-m", "harness.cli", *argv], env=environment,
                               stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        deadline = time.monotonic() + 60
        workers: list[int] = []
        while len(workers) < 2 and time.monotonic() < deadline and process.poll() is None:
            time.sleep(0.05)
            workers = children_of(process.pid)
        assert len(workers) >= 2, "the command never started its workers"
        time.sleep(0.3)  # past their initializer
        process.send_signal(signal.SIGKILL)
        process.wait(timeout=10)
        deadline = time.monotonic() + 5
        while any(alive(pid) for pid in workers) and time.monotonic() < deadline:
            time.sleep(0.05)
        survivors = [pid for pid in workers if alive(pid)]
    finally:
        process.kill()
    for pid in survivors:  # leave nothing running, whatever the outcome
        os.kill(pid, signal.SIGKILL)
    assert survivors == []
