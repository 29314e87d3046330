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

The ellipse is the one shape without a core: its contact with the ground is its lowest
point, in closed form (:mod:`harness.scene.ellipse`); against another body it is not
supported (a :class:`ValueError` says so).

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

import itertools
import math

import numpy as np

from harness.scene import Body, Box, Contact, Disk, Ellipse, Polygon, Rod, Scene, ellipse
from planar_impact import builders

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
    if isinstance(shape, Ellipse):
        raise TypeError("an ellipse has no polygonal core: its ground contact is its lowest "
                        "point (harness.scene.ellipse); nothing else takes an ellipse")
    raise TypeError(f"unknown shape {shape!r}; allowed: Disk, Rod, Box, Polygon")


def turned_core(body: Body) -> tuple[np.ndarray, float]:
    """Core points of ``body`` turned by its angle, before its position is added, and its
    radius (m): :func:`world_core` is these plus the position, so a body moved without
    turning needs only the addition.

    Written elementwise, ``(x cos θ − y sin θ, x sin θ + y cos θ)``, not as a product with
    :func:`rotation`: numpy's ``@`` goes through BLAS, whose kernels (FMA or not, AVX-512
    or not) round such products differently from CPU to CPU; separate IEEE multiplies and
    subtractions round the same everywhere (docs/verdicts.md, 'Same answers on every
    CPU')."""
    points, radius = local_core(body.shape)
    return turn(points, body.angle), radius


def turn(points, angle: float) -> np.ndarray:
    """Points ``(k, 2)`` (or one point ``(2,)``) turned by ``angle`` (rad, CCW), as ``(k, 2)``:
    ``(x cos θ − y sin θ, x sin θ + y cos θ)`` written elementwise, the same bits on every CPU
    (:func:`turned_core`; never ``rotation(angle) @ p``, which a BLAS kernel rounds)."""
    c, s = math.cos(angle), math.sin(angle)
    # plain floats: a core has a few points, where numpy's cost per call exceeds the arithmetic
    points = np.asarray(points, dtype=float)
    if points.ndim == 1:
        x, y = points.tolist()
        return np.array([[x * c - y * s, x * s + y * c]])
    turned = [(x * c - y * s, x * s + y * c) for x, y in points.tolist()]
    return np.array(turned, dtype=float).reshape(-1, 2)


def _along(points, direction) -> list[float]:
    """``core @ direction`` for a 2-D direction and a core as an array or a list of ``(x, y)``,
    as a list, written out (``x d_x + y d_y``: one rounding per operation on every CPU, never
    through a BLAS kernel; plain floats, as :func:`turned_core`)."""
    if isinstance(points, np.ndarray):
        points = points.tolist()
    dx, dy = float(direction[0]), float(direction[1])
    return [x * dx + y * dy for x, y in points]


def world_core(body: Body) -> tuple[np.ndarray, float]:
    """Core points of ``body`` in the world frame (from its pose) and its radius (m)."""
    turned, radius = turned_core(body)
    return turned + np.asarray(body.position, dtype=float), radius


def _edges(points: list) -> list[tuple[float, ...]]:
    """The edges of a core given as a list of ``(x, y)``, each as ``(start x, start y, end x,
    end y, Δx, Δy, |Δ|²)`` (``Δ`` = end − start): a point gives one degenerate edge, a
    segment one edge, a polygon one per side. Worked out once per pair of cores, for every
    test on them."""
    if len(points) <= 2:  # a point's degenerate edge, a segment's one edge
        pairs = [(points[0], points[-1])]
    else:
        pairs = zip(points, points[1:] + points[:1])
    edges = []
    for (sx, sy), (ex, ey) in pairs:
        dx, dy = ex - sx, ey - sy
        edges.append((sx, sy, ex, ey, dx, dy, dx * dx + dy * dy))
    return edges


