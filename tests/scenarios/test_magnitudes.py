"""Supported magnitudes (schema.MAGNITUDES): what validates, runs; what cannot run, is refused.

Issue 11 found files that validated and then crashed the run (1e300 kg: ZeroDivisionError;
5e-324 kg, 1e-300 m: LinAlgError). The promise tested here: a file inside the ranges reads,
and every law solves it with finite departures; a value just outside is one error naming
the key and the range.
"""

from __future__ import annotations

import copy
import itertools
import math
import tomllib

import pytest

from harness.run import runner
from harness.scenarios import SCENARIO_DIR, ScenarioError, parse_scenario
from harness.scenarios.schema import MAGNITUDES, TINY

BASE = tomllib.loads((SCENARIO_DIR / "disk-oblique.toml").read_text(encoding="utf-8"))


def disk_document(**body_values) -> dict:
    document = copy.deepcopy(BASE)
    document.pop("expect", None)  # expectations hold for the library values only
    document.pop("sweep", None)
    document["body"][0].update(body_values)
    return document


MASS, LENGTH = MAGNITUDES["mass"], MAGNITUDES["length"]
SPEED, SPIN = MAGNITUDES["speed"][1], MAGNITUDES["angular_velocity"][1]
CORNERS = list(itertools.product(MASS, LENGTH, (TINY, SPEED), (0.0, SPIN, -SPIN),
                                 (0.0, MAGNITUDES["friction"][1])))


@pytest.mark.parametrize(("mass", "radius", "speed", "spin", "friction"), CORNERS)
def test_every_corner_of_the_ranges_reads_and_every_law_solves_it(mass, radius, speed, spin,
                                                                   friction):
    document = disk_document(mass=mass, radius=radius, velocity=[speed, -speed],
                             angular_velocity=spin)
    document["friction"] = friction
    scenario = parse_scenario(document, "corner.toml")
    outcome = runner.run([scenario], engines=(), log=None, workers=1)
    assert [r.status for r in outcome.records] == ["ok"] * len(scenario.laws)
    for record in outcome.records:
        assert all(math.isfinite(value) for value in record.departure.values())


@pytest.mark.parametrize(("key", "value"), [
    ("mass", MASS[1] * 1.001), ("mass", MASS[0] / 1.001), ("mass", 5e-324), ("mass", 1e300),
    ("radius", LENGTH[0] / 1.001), ("radius", LENGTH[1] * 1.001), ("radius", 1e-300),
    ("angular_velocity", SPIN * 1.001), ("angular_velocity", 1e-300),
    ("mass", 10**400),
])
def test_just_outside_a_range_is_one_error_naming_key_and_range(key, value):
    with pytest.raises(ScenarioError) as raised:
        parse_scenario(disk_document(**{key: value}), "outside.toml")
    (error,) = raised.value.errors
    assert error.key == f"body.disk.{key}"
    assert "supported range" in error.problem and "|value| <=" in error.allowed


def test_an_engine_at_a_corner_finishes_within_its_bounds():
    """The slowest corner (a grazing 1e-12 m/s approach) ends by the step cap, not a hang."""
    document = disk_document(mass=MASS[1], radius=LENGTH[1], velocity=[1.0, -TINY])
    scenario = parse_scenario(document, "corner.toml")
    outcome = runner.run([scenario], engines=("pymunk",), presets=("defaults",), log=None,
                         workers=1, time_limit_s=30)
    (engine,) = [r for r in outcome.records if r.source == "pymunk"]
    assert not engine.status.startswith("error")
