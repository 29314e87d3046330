"""Every sample through an engine and preset, and the engines' bare stepping of the same impacts.

:func:`run_engine` is the survey's only call into the engines: today it runs the scenes one
by one through ``harness.engines.load_engine(name).run(scene, settings)``; a bulk path
(many impacts per engine world) replaces its body without changing what it returns.

:func:`bare_stepping` times, for the same scenes, the engine's own stepping with the
benchmark's bare steppers (harness/bench/engines.py): the same step call as the adapter in a
tight loop, from the adapter's start state, the reset outside (``bare_s``) and inside
(``bare_reset_s``) the timed region.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from harness.engines import STATUSES, load_engine
from harness.survey.laws import WIDTH


@dataclass(frozen=True)
class EngineResults:
    """One engine and preset over every sample (``n`` rows)."""

    engine: str
    engine_version: str
    preset: str
    velocities: np.ndarray  # (n, 6) post-impact speeds, padded like ContactTerms.u
    status: np.ndarray  # (n,) str, one of harness.engines.STATUSES
    steps: np.ndarray  # (n,) steps simulated
    wall_s: float  # s, the whole of run_engine


def run_engine(engine_name: str, preset: str, scenes) -> EngineResults:
    """Run every scene through ``engine_name`` at ``preset`` (the swap point for bulk paths)."""
    start = time.perf_counter()
    engine = load_engine(engine_name)
    settings = engine.settings(preset)  # one dict for every run: the adapters cache on it
    count = len(scenes)
    velocities = np.zeros((count, WIDTH))
    status = np.empty(count, dtype=object)
    steps = np.zeros(count, dtype=np.int64)
    run = engine.run
    for row, scene in enumerate(scenes):
        result = run(scene, settings)
        speeds = result.u_after
        velocities[row, :len(speeds)] = speeds
        status[row] = result.status
        steps[row] = result.steps
    assert set(status) <= set(STATUSES), set(status) - set(STATUSES)
    return EngineResults(engine_name, engine.version, preset, velocities, status.astype(str),
                         steps, time.perf_counter() - start)


def bare_stepping(engine_name: str, preset: str, scenes, steps) -> dict[str, float]:
    """Seconds of bare stepping of ``scenes`` (``steps[i]`` steps each, as the adapter took).

    Returns ``{"bare_s": …, "bare_reset_s": …, "impacts": n}``: the sums over the scenes of
    one timed pass each (the survey's impacts are all different, so there is no best-of).
    """
    from harness.bench.engines import _bare_stepper

    engine = load_engine(engine_name)
    settings = engine.settings(preset)
    clock = time.perf_counter
    bare = bare_reset = 0.0
    for scene, count in zip(scenes, steps):
        prepare, step_n = _bare_stepper(engine, scene, settings)
        prepare()
        begin = clock()
        step_n(int(count))
        bare += clock() - begin
        begin = clock()
        prepare()
        step_n(int(count))
        bare_reset += clock() - begin
    return {"bare_s": bare, "bare_reset_s": bare_reset, "impacts": len(scenes)}
