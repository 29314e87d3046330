"""A scenario's finished records kept whole in the result cache (harness/run/scenario_records.py,
``_scenario_key``): a warm run reads one entry per scenario, its results equal the cold
run's, and a damaged entry is reported and rebuilt, never trusted. Also the scenario checks
remembered by the file's text (harness/store/passed_checks.py)."""

from __future__ import annotations

import importlib.util
import json
import math
import os
from dataclasses import replace
from pathlib import Path

import pytest

from harness import cli
from harness.engines import ENGINE_NAMES
from harness.engines.facts import ENGINE_FACTS, engine_facts
from harness.run import plan, runner, scenario_records
from harness.run.records import read_results
from harness.scenarios import SCENARIO_DIR, checks, load_scenario
from harness.scenarios.library import load_scenarios_reporting
from harness.store.cache import ResultCache
from harness.store.passed_checks import PassedChecks

# Entry files read and written by hand (shared by the cache tests).
_spec = importlib.util.spec_from_file_location(
    "cache_entries", Path(__file__).parent / "cache_entries.py")
cache_entries = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(cache_entries)
read_entry, stored_records = cache_entries.read_entry, cache_entries.stored_records

ROD = load_scenario(SCENARIO_DIR / "rod-45-slip-reversal.toml")
SWEEP = load_scenario(SCENARIO_DIR / "sweep-disk-alpha.toml")  # 9 points
TWO_SLED = load_scenario(SCENARIO_DIR / "two-sled-row2.toml")  # analytic only
ENGINES = ("pymunk",)


def _run(scenarios, cache, **options):
    return runner.run(scenarios, engines=ENGINES, cache=cache, log=None, workers=1, **options)


def _comparable(record) -> dict:
    data = record.as_dict()
    for key in ("wall_time_s", "cached"):
        data.pop(key)
    if data["diagnostics"]:
        data["diagnostics"].pop("engine_wall_time_s", None)
    return data


def _scenario_entries(root) -> list:
    return sorted(root.glob("??/*.jsonl"))


def _entry_parts(path) -> tuple[dict, list[str], list[bytes]]:
    """A scenario entry's header, lines and byte parts, as ``ResultCache.put_lines`` lays them
    out: the header's line, then the pieces of the sizes it gives."""
    data = path.read_bytes()
    head_end = data.index(b"\n")
    header = json.loads(data[:head_end])
    pieces, start = [], head_end + 1
    for size in header["sizes"]:
        pieces.append(data[start:start + size])
        start += size
    assert start == len(data)
    text, *parts = pieces
    return header, text.decode("utf-8").split(",\n"), parts


class _CountingCache(ResultCache):
    """A cache that counts the entries it is asked for."""

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self.lookups = 0

    def get(self, key, check=None, *, count=True):
        if count:  # a lookup with count=False calls get again with count=True
            self.lookups += 1
        return super().get(key, check, count=count)

    def get_block(self, key, check_summary=None):
        self.lookups += 1
        return super().get_block(key, check_summary)


def test_a_warm_run_reads_one_entry_per_scenario_and_equals_the_cold_run(tmp_path):
    scenarios = [ROD, SWEEP, TWO_SLED]
    cold = _run(scenarios, ResultCache(tmp_path))
    assert len(_scenario_entries(tmp_path)) == 3
    cache = _CountingCache(tmp_path)
    warm = _run(scenarios, cache)
    # one per scenario (not one per engine run, point and reference) and each engine's facts
    assert cache.lookups == 3 + len(ENGINES)
    assert [_comparable(r) for r in warm.records] == [_comparable(r) for r in cold.records]
    assert warm.scenarios == cold.scenarios
    assert all(r.cached for r in warm.records if r.source != "analytic")
    engine_runs = sum(r.source != "analytic" for r in cold.records)
    assert cache.hits == engine_runs and cache.misses == 0  # counted as engine runs spared
    assert warm.provenance["cache"]["engine_runs"] == cold.provenance["cache"]["engine_runs"]
    assert not warm.warnings


def test_warm_records_equal_those_of_a_run_without_the_cache_kept_once(tmp_path):
    flat = load_scenario(SCENARIO_DIR / "flat-rod.toml")  # a several-contact reference
    fresh = _run([ROD, flat], None)
    _run([ROD, flat], ResultCache(tmp_path))
    stored = [record for _, _, record in stored_records(tmp_path)
              if record.get("kind") != ENGINE_FACTS]
    # engine runs and the flat face's reference; a point's records only in its scenario's
    assert sorted("velocities" in entry for entry in stored) == [False] + [True] * 4
    assert not any("records" in entry for entry in stored)
    warm = _run([ROD, flat], ResultCache(tmp_path))
    assert [_comparable(r) for r in warm.records] == [_comparable(r) for r in fresh.records]
    assert warm.scenarios == fresh.scenarios


