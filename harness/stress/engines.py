"""Engine stress: a disk and the 45° rod scaled over mass, size, speed, grazing, e, μ, step."""

from __future__ import annotations

import math
import time
from pathlib import Path

import numpy as np

from harness.engines import (
    PRESET_ROLES,
    EngineNotInstalled,
    UnsupportedScene,
    body_extent,
    engine_names,
    ke_norm,
    load_engine,
    source_label,
)
from harness.run import verdicts
from harness.run.executor import run_tasks
from harness.scene import Body, Disk, Rod, Scene
from harness.scene.geometry import impact_problem, scene_contact
from harness.store.cache import ResultCache
from harness.store.identity import code_version_of

OUTCOMES: dict[str, str] = {
    "stopped": "the run was stopped: over its time limit, or its worker process died (a crash "
               "inside the engine)",
    "error": "the adapter or engine raised an exception",
    "unsupported": "the adapter refuses to build the scene (UnsupportedScene: the engine cannot "
                   "represent it, as Box2D's polygons below its area floor b2_epsilon)",
    "non-finite": "NaN or infinite post-impact velocities",
    "blow-up": "kinetic-energy norm grew more than 1e3 times",
    "energy-gain": "kinetic energy gained where newton-lcp does not (the numerics')",
    "no-separation": "still in contact at the step cap",
    "no-contact": "the engine never saw the contact (tunnelled or missed within the cap)",
    "deep-penetration": "penetration beyond the verdict's bound (0.1 of the body's extent)",
    "clipped": "a speed at an engine's cap (pybullet 100 m/s, Box2D 2 m per step)",
    "flagged": "another failed verdict check (multi-contact, impulse, out-of-plane; "
               "docs/verdicts.md)",
    "ok": "a single impact: every verdict check holds",
}
OUTCOME_COLOURS = {"stopped": "#08306b", "error": "#000000", "unsupported": "#6baed6",
                   "non-finite": "#7f0000", "blow-up": "#d7301f", "energy-gain": "#fc8d59",
                   "no-separation": "#fdcc8a", "no-contact": "#ffffb2",
                   "deep-penetration": "#c994c7", "clipped": "#8c6bb1", "flagged": "#bdbdbd",
                   "ok": "#1a9850", "skipped": "#ffffff"}
#: Wall-clock seconds one stress run may take: the slowest (Drake at a 1 µs step over the
#: whole contact) take a few seconds; one 20 times slower is stuck, and is reported as
#: ``stopped``, the other runs going on.
RUN_TIME_LIMIT_S = 120.0
#: The digest of harness/stress/ (the cases, the outcomes and how a run is judged), which the
#: cached code's version (``code_version``) does not cover: in each run's cache key, and in
#: the provenance the report compares with today's before it links the stress page.
COMMAND_CODE_VERSION = code_version_of((Path(__file__).resolve().parent,))



def engine_cases(quick: bool) -> list[dict]:
    """Engine stress cases.

    Each is a dict ``{family, value, label, shape, mass, size, speed, grazing, e, mu, dt}``.
    """
    base = {"mass": 1.0, "size": 1.0, "speed": 1.0, "grazing": 1.0, "e": 0.5, "mu": 0.3, "dt": None}
    sweeps = {
        "mass": [1e-6, 1e-3, 1e3, 1e6],
        "size": [1e-4, 1e-2, 1e2, 1e3],
        "speed": [1e-6, 1e-3, 1e2, 1e4],
        "grazing": [1e-3, 1e-6, 1e-9],
        "e-mu": [(0.0, 0.0), (0.0, 10.0), (1.0, 0.0), (1.0, 10.0)],
        "time_step": [1e-6, 1e-4, 1e-2, 1e-1],
    }
    if not quick:
        sweeps.update(
            mass=[1e-6, 1e-4, 1e-2, 1e2, 1e4, 1e6],
            size=[1e-4, 1e-3, 1e-2, 1e-1, 1e1, 1e2, 1e3],
            speed=[1e-6, 1e-4, 1e-2, 1e1, 1e2, 1e3, 1e4],
            grazing=[1e-1, 1e-2, 1e-3, 1e-4, 1e-6, 1e-9],
            time_step=[1e-6, 1e-5, 1e-4, 1e-3, 1e-2, 3e-2, 1e-1],
        )
    cases = []
    for shape in ("disk", "rod"):
        cases.append(dict(base, family="reference", value=1.0, label="reference", shape=shape))
        for family, values in sweeps.items():
            for value in values:
                case = dict(base, family=family, shape=shape)
                if family == "e-mu":
                    case.update(e=value[0], mu=value[1], value=list(value),
                                label=f"e={value[0]:g},mu={value[1]:g}")
                else:
                    key = {"time_step": "dt"}.get(family, family)
                    case.update({key: value, "value": value, "label": f"{family}={value:g}"})
                cases.append(case)
    return cases


