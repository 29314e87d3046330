"""ResultCache: hits, misses, invalidation by payload and by code version, corruption."""

from __future__ import annotations

import json

import pytest

from harness.store.cache import ResultCache
from harness.store.identity import canonical_json, code_version

PAYLOAD = {"scenario": "disk-oblique", "point": 0, "engine": "pymunk", "engine_version": "7.3.1",
           "settings": {"time_step": 1e-4, "iterations": 50}}
RECORD = {"u_after": [0.1, -0.5, 3.25], "status": "ok", "wall_time_s": 0.001}


def test_miss_then_hit_returns_the_record(tmp_path):
    cache = ResultCache(tmp_path)
    key = cache.key(PAYLOAD)
    assert cache.get(key) is None
    cache.put(key, RECORD)
    assert cache.get(key) == RECORD
    assert (cache.hits, cache.misses) == (1, 1)
    assert cache.path(key).parent.name == key[:2]  # sharded
    assert not list(cache.path(key).parent.glob("*.tmp"))  # atomic write left no temporary
    # a second cache over the same directory (a rerun) hits too
    assert ResultCache(tmp_path).get(key) == RECORD


def test_key_depends_on_payload_values_not_on_key_order():
    cache = ResultCache("unused", version="v1")
    reordered = {name: PAYLOAD[name] for name in reversed(list(PAYLOAD))}
    assert cache.key(reordered) == cache.key(PAYLOAD)
    changed = dict(PAYLOAD, settings={"time_step": 1e-4, "iterations": 51})
    assert cache.key(changed) != cache.key(PAYLOAD)
    # floats are exact: one ulp apart is another key
    nudged = dict(PAYLOAD, settings={"time_step": 1.0000000000000002e-4, "iterations": 50})
    assert cache.key(nudged) != cache.key(PAYLOAD)


def test_code_change_invalidates(tmp_path):
    old = ResultCache(tmp_path, version="code-a")
    old.put(old.key(PAYLOAD), RECORD)
    new = ResultCache(tmp_path, version="code-b")
    assert new.get(new.key(PAYLOAD)) is None
    assert len(code_version()) == 64 and code_version() == code_version()


def test_code_version_hashes_the_sources(tmp_path, monkeypatch):
    from harness.store import identity

    package = tmp_path / "src" / "planar_impact"
    harness_dir = tmp_path / "harness" / "engines"
    package.mkdir(parents=True)
    harness_dir.mkdir(parents=True)
    (package / "solver.py").write_text("x = 1\n")
    (harness_dir / "pymunk_engine.py").write_text("y = 1\n")
    dirs = (package, tmp_path / "harness")
    before = identity.code_version_of(dirs)
    (harness_dir / "pymunk_engine.py").write_text("y = 2\n")  # an engine adapter changes
    identity.code_version_of.cache_clear()
    assert identity.code_version_of(dirs) != before


@pytest.mark.parametrize(
    "content", ["{not json", "", json.dumps({"key": "other", "record": {}}), "[1, 2]"]
)
def test_corrupted_file_is_a_miss(tmp_path, content):
    cache = ResultCache(tmp_path)
    key = cache.key(PAYLOAD)
    cache.put(key, RECORD)
    cache.path(key).write_text(content)
    assert cache.get(key) is None and cache.misses == 1
    cache.put(key, RECORD)  # and is repaired by the next put
    assert cache.get(key) == RECORD


def test_disabled_cache_never_hits_nor_writes(tmp_path):
    cache = ResultCache(tmp_path / "c", enabled=False)
    key = cache.key(PAYLOAD)
    cache.put(key, RECORD)
    assert cache.get(key) is None and not (tmp_path / "c").exists()


def test_payload_must_be_json_able():
    assert canonical_json({"b": 1.5, "a": (1, 2)}) == '{"a":[1,2],"b":1.5}'
    with pytest.raises(TypeError, match="not JSON-able"):
        ResultCache("unused", version="v").key({"x": object()})


def test_a_spelled_value_keys_as_the_value_itself():
    from harness.scenarios import SCENARIO_DIR, load_scenario
    from harness.store.identity import Spelled

    cache = ResultCache("unused", version="v1")
    scenario = load_scenario(SCENARIO_DIR / "sweep-tilted-box.toml")
    settings = {"time_step": 1e-4, "solref": [0.02, 1.0], "name": 'a "quoted" \u2713'}
    for point in scenario.point_list():
        scene = scenario.scene(point)
        plain = {"kind": "engine-run", "scene": scene, "settings": settings, "n": [scene]}
        spelled = {"kind": "engine-run", "scene": Spelled(scene), "settings": Spelled(settings),
                   "n": [Spelled(scene)]}
        assert canonical_json(spelled) == canonical_json(plain)
        assert cache.key(spelled) == cache.key(plain)


def test_a_listed_cache_finds_what_it_puts_and_what_was_there(tmp_path):
    cache = ResultCache(tmp_path)
    there, later, own = (cache.key({"n": n}) for n in range(3))
    cache.put(there, RECORD)
    cache.put_lines(there, ['{"x":1}'])
    with cache.listed():
        assert cache.get(there) == RECORD
        assert cache.get_lines(there) == [({"x": 1}, '{"x":1}')]
        assert cache.get(own) is None and cache.get(later) is None  # both listed absent
        ResultCache(tmp_path).put(later, RECORD)  # another process, after the listing
        cache.put(own, RECORD)
        assert cache.get(own) == RECORD
        assert cache.get(later) is None  # a miss: simulated again, never wrong
    assert cache.get(later) == RECORD  # outside: every entry opened
    assert (cache.hits, cache.misses) == (3, 3)
