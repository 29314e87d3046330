"""The engines on the drops, made once for the report and the command (``cached.
ENGINES_ON_DROPS``): the report's aggregates keep them in the result cache as the command
makes them, so ``impact-harness experiments`` (and ``findings --check`` through it) after a
suite reads them instead of running every engine on every drop and calibrating it again.

Both are computed here on the synthetic copy, each in a cache of its own: the command's
tables and ``--json`` parts from the report's entry must be those it computes itself.
"""

from __future__ import annotations

import dataclasses
import json

import pytest

from harness import cli
from harness.engines import load_engine
from harness.experiments import (
    aggregates,
    cached,
    calibrated_errors,
    drops_engines,
    fazeli,
    registry,
)
from harness.report.experiments import section_tables
from harness.store.cache import ResultCache

COMMAND = ["--replicates", "10", "--workers", "1", "--engines", "pymunk"]
HEADINGS = ("### The engines on the drops",
            "### Every engine and law at its fitted or calibrated settings")


def _hashed_load(monkeypatch):
    """``fazeli.load`` with the files hashed but not checked against the published hashes
    (the synthetic copy's are not those)."""
    real_load = fazeli.load

    def load(path, check_hashes=True):
        data = real_load(path, check_hashes=False)
        return dataclasses.replace(data, hashes={
            file.name: registry.sha256_of(path / file.name)
            for file in registry.FAZELI_2017.files})

    monkeypatch.setattr(fazeli, "load", load)


def _parts(path) -> dict:
    section = json.loads(path.read_text())["fazeli2017"]
    calibrated = {k: v for k, v in section["calibrated_errors"].items() if k != "seconds"}
    return {"rows": json.dumps(section["engines_on_drops"], sort_keys=True),
            "calibrated": json.dumps(calibrated, sort_keys=True)}


def _no_engine_on_the_drops(*args, **kwargs):
    raise AssertionError("an engine ran on the drops again")


@pytest.mark.slow
def test_the_command_reads_what_the_reports_aggregates_kept(synthetic_copy, own_cache,
                                                            monkeypatch, capsys, tmp_path):
    directory, _ = synthetic_copy
    _hashed_load(monkeypatch)
    command = ["experiments", "--data", str(directory), *COMMAND]
    # the command alone, in the cache of its own: computed
    assert cli.main([*command, "--json", str(tmp_path / "alone.json")]) == 0
    alone = capsys.readouterr()
    assert "pymunk (defaults): every drop" in alone.err
    # a second cache: the report's aggregates first, then the command
    monkeypatch.setenv("IMPACT_HARNESS_CACHE_DIR", str(tmp_path / "after-report"))
    aggregates.compute(fazeli.load(directory), engines=[load_engine("pymunk")], replicates=10,
                       workers=1, cache=ResultCache())
    capsys.readouterr()
    monkeypatch.setattr(drops_engines, "run_drops", _no_engine_on_the_drops)
    monkeypatch.setattr(calibrated_errors, "calibrate_engine", _no_engine_on_the_drops)
    assert cli.main([*command, "--json", str(tmp_path / "after-report.json")]) == 0
    after_report = capsys.readouterr()
    assert "the engines on the drops: read from the cache" in after_report.err
    for heading in HEADINGS:
        assert section_tables(after_report.out, heading) == section_tables(alone.out, heading)
    assert _parts(tmp_path / "after-report.json") == _parts(tmp_path / "alone.json")


def test_nothing_is_kept_for_files_not_hashed(synthetic_copy, tmp_path, monkeypatch):
    """A copy loaded without its hashes has no key that tells it from another copy: the
    report keeps nothing of it (and the command reads nothing)."""
    directory, _ = synthetic_copy
    data = fazeli.load(directory, check_hashes=False)
    assert data.hashes == {}
    kept = []
    monkeypatch.setattr(cached, "engines_on_drops_put", lambda *args, **kw: kept.append(1))
    aggregates.compute(data, engines=[], replicates=10, workers=1,
                       cache=ResultCache(tmp_path / "cache"))
    assert kept == []


def test_an_entry_is_keyed_by_its_inputs_and_an_edited_one_is_not_believed(tmp_path):
    cache = ResultCache(tmp_path / "cache")
    key = cached.engines_on_drops_payload(
        {"data.mat": "ab"}, "published", {"law": "poisson", "objective": "impulse",
                                          "mu": 0.3, "e": 0.7},
        {"poisson": [0.3, 0.7]}, [["pymunk", "defaults"]], 0, 24, 1000)
    assert cached.engines_on_drops_get(cache, key) is None
    kept = cached.engines_on_drops_put(cache, key, [{"engine": "pymunk"}], {"laws": []}, 1.5)
    assert cached.engines_on_drops_get(cache, key) == kept
    # another input (here the headline fit's μ in its last bit) is another entry
    other = json.loads(json.dumps(key))
    other["settings"]["fit"]["mu"] = 0.30000000000000004
    assert cached.engines_on_drops_get(cache, other) is None
    # an entry edited after it was written (its checksum recomputed or not) is a miss
    (entry,) = (tmp_path / "cache").rglob("*.json")
    entry.write_text(entry.read_text().replace("pymunk", "pymunc"))
    assert cached.engines_on_drops_get(cache, key) is None