def _closest_pair(points_a: list, points_b: list, edges_a: list,
                  edges_b: list) -> tuple[float, tuple, tuple]:
    """The closest vertex-edge pair of two cores given as lists of ``(x, y)`` and their
    :func:`_edges`: ``(distance, point on A, point on B)``.

    Every vertex of A against every edge of B, then every vertex of B against every edge of
    A, keeping the first pair of least distance (exact for disjoint convex cores). On the
    edge from ``s`` to ``e`` the closest point is ``s + t (e − s)`` with
    ``t = (x − s)·(e − s) / |e − s|²`` clamped to ``[0, 1]`` (``s`` itself for a point's
    degenerate edge). Plain floats: a core has a few points, where numpy's cost per call
    exceeds the arithmetic (tests/scene/test_geometry_reference.py keeps the array form
    and compares).
    """
    sqrt = math.sqrt
    best, on_a, on_b = math.inf, None, None
    for vertices, edges, vertex_on_a in ((points_a, edges_b, True), (points_b, edges_a, False)):
        for x, y in vertices:
            for sx, sy, _, _, dx, dy, length2 in edges:
                if length2 == 0.0:
                    cx, cy = sx, sy
                else:
                    # min(1.0, max(0.0, t)) without the calls: 0.0 unless t > 0.0 (NaN too)
                    t = ((x - sx) * dx + (y - sy) * dy) / length2
                    if not t > 0.0:
                        t = 0.0
                    elif not t < 1.0:
                        t = 1.0
                    cx, cy = sx + t * dx, sy + t * dy
                offset_x, offset_y = cx - x, cy - y
                distance = sqrt(offset_x * offset_x + offset_y * offset_y)
                if distance < best:
                    best = distance
                    on_a, on_b = ((x, y), (cx, cy)) if vertex_on_a else ((cx, cy), (x, y))
    return best, on_a, on_b


def _cores_intersect(points_a: list, points_b: list, edges_a: list, edges_b: list) -> bool:
    """Whether two cores (lists of ``(x, y)`` and their :func:`_edges`) cross: an edge of one
    properly crosses an edge of the other (touching ends are found by the distance test), or
    a point of one lies strictly inside the other (a counter-clockwise convex polygon of 3 or
    more points)."""
    for a0x, a0y, a1x, a1y, ux, uy, _ in edges_a:
        for b0x, b0y, b1x, b1y, vx, vy, _ in edges_b:
            # cross products u × (b − a0) and v × (a − b0), written out: a call per
            # product cost more than the product
            if ((ux * (b0y - a0y) - uy * (b0x - a0x)) * (ux * (b1y - a0y) - uy * (b1x - a0x))
                    < 0.0
                    and (vx * (a0y - b0y) - vy * (a0x - b0x))
                    * (vx * (a1y - b0y) - vy * (a1x - b0x)) < 0.0):
                return True
    return (_any_inside(points_a, points_b, edges_b)
            or _any_inside(points_b, points_a, edges_a))


def _any_inside(points: list, polygon: list, edges: list) -> bool:
    """Whether a point lies strictly inside a counter-clockwise convex ``polygon`` (its
    :func:`_edges` given)."""
    if len(polygon) < 3:
        return False
    for x, y in points:
        # the cross product Δ × ((x, y) − start) > 0.0 on every edge
        for sx, sy, _, _, dx, dy, _ in edges:
            if not dx * (y - sy) - dy * (x - sx) > 0.0:
                break
        else:
            return True
    return False


def _axis_list(edges: list) -> list[tuple[float, float]]:
    """Unit normals (both signs) of a core's :func:`_edges`; none for a point."""
    axes = []
    for _, _, _, _, dx, dy, _ in edges:
        length = math.hypot(dx, dy)
        if length > 0.0:
            normal = (dy / length, -dx / length)
            axes += [normal, (-normal[0], -normal[1])]
    return axes


def _tangent(normal: np.ndarray) -> np.ndarray:
    """The harness's tangent for a normal: ``t = (n_y, -n_x)`` (``+x`` for the ground)."""
    return np.array([normal[1], -normal[0]])


def _largest(values: list) -> float:
    """The largest of a list, the same bits on every CPU: where it is zero and the list holds
    zeros of both signs, ``+0.0`` (IEEE 754-2019's maximum: +0 above −0); where it holds a
    NaN, NaN (``numpy.max``'s). Not numpy's pick between two zeros: from 11 values its
    reduction follows its SIMD loops, and an AVX-512, an AVX2 and a baseline loop pick
    differently (docs/verdicts.md, 'Same answers on every CPU'); Python's ``max`` keeps the
    first."""
    largest = max(values)
    if largest == 0.0 and len(values) > 1 and not _one_zero_sign(values):
        return 0.0 if _no_nan(values) else float(np.max(values))
    return largest


