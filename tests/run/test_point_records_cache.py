"""A point's finished records kept in the result cache (harness/run/runner.py,
``_point_records_cached``): a warm run reads them instead of rebuilding them (when the
scenario's records are not kept whole: tests/run/test_scenario_records_cache.py), and they
equal the records a run without the cache builds."""

from __future__ import annotations

import json

from harness.run import runner
from harness.run.cache import ResultCache
from harness.scenarios import SCENARIO_DIR, load_scenario

ROD = load_scenario(SCENARIO_DIR / "rod-45-slip-reversal.toml")
FLAT = load_scenario(SCENARIO_DIR / "flat-rod.toml")
ENGINES = ("pymunk", "pybullet")


def _run(scenarios, cache):
    return runner.run(scenarios, engines=ENGINES, cache=cache, log=None, workers=1)


def _comparable(record) -> dict:
    data = record.as_dict()
    for key in ("wall_time_s", "cached"):
        data.pop(key)
    if data["diagnostics"]:
        data["diagnostics"].pop("engine_wall_time_s", None)
    return data


def _point_entries(cache: ResultCache) -> list:
    found = []
    for path in cache.root.glob("??/*.json"):
        stored = json.loads(path.read_text())
        if "records" in stored["record"]:
            found.append(path)
    return found


def test_warm_records_equal_the_records_of_a_run_without_the_cache(tmp_path):
    fresh = _run([ROD, FLAT], None)
    _run([ROD, FLAT], ResultCache(tmp_path))
    cache = ResultCache(tmp_path)
    warm = _run([ROD, FLAT], cache)
    assert len(_point_entries(cache)) == 2  # one point each
    assert [_comparable(r) for r in warm.records] == [_comparable(r) for r in fresh.records]
    assert all(r.cached for r in warm.records if r.source != "analytic")
    assert warm.scenarios == fresh.scenarios
    assert cache.hits == 2 * len(ENGINES) * 2  # engine runs only: 2 scenarios, 2 presets


def test_a_warm_run_reads_the_stored_records(tmp_path):
    _run([ROD], ResultCache(tmp_path))
    for path in tmp_path.glob("??/*.jsonl"):  # the scenario's records kept whole: read first
        path.unlink()
    (entry,) = _point_entries(ResultCache(tmp_path))
    stored = json.loads(entry.read_text())
    stored["record"]["records"][0]["status"] = "read from the cache"
    entry.write_text(json.dumps(stored))
    warm = _run([ROD], ResultCache(tmp_path))
    assert warm.records[0].status == "read from the cache"


def test_without_the_cache_nothing_is_stored_and_records_are_built(tmp_path):
    disabled = ResultCache(tmp_path, enabled=False)
    _run([ROD], disabled)
    assert not list(tmp_path.glob("??/*.json"))
