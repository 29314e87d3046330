"""validate finds a second feature striking within the impact (docs/verdicts.md,
'Sequences found before any run'): an error unless the file sets ``expect_sequence``."""

from __future__ import annotations

import tomllib

import pytest

from harness.scenarios import SCENARIO_DIR, ScenarioError, load_scenarios, parse_scenario
from harness.scenarios.checks import SEQUENCE_HORIZON_STEPS, second_strike
from harness.scene import geometry

TILTED = ("sweep-tilted-box", "sweep-tilted-rod")


def document(name):
    return tomllib.loads((SCENARIO_DIR / f"{name}.toml").read_text(encoding="utf-8"))


@pytest.mark.parametrize("name", TILTED)
def test_a_tilted_sweep_without_the_opt_in_is_refused_at_every_point(name):
    doc = document(name)
    assert doc.pop("expect_sequence") is True
    with pytest.raises(ScenarioError) as caught:
        parse_scenario(doc)
    errors = caught.value.errors
    assert len(errors) == len(doc["sweep"]["values"])
    assert all(e.key == "expect_sequence" and "second feature strikes" in e.problem
               for e in errors)
    assert all(("corner 1" if "box" in name else "end cap at +length/2") in e.problem
               for e in errors)


@pytest.mark.parametrize("name", TILTED)
def test_the_opt_in_lets_the_sweep_validate(name):
    scenario = parse_scenario(document(name))
    assert scenario.expect_sequence and len(scenario.point_list()) == 6


def test_expect_sequence_must_be_a_boolean():
    doc = document("sweep-tilted-rod")
    doc["expect_sequence"] = "yes"
    with pytest.raises(ScenarioError) as caught:
        parse_scenario(doc)
    assert any(e.key == "expect_sequence" and "true or false" in e.problem
               for e in caught.value.errors)


def test_no_other_library_point_has_a_second_strike_within_the_horizon():
    """The rest of the library is single impacts: the check (at pymunk's 1/60 s, the
    coarsest step) finds no second strike there, while both tilted sweeps opt in."""
    step = 1.0 / 60.0
    for scenario in load_scenarios():
        if scenario.system != "bodies":
            continue
        for point in scenario.point_list():
            scene = scenario.scene(point)
            strike = second_strike(scene, geometry.scene_contact(scene),
                                   SEQUENCE_HORIZON_STEPS * step, step)
            assert (strike is not None) == scenario.expect_sequence, (
                scenario.name, point.label, strike and strike.describe())


def test_a_strike_time_matches_the_closed_form_for_a_flat_rod():
    """A uniform thin rod lying almost flat, struck at one end with no friction: m_nn = 4/m
    (lever L/2, I = mL²/12), I_n = (1+e)·m·v/4, and the far end then comes down at
    v·(1 + 3(1+e)/4) − (1+e)v/4 = v·(1 + (1+e)/2) (docs/theory.md, 'Contact terms'). Its
    height L·sin θ is closed in L·sin θ / (v (1 + (1+e)/2)); the capsule's caps sit on the
    same line, so the same holds. Tolerance 1e-5 relative: the bisection's 2^-30 of a
    sample, and the tilt's O(θ²) change of the lever arms (θ = 0.1°: 3e-6)."""
    import math

    from harness.scene import Body, Rod, Scene

    theta, length, speed, e = math.radians(0.1), 1.0, 1.0, 0.5
    # the thin rod's inertia mL²/12 given explicitly (the capsule's caps would add ~5e-4)
    body = geometry.place_on_ground(Body("rod", Rod(length, 1e-4), 1.0, (0.0, 1.0),
                                         angle=theta, velocity=(0.0, -speed),
                                         inertia=length**2 / 12.0))
    scene = Scene((body,), e, 0.0, ground=True)
    strike = second_strike(scene, geometry.scene_contact(scene), 1.0, 1e-9)
    expected = length * math.sin(theta) / (speed * (1.0 + (1.0 + e) / 2.0))
    assert strike.time_s == pytest.approx(expected, rel=1e-5)
