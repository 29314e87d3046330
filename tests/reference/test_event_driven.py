"""The event-driven reference for nearly simultaneous contacts (harness.reference)."""

from __future__ import annotations

import math

import numpy as np

from harness.reference.event_driven import event_sequence
from harness.scene import Body, Box, Rod, Scene
from harness.scene.geometry import place_on_ground
from planar_impact import simultaneous as sim


def flat_box(vx=0.0, omega=0.0, mu=0.5, e=0.5):
    """A 1 × 0.5 m box of 2 kg (I = 5/24 kg m²) falling flat at 1 m/s on two corners."""
    mass, width, height = 2.0, 1.0, 0.5
    inertia = mass * (width**2 + height**2) / 12.0
    corners = [(-width / 2, -height / 2), (width / 2, -height / 2)]
    wn = np.array([(0.0, 1.0, rx) for rx, _ in corners])  # n = +y: (n_x, n_y, r_x n_y − r_y n_x)
    wt = np.array([(1.0, 0.0, -ry) for _, ry in corners])  # t = +x
    return sim.contact_system(mass_matrix=np.diag([mass, mass, inertia]), wn=wn, wt=wt,
                              u=[vx, -1.0, omega], mu=mu, e=e)


def tilted_box(tilt_degrees, vx=0.0):
    body = Body("box", Box(1.0, 0.5), 2.0, (0.0, 1.0), angle=math.radians(tilt_degrees),
                velocity=(vx, -1.0))
    return Scene((place_on_ground(body),), restitution=0.5, friction=0.5, ground=True)


def test_tilted_box_gives_a_sequence_of_impacts():
    result = event_sequence(tilted_box(3.0), "poisson")
    assert result.finished
    features = [event.feature for event in result.events]
    # Tilted counter-clockwise, corner 0 (−w/2, −h/2) is lowest and strikes first; the
    # spin it receives brings corner 1 down, which strikes later.
    assert features[:2] == [0, 1]
    assert result.events[0].time == 0.0 and result.events[1].time > 0.0
    assert not any(event.simultaneous for event in result.events)
    # Every feature leaves the ground without approaching it again (no gravity).
    assert result.velocity[1] > 0


def test_vanishing_tilt_approaches_the_sequential_answer():
    """As the tilt → 0 the sequence tends to the contacts struck one at a time in the order
    the tilt chose (corner 0 first), not to a simultaneous law."""
    results, _ = sim.all_orders(flat_box(), "poisson")
    order_01 = next(r for r in results if r.order == (0, 1))
    gaps = []
    for tilt in (1.0, 0.1, 0.01):
        answer = event_sequence(tilted_box(tilt), "poisson").speeds()
        gaps.append(np.max(np.abs(answer - order_01.u_after)))
    assert gaps[0] > gaps[1] > gaps[2]
    assert gaps[2] < 1e-3  # linear in the tilt: ~1e-4 at 0.01°


def test_rod_tilted_strikes_both_caps():
    body = Body("rod", Rod(1.0, 0.05), 1.0, (0.0, 1.0), angle=math.radians(2.0),
                velocity=(0.0, -1.0))
    scene = Scene((place_on_ground(body),), restitution=0.8, friction=0.3, ground=True)
    result = event_sequence(scene, "stronge")
    assert result.finished
    assert {event.feature for event in result.events} == {0, 1}
