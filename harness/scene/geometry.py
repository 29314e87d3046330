"""Contact geometry for planar scenes: where two shapes touch, along which normal, how far apart.

Every shape of :mod:`harness.scene` is a convex *core* swept by a *radius*:

========  =====================================  ======
shape     core (body frame)                      radius
========  =====================================  ======
Disk      the point ``(0, 0)``                   radius
Rod       the segment ``(±length/2, 0)``         radius
Box       its four corners (counter-clockwise)   0
Polygon   its vertices (counter-clockwise)       0
========  =====================================  ======

The distance between two shapes is the distance between their cores minus both radii; the
contact normal is the direction between the closest points of the cores. When the cores
themselves overlap, the penetration is found by the separating-axis test over the edge
normals of both cores (the face normals of their Minkowski difference), which is exact for
convex polygons and segments.

All functions return :class:`harness.scene.Contact` with

* ``normal``: unit vector from body A into body B (for the ground, A is the ground and the
  normal is ``(0, 1)``);
* ``point``: midway between the two surfaces' closest points (on both when they touch);
* ``gap``: signed distance in m, ``>= 0`` separated, ``< 0`` overlapping by ``-gap``;
* ``point_count``: how many distinct closest-point pairs there are within ``tolerance``
  (a box face lying flat on the ground gives 2: that scene is outside one-point theory).
"""

from __future__ import annotations

import math

import numpy as np

from harness.scene import Body, Box, Contact, Disk, Polygon, Rod, Scene

#: Default tolerance (m) within which two closest-point pairs count as the same distance.
DEFAULT_TOLERANCE = 1e-9

GROUND_NORMAL = np.array([0.0, 1.0])


# --------------------------------------------------------------------------------------------
# Cores
# --------------------------------------------------------------------------------------------
def rotation(angle: float) -> np.ndarray:
    """The 2×2 matrix rotating body-frame vectors by ``angle`` (rad, CCW) into the world."""
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, -s], [s, c]])


def local_core(shape) -> tuple[np.ndarray, float]:
    """Core points ``(k, 2)`` in the body frame and the radius swept around them (m)."""
    if isinstance(shape, Disk):
        return np.zeros((1, 2)), float(shape.radius)
    if isinstance(shape, Rod):
        half = shape.length / 2.0
        return np.array([[-half, 0.0], [half, 0.0]]), float(shape.radius)
    if isinstance(shape, (Box, Polygon)):
        return np.asarray(shape.vertices(), dtype=float), 0.0
    raise TypeError(f"unknown shape {shape!r}; allowed: Disk, Rod, Box, Polygon")


def world_core(body: Body) -> tuple[np.ndarray, float]:
    """Core points of ``body`` in the world frame (from its pose) and its radius (m)."""
    points, radius = local_core(body.shape)
    world = points @ rotation(body.angle).T + np.asarray(body.position, dtype=float)
    return world, radius


def _edges(core: np.ndarray) -> list[tuple[np.ndarray, np.ndarray]]:
    """Edges of a core: a point gives one degenerate edge, a segment one, a polygon k."""
    count = len(core)
    if count == 1:
        return [(core[0], core[0])]
    if count == 2:
        return [(core[0], core[1])]
    return [(core[i], core[(i + 1) % count]) for i in range(count)]


