"""ResultCache.slot_key: the key of a payload with a spelled value in one slot, the text
around the slot made once, equals ResultCache.key of the payload holding the value."""

from __future__ import annotations

from harness.scenarios import SCENARIO_DIR, load_scenario
from harness.store.cache import ResultCache
from harness.store.identity import Spelled


def test_a_slot_key_is_the_key_of_the_payload_holding_the_value():
    cache = ResultCache("unused", version="v1")
    scenes = [scenario.scene(point)
              for name in ("sweep-tilted-box", "disk-strikes-rod", "flat-box")
              for scenario in [load_scenario(SCENARIO_DIR / f"{name}.toml")]
              for point in scenario.point_list()]
    settings = {"time_step": 1e-4, "solref": [0.02, 1.0], "name": 'a "quoted" \u2713'}
    payloads = [{"kind": "engine-run", "engine": "pymunk", "engine_version": "7.0",
                 "settings": Spelled(settings)},
                {"kind": "engine-run", "engine": "mujoco", "engine_version": "3.1",
                 "settings": settings, "z": [1.5, None]}]
    keys = set()
    for payload in payloads:
        key_of = cache.slot_key(payload, "scene")
        for scene in scenes:
            key = key_of(Spelled(scene))
            assert key == cache.key({**payload, "scene": Spelled(scene)})
            assert key == cache.key({**payload, "scene": scene})
            keys.add(key)
    assert len(keys) == len(payloads) * len(scenes)  # each payload and scene its own key
    other = ResultCache("unused", version="v2").slot_key(payloads[0], "scene")
    assert other(Spelled(scenes[0])) not in keys  # the code version is in the key