def build_scene(case: dict):
    """The stressed scene: a disk (r 0.1·size) or the 45° rod (1·size) on the ground."""
    size, mass, speed = case["size"], case["mass"], case["speed"]
    # approach direction: |v_n|/|v_t| = grazing ratio (1 = 45°)
    vn = -speed * case["grazing"] / math.hypot(1.0, case["grazing"])
    vt = speed / math.hypot(1.0, case["grazing"])
    if case["shape"] == "disk":
        radius = 0.1 * size
        body = Body("disk", Disk(radius), mass, (0.0, radius), 0.0, (vt, vn), 0.0)
    else:
        angle, length, cap = math.radians(45.0), 1.0 * size, 0.005 * size
        low_y = -length / 2.0 * math.sin(angle)
        body = Body("rod", Rod(length, cap), mass, (0.0, -low_y + cap), angle, (vt, vn), 0.0,
                    inertia=mass * length**2 / 12.0)
    return Scene((body,), case["e"], case["mu"], ground=True,
                 name=f"{case['shape']}:{case['label']}")


# verdict reason -> stress outcome (the reasons without an outcome of their own are "flagged")
_REASON_OUTCOMES = {"blow-up": "blow-up", "energy-gain": "energy-gain",
                    "no-separation": "no-separation", "not-separated": "no-separation",
                    "no-contact": "no-contact", "penetration": "deep-penetration",
                    "clipped": "clipped"}


def _outcome(run, scene) -> str:
    """The run's stress outcome: its verdict (harness/run/verdicts/), as for the suite and
    the survey, with ``non-finite`` apart; the first failing reason decides."""
    u_after = np.asarray(run.u_after, dtype=float)
    if not np.all(np.isfinite(u_after)):
        return "non-finite"
    contact = scene_contact(scene)
    problem = impact_problem(scene, contact.point, contact.normal)
    try:
        law = problem.solve(mu=scene.friction, e=scene.restitution, law="newton-lcp")
        law_energy_change = float(law.energy_change)
    except ValueError:  # the law refuses the problem (rounding at an extreme): no attribution
        law_energy_change = None
    verdict = verdicts.judge(scene, problem, verdicts.numbers_from_run(run),
                             law_energy_change=law_energy_change)
    if verdict.single_impact:
        return "ok"
    return _REASON_OUTCOMES.get(verdict.names[0], "flagged")


