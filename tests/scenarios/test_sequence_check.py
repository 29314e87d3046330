"""validate finds a second feature striking within the impact (docs/verdicts.md,
'Sequences found before any run'): an error unless the file sets ``expect_sequence``."""

from __future__ import annotations

import tomllib

import numpy as np
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


def _touching_pair(rng):
    """Two bodies of random shapes, turns and speeds, B moved along the normal to touch A."""
    from harness.scene import Body, Box, Disk, Polygon, Rod

    def shape():
        return rng.choice([Disk(float(rng.uniform(0.02, 0.3))),
                           Rod(float(rng.uniform(0.2, 1.0)), float(rng.uniform(0.005, 0.05))),
                           Box(float(rng.uniform(0.1, 0.8)), float(rng.uniform(0.05, 0.5))),
                           Polygon(((0.0, 0.3), (-0.2, -0.1), (0.25, -0.15)))])

    def speeds():
        return tuple(rng.uniform(-3.0, 3.0, 2).tolist()), float(rng.uniform(-20.0, 20.0))

    (va, wa), (vb, wb) = speeds(), speeds()
    a = Body("a", shape(), 1.0, (0.0, 0.0), float(rng.uniform(-3.2, 3.2)), va, wa)
    b = Body("b", shape(), float(rng.uniform(0.2, 2.0)),
             tuple((rng.uniform(-0.4, 0.4, 2) + (0.0, 0.9)).tolist()),
             float(rng.uniform(-3.2, 3.2)), vb, wb)
    contact = geometry.body_contact(a, b)
    shifted = np.asarray(b.position) - contact.gap * np.asarray(contact.normal)
    return a, b.moved(position=(float(shifted[0]), float(shifted[1])))


def test_two_bodies_strike_as_found_by_the_full_sample_by_sample_scan(monkeypatch):
    """Between two bodies the samples no feature can reach are skipped on a bound of the gap
    (checks._first_body_touch); the strike found (body, feature, time to the bit, motion)
    is the one the scan from the first sample finds, strike or none."""
    from harness.scenarios import checks
    from harness.scene import Scene

    rng = np.random.default_rng(2026)
    found = []
    for _ in range(300):
        a, b = _touching_pair(rng)
        scene = Scene((a, b), float(rng.uniform(0.0, 1.0)), float(rng.uniform(0.0, 1.0)))
        contact = geometry.scene_contact(scene)
        horizon = float(rng.choice([1.0 / 30.0, 0.2, 1.0]))
        found.append(second_strike(scene, contact, horizon, horizon / 2.0))
    with monkeypatch.context() as patch:
        patch.setattr(checks, "_first_body_touch", lambda *args: 0)
        rng = np.random.default_rng(2026)
        for strike in found:
            a, b = _touching_pair(rng)
            scene = Scene((a, b), float(rng.uniform(0.0, 1.0)), float(rng.uniform(0.0, 1.0)))
            contact = geometry.scene_contact(scene)
            horizon = float(rng.choice([1.0 / 30.0, 0.2, 1.0]))
            assert second_strike(scene, contact, horizon, horizon / 2.0) == strike
    strikes = sum(s is not None for s in found)
    assert 30 < strikes < 270, strikes  # strikes and single impacts both among them
