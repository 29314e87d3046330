"""Box2D's velocity scale: the first-touch speed computed from the scene, and the scale
decided from it within a band (harness/engines/box2d/scaling.py)."""

from __future__ import annotations

import math
import random

import pytest

pytest.importorskip("Box2D", reason="Box2D not installed (pip install box2d==2.3.10)")

from harness.engines.box2d import scaling  # noqa: E402
from harness.scene import Body, Box, Rod, Scene  # noqa: E402
from harness.scene.reference import reference_scenes  # noqa: E402
from harness.survey.population import resolve_populations  # noqa: E402
from harness.survey.sampling import sample_population  # noqa: E402

SAMPLES = 40  # per population


@pytest.fixture(scope="module")
def scenes():
    return ([sample.scene for population in resolve_populations([])
             for sample in sample_population(population, SAMPLES, seed=7).samples]
            + [entry[0] for entry in reference_scenes().values()])


def test_the_written_out_speed_is_the_geometry_modules(scenes):
    # Two methods: the written-out formulas (ground, two disks, rod and disk) against the
    # contact points and normal of harness.scene.geometry and its contact_velocity. Both
    # compute the same exact quantity, so they agree within the sum of their bounds.
    compared = 0
    for scene in scenes:
        if scene.bodies[-1].shape.kind == "ellipse":
            continue  # the geometry module's ellipse is exact, Box2D's is its stand-in
        written, bound = scaling.first_touch_speed(scene)
        geometric, geometric_bound = scaling._geometry_speed(scene)
        assert abs(written - geometric) <= bound + geometric_bound, scene.name
        assert 0.0 < bound < 1e-12 * max(abs(written), 1.0)
        compared += 1
    assert compared > 250


@pytest.mark.parametrize("shape", [Rod(length=0.4, radius=0.01), Box(width=0.4, height=0.1)])
def test_a_flat_landing_takes_its_fastest_point(shape):
    # Both ends touch at once: the faster approaching one counts.
    lowest = shape.radius if shape.kind == "rod" else shape.height / 2.0
    body = Body("flat", shape, 1.0, (0.3, lowest), velocity=(0.5, -0.4), angular_velocity=3.0)
    scene = Scene((body,), 0.5, 0.3, ground=True)
    speed, _ = scaling.first_touch_speed(scene)
    assert speed == max(-(-0.4 + 3.0 * x) for x in (-0.2, 0.2)) == 1.0
    # Tilted by more than the touch band, only the lower end touches (the left one).
    tilted = Scene((body.moved(angle=1e-3),), 0.5, 0.3, ground=True)
    x, y = -0.2, (0.0 if shape.kind == "rod" else -0.05)
    lever = math.cos(1e-3) * x - math.sin(1e-3) * y
    assert scaling.first_touch_speed(tilted)[0] == -(-0.4 + 3.0 * lever)


def _scale_on_another_machine(speed: float, bound: float, shift: float) -> float:
    return scaling._auto_scale(speed + shift * bound, bound)[0]


def test_the_scale_is_the_smallest_power_of_two_lifting_the_speed_to_the_margin():
    generator = random.Random(3)
    target = scaling._AUTO_MARGIN * scaling.VELOCITY_THRESHOLD
    for _ in range(20000):
        speed = 10.0 ** generator.uniform(-6.0, 3.0)
        bound = speed * 10.0 ** generator.uniform(-16.0, -8.0)
        scale, at_boundary = scaling._auto_scale(speed, bound)
        assert scale >= 1.0 and math.frexp(scale)[0] == 0.5  # a power of two
        if not at_boundary:
            assert scale * speed >= target
            assert scale == 1.0 or scale / 2.0 * speed < target
        # Another machine's speed lies within 2·bound of this one's: a different scale
        # there only where this run says it is at the boundary.
        for shift in (-2.0, -1.0, 1.0, 2.0):
            if _scale_on_another_machine(speed, bound, shift) != scale:
                assert at_boundary, (speed, bound, shift)


@pytest.mark.parametrize("speed, expected, at_boundary", [
    (0.25, 16.0, True),  # 8 · 0.25 is 2 m/s exactly: the larger scale, at the boundary
    (0.3, 8.0, False),
    (1.0, 4.0, True),
    (2.0, 2.0, True),
    (2.5, 1.0, False),
    (0.0, 1.0, False),  # no approach: no scale
    (-1.0, 1.0, False),
])
def test_the_scale_at_and_off_the_boundary(speed, expected, at_boundary):
    bound = 8.0 * 2.0**-53 * abs(speed)
    assert scaling._auto_scale(speed, bound) == (expected, at_boundary)


