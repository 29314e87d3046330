"""Engine-adapter overhead: the harness's cost per impact beside the engine's bare stepping.

For every installed engine, preset and reference scene, in one run:

* ``harness_us`` -- ``engine.run(scene, settings)`` per impact (settings resolved once,
  caches warm): state set-up, stepping with per-step contact bookkeeping, read-out, status.
* ``bare_us`` -- the same number of engine steps from the same start state in a tight
  Python loop, with the same step call as the adapter (``cpSpaceStep`` through pymunk's cffi
  ``lib`` / ``p.stepSimulation`` / ``mj_step``) and the state set outside the timed region,
  on a world of the stepper's own (pymunk: without the harness's post_solve recorder).
* ``bare_reset_us`` -- the same loop with the state set-up timed too, the set-up being the
  adapter's own per-impact reset (``Engine.bare_stepper``): the least any Python harness
  must spend per impact.
  Both sides do exactly the same reset.
* ``ratio`` = ``harness_us / bare_us`` (target <= 1.3) and ``ratio_reset`` =
  ``harness_us / bare_reset_us``.

The velocity-level engines (pymunk, pybullet) resolve an impact in 2 steps, so their bare
stepping is a few microseconds and fixed per-impact costs of any Python driver dominate
``ratio``; ``ratio_reset`` isolates the harness's own work: the per-step contact queries and
the read-out the contract needs, the bookkeeping, the status and the result object.
MuJoCo's soft contact takes ~50 steps, where ``ratio`` is meaningful.

The benchmark checks its own results: reruns are bit-identical, and pymunk/pybullet
``accurate`` agree with ``planar_impact``'s ``newton-lcp`` to 1e-6.

``python -m harness.bench.engines [--quick] [--json PATH]``.
"""

from __future__ import annotations

import argparse
import json
import math
import platform
import sys
import time
from typing import Callable

from harness.engines import (
    EngineNotInstalled,
    UnsupportedScene,
    engine_names,
    ke_norm,
    load_engine,
    preset_label,
)
from harness.run import verdicts
from harness.scene import Scene
from harness.scene.geometry import impact_problem
from harness.scene.reference import newton_lcp_velocities, reference_scenes
from harness.store.files import write_text_atomically

RATIO_TARGET = 1.3


# ---------------------------------------------------------------------- scenes
def _bare_stepper(
    engine, scene: Scene, settings: dict
) -> tuple[Callable[[], None], Callable[[int], None]]:
    """``(prepare, step_n)``: set the run's start state; step the engine n times, nothing else."""
    # The engine's own reset and step call (Engine.bare_stepper), on a world of its own built
    # without contact reporting (pymunk: no post_solve recorder).
    stepper = engine.bare_stepper(scene, settings)
    return stepper.reset, stepper.step


# ---------------------------------------------------------------------- timing
def _time_harness(engine, scene, settings, impacts: int, rounds: int) -> float:
    best = math.inf
    run = engine.run
    for _ in range(rounds):
        start = time.perf_counter()
        for _ in range(impacts):
            run(scene, settings)
        best = min(best, (time.perf_counter() - start) / impacts)
    return best


def _time_bare(
    prepare, step_n, steps: int, impacts: int, rounds: int, include_reset: bool
) -> float:
    best = math.inf
    clock = time.perf_counter
    for _ in range(rounds):
        total = 0.0
        if include_reset:
            start = clock()
            for _ in range(impacts):
                prepare()
                step_n(steps)
            total = clock() - start
        else:
            for _ in range(impacts):
                prepare()
                start = clock()
                step_n(steps)
                total += clock() - start
        best = min(best, total / impacts)
    return best


