"""Scenario.definition_digest: what a scenario's cached records are keyed by."""

from __future__ import annotations

from dataclasses import fields, replace
from pathlib import Path

from harness.scenarios import SCENARIO_DIR, checks, load_scenario
from harness.scenarios.reader import load_scenario as read_file
from harness.store.identity import canonical_json

ROD = load_scenario(SCENARIO_DIR / "rod-45-slip-reversal.toml")


def test_the_digest_is_of_every_field_but_the_path():
    import hashlib

    definition = {f.name: getattr(ROD, f.name) for f in fields(ROD) if f.name != "path"}
    assert ROD.definition_digest == hashlib.sha256(
        canonical_json(definition).encode()).hexdigest()
    assert replace(ROD, path=Path("elsewhere.toml")).definition_digest == ROD.definition_digest
    assert replace(ROD, friction=ROD.friction + 0.1).definition_digest != ROD.definition_digest


def test_located_keeps_the_digest_and_sets_the_path():
    digest = ROD.definition_digest
    moved = ROD.located(Path("other.toml"))
    assert moved.path == Path("other.toml") and moved == replace(ROD, path=Path("other.toml"))
    assert "definition_digest" in vars(moved) and moved.definition_digest == digest


def test_a_scenario_that_passed_before_has_the_same_digest(tmp_path):
    path = SCENARIO_DIR / "rod-45-slip-reversal.toml"
    store = checks.use_passed_checks(tmp_path)
    try:
        first = read_file(path)  # read, checked, its text's key remembered
        store.save()
        checks.use_passed_checks(tmp_path)
        again = read_file(path)  # passed before: read again, not checked
    finally:
        checks.use_passed_checks(None)
    assert again.path == path and again == first
    assert again.definition_digest == first.definition_digest == ROD.definition_digest
