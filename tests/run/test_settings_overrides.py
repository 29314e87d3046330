"""``--set ENGINE.KEY=VALUE`` on ``run`` and ``suite`` (issue 14, item 3).

An override reaches every run of its engine, the record's ``settings_overrides`` (which the
report shows in the labels), the complete settings hashed into the cache key, and the
provenance; a bad one is bad input (exit 2), one line, before any scenario is read.
"""

from __future__ import annotations

import json

import pytest

from harness import cli
from harness.engines import load_engine, parse_overrides
from harness.run import command as run_command
from harness.run import runner
from harness.scenarios import SCENARIO_DIR, load_scenario
from harness.store.cache import ResultCache

DISK = SCENARIO_DIR / "disk-direct.toml"


def test_values_are_json_else_strings_and_keys_of_one_engine_merge():
    overrides = parse_overrides(["pymunk.iterations=50", "pymunk.time_step=1e-4",
                                        "mujoco.integrator=Euler", "mujoco.solref=[0.02, 1]"])
    assert overrides == {"pymunk": {"iterations": 50, "time_step": 1e-4},
                         "mujoco": {"integrator": "Euler", "solref": [0.02, 1]}}
    assert isinstance(overrides["pymunk"]["iterations"], int)


BAD_SETS = {
    # case: (--set value, words the one line must hold)
    "unknown-engine": ("bullet3.iterations=5", ["bullet3", "iterations", "allowed", "pymunk"]),
    "unknown-key": ("pymunk.iteratons=5", ["pymunk", "iteratons", "allowed", "iterations"]),
    "bad-value": ("pymunk.iterations=abc", ["pymunk", "iterations", "abc", "allowed"]),
    "bad-choice": ("mujoco.integrator=Eular", ["mujoco", "integrator", "Eular", "RK4"]),
    "out-of-range": ("pymunk.time_step=-1", ["pymunk", "time_step", "-1", "allowed"]),
    "no-equals": ("pymunk.iterations", ["ENGINE.KEY=VALUE"]),
    "no-key": ("pymunk=5", ["ENGINE.KEY=VALUE"]),
}


@pytest.mark.parametrize("command", ["run", "suite"])
@pytest.mark.parametrize("case", sorted(BAD_SETS))
def test_a_bad_override_is_one_line_and_exit_2_before_any_work(tmp_path, monkeypatch, capsys,
                                                               case, command):
    value, words = BAD_SETS[case]

    def no_work(*args, **kwargs):
        raise AssertionError("scenarios loaded before the arguments were checked")

    from harness.scenarios import library

    monkeypatch.setattr(library, "load_scenarios_reporting", no_work)
    out = ["--json", str(tmp_path / "r.json")] if command == "run" else [
        "--out", str(tmp_path / "out")]
    status = cli.main([command, *([str(DISK)] if command == "run" else []), *out,
                       "--no-cache", "--set", value])
    err = capsys.readouterr().err
    assert status == 2
    assert err.count("\n") == 1, err
    for word in words:
        assert word in err, (word, err)


def test_an_override_of_an_engine_not_selected_is_refused(capsys, tmp_path):
    status = cli.main(["run", str(DISK), "--json", str(tmp_path / "r.json"), "--no-cache",
                       "--engines", "pymunk", "--set", "box2d.velocity_iterations=3"])
    assert status == 2
    assert "not selected" in capsys.readouterr().err


def test_overrides_reach_the_runs_the_records_the_cache_key_and_the_provenance(tmp_path):
    scenario = load_scenario(DISK)
    cache = ResultCache(root=tmp_path / "cache", version="test")
    plain = runner.run([scenario], engines=("pymunk",), presets=("defaults",), cache=cache,
                       workers=1, log=None)
    changed = runner.run([scenario], engines=("pymunk",), presets=("defaults",), cache=cache,
                         workers=1, log=None, overrides={"pymunk": {"time_step": 1e-3}})
    # A different setting is a different cache key: simulated, not the plain run's entry.
    assert plain.provenance["cache"]["simulated"] == 1
    assert changed.provenance["cache"]["simulated"] == 1
    [record] = [r for r in changed.records if r.source == "pymunk"]
    assert record.diagnostics["settings_overrides"] == {"time_step": 1e-3}
    assert changed.provenance["settings_overrides"] == {"pymunk": {"time_step": 1e-3}}
    assert changed.provenance["engine_settings"]["pymunk"]["defaults"]["time_step"] == 1e-3
    # The engine ran with it: the same run by hand under the same settings agrees exactly.
    engine = load_engine("pymunk")
    by_hand = engine.run(scenario.scene(scenario.point_list()[0]), preset="defaults",
                         overrides={"time_step": 1e-3})
    assert record.u_after == by_hand.u_after.tolist()
    assert record.diagnostics["steps"] == by_hand.steps


def test_a_set_run_never_silently_replaces_results_of_the_plain_selection(tmp_path, capsys):
    results = tmp_path / "r.json"
    assert cli.main(["run", str(DISK), "--json", str(results), "--no-cache",
                     "--engines", "pymunk"]) == 0
    recorded = json.loads(results.read_text())["provenance"]["selection"]
    assert "settings_overrides" not in recorded  # older results files compare equal
    args = cli.build_parser("run").parse_args(["run", str(DISK), "--engines", "pymunk",
                                          "--set", "pymunk.iterations=1"])
    status, _ = run_command.execute(args, json_path=results, guard=True, log=None)
    assert status == 2
    assert "another selection" in capsys.readouterr().err
    assert json.loads(results.read_text())["provenance"]["selection"] == recorded
