"""The velocity scaling that serves ``e`` below Box2D's restitution threshold, and the
impact speed it needs, computed from the scene.

Box2D's problem: ``b2_velocityThreshold`` (1 m/s) is compiled into pybox2d, and a contact
point slower than it gets ``e = 0``. The laws are homogeneous in lengths and velocities, so
the run is a scaled copy of the scene (package docstring, "The restitution threshold"):
:func:`first_touch_speed` computes the approach speed at the first touch from the scene in
double precision, with a bound on its rounding; :func:`_prepared` picks the velocity scale
(a decision within a band, :func:`_auto_scale`) and the start a hair deep from it. Box2D's
own view of the speed (float32, in the scaled world) is read in the run itself
(:func:`_speed_results`).
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

from Box2D import b2

from harness.engines.box2d.building import _extent, _outline
from harness.engines.box2d.manifold import _approach_speed
from harness.engines.box2d.presets import (
    _BOOL_KEYS,
    MAX_ROTATION,
    MAX_TRANSLATION,
    VELOCITY_THRESHOLD,
)
from harness.engines.box2d.readout import _TOUCHING, _contact_in
from harness.scene import Scene, geometry

if TYPE_CHECKING:
    from harness.engines.box2d.world import _World

# "auto" lifts the first contact's approach speed to this multiple of the threshold: a margin
# of 2 keeps float32 rounding of the solver's own v_rel (computed anew) far from the edge.
_AUTO_MARGIN = 2.0
_MAX_AUTO_SCALE = 2.0**40  # a scene slower than 2^-39 m/s is refused rather than scaled
THRESHOLD_NOTE = "impact at or below b2_velocityThreshold (1 m/s): Box2D used e = 0"
_UNIT_ROUNDOFF = 2.0**-53
_POLYGONS = ("box", "polygon")
# Points of the first touch: those within this many body extents of the closest (the
# accurate preset's start depth, 2^-22 extents: the points Box2D finds touching at its start).
_TOUCH_EXTENTS = 2.0**-22


class _SpeedProbe(b2.contactListener):
    """PreSolve listener of a :class:`_World`: the approach speed at the run's first touching
    contact (:func:`_approach_speed`), for a run not touching at its start."""

    def __init__(self, world: _World):
        super().__init__()
        self.world = world
        self.speed: float | None = None

    def PreSolve(self, contact, old_manifold):
        if self.speed is not None:
            return
        values = _contact_in(contact)
        if values[0] & _TOUCHING and values[17]:
            self.speed = _approach_speed(values, self.world)


# ---------------------------------------------------------------------- the impact speed
def _core(shape) -> tuple[list, float]:
    """The body-frame core points and swept radius Box2D is given (:mod:`.building`: an
    ellipse is its stand-in polygon, a rod its two end caps' centres)."""
    if shape.kind == "disk":
        return [(0.0, 0.0)], float(shape.radius)
    if shape.kind == "rod":
        half = shape.length / 2.0
        return [(-half, 0.0), (half, 0.0)], float(shape.radius)
    return _outline(shape), 0.0


def first_touch_speed(scene: Scene, extent: float | None = None) -> tuple[float, float]:
    """``(speed, bound)`` of :func:`_first_touch` (its docstring)."""
    return _first_touch(scene, extent)[:2]


def _first_touch(scene: Scene, extent: float | None = None) -> tuple[float, float, tuple]:
    """``(speed, bound)``: the normal approach speed (m/s, positive approaching) at the
    fastest-approaching point of the scene's first touch, in double precision, and a bound on
    its distance from the exact value of the same formula (the rounding of its IEEE
    operations and of libm's ``cos``/``sin``, each within 1 ulp, 2u relative).

    The scene's pose is its first touch (the run's start is that pose rewound or advanced
    along free flight, which keeps every velocity), so this is the quantity Box2D's solver
    computes at its first touching contact (``v_rel``, :func:`_approach_speed`), there from
    float32 state. The points are those within :data:`_TOUCH_EXTENTS` body extents of the
    closest (a flat landing's several); the fastest of them counts, as Box2D's fastest
    point of its first contact did. ``extent``: the scene's largest body extent (m), when
    known.

    The third value: the speeds the first touch has where another machine's rounding could
    count another set of points (on the ground, a point within rounding of the touch band's
    edge: in or out, the fastest changes by far more than ``bound``); empty elsewhere.
    :func:`_scale_decision` is at the boundary where one of them picks another scale.
    """
    u = _UNIT_ROUNDOFF
    if extent is None:
        extent = _extent(scene)
    if scene.ground:
        (body,) = scene.bodies
        points, _ = _core(body.shape)
        cos, sin = math.cos(body.angle), math.sin(body.angle)
        heights = [sin * x + cos * y for x, y in points]  # above the centre, +y the normal
        near = min(heights) + _TOUCH_EXTENTS * extent
        v_y, rate = body.velocity[1], body.angular_velocity
        # A height is within 4u of |s·x| + |c·y| (libm's 2u, the product's and the sum's u),
        # near within that of the lowest's and u of itself: a point's height - near within
        # ``slack`` here, within 2·slack on another machine.
        reach = max(abs(sin * x) + abs(cos * y) for x, y in points)
        slack = 16.0 * u * (reach + abs(near))
        fastest, size, edge = -math.inf, 0.0, []
        for (x, y), height in zip(points, heights):
            lever = cos * x - sin * y  # the point's x offset from the centre
            if height <= near:
                fastest = max(fastest, -(v_y + rate * lever))
                size = max(size, abs(v_y) + abs(rate) * (abs(cos * x) + abs(sin * y)))
            if abs(height - near) <= 2.0 * slack:  # in or out, as another machine counts it
                edge.append((height <= near, -(v_y + rate * lever)))
        # lever: c·x and s·y within 3u each (libm's 2u, the product's u), their difference
        # u more; ω·lever and the sum a u each: within 6u of size (1 + O(u)).
        others = []
        if edge:  # the fastest of the points counted without, or with, each edge point
            certain = max((-(v_y + rate * (cos * x - sin * y))
                           for (x, y), height in zip(points, heights)
                           if height <= near and abs(height - near) > 2.0 * slack),
                          default=-math.inf)
            others = [certain] + [max(certain, speed) for _, speed in edge]
            others = [other for other in others if other != fastest and other > -math.inf]
        return fastest, 8.0 * u * size, tuple(others)
    body_a, body_b = scene.bodies
    kinds = (body_a.shape.kind, body_b.shape.kind)
    if kinds == ("disk", "disk"):
        # The line of centres is the normal; a disk's spin moves its contact point along
        # the tangent only.
        d_x = body_b.position[0] - body_a.position[0]
        d_y = body_b.position[1] - body_a.position[1]
        distance = math.hypot(d_x, d_y)
        if distance == 0.0:
            return 0.0, 0.0, ()
        dv_x = body_b.velocity[0] - body_a.velocity[0]
        dv_y = body_b.velocity[1] - body_a.velocity[1]
        # d and dv within u of themselves, hypot within 1 ulp: the normal within 4u per
        # component, the dot product 3u more, of |dv_x| + |dv_y|.
        return (-(dv_x * d_x + dv_y * d_y) / distance,
                8.0 * u * (abs(dv_x) + abs(dv_y)), ())
    if sorted(kinds) == ["disk", "rod"]:
        rod, disk = (body_a, body_b) if kinds[0] == "rod" else (body_b, body_a)
        return (*_rod_disk_speed(rod, disk), ())
    if kinds[0] in _POLYGONS and kinds[1] in _POLYGONS:
        speed, others = _polygons_speed(scene, extent)
        return speed, _pair_bound(scene, extent), others
    return (*_geometry_speed(scene), ())


def _rod_disk_speed(rod, disk) -> tuple[float, float]:
    """:func:`first_touch_speed` of a rod and a disk: the normal from the closest point of
    the rod's segment to the disk's centre (the sign of ``v_n`` is the same whichever body
    is A)."""
    u = _UNIT_ROUNDOFF
    cos, sin = math.cos(rod.angle), math.sin(rod.angle)
    half = rod.shape.length / 2.0
    w_x = disk.position[0] - rod.position[0]
    w_y = disk.position[1] - rod.position[1]
    along = min(max(w_x * cos + w_y * sin, -half), half)
    d_x, d_y = w_x - along * cos, w_y - along * sin
    distance = math.hypot(d_x, d_y)
    if distance == 0.0:
        return 0.0, 0.0
    rate = rod.angular_velocity  # the rod's point at along·(cos, sin) from its centre
    dv_x = disk.velocity[0] - (rod.velocity[0] - rate * along * sin)
    dv_y = disk.velocity[1] - (rod.velocity[1] + rate * along * cos)
    speed = -(dv_x * d_x + dv_y * d_y) / distance
    # d within ~6u of |w| (w's u, the projection's 5u with libm's), so the normal within
    # 12u |w| / distance; the velocities within 5u of their terms, the dot product 3u more.
    # ``along`` itself carries that 6u |w|, which the spin turns into 6u |ω| |w| of normal
    # speed (the rod's point moves along the normal): |w| is about the disk's radius, far
    # more than ``half`` for a rod lying on a large disk.
    size = (abs(disk.velocity[0]) + abs(disk.velocity[1]) + abs(rod.velocity[0])
            + abs(rod.velocity[1]) + abs(rate) * half)
    reach = math.hypot(w_x, w_y)
    return speed, 16.0 * u * (size * (1.0 + reach / distance) + abs(rate) * reach)


def _world_points(body) -> list:
    """A box's or polygon's vertices in the world frame, counter-clockwise."""
    cos, sin = math.cos(body.angle), math.sin(body.angle)
    x_0, y_0 = body.position
    return [(cos * x - sin * y + x_0, sin * x + cos * y + y_0) for x, y in _outline(body.shape)]


def _polygons_speed(scene: Scene, extent: float) -> tuple[float, tuple]:
    """:func:`first_touch_speed` of two convex polygons, as
    :func:`harness.scene.geometry.scene_contacts` finds their contact: the normal of the
    face of least penetration (separating axes: every edge of both), the contact the
    overlap of the points within the touch band of that face on both bodies, along the
    face; the relative normal velocity is linear along the face, so its largest value is at
    an end of that overlap. With it the speeds another machine's rounding could give
    (:func:`_first_touch`'s third value): where a point lies at the touch band's edge (the
    overlap's ends between those with only the points surely in and those with every point
    possibly in), and where another face's separation is the least penetration's within
    rounding (a corner on a corner: that face's normal and contact)."""
    body_a, body_b = scene.bodies
    points_a, points_b = _world_points(body_a), _world_points(body_b)
    best = None
    faces = []
    for sign, reference, incident in ((1.0, points_a, points_b), (-1.0, points_b, points_a)):
        for index, (x_0, y_0) in enumerate(reference):
            x_1, y_1 = reference[index - len(reference) + 1]
            edge = math.hypot(x_1 - x_0, y_1 - y_0)
            if edge == 0.0:  # a repeated vertex: no face (Box2D's build refuses it)
                continue
            n_x, n_y = (y_1 - y_0) / edge, (x_0 - x_1) / edge  # outward (counter-clockwise)
            separation = math.inf
            for x, y in incident:  # a loop: a generator costs a frame per edge
                height = (x - x_0) * n_x + (y - y_0) * n_y
                if height < separation:  # noqa: PLR1730 - hot path
                    separation = height
            face = (separation, sign * n_x, sign * n_y, edge)  # from A into B
            faces.append(face)
            if best is None or separation > best[0]:
                best = face
    # A height x·n_x + y·n_y carries u of |x| + |y| per operation, and the normal's rounding
    # (u of the positions over its face's length) times |x| + |y|: ``slack`` covers a height
    # (a separation) and the edge ``near`` here, twice it another machine's.
    reach = max(max(abs(x) + abs(y) for x, y in points_a),
                max(abs(x) + abs(y) for x, y in points_b))

    def slack_of(face: float) -> float:
        return 16.0 * _UNIT_ROUNDOFF * reach * (1.0 + reach / face)

    fastest, others = _polygons_contact(body_a, body_b, points_a, points_b, best[1], best[2],
                                        _TOUCH_EXTENTS * extent, slack_of(best[3]))
    others = set(others)
    for face in faces:  # another face as good within rounding: its contact's speeds too
        if face is not best and face[0] >= best[0] - 2.0 * (slack_of(face[3])
                                                              + slack_of(best[3])):
            speed, more = _polygons_contact(body_a, body_b, points_a, points_b, face[1],
                                            face[2], _TOUCH_EXTENTS * extent,
                                            slack_of(face[3]))
            others.update((speed, *more))
    return fastest, tuple(sorted(others - {fastest}))


def _polygons_contact(body_a, body_b, points_a, points_b, n_x: float, n_y: float,
                      band: float, slack: float) -> tuple[float, tuple]:
    """:func:`_polygons_speed` at the normal ``(n_x, n_y)`` (from A into B): the fastest
    approach at the ends of the overlap of the points within ``band`` of each body's
    nearest, and the speeds with the points within ``2·slack`` of that band's edge in or
    out."""
    t_x, t_y = n_y, -n_x
    # Each body's points nearest the other along the normal, and their extent along t (also
    # with only the points surely within the band, and with every point possibly within it).
    ends, inner, outer = [], [], []
    for side, points in ((1.0, points_a), (-1.0, points_b)):
        heights = [side * (x * n_x + y * n_y) for x, y in points]
        near = max(heights) - band
        along = [x * t_x + y * t_y for (x, y), height in zip(points, heights) if height >= near]
        ends.append((min(along), max(along)))
        if all(abs(height - near) > 2.0 * slack for height in heights):
            inner.append(ends[-1])
            outer.append(ends[-1])
            continue
        sure = [x * t_x + y * t_y for (x, y), height in zip(points, heights)
                if height >= near + 2.0 * slack]
        maybe = [x * t_x + y * t_y for (x, y), height in zip(points, heights)
                 if height >= near - 2.0 * slack]
        inner.append((min(sure), max(sure)) if sure else ends[-1])
        outer.append((min(maybe), max(maybe)))
    low, high = max(ends[0][0], ends[1][0]), min(ends[0][1], ends[1][1])
    (ax, ay), (bx, by) = body_a.position, body_b.position
    rate_a, rate_b = body_a.angular_velocity, body_b.angular_velocity

    # Any point on the line along t at ``along``: its offset along n adds nothing to v_n.
    def approach(along: float) -> float:
        x, y = along * t_x, along * t_y
        dv_x = (body_b.velocity[0] - rate_b * (y - by)) - (body_a.velocity[0] - rate_a * (y - ay))
        dv_y = (body_b.velocity[1] + rate_b * (x - bx)) - (body_a.velocity[1] + rate_a * (x - ax))
        return -(dv_x * n_x + dv_y * n_y)

    fastest = max(approach(low), approach(high))
    if inner == ends and outer == ends:
        return fastest, ()
    # Linear along t: the extremes of the largest end's speed at the ranges' corners.
    lows = (max(inner[0][0], inner[1][0]), max(outer[0][0], outer[1][0]))
    highs = (min(inner[0][1], inner[1][1]), min(outer[0][1], outer[1][1]))
    others = {max(approach(one), approach(other)) for one in lows for other in highs}
    return fastest, tuple(sorted(others - {fastest}))


def _geometry_speed(scene: Scene) -> tuple[float, float]:
    """:func:`first_touch_speed` of any other pair: the contact points and normal of
    :func:`harness.scene.geometry.scene_contacts` (closest points of the world cores, or
    the separating-axis face), the relative velocity at each."""
    extent = _extent(scene)
    contacts = geometry.scene_contacts(scene, _TOUCH_EXTENTS * extent)
    fastest = max(-geometry.contact_velocity(scene, contact)[0] for contact in contacts)
    return fastest, _pair_bound(scene, extent)


def _pair_bound(scene: Scene, extent: float) -> float:
    """The rounding bound of a two-body :func:`first_touch_speed` from world cores: they
    carry u·(|position| + extent) (libm's cos and sin within 2u); a normal from two closest
    points a distance D apart, or from a face of length D, carries that over D; taken 32u
    for the few dozen operations, of the velocities' and lever arms' sizes. ``extent``: the
    scene's largest body extent, an upper bound of each body's."""
    size = reach = 0.0
    closest = math.inf
    for body in scene.bodies:
        size += abs(body.velocity[0]) + abs(body.velocity[1]) + abs(body.angular_velocity) * extent
        reach += abs(body.position[0]) + abs(body.position[1]) + extent
        shape = body.shape
        if shape.kind == "box":
            closest = min(closest, shape.width, shape.height)
        elif shape.kind in ("disk", "rod"):
            closest = min(closest, shape.radius)
        else:
            points, _ = _core(shape)
            for (x_0, y_0), (x_1, y_1) in zip(points, points[1:] + points[:1]):
                if (x_0, y_0) != (x_1, y_1):
                    closest = min(closest, math.hypot(x_1 - x_0, y_1 - y_0))
    return 32.0 * _UNIT_ROUNDOFF * size * (1.0 + reach / closest)


def _auto_scale(speed: float, bound: float) -> tuple[float, bool]:
    """``(scale, at_boundary)``: the smallest power of two ``V >= 1`` with ``V·(speed −
    bound) >= 2 m/s`` (within the band the larger scale: harmless, the margin of 2 keeps
    either above the threshold), and whether another machine's ``speed`` (within ``2·bound``
    of this one's) could pick another scale; a speed within its bound of 0 is no approach
    (scale 1), at the boundary unless it is exactly 0."""
    target = _AUTO_MARGIN * VELOCITY_THRESHOLD
    if speed - bound <= 0.0:
        return 1.0, speed + bound > 0.0
    scale = 1.0
    while scale * (speed - bound) < target and scale < _MAX_AUTO_SCALE:
        scale *= 2.0
    at_boundary = abs(scale * speed - target) <= 3.0 * scale * bound or (
        scale > 1.0 and abs(scale / 2.0 * speed - target) <= 1.5 * scale * bound)
    return scale, at_boundary


def _scale_decision(scene: Scene, extent: float) -> tuple[float, float, float, bool]:
    """``(speed, bound, scale, at_boundary)``: :func:`_first_touch`'s speed and bound, and
    :func:`_auto_scale`'s decision, at the boundary too where a speed another machine's
    rounding could count instead (a point at the touch band's edge) picks another scale or
    is at its own boundary."""
    speed, bound, others = _first_touch(scene, extent)
    scale, at_boundary = _auto_scale(speed, bound)
    for other in others:
        other_scale, other_at_boundary = _auto_scale(other, bound)
        at_boundary = at_boundary or other_scale != scale or other_at_boundary
    return speed, bound, scale, at_boundary


def _box2d_starts(start, velocity: float, length: float, advance: float = 0.0) -> tuple:
    """The run-frame start states in Box2D units, ``advance`` s further along free flight."""
    starts = []
    for x, y, angle, vx, vy, omega in start:  # a loop: a generator costs a frame per plan
        starts.append((
            (float((x + vx * advance) * length), float((y + vy * advance) * length)),
            float(angle + omega * advance),
            (float(vx * velocity), float(vy * velocity)),
            float(omega * velocity / length),
        ))
    return tuple(starts)


class _Prepared:
    """A run's Box2D form: switches, pair values, sweeps, scales, start state, derived
    values and notes known before it runs, the largest body extent (m)."""

    __slots__ = ("derived", "dt", "extent", "iterations", "notes", "pair_values", "starts",
                 "velocity", "world_values")


def _prepared(scene: Scene, settings, start) -> _Prepared:
    """A run's :class:`_Prepared`: the velocity scale (``auto``: :func:`_auto_scale` of
    :func:`first_touch_speed`), the start ``detection_overlap`` extents deep along the path
    at that speed, the Box2D time step and the derived values."""
    prepared = _Prepared()
    length = float(settings["length_scale"])
    prepared.world_values = tuple(map(bool, map(settings.__getitem__, _BOOL_KEYS)))
    prepared.pair_values = (float(scene.restitution), float(scene.friction))
    prepared.iterations = (int(settings["velocity_iterations"]),
                           int(settings["position_iterations"]))
    extent = prepared.extent = _extent(scene)
    scale, overlap = settings["velocity_scale"], float(settings["detection_overlap"])
    at_boundary = None
    speed = 0.0
    if scale == "auto" or overlap > 0.0:
        speed, bound, scale_auto, at_boundary_auto = _scale_decision(scene, extent)
    if scale == "auto":
        scale, at_boundary = scale_auto, at_boundary_auto
    velocity = prepared.velocity = float(scale)
    # The overlap as a time along the path: depth = overlap·extent at the approach speed.
    advance = overlap * extent / speed if overlap > 0.0 and speed > 0.0 else 0.0
    prepared.starts = _box2d_starts(start, velocity, length, advance)
    time_step = float(settings["time_step"])
    prepared.dt = time_step * length / velocity
    prepared.derived = {
        "velocity_scale": velocity,
        "length_scale": length,
        "box2d_time_step": prepared.dt,
        "speed_cap": MAX_TRANSLATION / (length * time_step),
        "angular_speed_cap": MAX_ROTATION / time_step,
    }
    prepared.notes = ()
    if at_boundary is not None:  # another machine's rounding could pick another scale
        prepared.derived["velocity_scale_at_boundary"] = at_boundary
    return prepared


def _speed_results(derived: dict, speed: float, restitution: float,
                   notes: tuple[str, ...]) -> tuple[str, ...]:
    """Add the impact speed Box2D saw (``speed``, m/s in Box2D's units: its ``v_rel`` at
    the run's first touching contact, scaled by the velocity scale) to ``derived``;
    ``notes`` with the threshold's note added if it zeroed e."""
    derived["box2d_impact_speed"] = speed
    cleared = speed > VELOCITY_THRESHOLD
    derived["restitution_threshold_cleared"] = cleared
    if not cleared and restitution > 0.0:
        return (*notes, THRESHOLD_NOTE)
    return notes

