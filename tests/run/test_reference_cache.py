"""A several-contact point's reference kept in the result cache between runs
(harness/run/plan.py, ``point_reference_cached``)."""

from __future__ import annotations

import importlib.util
import json
from dataclasses import replace
from pathlib import Path

from harness.run import plan, references
from harness.scenarios import load_scenario
from harness.store.cache import ResultCache

# Entry files read and written by hand (shared by the cache tests).
_spec = importlib.util.spec_from_file_location(
    "cache_entries", Path(__file__).parent / "cache_entries.py")
cache_entries = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(cache_entries)
read_entry, write_entry = cache_entries.read_entry, cache_entries.write_entry


def _stored(cache: ResultCache) -> list:
    return sorted(cache.root.glob("??/*.json"))


def test_a_flat_face_reference_is_stored_once_and_read_back_unchanged(tmp_path):
    scenario = load_scenario("scenarios/flat-rod.toml")
    point = scenario.point_list()[0]
    cache = ResultCache(tmp_path)
    first = plan.point_reference_cached(scenario, point, cache)
    assert first["kind"] == references.SIMULTANEOUS
    assert len(_stored(cache)) == 1
    again = plan.point_reference_cached(scenario, point, ResultCache(tmp_path))
    # read back through JSON, equal to the one computed (floats round-trip exactly)
    assert again == json.loads(json.dumps(first))
    assert again == references.point_reference(scenario, point)
    assert (cache.hits, cache.misses) == (0, 0)  # stats count engine runs only


def test_the_second_lookup_reads_the_cache_rather_than_solving_again(tmp_path):
    scenario = load_scenario("scenarios/flat-rod.toml")
    point = scenario.point_list()[0]
    cache = ResultCache(tmp_path)
    plan.point_reference_cached(scenario, point, cache)
    (entry,) = _stored(cache)
    header, record = read_entry(entry)
    write_entry(entry, header, {**record, "why": "read from the cache"})  # whole, signed
    assert plan.point_reference_cached(scenario, point, cache)["why"] == "read from the cache"


def test_another_friction_is_another_entry(tmp_path):
    scenario = load_scenario("scenarios/flat-rod.toml")
    point = scenario.point_list()[0]
    cache = ResultCache(tmp_path)
    plan.point_reference_cached(scenario, point, cache)
    other = replace(scenario, friction=scenario.friction + 0.1)
    plan.point_reference_cached(other, other.point_list()[0], cache)
    assert len(_stored(cache)) == 2


def test_a_single_contact_reference_is_not_stored(tmp_path):
    scenario = load_scenario("scenarios/box-corner.toml")
    cache = ResultCache(tmp_path)
    reference = plan.point_reference_cached(scenario, scenario.point_list()[0], cache)
    assert reference["kind"] == references.SINGLE
    assert not _stored(cache)
