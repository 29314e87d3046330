"""The event-driven reference for nearly simultaneous contacts (harness.reference)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from harness.reference import event_driven as ed
from harness.reference.event_driven import event_sequence
from harness.scene import Body, Box, Rod, Scene
from harness.scene.geometry import local_core, place_on_ground, rotation
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


def scanned_first_contact(points_local, radius, position, angle, velocity, omega, horizon,
                          size):
    """``_first_contact`` as it was: every sample of every feature in Python floats with
    math's cosine and sine, the first bracket by a scan. The reference for the array form."""
    samples = max(64, math.ceil(abs(omega) * horizon / 0.05) + 1)
    times = np.linspace(0.0, horizon, samples + 1)
    best_time, best_feature = None, None
    instants = times.tolist()
    turns = [(math.cos(angle + omega * t), math.sin(angle + omega * t)) for t in instants]
    lifts = [position[1] + velocity[1] * t for t in instants]
    for k in range(len(points_local)):
        x, y = (float(v) for v in points_local[k])
        heights = [lift + (s * x + c * y) - radius for lift, (c, s) in zip(lifts, turns)]
        for a in range(samples):
            low, high = times[a], times[a + 1]
            if best_time is not None and low >= best_time:
                break
            if heights[a] > ed.TOUCH_TOLERANCE * size and heights[a + 1] <= 0.0:
                for _ in range(200):
                    middle = 0.5 * (low + high)
                    if middle in (low, high):
                        break
                    if ed._height(points_local, radius, position, angle, velocity, omega,
                                  middle, k) > 0.0:
                        low = middle
                    else:
                        high = middle
                if best_time is None or high < best_time:
                    best_time, best_feature = high, k
                break
    return best_time, best_feature


def random_flight(rng):
    """A box or rod in free flight near the ground: its lowest feature 0-5 cm up (exactly
    0 in a quarter of the cases, as after an impact), any turn and spin, and a horizon of
    up to some thousands of samples."""
    if rng.random() < 0.5:
        shape = Box(rng.uniform(0.2, 2.0), rng.uniform(0.05, 1.0))
    else:
        shape = Rod(rng.uniform(0.2, 2.0), rng.uniform(0.001, 0.1))
    points, radius = local_core(shape)
    size = float(np.max(np.linalg.norm(points, axis=1))) + radius
    angle = rng.uniform(-math.pi, math.pi)
    lowest = float(np.min(points @ rotation(angle).T[:, 1])) - radius
    gap = 0.0 if rng.random() < 0.25 else rng.uniform(0.0, 0.05)
    position = np.array([rng.uniform(-1, 1), gap - lowest])
    velocity = np.array([rng.uniform(-1, 1), rng.uniform(-1.0, 1.0)])
    omega = rng.uniform(-10.0, 10.0) if rng.random() < 0.8 else 0.0
    horizon = 10 ** rng.uniform(-2, 1)
    return points, radius, position, angle, velocity, omega, horizon, size


def test_first_contact_matches_the_scan_bit_for_bit():
    rng = np.random.default_rng(11)
    strikes = 0
    for _ in range(400):
        flight = random_flight(rng)
        expected = scanned_first_contact(*flight)
        assert ed._first_contact(*flight) == expected
        strikes += expected[0] is not None
    assert 50 < strikes < 400  # both outcomes were compared


@pytest.mark.parametrize("law", ["poisson", "newton-lcp", "stronge"])
@pytest.mark.parametrize("tilt", [0.01, 0.3, 3.0])
def test_speeds_after_each_impact_are_the_cut_sequence(law, tilt):
    scene = tilted_box(tilt, vx=0.4)
    whole = event_sequence(scene, law)
    assert len(whole.events) >= 2
    for k, event in enumerate(whole.events, start=1):
        cut = event_sequence(scene, law, max_impacts=k)
        assert cut.events == whole.events[:k]
        assert np.array_equal(cut.speeds(), np.array(event.speeds_after))


@pytest.mark.parametrize("tilt, vx", [(3.0, 0.0), (0.5, 0.4), (12.0, -0.7), (0.0, 0.2)])
def test_sequences_sharing_their_start_are_those_computed_alone(tilt, vx):
    """event_sequence with ``shared`` (a scene's sequences under several laws, their common
    flights and first impact worked out once) gives each law's sequence bit for bit (repr
    tells -0.0 from 0.0), in either order of the laws."""
    scene = tilted_box(tilt, vx)
    laws = ("newton-lcp", "poisson", "stronge", "newton", "stronge-paper")
    alone = {law: repr(event_sequence(scene, law)) for law in laws}
    for order in (laws, laws[::-1]):
        shared: dict = {}
        for law in order:
            assert repr(event_sequence(scene, law, shared=shared)) == alone[law], law
        assert any(key[0] == "flight" for key in shared)  # something was shared