def _results_without_timing(path) -> dict:
    document = json.loads(path.read_text(encoding="utf-8"))
    provenance = document["provenance"]
    for key in ("wall_time_s", "cache", "created_utc", "command"):
        provenance.pop(key, None)
    for record in document["records"]:
        record.pop("wall_time_s")
        record.pop("cached")
        (record["diagnostics"] or {}).pop("engine_wall_time_s", None)
    return document


def test_the_warm_results_file_equals_the_cold_one_apart_from_timing(tmp_path):
    files = [SCENARIO_DIR / "rod-45-slip-reversal.toml", SCENARIO_DIR / "flat-rod.toml",
             SCENARIO_DIR / "two-sled-row2.toml"]
    common = ["--engines", "pymunk,box2d", "--cache-dir", str(tmp_path / "cache"),
              "--workers", "1"]
    assert cli.main(["run", *map(str, files), *common, "--json", str(tmp_path / "cold.json")]) \
        == 0
    assert cli.main(["run", *map(str, files), *common, "--json", str(tmp_path / "warm.json")]) \
        == 0
    warm = json.loads((tmp_path / "warm.json").read_text(encoding="utf-8"))
    assert warm["provenance"]["cache"]["simulated"] == 0
    assert _results_without_timing(tmp_path / "warm.json") == \
        _results_without_timing(tmp_path / "cold.json")
    assert not list(tmp_path.glob("*.pickle"))  # the results file is the only form
    assert [r.u_after for r in read_results(tmp_path / "warm.json").records] == \
        [r.u_after for r in read_results(tmp_path / "cold.json").records]


@pytest.mark.parametrize("damage", ["header-not-json", "line-not-json", "truncated",
                                    "one-record-short", "nan-ok", "another-key",
                                    "another-scenario", "unknown-field", "edited-value"])
def test_a_damaged_scenario_entry_is_a_reported_miss_and_rebuilt(tmp_path, damage):
    clean = _run([SWEEP], ResultCache(tmp_path))
    (entry,) = _scenario_entries(tmp_path)
    header, lines, parts = _entry_parts(entry)
    records = [json.loads(line) for line in lines]
    if damage == "one-record-short":  # the header counts the lines: both agree
        records.pop()
        header["count"] -= 1
    elif damage == "nan-ok":
        ok = next(r for r in records if r["status"] == "ok" and r["source"] != "analytic")
        ok["u_after"][0] = math.nan
    elif damage == "another-key":
        header["key"] = "0" * 64
    elif damage == "another-scenario":
        records[3]["scenario"] = "disk-direct"
    elif damage == "unknown-field":
        records[0]["not_a_field"] = 1
    elif damage == "edited-value":  # still whole and readable: the checksum tells
        records[1]["wall_time_s"] += 1.0
    text = ",\n".join(json.dumps(record) for record in records)
    if damage == "line-not-json":
        text = text.replace("\n", "\n{", 1)
    body = text.encode("utf-8")
    header["sizes"] = [len(body), *(len(part) for part in parts)]  # whole, unless truncated
    data = json.dumps(header).encode("utf-8") + b"\n" + body + b"".join(parts)
    if damage == "header-not-json":
        data = b'{"key": "' + data
    elif damage == "truncated":
        data = data[:-10]
    entry.write_bytes(data)
    again = ResultCache(tmp_path)
    outcome = _run([SWEEP], again)
    assert [_comparable(r) for r in outcome.records] == [_comparable(r) for r in clean.records]
    assert len(again.rejected) == 1 and str(entry) in again.rejected[0]
    assert any(str(entry) in warning for warning in outcome.warnings)
    # rebuilt from the engine runs' entries (still cached), and stored whole again
    assert all(r.cached for r in outcome.records if r.source != "analytic")
    third = ResultCache(tmp_path)
    _run([SWEEP], third)
    assert not third.rejected


def test_another_selection_is_another_entry(tmp_path):
    _run([ROD], ResultCache(tmp_path))
    _run([ROD], ResultCache(tmp_path), presets=("defaults",))
    _run([ROD], ResultCache(tmp_path), overrides={"pymunk": {"iterations": 50}})
    _run([ROD], ResultCache(tmp_path), history=False)
    assert len(_scenario_entries(tmp_path)) == 4