def run_engine_case(task: dict) -> dict:
    """One engine stress run (top-level: runs in worker processes)."""
    case, engine_name, preset = task["case"], task["engine"], task["preset"]
    scene = build_scene(case)
    record = {"engine": engine_name, "preset": preset, "shape": case["shape"],
              "family": case["family"], "label": case["label"], "value": case["value"]}
    try:
        engine = load_engine(engine_name)
        overrides = (engine.time_step_overrides(preset, case["dt"]) if case["dt"] is not None
                     else None)
        settings = engine.settings(preset, overrides)
        run = engine.run(scene, settings)
    except UnsupportedScene as error:  # the engine's own limit, stated by its adapter
        record.update(outcome="unsupported", status="unsupported", error=str(error)[:300])
        return record
    except Exception as error:  # noqa: BLE001 - any failure is an outcome to report
        record.update(outcome="error", status="error",
                      error=f"{type(error).__name__}: {error}"[:300])
        return record
    extent = body_extent(scene.bodies[0].shape)
    u_before = scene.state()
    u_after = np.asarray(run.u_after, dtype=float)
    before = ke_norm(scene, u_before)
    with np.errstate(all="ignore"):
        energy_ratio = ((ke_norm(scene, u_after) / before) ** 2
                        if np.all(np.isfinite(u_after)) else None)
    record.update(
        outcome=_outcome(run, scene),
        status=run.status,
        steps=run.steps,
        max_penetration_relative=run.max_penetration / extent,
        energy_ratio=energy_ratio,
        u_after=[float(v) for v in u_after],
        engine_version=run.engine_version,
        wall_time_s=run.wall_time_s,
    )
    return record


def stopped_run(task: dict, reason: str) -> dict:
    """The record of a run the executor stopped (over :data:`RUN_TIME_LIMIT_S`, or its
    worker died): reported as ``stopped`` with the reason, never dropped."""
    case = task["case"]
    return {"engine": task["engine"], "preset": task["preset"], "shape": case["shape"],
            "family": case["family"], "label": case["label"], "value": case["value"],
            "outcome": "stopped", "status": "stopped", "error": reason[:300]}


def engine_stress(quick: bool, executor: str = "local", workers: int | None = None,
                  scheduler: str | None = None, use_cache: bool = True,
                  cache_root: Path = Path(".cache/results"), progress=None,
                  engines: tuple[str, ...] | None = None) -> dict:
    """All engine runs (cached), grouped; JSON-able. ``engines``: those to stress (default:
    every registered one, :func:`harness.engines.engine_names`, those added at run time
    included); each installed one runs every case under both preset roles (quick or full),
    one not installed is listed in ``skipped`` with the reason."""
    presets = PRESET_ROLES  # both roles, quick or full: an engine's defaults fail differently
    skipped, versions = {}, {}
    for name in engine_names() if engines is None else engines:
        try:
            versions[name] = load_engine(name).version
        except EngineNotInstalled as error:
            skipped[name] = str(error)
    cases = engine_cases(quick)
    tasks = [{"case": case, "engine": name, "preset": preset}
             for name in versions for preset in presets for case in cases]
    cache = ResultCache(cache_root, enabled=use_cache)
    keys = [cache.key({"kind": "stress-engine", "task": task,
                       "engine_version": versions[task["engine"]],
                       "stress_code": COMMAND_CODE_VERSION})
            for task in tasks]
    records: list[dict | None] = [cache.get(key) for key in keys]
    todo = [index for index, record in enumerate(records) if record is None]

    def keep(position: int, record: dict) -> None:
        """Store each run as soon as its chunk finishes: an interrupted stress test keeps
        what it finished (a stopped run is not stored: a rerun tries it again)."""
        index = todo[position]
        records[index] = record
        if record["outcome"] != "stopped" and (
                record["outcome"] != "error" or "not installed" not in record.get("error", "")):
            cache.put(keys[index], record)

    started = time.perf_counter()
    run_tasks(run_engine_case, [tasks[i] for i in todo], executor=executor, workers=workers,
              scheduler=scheduler, progress=progress, on_result=keep,
              time_limit=lambda task: RUN_TIME_LIMIT_S, stopped=stopped_run)
    counts: dict = {}
    for record in records:
        group = counts.setdefault(source_label(record["engine"], record["preset"]),
                                  {name: 0 for name in OUTCOMES})
        group[record["outcome"]] += 1
    return {"versions": versions, "skipped": skipped, "presets": list(presets), "runs": records,
            "counts": counts, "cache": cache.stats, "engine_seconds": time.perf_counter() - started,
            "tasks_run": len(todo)}
