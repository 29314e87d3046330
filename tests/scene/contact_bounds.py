"""How far a contact (harness/scene/geometry.py) computed on one machine can be from the same
contact computed on another: a forward error bound, derived step by step from the formulas of
tests/error_bounds.py (docs/verdicts.md, 'Same answers on every CPU').

Each machine's contact is within the bound of the exact contact of the same bodies (exact
inputs: shape sizes, angle, position), whatever its kernels round: BLAS products (FMA or
not, any summation order) or the elementwise form the library now uses, and a libm whose
``cos`` and ``sin`` are within 1 ulp. Two machines' contacts are therefore within the sum of
their bounds; :func:`contact_bound` works the bound out from this machine's quantities (the
other's differ from them by far less than the bound's own size, a second-order effect).

The steps (``u`` the unit roundoff, ``γ_n`` as in tests/error_bounds.py, ``|·|`` Euclidean):

1. World core. Each coordinate ``x cos θ − y sin θ + p`` is a dot product of three terms
   with ``cos θ`` and ``sin θ`` each within ``2u`` relative: within
   ``E = γ_5 max(|x| + |y| + |p|)`` (``γ_3`` of the sum, Higham eq. (3.5), and ``γ_2`` for
   libm, Lemma 3.3), so each core point within ``r = √2 E`` of its exact place.
2. Cores apart: the closest pair is a vertex ``X`` and the point ``F = S + t d`` of an edge
   (``d = T − S``, ``w = X − S``, ``t = w·d / |d|²`` clamped to ``[0, 1]``), ``v = F − X``
   (signed from A to B) and ``D = |v|``.

   * Moving every core point by at most ``r`` moves ``v`` by at most
     ``4r + (|w| + t|d|) δd`` with ``δd`` = :func:`direction_bound` ``(2r, |d|)`` (about
     ``r (8 + 4|w|/|d|)``): ``X`` moves ``r``, ``S`` moves ``r``, ``w`` by ``2r`` and the
     edge's unit direction by ``δd``, so the foot's distance ``w·d/|d|`` along it moves by
     ``2r + |w| δd`` and the foot by that plus ``r`` plus ``t|d| δd`` (at an end, ``F`` is
     that end: ``2r`` in all).
   * Rounding on the computed cores: ``d`` and ``w`` within ``u`` per component; ``w·d`` within
     ``γ_2 Σ|w_i d_i|`` plus what ``d`` and ``w`` carry; ``|d|²`` within ``γ_2 |d|²``; one
     division: ``t |d|`` within ``γ_6 (|w| + t|d|)``; then ``S + t d`` and ``F − X``, two and
     one roundings per component: ``√2 (γ_2 (|S|_∞ + t|d|_∞) + u t|d|_∞ + u |v|_∞)``, with
     ``|S|_∞ <= |F|_∞ + t|d|`` (the code takes Euclidean lengths, never smaller).
   * ``δv`` is the sum; the normal ``v / D`` is within :func:`direction_bound` ``(δv, D)``
     plus ``γ_3`` (the sum of squares, the square root and the division); the gap
     ``D − r_a − r_b`` within ``δv + γ_4 (D + r_a + r_b)``; the point (midway between the
     surfaces, each a closest point moved by its radius along the normal) within
     ``δv + (r_a + r_b) δn / 2 + γ_4 (|F_a| + |F_b| + r_a + r_b)``.
3. Cores touching or overlapping: the normal is an edge's unit normal ``(d_y, −d_x)/|d|``,
   within :func:`direction_bound` ``(2r + √2 u |d|, |d|)`` plus ``γ_3`` (``hypot``, within 1 ulp,
   and the division); a projection ``P·n`` of a core point within
   ``δp = |P| δn + r + γ_2 |P|_1`` (``|P|_1 = |P_x| + |P_y|``, taken at the largest); the
   separation, a difference of two projections, within ``2 δp`` plus ``u`` of it, and the gap
   within that plus ``γ_2 (|separation| + r_a + r_b)``.
4. Two points, or cores overlapping: the point is ``along t + middle n`` from the support
   intervals (projections on the tangent ``t`` and normal ``n``, each within ``δp``):
   within ``2 δp + (|along| + |middle|) δn + γ_2 (|along| + |middle|)``.

Decisions (the branch apart/overlapping, which pair is closest, which axis separates most,
which points are within ``tolerance`` of the support line, two points or one) are compared as
decisions with a band: where the quantity decided on is within its error bound of the
threshold (or of the runner-up), either outcome is right, and the values that follow from it
are not compared (:attr:`ContactBound.undecided` names them).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from harness.scene import Body, geometry
from tests.error_bounds import U, direction_bound, gamma


@dataclass
class ContactBound:
    """Bounds (m, or dimensionless for the normal) on how far a computed contact's fields can
    be from the exact contact; ``undecided``: the decisions within their band here."""

    normal: float
    gap: float
    point: float
    undecided: list[str] = field(default_factory=list)
    #: the normals either outcome of an undecided choice of pair or axis gives (the
    #: contact's own first), each within ``normal`` of the exact one for that outcome
    normals: list[np.ndarray] = field(default_factory=list)


def core_bound(body: Body) -> float:
    """``E``: each world-core coordinate of ``body`` is within this of its exact value (step 1)."""
    local, _ = geometry.local_core(body.shape)
    position = max(abs(float(body.position[0])), abs(float(body.position[1])))
    largest = max(abs(float(x)) + abs(float(y)) for x, y in local.tolist()) + position
    return gamma(5) * largest


def _edges(core):
    count = len(core)
    if count <= 2:
        return [(core[0], core[-1])]
    return [(core[i], core[(i + 1) % count]) for i in range(count)]


def _pair(vertex, start, end):
    """The closest point of the edge to ``vertex`` and its error terms (step 2)."""
    d, w = end - start, vertex - start
    length2 = float(d[0] * d[0] + d[1] * d[1])
    t = 0.0 if length2 == 0.0 else min(1.0, max(0.0, float(w[0] * d[0] + w[1] * d[1]) / length2))
    foot = start + t * d
    return foot, t, float(math.hypot(*d)), float(math.hypot(*w))


def _pairs(core_a, core_b):
    """Every vertex-edge pair: ``(distance, point on A, point on B, t, |d|, |w|)``."""
    pairs = []
    for vertex in core_a:
        for start, end in _edges(core_b):
            foot, t, d, w = _pair(vertex, start, end)
            pairs.append((float(math.hypot(*(foot - vertex))), vertex, foot, t, d, w))
    for vertex in core_b:
        for start, end in _edges(core_a):
            foot, t, d, w = _pair(vertex, start, end)
            pairs.append((float(math.hypot(*(vertex - foot))), foot, vertex, t, d, w))
    return pairs


def _difference_bound(r, pair) -> float:
    """``δv`` of step 2 for one vertex-edge pair."""
    distance, on_a, on_b, t, d, w = pair
    moved = (2.0 * r if t in (0.0, 1.0) or d == 0.0
             else 4.0 * r + (w + t * d) * direction_bound(2.0 * r, d))
    # |S|_∞ <= |F|_∞ + t|d|, and F is one of the pair's two points
    start = max(np.abs(on_a).max(), np.abs(on_b).max()) + t * d
    rounded = gamma(6) * (w + t * d) + math.sqrt(2.0) * (
        gamma(2) * (start + t * d) + U * t * d + U * distance)
    return moved + rounded


def contact_bound(body_a: Body, body_b: Body, tolerance: float) -> ContactBound:
    """The forward error bound of :func:`harness.scene.geometry.body_contact` (steps 1–4 of
    this module's docstring), with the decisions taken within their band."""
    core_a, radius_a = geometry.world_core(body_a)
    core_b, radius_b = geometry.world_core(body_b)
    r = math.sqrt(2.0) * max(core_bound(body_a), core_bound(body_b))
    largest = float(np.abs(np.vstack([core_a, core_b])).max())  # |P|_∞ of any core point
    radii = radius_a + radius_b
    undecided = []
    contact = geometry.body_contact(body_a, body_b, tolerance)
    normals = [np.asarray(contact.normal, dtype=float)]
    pairs = _pairs(core_a, core_b)
    distance = min(pair[0] for pair in pairs)
    apart = contact.gap + radii > 0.0  # the library's branch: cores apart (step 2)
    if apart:
        chosen = [pair for pair in pairs if pair[0] == distance]
        delta_v = max(_difference_bound(r, pair) for pair in chosen)
        normal = direction_bound(delta_v, distance) + gamma(3)
        gap = delta_v + gamma(4) * (distance + radii)
        feet = max(float(np.abs(pair[1]).sum() + np.abs(pair[2]).sum()) for pair in chosen)
        point = delta_v + radii * normal / 2.0 + gamma(4) * (feet + radii)
        # Which pair is closest: another pair within both pairs' bounds could be chosen.
        rivals = [pair for pair in pairs if pair[0] > distance
                  and pair[0] - distance <= delta_v + _difference_bound(r, pair)
                  and (np.abs(pair[1] - chosen[0][1]).max() > point
                       or np.abs(pair[2] - chosen[0][2]).max() > point)]
        if rivals:
            undecided.append("closest pair")
            normals += [(pair[2] - pair[1]) / pair[0] for pair in rivals]
        # Apart or touching: the distance against the library's threshold.
        threshold = 1e-12 * max(1.0, largest)
        if abs(distance - threshold) <= delta_v:
            undecided.append("apart or touching")
    else:
        lengths = [float(math.hypot(*(end - start))) for core in (core_a, core_b)
                   for start, end in _edges(core) if np.any(end != start)]
        if lengths:
            shortest = min(lengths)
            normal = direction_bound(2.0 * r + math.sqrt(2.0) * U * shortest,
                                     shortest) + gamma(3)
        else:  # two coincident points: the normal is the fixed (0, 1), exact
            normal = 0.0
        projection = largest * math.sqrt(2.0) * normal + r + gamma(2) * 2.0 * largest
        separation = contact.gap + radii
        gap = 2.0 * projection + U * abs(separation) + gamma(2) * (abs(separation) + radii)
        point = math.inf  # set by step 4 below: this branch's point is the interval's
        # Which axis separates most: another within both bounds of the best could be chosen.
        separations = _axis_separations(core_a, core_b)
        best = max(value for value, _ in separations)
        rivals = [axis for value, axis in separations if value >= best - 2.0 * gap
                  and np.abs(axis - contact.normal).max() > normal]
        if rivals:
            undecided.append("separating axis")
            normals += rivals
        if abs(distance - 1e-12 * max(1.0, largest)) <= 2.0 * projection:
            undecided.append("apart or touching")

    # Step 4, and the decisions of the support intervals.
    projection = largest * math.sqrt(2.0) * normal + r + gamma(2) * 2.0 * largest
    along, middle, near_undecided, width = _support(core_a, core_b, radius_a, radius_b,
                                                    contact.normal, tolerance, 2.0 * projection)
    if near_undecided:
        undecided.append("near points")
    if abs(width - tolerance) <= 2.0 * projection:
        undecided.append("point count")
    if contact.point_count == 2 or not apart:
        point = 2.0 * projection + (abs(along) + abs(middle)) * (normal + gamma(2))
    return ContactBound(normal=normal, gap=gap, point=point, undecided=undecided,
                        normals=normals)


def _axis_separations(core_a, core_b):
    """Each edge normal's separation ``min(B·n) − max(A·n)`` and the normal (step 3)."""
    rows = []
    for start, end in _edges(core_a) + _edges(core_b):
        edge = end - start
        length = float(math.hypot(*edge))
        if length > 0.0:
            axis = np.array([edge[1], -edge[0]]) / length
            for n in (axis, -axis):
                value = float((core_b @ n).min() - (core_a @ n).max())
                rows.append((value, n))
    return rows or [(0.0, np.array([0.0, 1.0]))]


def _support(core_a, core_b, radius_a, radius_b, normal, tolerance, band):
    """The point's ``along`` and ``middle`` (step 4), whether a core point lies within
    ``band`` of the ``tolerance`` cut of a support line, and the shared interval's width."""
    normal = np.asarray(normal, dtype=float)
    tangent = np.array([normal[1], -normal[0]])
    undecided = False
    intervals = []
    for core, side in ((core_a, 1.0), (core_b, -1.0)):
        heights = side * (core @ normal)
        cut = heights.max() - tolerance
        undecided |= bool(np.any(np.abs(heights - cut) <= band) and len(core) > 1)
        along = core[heights >= cut] @ tangent
        intervals.append((float(along.min()), float(along.max())))
    (a_lo, a_hi), (b_lo, b_hi) = intervals
    low, high = max(a_lo, b_lo), min(a_hi, b_hi)
    plane_a = float((core_a @ normal).max()) + radius_a
    plane_b = float((core_b @ normal).min()) - radius_b
    return 0.5 * (low + high), 0.5 * (plane_a + plane_b), undecided, high - low