def test_a_scenario_with_a_missing_engine_is_not_kept_whole(tmp_path, monkeypatch):
    from harness.engines import EngineNotInstalled

    real = plan.engine_status

    def pymunk_missing(engines, cache=None):
        versions, missing, settings = real(engines, cache)
        versions.pop("pymunk", None)
        settings.pop("pymunk", None)
        missing["pymunk"] = str(EngineNotInstalled("pymunk", "not installed (test)"))
        return versions, missing, settings

    monkeypatch.setattr(plan, "engine_status", pymunk_missing)
    outcome = _run([ROD], ResultCache(tmp_path))
    assert all(r.skipped for r in outcome.records if r.source != "analytic")
    assert not _scenario_entries(tmp_path)


def test_without_the_cache_no_scenario_entry(tmp_path):
    _run([ROD], ResultCache(tmp_path, enabled=False))
    assert not list(tmp_path.glob("??/*.json"))


# --------------------------------------------------------------------------------------------
# The scenario checks remembered by text
# --------------------------------------------------------------------------------------------
@pytest.fixture
def counted_checks(monkeypatch):
    """Count the calls of the point checks (the reader's reference to them)."""
    from harness.scenarios import reader

    calls = []
    real = reader.check_points

    def counting(table_reader, scenario):
        calls.append(scenario.name)
        return real(table_reader, scenario)

    monkeypatch.setattr(reader, "check_points", counting)
    yield calls
    checks.use_passed_checks(None)


def test_a_text_that_passed_the_checks_is_not_checked_again(tmp_path, counted_checks):
    source = SCENARIO_DIR / "rod-45-slip-reversal.toml"
    copy = tmp_path / "files" / source.name
    copy.parent.mkdir()
    copy.write_text(source.read_text(encoding="utf-8"), encoding="utf-8")
    checks.use_passed_checks(tmp_path / "cache")
    first, errors = load_scenarios_reporting([copy])
    assert not errors and counted_checks == [ROD.name]
    checks.use_passed_checks(tmp_path / "cache")  # a new run: the store read from disk
    second, _ = load_scenarios_reporting([copy])
    assert counted_checks == [ROD.name] and second == first
    copy.write_text(copy.read_text(encoding="utf-8") + "\n# changed\n", encoding="utf-8")
    checks.use_passed_checks(tmp_path / "cache")
    load_scenarios_reporting([copy])
    assert counted_checks == [ROD.name, ROD.name]  # another text: checked


def test_a_file_with_problems_is_checked_every_time(tmp_path, counted_checks):
    bad = tmp_path / "away.toml"
    text = (SCENARIO_DIR / "disk-direct.toml").read_text(encoding="utf-8")
    moving_away = text.split("[expect]")[0].replace("velocity = [0.0, -1.0]",
                                                    "velocity = [0.0, 1.0]")
    assert moving_away != text.split("[expect]")[0]
    bad.write_text(moving_away, encoding="utf-8")
    for _ in range(2):
        checks.use_passed_checks(tmp_path / "cache")
        scenarios, errors = load_scenarios_reporting([bad])
        assert not scenarios and any("do not approach" in str(e) for e in errors)
    assert len(counted_checks) == 2


def test_a_damaged_checks_store_is_reported_and_every_file_checked(tmp_path, counted_checks):
    (tmp_path / "cache").mkdir()
    store = tmp_path / "cache" / PassedChecks.FILE_NAME
    store.write_text('{"format": 1, "passed": ["not a key"]}', encoding="utf-8")
    passed = checks.use_passed_checks(tmp_path / "cache")
    scenarios, errors = load_scenarios_reporting([SCENARIO_DIR / "disk-direct.toml"])
    assert scenarios and not errors and len(counted_checks) == 1
    assert len(passed.problems) == 1 and str(store) in passed.problems[0]
    rewritten = json.loads(store.read_text(encoding="utf-8"))  # plain JSON: keys only
    assert rewritten["passed"] == [checks.passed_checks.key(
        (SCENARIO_DIR / "disk-direct.toml").read_text(encoding="utf-8"))]


def test_by_default_nothing_is_remembered(tmp_path, counted_checks):
    for _ in range(2):
        load_scenarios_reporting([SCENARIO_DIR / "disk-direct.toml"])
    assert len(counted_checks) == 2


def test_the_run_command_remembers_checks_in_its_cache_and_not_with_no_cache(tmp_path,
                                                                             counted_checks):
    file = str(SCENARIO_DIR / "two-sled-row2.toml")
    cache_dir = tmp_path / "cache"
    for _ in range(2):
        assert cli.main(["run", file, "--cache-dir", str(cache_dir), "--json",
                         str(tmp_path / "r.json")]) == 0
    assert len(counted_checks) == 1 and (cache_dir / PassedChecks.FILE_NAME).is_file()
    assert cli.main(["run", file, "--no-cache", "--json", str(tmp_path / "r.json")]) == 0
    assert len(counted_checks) == 2
    assert checks.passed_checks.root is None  # the run leaves the store disabled


