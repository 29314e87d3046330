"""The cost of storing one engine run in the result cache, as a pool worker stores it.

``python -m harness.bench.cache_put [--runs 600] [--repeats 3]`` runs the library's engine
tasks once (both presets, every installed engine the registry lists, repeated up to
``--runs``), then, per repeat, stores their outputs (:func:`harness.run.tasks.engine_task`'s,
what ``_stored_by_worker`` stores) into a fresh cache directory, a pack per chunk of
:data:`harness.run.executor.MAX_CHUNK` as a worker stores a chunk's runs, and prints the time
per engine run: wall, and the process's user and system CPU (the median repeat by user CPU).
A cold run of the 1,000-file benchmark stores 16,056 of them, on the pool's workers.
"""

from __future__ import annotations

import argparse
import itertools
import os
import tempfile
import time
from collections.abc import Iterator, Sequence
from pathlib import Path

from harness import bounds
from harness.engines import PRESET_ROLES, EngineNotInstalled, engine_names, load_engine
from harness.run import tasks
from harness.run.executor import MAX_CHUNK
from harness.scenarios import Scenario, load_scenarios
from harness.store.cache import ResultCache


def engine_outputs(runs: int, scenarios: Sequence[Scenario] | None = None) -> list[dict]:
    """``runs`` outputs of the engine tasks of ``scenarios`` (default: the library), cycled
    when there are fewer, skipped runs left out."""
    outputs = list(itertools.islice(_task_outputs(scenarios), runs))
    if not outputs:
        raise SystemExit("cache_put: no engine is installed")
    return [outputs[index % len(outputs)] for index in range(runs)]


def _task_outputs(scenarios: Sequence[Scenario] | None) -> Iterator[dict]:
    """The output of each engine task of ``scenarios`` (default: the library), every engine
    the registry lists (those registered at run time too) under each preset role, run as it
    is asked for."""
    for scenario in load_scenarios(None) if scenarios is None else scenarios:
        for point in scenario.point_list():
            for name in scenario.engines_among(engine_names()):
                try:
                    engine = load_engine(name)
                except EngineNotInstalled:
                    continue
                for preset in PRESET_ROLES:
                    settings = engine.settings(preset, scenario.engine_settings.get(name, {}))
                    output = tasks.engine_task({"engine": name, "scene": scenario.scene(point),
                                                "settings": settings})
                    if "velocities" in output:
                        yield output


def time_puts(outputs: list[dict], root: Path) -> tuple[float, float, float]:
    """``(wall, user, system)`` seconds per output stored into a cache at ``root``, a pack
    per chunk of :data:`harness.run.executor.MAX_CHUNK`."""
    cache = ResultCache(root, version="bench")
    keys = [cache.key({"run": index}) for index in range(len(outputs))]
    items = list(zip(keys, outputs))
    before, start = os.times(), time.perf_counter()
    for first in range(0, len(items), MAX_CHUNK):
        cache.put_many(items[first:first + MAX_CHUNK])
    wall, after = time.perf_counter() - start, os.times()
    return (wall / len(keys), (after.user - before.user) / len(keys),
            (after.system - before.system) / len(keys))


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=bounds.option("count"), default=600,
                        help="engine outputs to put")
    parser.add_argument("--repeats", type=bounds.option("repeats"), default=3)
    args = parser.parse_args(argv)
    outputs = engine_outputs(args.runs)
    with tempfile.TemporaryDirectory(prefix="cache-put-") as directory:
        timings = sorted((time_puts(outputs, Path(directory) / f"cache{repeat}")
                          for repeat in range(args.repeats)), key=lambda timing: timing[1])
    wall, user, system = timings[len(timings) // 2]
    print(f"cache put of {len(outputs)} engine runs: {wall * 1e6:.0f} us wall, "
          f"{user * 1e6:.0f} us user CPU, {system * 1e6:.0f} us system CPU per put "
          f"(median of {args.repeats})")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