def run_engine_overhead_benchmark(quick: bool = True,
                                  engines: tuple[str, ...] | None = None) -> dict:
    """Measure harness vs bare stepping per engine, preset and scene; returns a dict.

    ``engines``: the engines to measure (default: every registered one,
    :func:`harness.engines.engine_names`, those added at run time included).

    ``{"engines": {name: {"available": bool, "reason": str|None, "rows": [...]}}, ...}``;
    each row has ``scene, preset, steps, harness_us, bare_us, bare_reset_us, ratio,
    ratio_reset, deterministic, newton_lcp_error`` (None where not applicable) and
    ``meets_target`` (ratio <= 1.3).
    """
    scenes = reference_scenes()
    chosen = ("disk", "rod-45", "two-disks") if quick else tuple(scenes)
    rounds = 5 if quick else 7

    report: dict = {
        "quick": quick,
        "ratio_target": RATIO_TARGET,
        "python": platform.python_version(),
        "machine": platform.machine(),
        "engines": {},
    }
    for name in engine_names() if engines is None else engines:
        try:
            engine = load_engine(name)
        except EngineNotInstalled as error:
            report["engines"][name] = {"available": False, "reason": str(error), "rows": []}
            continue
        impacts = engine.bench_impacts[0 if quick else 1]
        rows = []
        for preset in ("defaults", "accurate"):
            settings = engine.settings(preset)
            for scene_name in chosen:
                scene, contact, normal = scenes[scene_name]
                try:
                    first = engine.run(scene, settings)  # warm caches
                except UnsupportedScene as error:  # skipped, as by the runner and check_engine
                    rows.append({"scene": scene_name, "preset": preset, "skipped": str(error)})
                    continue
                again = engine.run(scene, settings)
                deterministic = first == again
                # The verdict, as every suite, survey and stress run gets: a benchmarked run
                # that is not the single impact it claims to be is marked, not timed silently.
                problem = impact_problem(scene, contact, normal)
                law_change = problem.solve(mu=scene.friction, e=scene.restitution,
                                           law="newton-lcp").energy_change
                verdict = verdicts.judge(scene, problem, verdicts.numbers_from_run(first),
                                         law_energy_change=law_change)
                law_error = None
                if engine.own_law == "newton-lcp":
                    law = newton_lcp_velocities(scene, contact, normal)
                    diff = first.u_after - law.u_after
                    law_error = ke_norm(scene, diff) / ke_norm(scene, scene.state())
                steps = first.steps
                prepare, step_n = _bare_stepper(engine, scene, settings)
                count = impacts
                # Rounds interleaved (harness, bare, bare+reset; best of each): a burst of
                # machine noise then hits all three alike instead of one of them.
                harness = bare = bare_reset = math.inf
                for _ in range(rounds):
                    harness = min(harness, _time_harness(engine, scene, settings, count, 1))
                    bare = min(bare, _time_bare(prepare, step_n, steps, count, 1,
                                                include_reset=False))
                    bare_reset = min(bare_reset, _time_bare(prepare, step_n, steps, count, 1,
                                                            include_reset=True))
                engine.run(scene, settings)  # leave the engine's caches in a clean state
                rows.append({
                    "scene": scene_name,
                    "preset": preset,
                    "steps": steps,
                    "status": first.status,
                    "verdict": "ok" if verdict.single_impact else ",".join(verdict.names),
                    "harness_us": harness * 1e6,
                    "bare_us": bare * 1e6,
                    "bare_reset_us": bare_reset * 1e6,
                    "ratio": harness / bare,
                    "ratio_reset": harness / bare_reset,
                    "meets_target": harness / bare <= RATIO_TARGET,
                    "deterministic": deterministic,
                    "newton_lcp_error": law_error,
                })
        report["engines"][name] = {"available": True, "reason": None, "version": engine.version,
                                   "rows": rows}
    return report


def format_table(report: dict) -> str:
    """The benchmark as a plain-text table."""
    lines = [
        f"engine overhead per impact (quick={report['quick']}; "
        f"target ratio <= {report['ratio_target']})",
        f"{'engine':9} {'preset':14} {'scene':11} {'steps':>5} {'harness µs':>11} {'bare µs':>9} "
        f"{'bare+reset µs':>13} {'ratio':>6} {'ratio(reset)':>12} {'det':>4} {'vs newton-lcp':>13} "
        f"verdict",
    ]
    for name, entry in report["engines"].items():
        if not entry["available"]:
            lines.append(f"{name:9} not available: {entry['reason']}")
            continue
        for row in entry["rows"]:
            if "skipped" in row:
                lines.append(f"{name:9} {preset_label(name, row['preset']):14} "
                             f"{row['scene']:11} skipped: {row['skipped']}")
                continue
            law = "" if row["newton_lcp_error"] is None else f"{row['newton_lcp_error']:.1e}"
            lines.append(
                f"{name:9} {preset_label(name, row['preset']):14} {row['scene']:11} "
                f"{row['steps']:5d} "
                f"{row['harness_us']:11.1f} {row['bare_us']:9.1f} {row['bare_reset_us']:13.1f} "
                f"{row['ratio']:6.2f} {row['ratio_reset']:12.2f} "
                f"{'yes' if row['deterministic'] else 'NO':>4} "
                f"{law:>13} {row.get('verdict', '')}"
            )
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m harness.bench.engines",
                                     description=__doc__.split("\n")[0])
    parser.add_argument("--quick", action="store_true", help="fewer scenes and repetitions")
    parser.add_argument("--json", metavar="PATH", help="also write the results as JSON")
    args = parser.parse_args(argv)
    report = run_engine_overhead_benchmark(quick=args.quick)
    print(format_table(report))
    if args.json:
        write_text_atomically(args.json, json.dumps(report, indent=2))  # regular files only
    bad = [
        (name, row["scene"], row["preset"])
        for name, entry in report["engines"].items()
        for row in entry["rows"]
        if not row.get("deterministic", True)
        or (row["preset"] == "accurate" and row.get("newton_lcp_error") is not None
            and row["newton_lcp_error"] > 1e-6)
    ]
    if bad:
        print(f"self-check failed (not bit-identical, or accurate off newton-lcp by > 1e-6): {bad}",
              file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