def test_cache_info_and_prune_see_the_scenario_entries(tmp_path):
    ResultCache(tmp_path).make_root()  # marked as the harness's (a run does this)
    ResultCache(tmp_path, version="old").put_lines("a" * 64, ['{"x":1}'])
    ResultCache(tmp_path, version="new").put_lines("b" * 64, ['{"x":2}'])
    cache = ResultCache(tmp_path, version="new")
    assert cache.info()["entries"] == 2
    assert cache.prune()["entries"] == 1  # written by other code
    assert [path.name for path in _scenario_entries(tmp_path)] == ["b" * 64 + ".jsonl"]
    assert cache.get_lines("b" * 64) == [({"x": 2}, '{"x":2}')]


def test_records_built_on_forked_workers_equal_those_built_inline(tmp_path, monkeypatch):
    scenarios = [ROD, SWEEP, TWO_SLED, load_scenario(SCENARIO_DIR / "flat-rod.toml")]
    inline = _run(scenarios, ResultCache(tmp_path / "inline"))
    monkeypatch.setattr(scenario_records, "MIN_PARALLEL_RECORDS", 1)
    forked = runner.run(scenarios, engines=ENGINES, cache=ResultCache(tmp_path / "forked"),
                        log=None, workers=2)
    assert forked._records == [None] * len(inline.records)  # lines came back, not records
    assert [_comparable(r) for r in forked.records] == [_comparable(r) for r in inline.records]
    assert forked.scenarios == inline.scenarios and forked.gates == inline.gates
    # each worker stored its scenarios' entries, as the inline build does
    assert ([path.name for path in _scenario_entries(tmp_path / "forked")]
            == [path.name for path in _scenario_entries(tmp_path / "inline")])


def test_on_the_local_pool_each_worker_stores_the_runs_it_simulates(tmp_path, monkeypatch):
    stored_here = []
    real_put = ResultCache.put
    main = os.getpid()

    def put(self, key, record):
        if os.getpid() == main and "velocities" in record:
            stored_here.append(key)
        return real_put(self, key, record)

    monkeypatch.setattr(ResultCache, "put", put)  # the forked workers inherit it
    cold = runner.run([SWEEP], engines=ENGINES, cache=ResultCache(tmp_path), log=None,
                      workers=2)
    assert cold.provenance["cache"]["simulated"] == 18 and stored_here == []
    for path in _scenario_entries(tmp_path):  # the scenario kept whole aside, every run read
        path.unlink()
    again = ResultCache(tmp_path)
    _run([SWEEP], again)
    assert again.hits == 18 and again.misses == 0


def test_a_passed_text_is_not_checked_again_and_gets_its_files_path(tmp_path, monkeypatch):
    from harness.scenarios import reader

    source = SCENARIO_DIR / "sweep-disk-alpha.toml"
    first, second = tmp_path / "a" / source.name, tmp_path / "b" / source.name
    for copy in (first, second):
        copy.parent.mkdir()
        copy.write_text(source.read_text(encoding="utf-8"), encoding="utf-8")
    try:
        checks.use_passed_checks(tmp_path / "cache")
        (read,), _ = load_scenarios_reporting([first])
        checks.use_passed_checks(tmp_path / "cache")  # the next run: the store read from disk
        monkeypatch.setattr(reader, "check_points", None)  # checking would raise
        (again,), errors = load_scenarios_reporting([second])
    finally:
        checks.use_passed_checks(None)
    assert not errors and again.path == second
    assert again == replace(read, path=second) and again.point_list() == read.point_list()


def test_cache_info_and_prune_see_the_scenario_checks_store(tmp_path):
    ResultCache(tmp_path).make_root()  # marked as the harness's (a run does this)
    try:
        checks.use_passed_checks(tmp_path)
        load_scenarios_reporting([SCENARIO_DIR / "disk-direct.toml"])
    finally:
        checks.use_passed_checks(None)
    store = tmp_path / PassedChecks.FILE_NAME
    # the store and the installed engines' facts (which engines the checks depend on)
    facts = len(engine_facts(ENGINE_NAMES).versions)
    assert ResultCache(tmp_path).info()["entries"] == 1 + facts
    assert ResultCache(tmp_path).prune()["entries"] == 0  # this code's: kept
    assert ResultCache(tmp_path, version="other").prune()["entries"] == 1 + facts
    assert not store.exists()
