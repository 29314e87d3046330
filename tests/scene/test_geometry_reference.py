"""The contact geometry against its straightforward form, bit for bit on every CPU.

harness/scene/geometry.py finds the closest pair of two cores with plain floats and numpy's
elementwise operations; the functions below are the array form it replaced (every
vertex-edge pair as numpy vectors, numpy reductions), kept here as the reference. Neither
takes a product through numpy's ``@``: a BLAS kernel rounds a product as it likes (FMA or
not, AVX-512 or not: issue 35), while the products written out, ``x_0 y_0 + x_1 y_1``, are
IEEE multiplies and additions, each rounded one way on every CPU. Both forms perform the same
operations in the same order, so they agree bit for bit: the comparison
(:func:`assert_same_contacts`) is exact, on every machine and kernel, and any departure is a
difference in the logic (a branch, a tie, a signed zero), never rounding. What differs
between machines is libm's ``cos`` and ``sin``, the same in both forms (one call each);
tests/scene/test_geometry_other_machines.py bounds that and every BLAS rounding of an older
form against another machine's contacts, and
:func:`test_contacts_are_the_same_bits_under_another_kernel` reruns the library under the
oldest kernel. The comparisons that take no BLAS product are marked ``blas_free`` too:
tests/other_kernels.py runs them with numpy's SIMD off, not again under each BLAS kernel
(they cannot see it; the rerun test checks that claim under each).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from harness.scene import Body, Box, Contact, Disk, Polygon, Rod, geometry


# ----------------------------------------------------------------------- the reference form
def _edges(core):
    count = len(core)
    if count == 1:
        return [(core[0], core[0])]
    if count == 2:
        return [(core[0], core[1])]
    return [(core[i], core[(i + 1) % count]) for i in range(count)]


def _dot(a, b):
    # x-products first, then y, one rounding each: what the library computes (never numpy's
    # ``@``, which goes through a BLAS kernel that rounds differently on another CPU)
    return float(a[0] * b[0] + a[1] * b[1])


def _closest_on_segment(x, a, b):
    ab = b - a
    length2 = _dot(ab, ab)
    if length2 == 0.0:
        return a.copy()
    t = min(1.0, max(0.0, _dot(x - a, ab) / length2))
    return a + t * ab


def _cross(a, b):
    return float(a[0] * b[1] - a[1] * b[0])


def _segments_cross(a0, a1, b0, b1):
    d1 = _cross(a1 - a0, b0 - a0)
    d2 = _cross(a1 - a0, b1 - a0)
    d3 = _cross(b1 - b0, a0 - b0)
    d4 = _cross(b1 - b0, a1 - b0)
    return d1 * d2 < 0.0 and d3 * d4 < 0.0


def _inside_polygon(x, polygon):
    if len(polygon) < 3:
        return False
    return all(_cross(b - a, x - a) > 0.0 for a, b in _edges(polygon))


def _cores_intersect(core_a, core_b):
    for a0, a1 in _edges(core_a):
        for b0, b1 in _edges(core_b):
            if _segments_cross(a0, a1, b0, b1):
                return True
    return any(_inside_polygon(x, core_b) for x in core_a) or any(
        _inside_polygon(x, core_a) for x in core_b)


def _axes(core):
    axes = []
    for a, b in _edges(core):
        edge = b - a
        length = math.hypot(edge[0], edge[1])
        if length > 0.0:
            normal = np.array([edge[1], -edge[0]]) / length
            axes += [normal, -normal]
    return axes


def _times(core, direction):
    """``core @ direction`` elementwise (:func:`_dot` row by row)."""
    return core[:, 0] * direction[0] + core[:, 1] * direction[1]


def _max(values) -> float:
    """``values.max()``, ``+0.0`` above ``-0.0`` (IEEE 754-2019's maximum, the library's
    rule): numpy's pick between zeros of both signs follows its SIMD loops from 11 values."""
    largest = float(values.max())
    zeros = values[values == 0.0]
    if largest == 0.0 and not np.isnan(values).any():
        return 0.0 if not np.signbit(zeros).all() else -0.0
    return largest


