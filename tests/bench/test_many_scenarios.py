"""``harness.bench.many_scenarios``: valid, distinct, perturbed copies of the library."""

from __future__ import annotations

import tomllib

from harness.bench import many_scenarios
from harness.scenarios.library import load_scenarios, scenario_files


def test_copies_load_as_scenarios_with_values_within_the_spread(tmp_path):
    originals = {tomllib.loads(p.read_text())["name"]: tomllib.loads(p.read_text())
                 for p in scenario_files()}
    count = len(originals) + 3  # every library file, and a second round
    paths = many_scenarios.write_copies(tmp_path, count, seed=1)
    scenarios = load_scenarios(tmp_path)
    assert len(scenarios) == count == len({s.name for s in scenarios})
    spread = many_scenarios.SPREAD
    for path in paths:
        copy = tomllib.loads(path.read_text())
        original = originals[copy["name"].rsplit("-", 1)[0]]
        assert "expect" not in copy
        for key in ("restitution", "friction"):
            if original.get(key):
                ratio = copy[key] / original[key]
                assert 1 - spread <= ratio <= 1 + spread or copy[key] == 1.0
        for body, before in zip(copy.get("body", []), original.get("body", [])):
            for value, old in zip(body.get("velocity", ()), before.get("velocity", ())):
                if old:
                    assert 1 - spread <= value / old <= 1 + spread
            assert {k: v for k, v in body.items() if k != "velocity"} == \
                {k: v for k, v in before.items() if k != "velocity"}