def _smallest(values: list) -> float:
    """The smallest of a list, the same bits on every CPU: ``-0.0`` between zeros of both
    signs (IEEE 754-2019's minimum), NaN where the list holds one (see :func:`_largest`)."""
    smallest = min(values)
    if smallest == 0.0 and len(values) > 1 and not _one_zero_sign(values):
        return -0.0 if _no_nan(values) else float(np.min(values))
    return smallest


def _no_nan(values: list) -> bool:
    return all(value == value for value in values)


def _one_zero_sign(values: list) -> bool:
    """Whether the zeros of ``values`` all have one sign and none is NaN: the extreme is then
    a zero of that sign, as Python's is (a ground body's lowest point lies at exactly 0.0,
    so most ground contacts take this quick test)."""
    signs = {math.copysign(1.0, value) for value in values if value == 0.0}
    return len(signs) == 1 and all(value == value for value in values)


def _support_interval(core, normal, tangent, side, tolerance,
                      along_normal: list | None = None,
                      intervals: dict | None = None) -> tuple[float, float]:
    """Tangential extent of the core points nearest the other body along ``normal``.

    ``side = +1`` for body A (its points furthest along ``normal``), ``-1`` for body B;
    ``along_normal``: ``core @ normal`` as a list, when already known; ``intervals``: the
    extents already found for this core and tangent, by their near points (another tolerance
    mostly picks the same points).
    """
    if along_normal is None:
        along_normal = _along(core, normal)
    heights = [side * value for value in along_normal]
    threshold = _largest(heights) - tolerance
    near = [index for index, height in enumerate(heights) if height >= threshold]
    if intervals is not None and tuple(near) in intervals:
        return intervals[tuple(near)]
    along = _along(core[near], tangent)
    interval = _smallest(along), _largest(along)
    if intervals is not None:
        intervals[tuple(near)] = interval
    return interval


# --------------------------------------------------------------------------------------------
# Contacts
# --------------------------------------------------------------------------------------------
def ground_contact(body: Body, tolerance: float = DEFAULT_TOLERANCE) -> Contact:
    """Contact between the fixed ground (half-space ``y <= 0``, body A) and ``body`` (B)."""
    if isinstance(body.shape, Ellipse):
        return _ellipse_ground_contact(body)
    core, radius = world_core(body)
    return core_ground_contact(core, radius, tolerance)


def core_ground_contact(core: np.ndarray, radius: float,
                        tolerance: float = DEFAULT_TOLERANCE) -> Contact:
    """:func:`ground_contact` of a body given by its world core and radius."""
    points = core.tolist()
    lowest = _smallest([y for _, y in points])
    gap = lowest - radius
    near = [x for x, y in points if y <= lowest + tolerance]
    x_min, x_max = _smallest(near), _largest(near)
    point_count = 2 if x_max - x_min > tolerance else 1
    # Ground surface at y = 0, body surface at y = gap: the point is midway.
    point = np.array([0.5 * (x_min + x_max), 0.5 * gap])
    return Contact(point=point, normal=GROUND_NORMAL.copy(), gap=float(gap),
                   point_count=point_count)


def _ellipse_ground_contact(body: Body) -> Contact:
    """:func:`ground_contact` of an ellipse: its lowest point, one point (strictly convex)."""
    shape = body.shape
    offset_x, offset_y = ellipse.lowest_offset(body.angle, shape.semi_x, shape.semi_y)
    x, y = body.position
    gap = float(y) + offset_y
    return Contact(point=np.array([float(x) + offset_x, 0.5 * gap]),
                   normal=GROUND_NORMAL.copy(), gap=gap, point_count=1)