def _min(values) -> float:
    """``values.min()``, ``-0.0`` below ``+0.0`` (IEEE 754-2019's minimum; :func:`_max`)."""
    smallest = float(values.min())
    zeros = values[values == 0.0]
    if smallest == 0.0 and not np.isnan(values).any():
        return -0.0 if np.signbit(zeros).any() else 0.0
    return smallest


def _support_interval(core, normal, tangent, side, tolerance):
    heights = side * _times(core, normal)
    near = core[heights >= heights.max() - tolerance]
    along = _times(near, tangent)
    return _min(along), _max(along)


def reference_world_core(body):
    """The body's core turned and placed, ``R(θ) p + position`` row by row (elementwise, as
    the library writes it, never a BLAS product)."""
    local, radius = geometry.local_core(body.shape)
    c, s = math.cos(body.angle), math.sin(body.angle)
    rows = [(x * c - y * s + body.position[0], x * s + y * c + body.position[1])
            for x, y in local.tolist()]
    return np.array(rows, dtype=float), radius


def reference_ground_contact(body, tolerance=geometry.DEFAULT_TOLERANCE):
    core, radius = reference_world_core(body)
    lowest = _min(core[:, 1])
    gap = lowest - radius
    near = core[core[:, 1] <= lowest + tolerance]
    x_min, x_max = _min(near[:, 0]), _max(near[:, 0])
    point_count = 2 if x_max - x_min > tolerance else 1
    point = np.array([0.5 * (x_min + x_max), 0.5 * gap])
    return Contact(point=point, normal=geometry.GROUND_NORMAL.copy(), gap=float(gap),
                   point_count=point_count)


def reference_body_contact(body_a, body_b, tolerance=geometry.DEFAULT_TOLERANCE):
    core_a, radius_a = reference_world_core(body_a)
    core_b, radius_b = reference_world_core(body_b)
    scale = max(1.0, float(np.abs(np.vstack([core_a, core_b])).max()))
    touching_cores = 1e-12 * scale
    pairs = []
    for vertex in core_a:
        for b0, b1 in _edges(core_b):
            closest = _closest_on_segment(vertex, b0, b1)
            pairs.append((math.sqrt(_dot(closest - vertex, closest - vertex)), vertex, closest))
    for vertex in core_b:
        for a0, a1 in _edges(core_a):
            closest = _closest_on_segment(vertex, a0, a1)
            pairs.append((math.sqrt(_dot(vertex - closest, vertex - closest)), closest, vertex))
    distance, closest_a, closest_b = min(pairs, key=lambda pair: pair[0])
    if distance > touching_cores and not _cores_intersect(core_a, core_b):
        normal = (closest_b - closest_a) / distance
        core_separation = distance
    else:
        axes = _axes(core_a) + _axes(core_b)
        if not axes:
            axes = [geometry.GROUND_NORMAL.copy()]
        separations = [float(_times(core_b, axis).min() - _times(core_a, axis).max())
                       for axis in axes]
        best = int(np.argmax(separations))
        normal, core_separation = axes[best], min(0.0, separations[best])
    tangent = np.array([normal[1], -normal[0]])
    a_lo, a_hi = _support_interval(core_a, normal, tangent, +1, tolerance)
    b_lo, b_hi = _support_interval(core_b, normal, tangent, -1, tolerance)
    low, high = max(a_lo, b_lo), min(a_hi, b_hi)
    point_count = 2 if high - low > tolerance else 1
    gap = core_separation - radius_a - radius_b
    if point_count == 1 and core_separation > 0.0:
        point = 0.5 * ((closest_a + radius_a * normal) + (closest_b - radius_b * normal))
    else:
        plane_a = _max(_times(core_a, normal)) + radius_a
        plane_b = _min(_times(core_b, normal)) - radius_b
        along = 0.5 * (low + high) if high >= low else 0.5 * (max(a_lo, b_lo) + min(a_hi, b_hi))
        point = along * tangent + 0.5 * (plane_a + plane_b) * normal
    return Contact(point=point, normal=normal, gap=float(gap), point_count=point_count)


