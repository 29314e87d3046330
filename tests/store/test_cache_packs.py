"""ResultCache packs: many records in one file, each checked on its own, removed only as
the cache's own; a run writes one pack per engine chunk, not one file per engine run."""

from __future__ import annotations

import importlib.util
import json
import os
from pathlib import Path

import pytest

from harness.run import runner
from harness.scenarios import load_scenario
from harness.store.cache import ResultCache
from harness.store.cache_directory import NotOurCache
from harness.store.packs import PACK_DIRECTORY, PACK_SIZE, PendingPuts

_spec = importlib.util.spec_from_file_location(
    "cache_entries", Path(__file__).parent.parent / "run" / "cache_entries.py")
cache_entries = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(cache_entries)

SWEEP = Path(__file__).resolve().parents[2] / "scenarios" / "sweep-disk-alpha.toml"


def _items(cache: ResultCache, count: int, start: int = 0) -> list[tuple[str, dict]]:
    return [(cache.key({"n": n}), {"status": "ok", "n": n, "velocities": [[0.1 * n, 0.0, -n]]})
            for n in range(start, start + count)]


def _packs(root: Path) -> list[Path]:
    return sorted((root / PACK_DIRECTORY).glob("*.pack"))


def test_records_put_together_are_one_file_and_read_back_each(tmp_path):
    cache = ResultCache(tmp_path, version="v")
    items = _items(cache, 5)
    cache.put_many(items)
    (pack,) = _packs(tmp_path)
    assert not list((tmp_path / PACK_DIRECTORY).glob(".*.tmp"))  # written atomically
    again = ResultCache(tmp_path, version="v")  # another process: reads the packs' headers
    assert [again.get(key) for key, _ in items] == [record for _, record in items]
    assert (again.hits, again.misses, again.rejected) == (5, 0, [])
    header, bodies = cache_entries.read_pack(pack)
    assert header["code_version"] == "v" and header["keys"] == [key for key, _ in items]
    assert [json.loads(body) for body in bodies] == [record for _, record in items]


def test_a_listed_cache_reads_the_packs_once_and_sees_its_own(tmp_path):
    writer = ResultCache(tmp_path, version="v")
    first, later, own = _items(writer, 2), _items(writer, 2, 10), _items(writer, 2, 20)
    writer.put_many(first)
    cache = ResultCache(tmp_path, version="v")
    with cache.listed():
        assert cache.get(first[0][0]) == first[0][1]
        ResultCache(tmp_path, version="v").put_many(later)  # another process, after the read
        cache.put_many(own)
        assert cache.get(later[0][0]) is None  # a miss: simulated again
        assert cache.get(own[1][0]) == own[1][1]
    assert cache.get(later[1][0]) == later[1][1]  # outside: a miss reads the new packs


def test_an_edited_record_is_a_miss_and_its_neighbours_are_read(tmp_path):
    cache = ResultCache(tmp_path, version="v")
    items = _items(cache, 4)
    cache.put_many(items)
    (pack,) = _packs(tmp_path)
    cache_entries.replace_record(pack, 2, json.dumps({"status": "ok", "n": 99}).encode(),
                                 sign=False)
    again = ResultCache(tmp_path, version="v")
    assert [again.get(key) is None for key, _ in items] == [False, False, True, False]
    (rejected,) = again.rejected
    assert str(pack) in rejected and "checksum differs" in rejected


@pytest.mark.parametrize("damage", ["truncated", "header-not-json", "header-not-a-pack"])
def test_a_pack_that_is_not_whole_is_a_miss_for_all_its_records(tmp_path, damage):
    cache = ResultCache(tmp_path, version="v")
    items = _items(cache, 3)
    cache.put_many(items)
    (pack,) = _packs(tmp_path)
    data = pack.read_bytes()
    if damage == "truncated":
        pack.write_bytes(data[:-5])
    elif damage == "header-not-json":
        pack.write_bytes(b"{" + data)
    else:
        pack.write_bytes(b'{"code_version": "v", "keys": "all"}\n' + data.partition(b"\n")[2])
    again = ResultCache(tmp_path, version="v")
    assert all(again.get(key) is None for key, _ in items)
    assert len(again.rejected) == 1 and str(pack) in again.rejected[0]


def test_another_code_versions_pack_is_not_indexed_nor_rejected(tmp_path):
    old = ResultCache(tmp_path, version="old")
    items = _items(old, 2)
    old.put_many(items)
    new = ResultCache(tmp_path, version="new")
    assert new.get(items[0][0]) is None  # its key, asked of the new code: a miss
    assert new.rejected == []