def place_stand_in(body: Body) -> Body:
    """``body`` with its ellipse's stand-in polygon placed on its lowest point (at the body's
    angle): the first contact point with the ground (:meth:`harness.scene.Ellipse.stand_in`);
    any other body unchanged."""
    shape = body.shape
    if not isinstance(shape, Ellipse):
        return body
    phi = ellipse.lowest_parameter(body.angle, shape.semi_x, shape.semi_y)
    return body.moved(shape=Ellipse(shape.semi_x, shape.semi_y, phi))


def _refuse_ellipse(*bodies: Body) -> None:
    for body in bodies:
        if isinstance(body.shape, Ellipse):
            raise ValueError(f"body {body.name!r}: an ellipse touches only the ground here "
                             "(its contact with another body is not supported)")


def body_contact(body_a: Body, body_b: Body, tolerance: float = DEFAULT_TOLERANCE) -> Contact:
    """Contact between two convex bodies; the normal points from ``body_a`` into ``body_b``."""
    _refuse_ellipse(body_a, body_b)
    core_a, radius_a = world_core(body_a)
    core_b, radius_b = world_core(body_b)
    return core_contact(core_a, radius_a, core_b, radius_b, tolerance)


def core_separation(core_a: np.ndarray, core_b: np.ndarray):
    """How far apart two world cores are: ``(separation, normal, closest_a, closest_b)``.

    ``separation`` (m) is the distance between the cores when they are apart, else minus
    their least penetration (<= 0); ``normal`` the unit vector from A into B; ``closest_a``
    and ``closest_b`` the cores' closest points (used when the cores are apart). The gap of
    the bodies is ``separation − radius_a − radius_b``.
    """
    points_a, points_b = core_a.tolist(), core_b.tolist()
    scale = max(1.0, max(map(abs, itertools.chain.from_iterable(points_a + points_b))))
    touching_cores = 1e-12 * scale

    edges_a, edges_b = _edges(points_a), _edges(points_b)
    distance, closest_a, closest_b = _closest_pair(points_a, points_b, edges_a, edges_b)

    if distance > touching_cores and not _cores_intersect(points_a, points_b, edges_a,
                                                          edges_b):
        normal = np.array([(closest_b[0] - closest_a[0]) / distance,
                           (closest_b[1] - closest_a[1]) / distance])
        return distance, normal, closest_a, closest_b
    # Cores touch or overlap: the separating axis of least penetration (<= 0).
    axes = _axis_list(edges_a) + _axis_list(edges_b)
    if not axes:  # two coincident points (concentric disks): no defined direction
        axes = [(0.0, 1.0)]
    # Each axis's products with both cores, x a_x + y a_y as :func:`_along` writes them (no
    # BLAS kernel), for every axis at once: numpy's elementwise products and sum, broadcast.
    columns = np.array(axes)
    along_b = (columns[:, :1] * core_b[:, 0] + columns[:, 1:] * core_b[:, 1]).tolist()
    along_a = (columns[:, :1] * core_a[:, 0] + columns[:, 1:] * core_a[:, 1]).tolist()
    # Python's min and max may keep another zero than numpy's; a zero separation becomes
    # min(0.0, ±0.0) = 0.0 below either way, and ±0.0 tie in the argmax.
    separations = [min(b) - max(a) for a, b in zip(along_a, along_b)]
    best = int(np.argmax(separations))  # the first of the largest
    return min(0.0, separations[best]), np.array(axes[best]), closest_a, closest_b


def core_contact(core_a: np.ndarray, radius_a: float, core_b: np.ndarray, radius_b: float,
                 tolerance: float = DEFAULT_TOLERANCE, separation=None) -> Contact:
    """:func:`body_contact` of two bodies given by their world cores and radii;
    ``separation``: :func:`core_separation` of these cores, when already known."""
    return core_contacts(core_a, radius_a, core_b, radius_b, (tolerance,), separation)[0]


def core_contacts(core_a: np.ndarray, radius_a: float, core_b: np.ndarray, radius_b: float,
                  tolerances, separation=None) -> list[Contact]:
    """:func:`core_contact` at each of ``tolerances``, the products along the normal and
    tangent formed once for all of them."""
    if separation is None:
        separation = core_separation(core_a, core_b)
    tangent = _tangent(separation[1])
    along_normal_a = _along(core_a, separation[1])
    along_normal_b = _along(core_b, separation[1])
    intervals_a: dict = {}
    intervals_b: dict = {}
    return [_core_contact(core_a, radius_a, core_b, radius_b, tolerance, separation, tangent,
                          along_normal_a, along_normal_b, intervals_a, intervals_b)
            for tolerance in tolerances]