def _exact_rod_disk_speed(rod, disk) -> float:
    # The rod-and-disk formula of first_touch_speed in exact rational arithmetic, given the
    # cos and sin libm returned (their own error is a separate 2u of the bound).
    from decimal import Decimal, localcontext
    from fractions import Fraction as F

    cos, sin = F(math.cos(rod.angle)), F(math.sin(rod.angle))
    half = F(rod.shape.length) / 2
    w_x = F(disk.position[0]) - F(rod.position[0])
    w_y = F(disk.position[1]) - F(rod.position[1])
    along = min(max(w_x * cos + w_y * sin, -half), half)
    d_x, d_y = w_x - along * cos, w_y - along * sin
    rate = F(rod.angular_velocity)
    dv_x = F(disk.velocity[0]) - (F(rod.velocity[0]) - rate * along * sin)
    dv_y = F(disk.velocity[1]) - (F(rod.velocity[1]) + rate * along * cos)
    numerator, square = -(dv_x * d_x + dv_y * d_y), d_x * d_x + d_y * d_y
    with localcontext() as context:
        context.prec = 60
        root = (Decimal(square.numerator) / Decimal(square.denominator)).sqrt()
        return float(Decimal(numerator.numerator) / Decimal(numerator.denominator) / root)


@pytest.mark.parametrize("radius", [1.0, 50.0, 1e3, 1e5])
@pytest.mark.parametrize("phi", [0.7, 1.3, 2.2, -0.4])
def test_a_spinning_rod_lying_on_a_large_disk_is_within_the_bound(radius, phi):
    # The rod tangent to the disk: the closest point of its segment to the disk's centre
    # sits mid-rod, where ``along`` (a dot product of the centres' offset |w|, about the
    # disk's radius) carries rounding of |w|, which the spin turns into normal speed.
    from harness.scene.model import Disk

    rod_radius, half = 0.001, 0.01
    cos, sin = math.cos(phi), math.sin(phi)
    disk = Body("disk", Disk(radius), 1.0, (0.0, 0.0))
    rod = Body("rod", Rod(length=2 * half, radius=rod_radius), 1.0,
               ((radius + rod_radius) * cos, (radius + rod_radius) * sin),
               angle=phi + math.pi / 2, velocity=(-0.1 * cos, -0.1 * sin),
               angular_velocity=1000.0)
    exact = _exact_rod_disk_speed(rod, disk)
    for bodies in ((rod, disk), (disk, rod)):
        speed, bound = scaling.first_touch_speed(Scene(bodies, 0.5, 0.3))
        assert abs(speed - exact) <= bound, (speed, exact, bound)


def _nudged_math(cos_way: int, sin_way: int):
    # math with cos and sin one ulp off (another libm, within its 1 ulp)
    import types

    nudged = types.SimpleNamespace(**{name: getattr(math, name) for name in dir(math)
                                      if not name.startswith("_")})
    nudged.cos = lambda x: math.nextafter(math.cos(x), cos_way * math.inf) if cos_way \
        else math.cos(x)
    nudged.sin = lambda x: math.nextafter(math.sin(x), sin_way * math.inf) if sin_way \
        else math.sin(x)
    return nudged

def _flips_only_at_the_boundary(monkeypatch, scene, where) -> int:
    """1 where libm's cos and sin nudged an ulp either way (:func:`_nudged_math`) change the
    scene's velocity scale, else 0; where they do, every one of the decisions is at the
    boundary (``where``: what the failure names)."""
    from harness.engines.box2d.building import _extent

    decisions = set()
    for ways in ((0, 0), (1, 0), (-1, 0), (0, 1), (0, -1), (1, 1), (-1, -1)):
        monkeypatch.setattr(scaling, "math", _nudged_math(*ways))
        decisions.add(scaling._scale_decision(scene, _extent(scene))[2:])
    monkeypatch.setattr(scaling, "math", math)
    if len({scale for scale, _ in decisions}) == 1:
        return 0
    assert all(at_boundary for _, at_boundary in decisions), (where, decisions)
    return 1



