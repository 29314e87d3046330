"""What a run does: the engines and presets asked for, the engines installed, and the work
list -- every (scenario, point, engine, preset) run, looked up in the result cache, the misses
made into tasks (:mod:`harness.run.tasks`) -- and each several-contact point's reference,
read from the cache or made a task too.

The scene an engine runs at a point is :func:`engine_scene`; the key of an engine run is the
scene (spelled once per point, :class:`harness.store.identity.Spelled`), the engine, its
version and the complete settings, under the code version every key holds.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field, replace
from typing import Any, Sequence

from harness import engines as registry
from harness.engines import preset_choices, preset_role
from harness.engines.facts import engine_facts
from harness.reference.event_driven import sequence_outline
from harness.run import references
from harness.run.tasks import POINT_REFERENCE, check_engine_output
from harness.scenarios import PRESETS, Scenario
from harness.scenarios.schema import ONE_POINT_TOLERANCE
from harness.store.identity import Spelled


def parse_engines(text: str | Sequence[str] | None) -> tuple[str, ...]:
    """``"pymunk,mujoco"`` (or a list) -> engine names; None or ``all`` (as ``experiments
    --engines all`` takes it): every engine registered now (:func:`harness.engines.
    engine_names`, those registered at run time too). Raises ``ValueError`` for a name not
    registered, naming the registered ones."""
    registered = registry.engine_names()
    if text is None or (isinstance(text, str) and text.strip() == "all"):
        return registered
    items = text.split(",") if isinstance(text, str) else [
        part for item in text for part in str(item).split(",")]
    names = tuple(dict.fromkeys(item.strip() for item in items if item.strip()))
    unknown = [name for name in names if name not in registered]
    if unknown:
        raise ValueError(f"--engines: unknown engine(s) {', '.join(unknown)}; allowed (the "
                         f"registered engines): {', '.join(registered)}, or all")
    return names


def parse_presets(text: str | None) -> tuple[str, ...]:
    """``--preset``: ``all``, a preset role, or an engine's name for one (``matched-bounce``
    selects the role MuJoCo gives that name, ``accurate``, for every engine)."""
    if text in (None, "all"):
        return PRESETS
    try:
        return (preset_role(None, text),)
    except ValueError:
        raise ValueError(f"--preset: {text!r}; allowed: {', '.join(preset_choices())}, all") \
            from None


def engine_status(engines: Sequence[str], cache=None) -> tuple[dict, dict, dict]:
    """``({engine: version}, {engine: reason it is skipped}, {engine: {preset: settings}})``
    of the installed engines, without importing those whose facts ``cache`` keeps
    (:mod:`harness.engines.facts`)."""
    facts = engine_facts(engines, cache)
    return facts.versions, facts.missing, facts.settings


def settings_of(engine, preset: str, overrides: dict, memo: dict) -> dict | str:
    """``engine.settings(preset, overrides)``, or the ``ValueError``'s message; computed
    once per engine, preset and overrides (a deep copy and a check each: thousands of tasks
    share a handful)."""
    key = (engine.name, preset, json.dumps(overrides, sort_keys=True, default=repr))
    if key not in memo:
        try:
            memo[key] = engine.settings(preset, overrides)
        except ValueError as error:
            memo[key] = str(error)
    return memo[key]


def scene_payload(scene):
    """The scene as a cache key's payload holds it: the dataclass itself, hashed field by
    field (:func:`harness.store.identity.canonical_json`), never copied."""
    return scene


def engine_scene(scenario: Scenario, point):
    """The scene the engines run at ``point``: ``scenario.scene(point)``, and for a tilt whose
    reference is a sequence of impacts (``expect_sequence``) with ``run_until`` set to the
    sequence's last impact (``newton-lcp``, the primary reference), so that every engine runs
    the whole sequence, not only its first impact (harness/engines/contract.py, 'The loop')."""
    scene = scenario.scene(point)
    if references.kind_of(scenario) != references.EVENT_DRIVEN or not scene.ground:
        return scene
    outline = sequence_outline(scene)
    if len(outline.features) < 2 and outline.last_impact == 0.0:
        return scene  # one impact: the first separation ends it
    return replace(scene, run_until=outline.last_impact)


# --------------------------------------------------------------------------------------------
# The engine runs
# --------------------------------------------------------------------------------------------
@dataclass
class EnginePlan:
    """A run's engine runs: ``entries``, one ``(scenario, point, engine, preset, item)`` per run
    in run order, where ``item`` gets the run's ``output`` (read from the cache, a skip, or,
    once simulated, the task's), ``cached``, its cache ``key``, its ``overrides`` and whether
    it records its ``history``; ``tasks``, the runs to simulate, with their cache ``keys`` and
    the ``slots`` (items) their outputs go to."""

    entries: list[tuple[Scenario, Any, str, str, dict]] = field(default_factory=list)
    tasks: list[dict] = field(default_factory=list)
    keys: list[str | None] = field(default_factory=list)
    slots: list[dict] = field(default_factory=list)


def plan_engine_runs(scenarios: Sequence[Scenario], *, wanted_engines: Sequence[str],
                     presets: Sequence[str], missing: dict, command_overrides: dict,
                     history: bool | None, cache, time_limit_s: float | None,
                     store_in_worker: tuple | None) -> EnginePlan:
    """The :class:`EnginePlan` of ``scenarios`` (those the run builds records for): every
    engine run of every point, its settings (the preset, the scenario's
    ``[engine_settings]``, then ``--set``), its key, its output when the cache holds it;
    the others tasks, stored by their worker when ``store_in_worker`` (cache root and code
    version) is given. A missing engine or bad settings give the run's output at once."""
    work = EnginePlan()
    settings_memo: dict = {}
    keys_of: dict = {}  # ResultCache.slot_key by engine and id of settings_memo's values
    for scenario in scenarios:
        if scenario.analytic_only:
            continue
        for point in scenario.point_list():
            scene = None
            for engine_name in scenario.engines_among(wanted_engines):
                for preset in presets:
                    item: dict = {}
                    work.entries.append((scenario, point, engine_name, preset, item))
                    if engine_name in missing:
                        item["output"] = {"status": f"skipped: {missing[engine_name]}"}
                        continue
                    engine = registry.load_engine(engine_name)  # at call time: tests replace it
                    overrides = {**scenario.engine_settings.get(engine_name, {}),
                                 **command_overrides.get(engine_name, {})}
                    item["overrides"] = overrides
                    item["history"] = scenario.sweep is None if history is None else history
                    settings = settings_of(engine, preset, overrides, settings_memo)
                    if isinstance(settings, str):
                        item["output"] = {"status": f"error: settings: {settings}"}
                        continue
                    if scene is None:
                        scene = engine_scene(scenario, point)
                        # spelled once for the keys of all the point's engine runs
                        spelled_scene = None if cache is None else Spelled(scene_payload(scene))
                    key = None
                    if cache is not None:  # the key's text around the scene made once
                        key_of = keys_of.get((engine_name, id(settings)))
                        if key_of is None:
                            key_of = keys_of[engine_name, id(settings)] = cache.slot_key(
                                {"kind": "engine-run", "engine": engine_name,
                                 "engine_version": engine.version,
                                 "settings": Spelled(settings)}, "scene")
                        key = key_of(spelled_scene)
                    item["key"] = key
                    speeds = 3 * len(scene.bodies)
                    cached = None if cache is None else cache.get(
                        key, check=lambda output, speeds=speeds: check_engine_output(output,
                                                                                   speeds))
                    if cached is not None:
                        item["output"], item["cached"] = cached, True
                        continue
                    work.tasks.append({"engine": engine_name, "settings": settings,
                                       "scene": scene, "time_limit_s": time_limit_s,
                                       "store": None if store_in_worker is None
                                       else (*store_in_worker, key)})
                    work.keys.append(key)
                    work.slots.append(item)
    return work