def _core_contact(core_a, radius_a, core_b, radius_b, tolerance, separation, tangent,
                  along_normal_a, along_normal_b, intervals_a, intervals_b) -> Contact:
    apart, normal, closest_a, closest_b = separation  # apart: the cores' separation (m)
    a_lo, a_hi = _support_interval(core_a, normal, tangent, +1, tolerance, along_normal_a,
                                   intervals_a)
    b_lo, b_hi = _support_interval(core_b, normal, tangent, -1, tolerance, along_normal_b,
                                   intervals_b)
    low, high = max(a_lo, b_lo), min(a_hi, b_hi)
    point_count = 2 if high - low > tolerance else 1

    gap = apart - radius_a - radius_b
    normal_x, normal_y = normal.tolist()
    if point_count == 1 and apart > 0.0:
        (ax, ay), (bx, by) = closest_a, closest_b
        point = [0.5 * ((ax + radius_a * normal_x) + (bx - radius_b * normal_x)),
                 0.5 * ((ay + radius_a * normal_y) + (by - radius_b * normal_y))]
    else:
        # Midway between the two support lines, at the middle of the shared interval.
        plane_a = _largest(along_normal_a) + radius_a
        plane_b = _smallest(along_normal_b) - radius_b
        along = 0.5 * (low + high) if high >= low else 0.5 * (max(a_lo, b_lo) + min(a_hi, b_hi))
        middle = 0.5 * (plane_a + plane_b)
        point = [along * normal_y + middle * normal_x, along * -normal_x + middle * normal_y]
    return Contact(point=np.array(point), normal=normal, gap=float(gap),
                   point_count=point_count)


def scene_contact(scene: Scene, tolerance: float = DEFAULT_TOLERANCE) -> Contact:
    """The contact of a scene: ground against its body, or its first body against its second."""
    if scene.ground:
        return ground_contact(scene.bodies[0], tolerance)
    return body_contact(scene.bodies[0], scene.bodies[1], tolerance)


def scene_contact_each(scene: Scene, tolerances) -> list[Contact]:
    """:func:`scene_contact` at each of ``tolerances``, the cores and the separation found
    once for all of them (the scenario checks ask for two tolerances at every point)."""
    if scene.ground:
        if isinstance(scene.bodies[0].shape, Ellipse):
            return [_ellipse_ground_contact(scene.bodies[0])] * len(tolerances)
        core, radius = world_core(scene.bodies[0])
        return [core_ground_contact(core, radius, tolerance) for tolerance in tolerances]
    core_a, radius_a = world_core(scene.bodies[0])
    core_b, radius_b = world_core(scene.bodies[1])
    return core_contacts(core_a, radius_a, core_b, radius_b, tolerances)


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
        if isinstance(scene.bodies[0].shape, Ellipse):
            return [_ellipse_ground_contact(scene.bodies[0])]
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
    offset = contact.point - _along(contact.point[None], tangent)[0] * tangent  # mid-plane
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
    if isinstance(body.shape, Ellipse):
        shape = body.shape
        return float(body.position[1]) + ellipse.lowest_offset(body.angle, shape.semi_x,
                                                               shape.semi_y)[1]
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
    return _along(velocity[None], normal)[0], _along(velocity[None], _tangent(normal))[0]


def impact_problem(scene: Scene, point, normal):
    """The scene's impact as a :class:`planar_impact.builders.ImpactProblem`: the bodies'
    masses, inertias and state with the contact at ``point`` along ``normal`` (A into B)."""
    planar = [builders.PlanarBody(mass=b.mass, inertia=b.moment_of_inertia,
                                  position=tuple(b.position), velocity=tuple(b.velocity),
                                  angular_velocity=b.angular_velocity)
              for b in scene.bodies]
    if scene.ground:
        return builders.rigid_body_against_ground(planar[0], point, normal=tuple(normal))
    return builders.two_bodies(planar[0], planar[1], point, tuple(normal))