def test_a_point_at_the_touch_bands_edge_is_a_decision_at_the_boundary(monkeypatch):
    # A triangle landing on a face tilted so that the face's far end lies at the touch
    # band's edge (2^-22 extents above the lowest point): whether it counts rests on the
    # last bits of cos and sin. The far end approaches at 0.26 m/s (scale 8), the near one
    # at 0.24 (scale 16): where machines a libm ulp apart pick different scales, each must
    # say it is at the boundary.
    from harness.engines.box2d.building import _extent
    from harness.scene.model import Polygon

    raw = [(0.0, 0.0), (0.3, 0.1), (0.0, 0.3)]
    centre = (sum(x for x, _ in raw) / 3, sum(y for _, y in raw) / 3)
    shape = Polygon(tuple((x - centre[0], y - centre[1]) for x, y in raw))
    band = scaling._TOUCH_EXTENTS * _extent(Scene((Body("p", shape, 1.0, (0.0, 0.5)),), 0.5,
                                                  0.3, ground=True))
    edge = -math.atan2(0.1, 0.3) + band / math.hypot(0.3, 0.1)
    cos, sin = math.cos(edge), math.sin(edge)
    (x_0, y_0), (x_1, y_1) = shape.points[:2]
    lever_0, lever_1 = cos * x_0 - sin * y_0, cos * x_1 - sin * y_1
    rate = -0.02 / (lever_1 - lever_0)
    v_y = -0.24 - rate * lever_0
    flipped = 0
    for step in range(-300, 300):
        body = Body("p", shape, 1.0, (0.0, 0.5), angle=edge + step * 1e-18,
                    velocity=(0.0, v_y), angular_velocity=rate)
        scene = Scene((body,), 0.5, 0.3, ground=True)
        flipped += _flips_only_at_the_boundary(monkeypatch, scene, step)
    assert flipped > 0  # the window holds the edge


def test_a_corner_at_the_touch_bands_edge_between_two_boxes_is_at_the_boundary(monkeypatch):
    # A box landing on another's top face tilted so that its far bottom corner lies at the
    # touch band's edge: in or out of the contact as the last bits of cos and sin fall. The
    # near corner approaches at about 0.24 m/s (scale 16), the far at 0.26 (scale 8).

    width, height, base = 0.4, 0.1, 0.3
    lower = Body("a", Box(1.0, 0.2), 1.0, (0.0, 0.0), angle=base)
    band = scaling._TOUCH_EXTENTS * math.hypot(0.5, 0.1)
    edge = base + math.asin(band / width)
    cos_a, sin_a = math.cos(base), math.sin(base)
    corner = (cos_a * 0.05 - sin_a * 0.1, sin_a * 0.05 + cos_a * 0.1)  # on a's top face
    flipped = 0
    for step in range(-300, 300):
        angle = edge + step * 1e-18
        cos_b, sin_b = math.cos(angle), math.sin(angle)
        centre = (corner[0] + cos_b * width / 2 - sin_b * height / 2,
                  corner[1] + sin_b * width / 2 + cos_b * height / 2)
        upper = Body("b", Box(width, height), 1.0, centre, angle=angle,
                     velocity=(sin_a * 0.25, -cos_a * 0.25), angular_velocity=-0.05)
        scene = Scene((lower, upper), 0.5, 0.3)
        flipped += _flips_only_at_the_boundary(monkeypatch, scene, step)
    assert flipped > 0  # the window holds the edge


def test_a_corner_on_a_corner_is_a_decision_at_the_boundary(monkeypatch):
    # Two boxes corner to corner: A's top face and its right face are equally the face of
    # least penetration, and which one wins (so the normal, and the speed: 0.24 m/s along
    # one, 0.26 along the other) rests on the last bits of cos and sin.

    flipped = 0
    for step in range(40):
        angle = 0.3 + step * 1e-3
        cos, sin = math.cos(angle), math.sin(angle)
        lower = Body("a", Box(0.4, 0.1), 1.0, (0.0, 0.0), angle=angle)
        upper = Body("b", Box(0.4, 0.1), 1.0, (cos * 0.4 - sin * 0.1, sin * 0.4 + cos * 0.1),
                     angle=angle, velocity=(-cos * 0.26 + sin * 0.24, -sin * 0.26 - cos * 0.24))
        scene = Scene((lower, upper), 0.5, 0.3)
        flipped += _flips_only_at_the_boundary(monkeypatch, scene, angle)
    assert flipped > 0
