"""Preset roles and the names engines show for them (harness/engines/__init__.py, presets).

The harness runs, caches and records every engine by the same two roles, ``defaults`` and
``accurate``; MuJoCo shows its second role as ``matched-bounce`` because it matches the
bounce but not a dissipative law (docs/engines.md, 'MuJoCo'). These tests pin that the name
reaches every place a user sees or types a preset, and that its energy gains are flagged.
"""

from __future__ import annotations

import pytest

from harness.engines import (
    ENGINE_NAMES,
    PRESET_ROLES,
    EngineSettingsError,
    preset_choices,
    preset_label,
    preset_role,
    source_label,
)
from harness.run.plan import parse_presets
from harness.run.records import Record, Results


def test_only_mujoco_renames_a_role_and_roles_stay_the_harness_keys():
    assert PRESET_ROLES == ("defaults", "accurate")
    shown = {(engine, role): preset_label(engine, role)
             for engine in ENGINE_NAMES for role in PRESET_ROLES}
    renamed = {key: name for key, name in shown.items() if name != key[1]}
    assert renamed == {("mujoco", "accurate"): "matched-bounce"}
    assert source_label("mujoco", "accurate") == "mujoco.matched-bounce"
    assert source_label("pymunk", "accurate") == "pymunk.accurate"
    assert source_label("mujoco", None) == "mujoco"


def test_a_typed_name_selects_its_role():
    assert preset_role("mujoco", "matched-bounce") == "accurate"
    assert preset_role("mujoco", "defaults") == "defaults"
    assert preset_role("pybullet", "accurate") == "accurate"
    # Across engines (the CLIs' --preset), either name selects the role.
    assert preset_role(None, "matched-bounce") == preset_role(None, "accurate") == "accurate"
    assert preset_choices() == ("defaults", "accurate", "matched-bounce")
    with pytest.raises(ValueError, match="use mujoco.matched-bounce"):
        preset_role("mujoco", "accurate")
    with pytest.raises(ValueError, match="unknown preset 'matched-bounce'"):
        preset_role("pymunk", "matched-bounce")
    with pytest.raises(ValueError, match="unknown preset 'best'"):
        preset_role(None, "best")


def test_the_run_cli_accepts_the_name():
    assert parse_presets("matched-bounce") == ("accurate",)
    assert parse_presets("all") == PRESET_ROLES
    with pytest.raises(ValueError, match="matched-bounce"):
        parse_presets("exact")


def test_records_keep_the_role_and_show_the_name():
    records = [Record(scenario="s", point={}, source=engine, preset=role)
               for role in PRESET_ROLES for engine in ("pymunk", "mujoco")]
    assert [r.preset for r in records] == ["defaults", "defaults", "accurate", "accurate"]
    results = Results(records)
    assert results.engine_labels() == ["pymunk.defaults", "mujoco.defaults", "pymunk.accurate",
                                       "mujoco.matched-bounce"]
    assert results.engine_roles()[-1] == ("mujoco", "accurate")


def test_the_adapter_takes_either_name_and_records_the_role():
    pytest.importorskip("mujoco")
    from harness.engines import load_engine, preset_label
    from harness.scenarios import SCENARIO_DIR, load_scenario

    engine = load_engine("mujoco")
    assert engine.settings("matched-bounce") == engine.settings("accurate")
    assert preset_label("mujoco", "accurate") == "matched-bounce"
    scene = load_scenario(SCENARIO_DIR / "disk-oblique.toml").scene()
    assert engine.run(scene, preset="matched-bounce").preset == "accurate"
    with pytest.raises(EngineSettingsError, match="unknown preset 'matched-bounce'"):
        load_engine("pymunk").settings("matched-bounce")


def test_matched_bounce_energy_gain_is_flagged_and_counted(tmp_path):
    """``rod-50-newton-energy-gain``: MuJoCo's matched bounce gains more than newton-lcp does
    (the issue's measurement: +0.30 J against newton-lcp's +0.11 J), so the gain is the
    numerics' and fails the run; the summary names the run by its shown label and counts it.
    """
    pytest.importorskip("mujoco")
    from harness.report.summary import write_summary
    from harness.run import runner
    from harness.scenarios import SCENARIO_DIR, load_scenario

    scenario = load_scenario(SCENARIO_DIR / "rod-50-newton-energy-gain.toml")
    outcome = runner.run([scenario], engines=("mujoco",), presets=("accurate",), cache=None,
                         workers=1, log=None)
    (record,) = [r for r in outcome.records if r.source == "mujoco"]
    (law,) = [r for r in outcome.records if r.law == "newton-lcp"]
    assert record.label == "mujoco.matched-bounce"
    assert record.energy_change > law.energy_change > 0.0
    gain = [r for r in record.reasons if r["name"] == "energy-gain"]
    assert gain and gain[0]["attribution"] == "numerics" and gain[0]["fails"]
    assert not record.ok
    text = write_summary(Results(outcome.records, outcome.provenance, outcome.scenarios),
                         tmp_path).read_text()
    assert "| mujoco.matched-bounce |" in text
    assert "- energy-gain: 1" in text
    assert "mujoco.matched-bounce: energy-gain" in text
