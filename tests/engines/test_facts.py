"""The engines' facts kept in the result cache (harness/engines/facts.py): what a warm run
reads instead of importing the engines equals what the loaded adapters report, and a warm
run notices an engine installed, removed or reinstalled (its install fingerprint changes)."""

from __future__ import annotations

import pytest

from harness import engines as registry
from harness.engines import ENGINE_NAMES, EngineNotInstalled, install_fingerprint, load_engine
from harness.engines import facts as facts_module
from harness.engines.facts import engine_facts
from harness.run import runner
from harness.scenarios import PRESETS, SCENARIO_DIR, checks, load_scenario
from harness.store.cache import ResultCache

ROD = load_scenario(SCENARIO_DIR / "rod-45-slip-reversal.toml")


def _installed() -> list[str]:
    return [name for name in ENGINE_NAMES if name not in engine_facts(ENGINE_NAMES).missing]


def _refuse_loading(monkeypatch):
    def refuse(name):
        raise AssertionError(f"{name} loaded although its facts are kept")

    monkeypatch.setattr(registry, "load_engine", refuse)


@pytest.mark.parametrize("name", ENGINE_NAMES)
def test_kept_facts_equal_what_the_loaded_adapter_reports(tmp_path, monkeypatch, name):
    if install_fingerprint(name) is None:
        pytest.skip(f"{name} is not installed")
    engine_facts([name], ResultCache(tmp_path))  # learnt by loading, and kept
    adapter = load_engine(name)
    _refuse_loading(monkeypatch)
    kept = engine_facts([name], ResultCache(tmp_path))
    assert kept.versions == {name: adapter.version} and not kept.missing
    assert kept.settings == {name: {preset: adapter.settings(preset, None)
                                    for preset in PRESETS}}


def test_a_changed_install_fingerprint_loads_the_engine_again(tmp_path, monkeypatch):
    name = _installed()[0]
    engine_facts([name], ResultCache(tmp_path))
    loads = []
    real = registry.load_engine
    monkeypatch.setattr(registry, "load_engine", lambda n: loads.append(n) or real(n))
    engine_facts([name], ResultCache(tmp_path))
    assert loads == []
    monkeypatch.setattr(facts_module, "install_fingerprint", lambda n: "reinstalled")
    engine_facts([name], ResultCache(tmp_path))
    assert loads == [name]


def test_without_the_cache_every_engine_is_loaded(tmp_path, monkeypatch):
    name = _installed()[0]
    engine_facts([name], ResultCache(tmp_path))
    _refuse_loading(monkeypatch)
    with pytest.raises(AssertionError, match="loaded although"):
        engine_facts([name], ResultCache(tmp_path, enabled=False))


def test_a_warm_run_notices_an_engine_removed_since(tmp_path, monkeypatch):
    name = "pymunk"
    if install_fingerprint(name) is None:
        pytest.skip("pymunk is not installed")
    cold = runner.run([ROD], engines=(name,), cache=ResultCache(tmp_path), log=None, workers=1)
    assert not cold.provenance["engines_missing"]

    def removed(engine):
        raise EngineNotInstalled(engine, "removed (test)")

    monkeypatch.setattr(facts_module, "install_fingerprint", lambda n: None)
    monkeypatch.setattr(registry, "load_engine", removed)
    warm = runner.run([ROD], engines=(name,), cache=ResultCache(tmp_path), log=None, workers=1)
    assert name in warm.provenance["engines_missing"]
    assert name not in warm.provenance["engine_versions"]
    engine_records = [r for r in warm.records if r.source == name]
    assert engine_records and all(r.skipped for r in engine_records)


def test_the_checks_context_follows_the_installed_engines(tmp_path, monkeypatch):
    before = checks._checks_context(tmp_path)
    name = _installed()[0]
    assert f'"{name}"' in before

    def removed(engine):
        if engine == name:
            raise EngineNotInstalled(engine, "removed (test)")
        return load_engine(engine)

    real_fingerprint = facts_module.install_fingerprint
    monkeypatch.setattr(facts_module, "install_fingerprint",
                        lambda n: None if n == name else real_fingerprint(n))
    monkeypatch.setattr(registry, "load_engine", removed)
    after = checks._checks_context(tmp_path)
    assert after != before and f'"{name}"' not in after