# -------------------------------------------------------------------------------- helpers
def bits(contact: Contact) -> tuple:
    """Everything a contact holds, as bytes (so 0.0 and -0.0 differ)."""
    return (np.asarray(contact.point, dtype=float).tobytes(),
            np.asarray(contact.normal, dtype=float).tobytes(),
            np.float64(contact.gap).tobytes(), contact.point_count)


def assert_same_contacts(found, expected, what) -> None:
    """Contacts ``found`` are those ``expected`` (lists of them), bit for bit: both forms
    perform the same IEEE operations in the same order, with no BLAS product (module
    docstring), so any difference at all is a defect."""
    assert len(found) == len(expected), what
    for contact, reference in zip(found, expected):
        assert bits(contact) == bits(reference), (what, contact, reference)


def regular_polygon(sides, radius):
    return Polygon(tuple((radius * math.cos(2 * math.pi * k / sides),
                          radius * math.sin(2 * math.pi * k / sides)) for k in range(sides)))


def random_shape(rng):
    kind = int(rng.integers(4))
    if kind == 0:
        return Disk(float(rng.uniform(0.01, 0.5)))
    if kind == 1:
        return Rod(float(rng.uniform(0.1, 2.0)), float(rng.choice([0.0, rng.uniform(0.001, 0.1)])))
    if kind == 2:
        return Box(float(rng.uniform(0.05, 1.0)), float(rng.uniform(0.05, 1.0)))
    return regular_polygon(int(rng.integers(3, 9)), float(rng.uniform(0.05, 0.5)))


def random_angle(rng):
    # Exact quarter turns lay faces flat and give exact zeros in the cores.
    return float(rng.choice([0.0, math.pi / 2, math.pi, -math.pi / 2, rng.uniform(-7.0, 7.0)]))


TOLERANCES = (geometry.DEFAULT_TOLERANCE, 1e-6)


# ---------------------------------------------------------------------------------- tests
@pytest.mark.kernel_sensitive
@pytest.mark.blas_free
def test_random_pairs_apart_touching_and_overlapping_give_the_reference_contact():
    rng = np.random.default_rng(20261122)
    branches = {"apart": 0, "cores touch or overlap": 0, "two points": 0}
    for _ in range(3000):
        a = Body("a", random_shape(rng), 1.0, (0.0, 0.0), random_angle(rng))
        position = rng.uniform(-1.0, 1.0, 2) * float(rng.choice([0.0, 0.1, 0.5, 1.0]))
        b = Body("b", random_shape(rng), 1.0, (float(position[0]), float(position[1])),
                 random_angle(rng))
        for tolerance in TOLERANCES:
            expected = reference_body_contact(a, b, tolerance)
            assert_same_contacts([geometry.body_contact(a, b, tolerance)], [expected], (a, b))
            branches["apart" if expected.gap > 0 else "cores touch or overlap"] += 1
            branches["two points"] += expected.point_count == 2
    assert min(branches.values()) > 100, branches  # every branch is exercised


@pytest.mark.kernel_sensitive
@pytest.mark.blas_free
def test_faces_lying_exactly_on_faces_give_the_reference_contact():
    # Stacked boxes and polygons touching along a face: two points, exact zeros, ties.
    rng = np.random.default_rng(7)
    for _ in range(500):
        lower = Box(float(rng.uniform(0.2, 1.0)), float(rng.choice([0.2, 0.25, 0.5])))
        upper = rng.choice([Box(float(rng.uniform(0.1, 1.0)), 0.5), Rod(0.5, 0.25),
                            regular_polygon(4, 0.25 * math.sqrt(2.0))])
        shift = float(rng.choice([0.0, 0.25, rng.uniform(-0.5, 0.5)]))
        height = lower.height / 2 + 0.25 + float(rng.choice([0.0, 1e-10, -1e-10, 0.1]))
        angle = math.pi / 4 if isinstance(upper, Polygon) else 0.0
        a = Body("a", lower, 1.0, (0.0, 0.0))
        b = Body("b", upper, 1.0, (shift, height), angle)
        for first, second in ((a, b), (b, a)):
            for tolerance in TOLERANCES:
                expected = reference_body_contact(first, second, tolerance)
                assert_same_contacts([geometry.body_contact(first, second, tolerance)],
                                     [expected], (first, second))