def test_prune_removes_the_packs_of_other_code_and_keeps_this_ones(tmp_path):
    old = ResultCache(tmp_path, version="old")
    old.put_many(_items(old, 2))
    new = ResultCache(tmp_path, version="new")
    items = _items(new, 2)
    new.put_many(items)
    assert new.prune()["entries"] == 1
    (kept,) = _packs(tmp_path)
    assert cache_entries.read_pack(kept)[0]["code_version"] == "new"
    assert ResultCache(tmp_path, version="new").get(items[0][0]) == items[0][1]


def test_more_records_than_a_pack_holds_make_several(tmp_path):
    cache = ResultCache(tmp_path, version="v")
    items = _items(cache, PACK_SIZE + 3)
    cache.put_many(items)
    assert len(_packs(tmp_path)) == 2
    again = ResultCache(tmp_path, version="v")
    assert again.get(items[-1][0]) == items[-1][1] and again.get(items[0][0]) == items[0][1]


def test_pending_puts_write_a_pack_when_full_and_the_rest_when_flushed(tmp_path):
    cache = ResultCache(tmp_path, version="v")
    pending = PendingPuts(cache)
    for key, record in _items(cache, PACK_SIZE + 1):
        pending.put(key, record)
    assert len(_packs(tmp_path)) == 1 and len(pending.items) == 1
    pending.flush()
    assert len(_packs(tmp_path)) == 2 and not pending.items
    PendingPuts(None).put("k", {})  # no cache: nothing stored, nothing raised


def test_pending_puts_write_what_waited_too_long(tmp_path, monkeypatch):
    clock = [100.0]
    monkeypatch.setattr("harness.store.packs.time.monotonic", lambda: clock[0])
    cache = ResultCache(tmp_path, version="v")
    pending = PendingPuts(cache, max_wait_s=2.0)
    first, second, third = _items(cache, 3)
    pending.put(*first)
    clock[0] += 1.0
    pending.put(*second)
    assert not _packs(tmp_path)
    clock[0] += 1.5  # the first waited 2.5 s: the three written, a kill loses none of them
    pending.put(*third)
    assert len(_packs(tmp_path)) == 1 and not pending.items


def test_clear_removes_the_packs_and_nothing_else_of_theirs(tmp_path):
    cache = ResultCache(tmp_path / "cache", version="v")
    cache.put_many(_items(cache, 3))
    cache.put(cache.key({"single": 1}), {"status": "ok"})
    packs = cache.root / PACK_DIRECTORY
    stale = packs / ".abcdef12-left-by-a-kill.tmp"
    stale.write_bytes(b"")
    assert cache.info()["entries"] == 2  # a pack and a single entry
    assert cache.clear()["entries"] == 2
    assert not stale.exists() and not packs.exists()
    assert sorted(os.listdir(cache.root)) == ["IMPACT-HARNESS-CACHE", "cache.key"]  # kept
    # a file of another name in the packs' directory is never the cache's to remove
    cache.put_many(_items(cache, 1))
    (packs / "notes.txt").write_text("mine")
    cache.clear()
    assert (packs / "notes.txt").read_text() == "mine" and not _packs(cache.root)


def test_an_unmarked_directory_with_packs_is_adopted_only_when_they_are_all_it_holds(tmp_path):
    cache = ResultCache(tmp_path / "cache", version="v")
    cache.put_many(_items(cache, 1))
    cache.marker.unlink()  # a cache of a harness before the marker
    assert ResultCache(tmp_path / "cache", version="v").prepare() is None
    assert cache.marked()
    cache.marker.unlink()
    (cache.root / PACK_DIRECTORY / "theirs.txt").write_text("theirs")
    assert "not a cache the harness made" in ResultCache(tmp_path / "cache").prepare()
    with pytest.raises(NotOurCache):
        ResultCache(tmp_path / "cache").clear()
    assert (cache.root / PACK_DIRECTORY / "theirs.txt").exists()


def test_a_run_writes_one_pack_per_chunk_not_one_file_per_engine_run(tmp_path):
    outcome = runner.run([load_scenario(SWEEP)], engines=("pymunk",), presets=("defaults",),
                         cache=ResultCache(tmp_path), workers=1, log=None, time_limit_s=None,
                         chunk_size=4)
    runs = [r for r in outcome.records if r.source != "analytic"]
    assert len(runs) == 9
    assert len(_packs(tmp_path)) == 3  # chunks of 4, 4 and 1
    assert len(cache_entries.engine_run_records(tmp_path)) == 9
    singles = [record for path, index, record in cache_entries.stored_records(tmp_path)
               if index is None]
    assert not any("velocities" in record for record in singles)  # engine facts only