def _closest_on_segment(x: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    ab = b - a
    length2 = float(ab @ ab)
    if length2 == 0.0:
        return a.copy()
    t = min(1.0, max(0.0, float((x - a) @ ab) / length2))
    return a + t * ab


def _cross(a: np.ndarray, b: np.ndarray) -> float:
    return float(a[0] * b[1] - a[1] * b[0])


def _segments_cross(a0, a1, b0, b1) -> bool:
    """Proper crossing of two segments (touching ends are found by the distance test)."""
    d1 = _cross(a1 - a0, b0 - a0)
    d2 = _cross(a1 - a0, b1 - a0)
    d3 = _cross(b1 - b0, a0 - b0)
    d4 = _cross(b1 - b0, a1 - b0)
    return d1 * d2 < 0.0 and d3 * d4 < 0.0


def _inside_polygon(x: np.ndarray, polygon: np.ndarray) -> bool:
    """Strictly inside a counter-clockwise convex polygon (needs 3 or more vertices)."""
    if len(polygon) < 3:
        return False
    return all(_cross(b - a, x - a) > 0.0 for a, b in _edges(polygon))


def _cores_intersect(core_a: np.ndarray, core_b: np.ndarray) -> bool:
    for a0, a1 in _edges(core_a):
        for b0, b1 in _edges(core_b):
            if _segments_cross(a0, a1, b0, b1):
                return True
    return any(_inside_polygon(x, core_b) for x in core_a) or any(
        _inside_polygon(x, core_a) for x in core_b
    )


def _axes(core: np.ndarray) -> list[np.ndarray]:
    """Unit normals (both signs) of a core's edges; none for a point."""
    axes = []
    for a, b in _edges(core):
        edge = b - a
        length = math.hypot(edge[0], edge[1])
        if length > 0.0:
            normal = np.array([edge[1], -edge[0]]) / length
            axes += [normal, -normal]
    return axes


def _tangent(normal: np.ndarray) -> np.ndarray:
    """The harness's tangent for a normal: ``t = (n_y, -n_x)`` (``+x`` for the ground)."""
    return np.array([normal[1], -normal[0]])


def _support_interval(core, normal, tangent, side, tolerance) -> tuple[float, float]:
    """Tangential extent of the core points nearest the other body along ``normal``.

    ``side = +1`` for body A (its points furthest along ``normal``), ``-1`` for body B.
    """
    heights = side * (core @ normal)
    near = core[heights >= heights.max() - tolerance]
    along = near @ tangent
    return float(along.min()), float(along.max())


# --------------------------------------------------------------------------------------------
# Contacts
# --------------------------------------------------------------------------------------------
def ground_contact(body: Body, tolerance: float = DEFAULT_TOLERANCE) -> Contact:
    """Contact between the fixed ground (half-space ``y <= 0``, body A) and ``body`` (B)."""
    core, radius = world_core(body)
    lowest = float(core[:, 1].min())
    gap = lowest - radius
    near = core[core[:, 1] <= lowest + tolerance]
    x_min, x_max = float(near[:, 0].min()), float(near[:, 0].max())
    point_count = 2 if x_max - x_min > tolerance else 1
    # Ground surface at y = 0, body surface at y = gap: the point is midway.
    point = np.array([0.5 * (x_min + x_max), 0.5 * gap])
    return Contact(point=point, normal=GROUND_NORMAL.copy(), gap=float(gap),
                   point_count=point_count)


def body_contact(body_a: Body, body_b: Body, tolerance: float = DEFAULT_TOLERANCE) -> Contact:
    """Contact between two convex bodies; the normal points from ``body_a`` into ``body_b``."""
    core_a, radius_a = world_core(body_a)
    core_b, radius_b = world_core(body_b)
    scale = max(1.0, float(np.abs(np.vstack([core_a, core_b])).max()))
    touching_cores = 1e-12 * scale

    # Closest vertex-edge pairs: exact for disjoint convex cores.
    pairs = []
    for vertex in core_a:
        for b0, b1 in _edges(core_b):
            closest = _closest_on_segment(vertex, b0, b1)
            pairs.append((float(np.linalg.norm(closest - vertex)), vertex, closest))
    for vertex in core_b:
        for a0, a1 in _edges(core_a):
            closest = _closest_on_segment(vertex, a0, a1)
            pairs.append((float(np.linalg.norm(vertex - closest)), closest, vertex))
    distance, closest_a, closest_b = min(pairs, key=lambda pair: pair[0])

    if distance > touching_cores and not _cores_intersect(core_a, core_b):
        normal = (closest_b - closest_a) / distance
        core_separation = distance
    else:
        # Cores touch or overlap: the separating axis of least penetration (<= 0).
        axes = _axes(core_a) + _axes(core_b)
        if not axes:  # two coincident points (concentric disks): no defined direction
            axes = [GROUND_NORMAL.copy()]
        separations = [float((core_b @ axis).min() - (core_a @ axis).max()) for axis in axes]
        best = int(np.argmax(separations))
        normal, core_separation = axes[best], min(0.0, separations[best])

    tangent = _tangent(normal)
    a_lo, a_hi = _support_interval(core_a, normal, tangent, +1, tolerance)
    b_lo, b_hi = _support_interval(core_b, normal, tangent, -1, tolerance)
    low, high = max(a_lo, b_lo), min(a_hi, b_hi)
    point_count = 2 if high - low > tolerance else 1

    gap = core_separation - radius_a - radius_b
    if point_count == 1 and core_separation > 0.0:
        surface_a = closest_a + radius_a * normal
        surface_b = closest_b - radius_b * normal
        point = 0.5 * (surface_a + surface_b)
    else:
        # Midway between the two support lines, at the middle of the shared interval.
        plane_a = float((core_a @ normal).max()) + radius_a
        plane_b = float((core_b @ normal).min()) - radius_b
        along = 0.5 * (low + high) if high >= low else 0.5 * (max(a_lo, b_lo) + min(a_hi, b_hi))
        point = along * tangent + 0.5 * (plane_a + plane_b) * normal
    return Contact(point=point, normal=normal, gap=float(gap), point_count=point_count)


def scene_contact(scene: Scene, tolerance: float = DEFAULT_TOLERANCE) -> Contact:
    """The contact of a scene: ground against its body, or its first body against its second."""
    if scene.ground:
        return ground_contact(scene.bodies[0], tolerance)
    return body_contact(scene.bodies[0], scene.bodies[1], tolerance)


def scene_contacts(scene: Scene, tolerance: float = DEFAULT_TOLERANCE) -> list[Contact]:
    """Every contact point of a scene within ``tolerance`` (m) of the closest one, each a
    one-point :class:`Contact` (``point_count`` 1), ordered along the tangent.

    Against the ground: one contact per core point (box or polygon corner, rod end cap, the
    disk's centre) whose surface lies within ``tolerance`` of the lowest; each keeps its own
    height as its gap. Between two bodies: the ends of the shared support interval of
    :func:`body_contact` when it finds two points, else its single point. A box lying flat
    gives its two bottom corners; a box tilted so that its far corner is higher than
    ``tolerance`` gives one (docs/multi-contact.md, 'Scenes with several contacts').
    """
    if scene.ground:
        core, radius = world_core(scene.bodies[0])
        lowest = float(core[:, 1].min())
        near = core[core[:, 1] <= lowest + tolerance]
        near = near[np.argsort(near[:, 0], kind="stable")]
        return [Contact(point=np.array([float(x), 0.5 * (float(y) - radius)]),
                        normal=GROUND_NORMAL.copy(), gap=float(y) - radius, point_count=1)
                for x, y in near]
    contact = body_contact(scene.bodies[0], scene.bodies[1], tolerance)
    if contact.point_count == 1:
        return [contact]
    core_a, _ = world_core(scene.bodies[0])
    core_b, _ = world_core(scene.bodies[1])
    normal = np.asarray(contact.normal, dtype=float)
    tangent = _tangent(normal)
    a_lo, a_hi = _support_interval(core_a, normal, tangent, +1, tolerance)
    b_lo, b_hi = _support_interval(core_b, normal, tangent, -1, tolerance)
    offset = contact.point - float(contact.point @ tangent) * tangent  # the mid-plane
    return [Contact(point=offset + along * tangent, normal=normal.copy(), gap=contact.gap,
                    point_count=1) for along in (max(a_lo, b_lo), min(a_hi, b_hi))]


def contact_rows(scene: Scene, contacts) -> tuple[np.ndarray, np.ndarray]:
    """The rows ``w_n^(i)``, ``w_t^(i)`` of each contact, stacked ``(m, p)`` in the scene's
    speeds (eq. (75) of the paper; docs/multi-contact.md, 'Setting: eq. (75)'), built as
    :func:`impact_problem` builds the single contact's."""
    problems = [impact_problem(scene, c.point, c.normal) for c in contacts]
    return (np.array([p.wn for p in problems], dtype=float),
            np.array([p.wt for p in problems], dtype=float))


def lowest_point(body: Body) -> float:
    """The lowest ``y`` (m) of the body's surface."""
    core, radius = world_core(body)
    return float(core[:, 1].min()) - radius


def place_on_ground(body: Body) -> Body:
    """``body`` shifted vertically so that its lowest point lies on ``y = 0``."""
    x, y = body.position
    return body.moved(position=(float(x), float(y) - lowest_point(body)))


def point_velocity(body: Body, point) -> np.ndarray:
    """Velocity (m/s) of the material point of ``body`` at world position ``point``."""
    r = np.asarray(point, dtype=float) - np.asarray(body.position, dtype=float)
    vx, vy = body.velocity
    omega = body.angular_velocity
    return np.array([vx - omega * r[1], vy + omega * r[0]])


def contact_velocity(scene: Scene, contact: Contact) -> tuple[float, float]:
    """Relative contact velocity ``(v_n, v_t)`` of B with respect to A (m/s).

    ``v_n < 0`` means approach; the tangent is ``t = (n_y, -n_x)``, ``+x`` for the ground.
    """
    velocity = point_velocity(scene.bodies[-1], contact.point)
    if not scene.ground:
        velocity = velocity - point_velocity(scene.bodies[0], contact.point)
    normal = np.asarray(contact.normal, dtype=float)
    return float(velocity @ normal), float(velocity @ _tangent(normal))


def impact_problem(scene: Scene, point, normal):
    """The scene's impact as a :class:`planar_impact.builders.ImpactProblem`: the bodies'
    masses, inertias and state with the contact at ``point`` along ``normal`` (A into B)."""
    from planar_impact import builders

    planar = [builders.PlanarBody(mass=b.mass, inertia=b.moment_of_inertia,
                                  position=tuple(b.position), velocity=tuple(b.velocity),
                                  angular_velocity=b.angular_velocity)
              for b in scene.bodies]
    if scene.ground:
        return builders.rigid_body_against_ground(planar[0], point, normal=tuple(normal))
    return builders.two_bodies(planar[0], planar[1], point, tuple(normal))