@pytest.mark.kernel_sensitive
@pytest.mark.blas_free
def test_ground_contacts_give_the_reference_contact():
    rng = np.random.default_rng(11)
    for _ in range(2000):
        body = Body("b", random_shape(rng), 1.0, tuple(rng.uniform(-0.5, 0.5, 2).tolist()),
                    random_angle(rng))
        for candidate in (body, geometry.place_on_ground(body)):
            for tolerance in TOLERANCES:
                expected = reference_ground_contact(candidate, tolerance)
                assert_same_contacts([geometry.ground_contact(candidate, tolerance)],
                                     [expected], candidate)


@pytest.mark.parametrize("values", [[0.0, -0.0], [-0.0, 0.0], [-0.0, 0.0, 0.0, -1.0],
                                    [1.0, -0.0, 0.0, 0.0, -0.0], [-2.0, -0.0], [3.0, 3.0],
                                    [0.0, 0.0, 1.0], [-0.0, 1.0, -0.0], [0.0, -1.0, 0.0],
                                    [0.0, math.nan], [math.nan, 0.0, 0.5], [-0.0, math.nan],
                                    [0.0, 2.0, 1.0, 0.0, 3.0, 0.0, 4.0, 5.0, 6.0, -0.0],
                                    [-0.0] * 9 + [1.0], [0.0] * 17 + [-1.0],
                                    [-0.0] * 12 + [0.0] * 5 + [-1.0] * 3,
                                    [0.0] * 7 + [-0.0] * 9 + [1.0] * 2 + [-1.0] * 2])
def test_largest_and_smallest_pick_a_signed_zero_by_ieee_not_by_numpys_simd(values):
    # World cores seldom hold -0.0 (the products that turn them add +0.0), so the random
    # cases above rarely reach the choice between zeros; it is checked here directly. Between
    # zeros of both signs the largest is +0.0 and the smallest -0.0 (IEEE 754-2019's maximum
    # and minimum), whatever the length: numpy's max and min pick by their SIMD loops from 11
    # values (AVX-512, AVX2 and the baseline differ, tested with NPY_DISABLE_CPU_FEATURES).
    array = np.array(values)
    for got, extreme, numpys, sign in (
            (geometry._largest(values), _max(array), np.max(array), 1.0),  # noqa: SLF001
            (geometry._smallest(values), _min(array), np.min(array), -1.0)):  # noqa: SLF001
        assert np.float64(got).tobytes() == np.float64(extreme).tobytes()
        if any(math.isnan(value) for value in values):
            assert math.isnan(got)
        elif got == 0.0 and len({math.copysign(1.0, v) for v in values if v == 0.0}) == 2:
            assert math.copysign(1.0, got) == sign
        else:  # one zero sign, or no zero at the extreme: numpy's value, to the bit
            assert np.float64(got).tobytes() == numpys.tobytes()


@pytest.mark.kernel_sensitive
@pytest.mark.blas_free
def test_contacts_at_several_tolerances_are_each_tolerances_reference_contact():
    # core_contacts shares the support intervals of equal near points between tolerances:
    # random pairs and faces lying flat (where the tolerances pick different near points),
    # tolerances in either order.
    rng = np.random.default_rng(404)
    flat = 0
    for index in range(1500):
        if index % 2:
            a = Body("a", random_shape(rng), 1.0, (0.0, 0.0), random_angle(rng))
            position = rng.uniform(-1.0, 1.0, 2) * float(rng.choice([0.0, 0.1, 0.5, 1.0]))
            b = Body("b", random_shape(rng), 1.0, (float(position[0]), float(position[1])),
                     random_angle(rng))
        else:
            a = Body("a", Box(float(rng.uniform(0.2, 1.0)), 0.5), 1.0, (0.0, 0.0))
            tilt = float(rng.choice([0.0, 1e-8, 1e-5, 1e-3]))
            b = Body("b", Box(float(rng.uniform(0.1, 1.0)), 0.5), 1.0,
                     (float(rng.uniform(-0.5, 0.5)), 0.5 + float(rng.choice([0.0, 1e-10]))),
                     tilt)
        core_a, radius_a = geometry.world_core(a)
        core_b, radius_b = geometry.world_core(b)
        for tolerances in ((1e-9, 1e-6, 1e-3), (1e-3, 1e-9)):
            found = geometry.core_contacts(core_a, radius_a, core_b, radius_b, tolerances)
            expected = [reference_body_contact(a, b, tolerance) for tolerance in tolerances]
            assert_same_contacts(found, expected, (a, b))
            flat += len({e.point_count for e in expected}) > 1
    assert flat > 50  # the tolerances disagree on the point count often enough