# --------------------------------------------------------------------------------------------
# The several-contact references
# --------------------------------------------------------------------------------------------


def point_reference_cached(scenario: Scenario, point, cache=None) -> dict:
    """:func:`harness.run.references.point_reference`, read from ``cache`` when it holds it.

    A several-contact reference (a flat face's m-contact laws, a tilt's event sequence) costs
    up to a second per point, far more than the engine runs it judges; it depends only on
    the scene at the point, its μ, e and laws and the situation the scenario declares, which
    make the key. A single-contact reference costs nothing and is not stored.
    """
    key = reference_key(scenario, point, cache)
    if key is None:
        return references.point_reference(scenario, point)
    cached = stored_reference(cache, key)
    if cached is not None:
        return cached
    reference = references.point_reference(scenario, point)
    store_reference(cache, key, reference)
    return reference


def reference_key(scenario: Scenario, point, cache) -> str | None:
    """The cache key of a point's several-contact reference (:func:`point_reference_cached`);
    None without a cache or for a single-contact point (never stored)."""
    kind = references.kind_of(scenario)
    if cache is None or kind == references.SINGLE:
        return None
    fixed = scenario.at(point)
    return cache.key({"kind": POINT_REFERENCE, "situation": kind,
                      "scene": scene_payload(scenario.scene(point)),
                      "friction": fixed.friction, "restitution": fixed.restitution,
                      "laws": list(fixed.laws), "one_point_tolerance": ONE_POINT_TOLERANCE})


def stored_reference(cache, key: str) -> dict | None:
    return cache.get(key, check=lambda stored: None if isinstance(stored.get("kind"), str)
                     else "no reference kind", count=False)


def store_reference(cache, key: str, reference: dict) -> None:
    try:
        cache.put(key, reference)
    except OSError:  # the run goes on without the cache (the engine runs' store warns)
        pass


def reference_tasks(scenarios: Sequence[Scenario], cache
                     ) -> tuple[list[dict], list, dict[tuple[str, int], dict]]:
    """The reference tasks (:func:`harness.run.tasks.reference_task`) of the several-contact
    points of ``scenarios`` whose reference the cache does not hold, their cache keys (None
    without a cache), and the references the cache holds, by ``(scenario name, point index)`` (read
    once here, handed to the records)."""
    tasks, keys, found = [], [], {}
    for scenario in scenarios:
        if references.kind_of(scenario) == references.SINGLE:
            continue
        for point in scenario.point_list():
            key = reference_key(scenario, point, cache)
            stored = None if key is None else stored_reference(cache, key)
            if stored is not None:
                found[scenario.name, point.index] = stored
                continue
            tasks.append({"kind": POINT_REFERENCE, "scenario": scenario.name,
                          "point": point.index, "situation": references.kind_of(scenario),
                          "scene": scenario.scene(point),
                          "laws": references.PointLaws.of(scenario.at(point))})
            keys.append(key)
    return tasks, keys, found


__all__ = ["EnginePlan", "engine_scene", "engine_status", "parse_engines", "parse_presets",
           "plan_engine_runs", "point_reference_cached", "reference_key", "reference_tasks",
           "scene_payload", "settings_of", "store_reference", "stored_reference"]
