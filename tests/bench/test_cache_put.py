"""harness.bench.cache_put: it times stores of real engine outputs (a pack per chunk), each
stored whole."""

from __future__ import annotations

import json

from harness.bench import cache_put
from harness.store.cache import ResultCache


def test_the_timed_puts_store_every_output_whole(tmp_path):
    outputs = cache_put.engine_outputs(5)
    wall, user, system = cache_put.time_puts(outputs, tmp_path)
    assert wall > 0 and user >= 0 and system >= 0
    cache = ResultCache(tmp_path, version="bench")
    stored = [cache.get(cache.key({"run": index})) for index in range(len(outputs))]
    assert stored == [json.loads(json.dumps(output)) for output in outputs]