@pytest.mark.kernel_sensitive
@pytest.mark.blas_free
def test_scene_contact_each_is_scene_contact_at_each_tolerance():
    # The scenario checks' two contacts of a point from one world core per body: ground
    # scenes (resting and lifted bodies, faces flat) and pairs, tolerances in either order.
    from harness.scene import Scene

    rng = np.random.default_rng(1123)
    flat = 0
    for index in range(1000):
        a = Body("a", random_shape(rng), 1.0, tuple(rng.uniform(-0.5, 0.5, 2).tolist()),
                 random_angle(rng))
        if index % 4 == 3:  # a box tilted off lying flat by less than some tolerances
            a = Body("a", Box(float(rng.uniform(0.1, 1.0)), 0.5), 1.0, (0.0, 1.0),
                     float(rng.choice([0.0, 1e-8, 1e-5, 1e-3])))
        if index % 2:
            scene = Scene((a if index % 8 == 1 else geometry.place_on_ground(a),), 0.5, 0.3,
                          ground=True)
        else:
            position = rng.uniform(-1.0, 1.0, 2) * float(rng.choice([0.0, 0.1, 0.5, 1.0]))
            b = Body("b", random_shape(rng), 1.0, (float(position[0]), float(position[1])),
                     random_angle(rng))
            scene = Scene((a, b), 0.5, 0.3)
        for tolerances in ((1e-4, geometry.DEFAULT_TOLERANCE), (1e-9, 1e-3, 1e-6)):
            found = geometry.scene_contact_each(scene, tolerances)
            expected = [geometry.scene_contact(scene, tolerance) for tolerance in tolerances]
            # Both are the library's own, from the same products: exact on every machine.
            assert [bits(c) for c in found] == [bits(e) for e in expected], scene
            flat += len({e.point_count for e in expected}) > 1
    assert flat > 20  # tolerances that disagree on the point count are among them


def contacts_digest(count: int = 400) -> str:
    """SHA-256 of every bit of the library's contacts of ``count`` random pairs and ground
    bodies at both :data:`TOLERANCES` (run here and, by the test below, under another
    kernel)."""
    import hashlib

    rng = np.random.default_rng(35)
    digest = hashlib.sha256()
    for _ in range(count):
        a = Body("a", random_shape(rng), 1.0, tuple(rng.uniform(-0.5, 0.5, 2).tolist()),
                 random_angle(rng))
        b = Body("b", random_shape(rng), 1.0, tuple(rng.uniform(-1.0, 1.0, 2).tolist()),
                 random_angle(rng))
        for tolerance in TOLERANCES:
            for contact in (geometry.body_contact(a, b, tolerance),
                            geometry.ground_contact(a, tolerance)):
                digest.update(repr(bits(contact)).encode())
    return digest.hexdigest()


@pytest.mark.kernel_sensitive
def test_contacts_are_the_same_bits_under_another_kernel():
    # Bit for bit, rerun against rerun on this machine: the contacts take no BLAS product, so
    # OpenBLAS's oldest kernel (Prescott, x86-64) with numpy's SIMD loops off must give the
    # same bits as this run's kernels (whichever tests/other_kernels.py chose).
    from tests.other_kernels import printed_under_old_kernel

    there = printed_under_old_kernel("tests.scene.test_geometry_reference", "contacts_digest")
    assert there == contacts_digest()
