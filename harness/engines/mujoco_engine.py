"""MuJoCo adapter.

MuJoCo has no restitution coefficient: a contact is a soft constraint whose reference
acceleration is ``a_ref = -b·v - k·r`` (``r`` the penetration, ``v`` its rate); with an
impedance ``d`` near 1 the constraint space follows it, so over an impact the normal
direction behaves as a spring-damper that cannot pull. Its restitution follows from the
damping ratio ``ζ = b / (2·sqrt(k))`` alone (:func:`restitution_of_damping_ratio`): the
contact ends when ``k·r + b·v`` reaches 0, before the bodies separate, which is why
``e = 0.5`` needs ``ζ = 0.2553`` and not the linear formula's 0.2155. Friction is soft too,
and under ``accurate`` the same damping sets how much of the slip it removes (below).

Presets: ``defaults`` and ``matched-bounce``, the name this engine shows for the harness's
``accurate`` role (harness/engines/__init__.py): it matches the bounce ``e·|v_n|``, but with
friction leaving ``e²`` of the slip it creates kinetic energy in a part of the impacts with
``m_nt ≠ 0`` (docs/engines.md, 'MuJoCo'); no setting that keeps the bounce prevents it.

``matched-bounce`` sets, from the scene's ``e``, ``solref = (-k, -b)`` (MuJoCo's direct form) with
``ζ`` from the unilateral map and ``k`` such that the contact lasts ``contact_steps`` steps,
and a flat ``solimp`` (``d = 0.9999`` at every depth). ``defaults`` is MuJoCo's
``solref = (0.02, 1)``, ``solimp = (0.9, 0.95, 0.001, 0.5, 2)`` -- ``e`` is then not used
(measured restitution ≈ 0.13).

Planar motion: slide x, slide z and hinge y joints with an explicit ``<inertial>`` (mass and
the scene's inertia). The scene's (x, y) is MuJoCo's (x, z); the hinge's angle and rate are
``-θ`` and ``-ω``. Shapes: disk -> sphere; rod -> capsule along the body's x; box -> box;
polygon -> mesh (the polygon extruded along y); ellipse -> ellipsoid with semi-axes
``(semi_x, c, semi_y)`` (:func:`_geom_size`). Ground: an infinite plane, normal +z.
``μ = 0`` uses ``condim = 1`` (frictionless contact); otherwise ``condim = 3``.

Friction under ``matched-bounce``: the slip falls to ``e²`` of its start, and not at all at e = 1
    MuJoCo's friction rows have no spring term, only the contact's damping ``b``. Pyramidal
    cone: the two edge rows ``J_n ± μ·J_t`` both get ``a_ref = -b·(v_n ± μ·v_t) - k·r``;
    while both push, their difference gives the tangential reference ``a_t = -b·v_t`` (the
    ``k·r`` terms cancel). Elliptic cone: ``K = 0`` on the friction rows, so again
    ``a_t = -b·v_t``. With ``d`` near 1 the contact point's slip falls as ``exp(-b·t)`` while
    inside the cone, and over the contact time ``T = φ(ζ)/ω₀`` (:func:`contact_time_factor`)
    by ``exp(-b·T) = exp(-2ζ·φ(ζ)) = e²``: the ``b = 2ζω₀`` that sets the bounce also sets
    the friction. Measured (disk, slip 0.1 m/s, μ 0.3): slip ratio 0.8103 / 0.4905 / 0.2506
    / 0.0908 / 0.0100 at e = 0.9 / 0.7 / 0.5 / 0.3 / 0.1, e² within 8e-4 (the cone saturates
    only as the normal force vanishes at the end). A larger slip saturates the cone early and
    keeps more (reference disk, slip 1 m/s, e = 0.5: 0.265; docs/engines.md, 'MuJoCo').
    At ``e = 1`` (ζ = 0, b = 0) both edges get the same ``a_ref = -k·r``, carry equal forces,
    and the tangential impulse is exactly 0: the bounce is frictionless whatever μ and the
    spin. ``disk-backspin-elastic`` comes out with v_x 1 and ω -20 as it went in; its 28.9%
    departure from Poisson is the distance of the frictionless bounce from the law
    (1/sqrt(12)). The elliptic cone, impratio 100, noslip 50 and CG also give exactly 0
    (PGS 1.6e-6 N s, its iteration error): ``impratio`` scales only the regularisation ``R``,
    tiny at ``d = 0.9999``, and noslip works towards the same ``a_ref``.
    This is MuJoCo's contact model fed the adapter's e -> ζ map, not a set-up error: the
    geom friction reaches the contact (``mu`` 0.3 by the max rule) and ``condim`` 3 makes
    four pyramid rows. MuJoCo's one way to decouple, ``solreffriction``, exists only on
    explicit ``<pair>`` contacts and acts only with the elliptic cone. Tried, not used: a
    friction damping strong enough to give Poisson's tangential result at e = 1
    (``solreffriction = (0, -1e5)``: v_x 1.3334, ω -13.334) spoils the bounce through the
    cone (v_y 0.215 instead of 1; 0.824 at ``-1e4``).

Pair values: MuJoCo takes the larger friction of the two geoms, so the partner (plane, or
``bodies[1]``) has friction 0 and ``bodies[0]`` has ``μ``; both geoms get the same
``solref``/``solimp`` (MuJoCo averages them).

Reuse: one compiled ``MjModel`` and ``MjData`` per topology (ground or not, shape kinds),
for ``run`` and ``run_many`` alike (``run_many`` is ``run`` per scene: the engine steps one
impact per model, see docs/engines.md, 'MuJoCo'). For disks, rods and boxes a scene's
sizes, bounding spheres and boxes, masses and inertias are written into the model,
``mj_setConst`` derives subtree masses, ``invweight0``, ``dof_M0`` and ``dof_length``, and
:func:`_write_statistics` the statistics (MuJoCo 4's ``mj_setConst`` leaves them; the
solver reads ``meaninertia``): every array equals a fresh compile's, bit for bit
(tests/engines/test_mujoco_geometry.py). A polygon's mesh goes through the compiler
(hull, centroid, inertial frame): a copy of the topology's parsed spec takes the scene's
values and is compiled, about half the cost of parsing XML; the models of a topology share
one ``MjData`` per layout. Each run makes the model hold every option and contact parameter
of its settings, ``e`` and ``μ`` (rewritten whenever they differ by value from what the
model holds) and calls ``mj_resetData``, so reruns are bit-identical. A step reads its
contacts through one numpy view of the data's arena, made once per data
(``_contact_rows``), and its constraint forces through views of the same arena made once
per row count (``_force_view``) and kept while the data, model and options stay. The
contact impulse is MuJoCo's total constraint impulse on body B, ``M·Δq̇`` (exact here: no
gravity, no passive forces, constant mass matrix).

Settings (``defaults`` | ``accurate``, shown as ``matched-bounce``) are listed in
:data:`SETTING_DOCS`.
"""

from __future__ import annotations

import functools
import math
import struct
from collections import OrderedDict
from dataclasses import dataclass, field
from fractions import Fraction

import mujoco
import numpy as np

from harness.engines.contract import (
    BENCH_REFERENCE_LABEL,
    Engine,
    RawContacts,
    StepTiming,
    body_extent,
)
from harness.engines.settings import (
    EngineSettingsError,
    check_choice,
    check_int,
    check_number,
    check_vector,
)
from harness.scene import Scene

# Fraction of a step of free flight by which the start is past the touching pose.
_DETECTION_OVERLAP = 1e-6
# Smallest restitution the unilateral spring-damper is asked for: e = 0 needs ζ = ∞.
MIN_RESTITUTION = 1e-3

SETTING_DOCS: dict[str, str] = {
    "time_step": "s, opt.timestep (default 0.002)",
    "integrator": "opt.integrator: Euler | implicit | implicitfast | RK4 (default Euler)",
    "cone": "opt.cone: pyramidal | elliptic (default pyramidal)",
    "solver": "opt.solver: Newton | CG | PGS (default Newton)",
    "iterations": "opt.iterations (default 100)",
    "tolerance": "opt.tolerance (default 1e-8)",
    "ls_iterations": "opt.ls_iterations, line-search iterations (default 50)",
    "noslip_iterations": "opt.noslip_iterations (default 0)",
    "noslip_tolerance": "opt.noslip_tolerance (default 1e-6)",
    "impratio": "opt.impratio, friction-to-normal impedance ratio (default 1)",
    "solref": "[timeconst s, dampratio] or direct [-stiffness, -damping], or \"restitution\": "
    "direct form from e and contact_steps (default [0.02, 1])",
    "contact_steps": "steps a contact lasts when solref is \"restitution\"",
    "solimp": "[dmin, dmax, width m, midpoint, power] (default [0.9, 0.95, 0.001, 0.5, 2])",
    "margin": "m, geom margin: contacts become active this far apart (default 0)",
    "max_steps": "step cap; reported as status no-separation when hit in contact",
    "approach_steps": "steps of free flight before first touch (0 = touching at the first step)",
}

_DEFAULTS = {
    "time_step": 0.002,
    "integrator": "Euler",
    "cone": "pyramidal",
    "solver": "Newton",
    "iterations": 100,
    "tolerance": 1e-8,
    "ls_iterations": 50,
    "noslip_iterations": 0,
    "noslip_tolerance": 1e-6,
    "impratio": 1.0,
    "solref": [0.02, 1.0],
    "contact_steps": 100,
    "solimp": [0.9, 0.95, 0.001, 0.5, 2.0],
    "margin": 0.0,
    "max_steps": 20000,
    "approach_steps": 0.0,
}
PRESETS: dict[str, dict] = {
    "defaults": dict(_DEFAULTS),
    "accurate": dict(
        _DEFAULTS,
        # RK4 over a 0.5 ms contact of 50 steps reproduces the unilateral spring-damper's
        # bounce to ~1e-5 (Euler's first-order error is ~0.5/contact_steps: -0.9% at e = 0.5
        # with 100 steps, -4% at e = 0.1), at the cost of Euler with ~100 steps.
        time_step=1e-5,
        integrator="RK4",
        solref="restitution",
        contact_steps=50,
        solimp=[0.9999, 0.9999, 0.001, 0.5, 2.0],
    ),
}

_INTEGRATORS = {
    "Euler": mujoco.mjtIntegrator.mjINT_EULER,
    "RK4": mujoco.mjtIntegrator.mjINT_RK4,
    "implicit": mujoco.mjtIntegrator.mjINT_IMPLICIT,
    "implicitfast": mujoco.mjtIntegrator.mjINT_IMPLICITFAST,
}
_CONES = {"pyramidal": mujoco.mjtCone.mjCONE_PYRAMIDAL, "elliptic": mujoco.mjtCone.mjCONE_ELLIPTIC}
_SOLVERS = {
    "Newton": mujoco.mjtSolver.mjSOL_NEWTON,
    "CG": mujoco.mjtSolver.mjSOL_CG,
    "PGS": mujoco.mjtSolver.mjSOL_PGS,
}


# ---------------------------------------------------------------------- e <-> ζ
def contact_time_factor(damping_ratio: float) -> float:
    """``ω₀·T``: duration ``T`` of a unilateral spring-damper contact times its ``ω₀ = sqrt(k)``.

    The penetration obeys ``r'' + 2ζω₀ r' + ω₀² r = 0`` from ``r = 0, r' = v₀`` until the
    contact force ``2ζω₀ r' + ω₀² r`` returns to 0 (it cannot pull).
    """
    zeta = float(damping_ratio)
    if zeta < 0:
        raise ValueError(f"damping ratio must be >= 0, got {zeta}")
    if zeta == 0.0:
        return math.pi
    if zeta < 1.0:
        s = math.sqrt(1.0 - zeta * zeta)
        return math.atan2(2.0 * zeta * s, -(1.0 - 2.0 * zeta * zeta)) / s
    if zeta == 1.0:
        return 2.0
    sigma = math.sqrt(zeta * zeta - 1.0)
    return math.atanh(2.0 * zeta * sigma / (2.0 * zeta * zeta - 1.0)) / sigma


def restitution_of_damping_ratio(damping_ratio: float) -> float:
    """Restitution of the unilateral spring-damper: ``e = exp(-ζ·ω₀T(ζ))``.

    Closed form: in the underdamped case the force vanishes at phase
    ``φ = atan2(2ζs, 2ζ² - 1)`` (``s = sqrt(1 - ζ²)``), where the exit speed is
    ``v₀·exp(-ζφ/s)``; the overdamped branch is its analytic continuation.
    ``e(0.2553) = 0.5``, ``e(1) = exp(-2)``, ``e → 1/(4ζ²)`` for large ``ζ``.
    """
    zeta = float(damping_ratio)
    return math.exp(-zeta * contact_time_factor(zeta))


def damping_ratio_for_restitution(restitution: float) -> float:
    """Inverse of :func:`restitution_of_damping_ratio` (bisection to rounding).

    ``e`` is clamped to ``[MIN_RESTITUTION, 1]``: ``e = 0`` would need ``ζ = ∞``.
    """
    e = min(max(float(restitution), MIN_RESTITUTION), 1.0)
    if e == 1.0:
        return 0.0
    low, high = 0.0, 1.0
    while restitution_of_damping_ratio(high) > e:
        high *= 2.0
    for _ in range(200):
        middle = 0.5 * (low + high)
        if restitution_of_damping_ratio(middle) > e:
            low = middle
        else:
            high = middle
        if high - low <= 1e-15 * high:
            break
    return 0.5 * (low + high)


def restitution_solref(
    restitution: float, time_step: float, contact_steps: float
) -> tuple[float, float, float]:
    """Direct ``solref = (-k, -b)`` giving restitution ``e`` over ``contact_steps`` steps.

    Returns ``(-k, -b, ζ)``. With ``d`` the (flat) impedance MuJoCo's constraint space follows
    ``r'' = -b r' - k r`` (its ``K = k/d²``, ``B = b/d`` are scaled back by ``d``).
    """
    zeta = damping_ratio_for_restitution(restitution)
    omega = contact_time_factor(zeta) / (contact_steps * time_step)
    return (-omega * omega, -2.0 * zeta * omega, zeta)


# ---------------------------------------------------------------------- model
def _geom_size(shape, extent: float) -> list[float]:
    """The geom's ``size`` as the compiler holds it, for a disk, rod or box in the body frame.

    A sphere's ``[r, 0, 0]``; a capsule's ``[r, half-length, 0]`` (the half-length its fromto
    along x gives, exact); a box's half-sizes, ``extent`` (its :func:`body_extent`, the depth
    the prism gets along y) as the middle one; an ellipsoid's semi-axes, ``extent`` (the
    larger of the ellipse's two) as the out-of-plane one. The one source of the sizes the
    XML, a spec and an edited model get.

    The ellipsoid's third semi-axis changes neither contact nor inertia: turned about y only
    (the hinge), its height above the plane does not depend on y, so its lowest point, the
    plane's one contact, lies in y = 0 on the ellipse itself for any value; the inertia is
    the scene's, explicit. ``extent`` keeps its bounding sphere the ellipse's and the
    ellipsoid no flatter than the ellipse.
    """
    kind = shape.kind
    if kind == "disk":
        return [float(shape.radius), 0.0, 0.0]
    if kind == "rod":
        return [float(shape.radius), shape.length / 2.0, 0.0]
    if kind == "ellipse":
        return [float(shape.semi_x), extent, float(shape.semi_y)]
    return [shape.width / 2.0, extent, shape.height / 2.0]


def _mesh_vertices(shape, extent: float) -> list[float]:
    """A polygon extruded along y to ``±extent``: ``x, y, z`` of every vertex, flat."""
    return [value for x, y in shape.vertices().tolist() for side in (-extent, extent)
            for value in (x, side, y)]


def _geom_xml(shape, name: str, extent: float) -> tuple[str, str]:
    """(asset xml, geom xml) for ``shape`` in the body frame (scene x -> x, scene y -> z);
    ``extent``: its :func:`body_extent`."""
    kind = shape.kind
    if kind == "polygon":
        vertices = " ".join(map(repr, _mesh_vertices(shape, extent)))
        return (
            f'<mesh name="{name}_mesh" vertex="{vertices}"/>',
            f'<geom name="{name}" type="mesh" mesh="{name}_mesh"/>',
        )
    size = _geom_size(shape, extent)
    if kind == "disk":
        return "", f'<geom name="{name}" type="sphere" size="{size[0]!r}"/>'
    if kind == "rod":
        half = size[1]
        return "", (
            f'<geom name="{name}" type="capsule" size="{size[0]!r}" '
            f'fromto="{-half!r} 0 0 {half!r} 0 0"/>'
        )
    if kind == "ellipse":
        return "", f'<geom name="{name}" type="ellipsoid" size="{" ".join(map(repr, size))}"/>'
    return "", f'<geom name="{name}" type="box" size="{" ".join(map(repr, size))}"/>'


def _model_xml(scene: Scene) -> str:
    assets, bodies = [], []
    for index, body in enumerate(scene.bodies):
        asset, geom = _geom_xml(body.shape, f"g{index}", body_extent(body.shape))
        assets.append(asset)
        inertia = float(body.moment_of_inertia)
        bodies.append(
            f'<body name="b{index}">'
            f'<joint name="b{index}_x" type="slide" axis="1 0 0"/>'
            f'<joint name="b{index}_z" type="slide" axis="0 0 1"/>'
            f'<joint name="b{index}_r" type="hinge" axis="0 1 0"/>'
            f'<inertial pos="0 0 0" mass="{float(body.mass)!r}" '
            f'diaginertia="{inertia!r} {inertia!r} {inertia!r}"/>'
            f"{geom}</body>"
        )
    ground = '<geom name="ground" type="plane" size="0 0 1"/>' if scene.ground else ""
    return (
        '<mujoco model="planar-impact">'
        '<option gravity="0 0 0"/>'
        f"<asset>{''.join(assets)}</asset>"
        f"<worldbody>{ground}{''.join(bodies)}</worldbody>"
        "</mujoco>"
    )


# ---------------------------------------------------------------------- geometry
# Shapes whose geometry is written into a compiled model (geom_size and what the compiler
# derives from it); a mesh (polygon) is compiled: its convex hull, centroid and bounding
# volumes come from the compiler's own arithmetic (qhull, volume integrals).
_EDITABLE_KINDS = frozenset(("disk", "rod", "box"))
# Compiled models a polygon world keeps (least recently used dropped first), ~120 kB each.
# A compile is costly (mostly the bindings' wrapper of the new model); a survey part
# (at most 125 samples per family with two workers, harness/survey/parts.py) runs the same
# polygons under each preset in turn, so the second preset finds them all compiled.
_MAX_COMPILED = 128
# The capsule's frame: fromto along +x turns the geom's z axis onto x (the compiler's quat).
_CAPSULE_QUAT = (0.7071067811865476, 0.0, -0.7071067811865475, 0.0)
_IDENTITY_QUAT = (1.0, 0.0, 0.0, 0.0)
_MJ_EPS = 1e-14  # mjEPS
# The radius the compiler's statistics give an infinite plane (their bounding box).
_PLANE_STAT_RADIUS = 0.01


def _topology(scene: Scene) -> tuple:
    """What a compiled model's layout depends on: ground or not, and the shape kinds."""
    return (scene.ground, tuple(body.shape.kind for body in scene.bodies))


def _rotate(vector: list[float], quat: tuple) -> list[float]:
    """The compiler's ``mjuu_rotVecQuat``, operation for operation (the same roundings)."""
    if vector[0] == 0 and vector[1] == 0 and vector[2] == 0:
        return [0.0, 0.0, 0.0]
    if quat == _IDENTITY_QUAT:
        return list(vector)
    w, x, y, z = quat
    t0 = w * vector[0] + y * vector[2] - z * vector[1]
    t1 = w * vector[1] + z * vector[0] - x * vector[2]
    t2 = w * vector[2] + x * vector[1] - y * vector[0]
    return [vector[0] + 2 * (y * t2 - z * t1),
            vector[1] + 2 * (z * t0 - x * t2),
            vector[2] + 2 * (x * t1 - y * t0)]


def _geom_values(shape, extent: float) -> tuple:
    """``(geom_size, geom_rbound, geom_aabb, body bvh_aabb)`` the compiler gives ``shape``
    (``extent``: its :func:`body_extent`, which sets a box's depth).

    The size is :func:`_geom_size`'s; the bounding sphere and box are the compiler's
    formulas; the body's bounding volume is the geom's box turned into the body frame corner
    by corner, as the compiler's bounding-volume hierarchy does
    (``mjCBoundingVolumeHierarchy::MakeBVH``).
    """
    size = _geom_size(shape, extent)
    kind = shape.kind
    if kind == "disk":
        radius = size[0]
        rbound, half, quat = radius, [radius] * 3, _IDENTITY_QUAT
    elif kind == "rod":
        radius, half_length = size[0], size[1]
        rbound = radius + half_length
        half, quat = [radius, radius, half_length + radius], _CAPSULE_QUAT
    else:
        rbound = math.sqrt(size[0] * size[0] + size[1] * size[1] + size[2] * size[2])
        half, quat = list(size), _IDENTITY_QUAT
    if quat == _IDENTITY_QUAT and min(half) > _MJ_EPS:
        bvh = [0.0, 0.0, 0.0, *half]  # the corner loop below gives exactly this
    else:
        half_x, half_y, half_z = half
        corners = [_rotate([x, y, z], quat) for z in (-half_z, half_z)
                   for y in (-half_y, half_y) for x in (-half_x, half_x)]  # the compiler's order
        columns = list(zip(*corners))
        low = [min(column) for column in columns]
        high = [max(column) for column in columns]
        for axis in range(3):  # the compiler inflates a flat box
            if abs(low[axis] - high[axis]) < _MJ_EPS:
                low[axis] -= _MJ_EPS
                high[axis] += _MJ_EPS
        bvh = [(high[axis] + low[axis]) / 2 for axis in range(3)]
        bvh += [(high[axis] - low[axis]) / 2 for axis in range(3)]
    return size, rbound, [0.0, 0.0, 0.0, *half], bvh


def _body_key(body, inertia: float) -> tuple:
    """What a compiled model depends on of one body: shape kind and dimensions, mass and
    inertia (``inertia``: its moment of inertia, a polygon's costs tens of µs)."""
    shape = body.shape
    kind = shape.kind
    if kind == "disk":
        dimensions = (shape.radius,)
    elif kind == "rod":
        dimensions = (shape.length, shape.radius)
    elif kind == "box":
        dimensions = (shape.width, shape.height)
    elif kind == "ellipse":  # the true ellipse: its stand-in's placement does not matter
        dimensions = (shape.semi_x, shape.semi_y)
    else:
        dimensions = tuple(map(tuple, shape.vertices().tolist()))
    return (kind, dimensions, float(body.mass), float(inertia))


def _geometry_key(scene: Scene) -> tuple:
    """:attr:`_Geometry.key` of ``scene`` alone."""
    return (scene.ground,
            tuple(_body_key(body, body.moment_of_inertia) for body in scene.bodies))


class _Geometry:
    """One scene's geometry in the form a world takes it (computed once per plan).

    ``key`` identifies it (ground; per body :func:`_body_key`: the shape's kind and
    dimensions, mass and inertia); ``extents`` the bodies' :func:`body_extent`; ``bodies``
    holds, for editable shapes, per body the geom's values (:func:`_geom_values`), the mass
    and the inertia; ``None`` for a scene with a polygon, which is compiled (from ``scene``).
    ``inertias``: the bodies' moments of inertia where already computed.
    """

    __slots__ = ("bodies", "extents", "key", "scene")

    def __init__(self, scene: Scene, inertias=None) -> None:
        parts, extents, bodies = [], [], []
        for index, body in enumerate(scene.bodies):
            shape = body.shape
            extent = body_extent(shape)
            extents.append(extent)
            part = _body_key(body, body.moment_of_inertia if inertias is None
                             else inertias[index])
            parts.append(part)
            if shape.kind not in _EDITABLE_KINDS:
                bodies = None
            elif bodies is not None:
                mass, inertia = part[2], part[3]
                bodies.append((*_geom_values(shape, extent), mass, [inertia] * 3))
        self.key = (scene.ground, tuple(parts))
        self.extents = extents
        self.bodies = bodies
        self.scene = scene


def _xml_float32(value: float) -> float:
    """The float32 MuJoCo's XML reader makes of ``repr(value)``, as a double.

    The reader rounds the decimal to float32 directly; a spec takes the double and rounds
    that. The two differ only where ``value`` lies exactly halfway between two float32 and
    its shortest decimal does not: the decimal then decides the side.
    """
    rounded = _to_float32(value)
    if rounded == value:
        return value
    mirror = value + (value - rounded)  # exact; a float32 only when value is halfway
    if _to_float32(mirror) != mirror:
        return rounded
    decimal, exact = Fraction(repr(value)), Fraction(value)
    if decimal == exact:
        return rounded  # a true tie: to even, as the conversion did
    return max(rounded, mirror) if decimal > exact else min(rounded, mirror)


def _xml_float32s(values: list[float]) -> list[float]:
    """:func:`_xml_float32` of every value: the rounding in one pass of numpy (the same
    float32 conversion, to nearest, ties to even); the rare halfway values one by one."""
    array = np.array(values)
    rounded = array.astype(np.float32).astype(float)
    mirror = array + (array - rounded)
    halfway = (rounded != array) & (mirror.astype(np.float32).astype(float) == mirror)
    result = rounded.tolist()
    for index in np.flatnonzero(halfway).tolist():
        result[index] = _xml_float32(values[index])
    return result


def _to_float32(value: float) -> float:
    """``value`` rounded to float32 (to nearest, ties to even), as a double."""
    return _FLOAT32.unpack(_FLOAT32.pack(value))[0]


_FLOAT32 = struct.Struct("<f")


def _write_spec(spec: mujoco.MjSpec, geometry: _Geometry) -> None:
    """Put a scene's masses, inertias and shapes (its ``geometry``) into a spec parsed from
    :func:`_model_xml` of a scene of the same topology: the values that XML would give
    (compiled alike)."""
    for index, (body, extent, (kind, _, mass, inertia)) in enumerate(
            zip(geometry.scene.bodies, geometry.extents, geometry.key[1])):
        spec_body = spec.body(f"b{index}")
        spec_body.mass = mass
        spec_body.inertia = [inertia, inertia, inertia]
        if kind == "polygon":
            spec.mesh(f"g{index}_mesh").uservert = _xml_float32s(
                _mesh_vertices(body.shape, extent))
            continue
        geom = spec.geom(f"g{index}")
        size = _geom_size(body.shape, extent)
        if kind in ("box", "ellipse"):
            geom.size = size
        else:  # the XML gives a sphere and a capsule their radius; a capsule its fromto
            geom.size = [size[0], *geom.size[1:]]
            if kind == "rod":
                half = size[1]
                geom.fromto = [-half, 0.0, 0.0, half, 0.0, 0.0]


def _write_statistics(m: mujoco.MjModel, rbounds: list[float], masses: list[float],
                      ground: bool) -> None:
    """``m.stat`` as the compiler computes it (MuJoCo 4's ``mj_setConst`` leaves it alone).

    ``meaninertia`` scales the solver's tolerance, so it must be the compiler's to the bit.
    Every body, joint and geom sits at the origin at ``qpos0``; the bounding box of the
    geoms' spheres is ``±reach`` on every axis, the infinite ground plane counting as
    radius 0.01 (MuJoCo 4; measured, tests/engines/test_mujoco_geometry.py).
    """
    stat = m.stat
    reach = max(rbounds)
    if ground:
        reach = max(reach, _PLANE_STAT_RADIUS)
    stat.center = [0.0, 0.0, 0.0]
    count = len(rbounds)
    mean_size = 0.0
    for rbound in rbounds:
        mean_size += max(rbound, 1e-5) / count
    stat.meansize = mean_size
    stat.extent = max(max(1e-5, reach - -reach), 2 * mean_size)
    mean_mass = 0.0
    for mass in masses:
        mean_mass += mass
    stat.meanmass = mean_mass / count
    mean_inertia = 0.0
    for diagonal in m.dof_M0.tolist():
        mean_inertia += diagonal
    stat.meaninertia = mean_inertia / m.nv


def _layout(model: mujoco.MjModel) -> bytes:
    """Every size of ``model`` that MjData's layout depends on (its integer ``n*`` counts).

    The bindings hold them in one array (``_sizes``, named by ``_size_fields``: a private
    field of the mujoco bindings, pinned in pyproject.toml; one read,
    ~1 µs, where the ~100 attributes read one by one cost ~25 µs a newly compiled polygon
    model; tests/engines/test_mujoco_reads.py checks it against the attributes).
    """
    return model._sizes.tobytes()


@dataclass
class _Model:
    """A world: one compiled model per topology (ground, shape kinds) and its data.

    Without a polygon the model's geometry is rewritten in place for each scene
    (:meth:`MujocoEngine._hold`); with one, ``compiled`` keeps a compiled model per
    geometry, all stepping the same ``MjData`` when their layouts agree. The numpy views
    (of the data: :func:`_use_data`; of the model's edited arrays: ``edits``) are made once:
    each attribute read through the bindings makes a new array.
    """

    model: mujoco.MjModel
    data: mujoco.MjData
    body_geoms: list[int]  # geom id of each scene body
    body_ids: list[int]
    extents: list[float]  # body_extent of each scene body's shape
    geometry: tuple | None = None  # geometry_key of the geometry the model holds
    # Polygon worlds: geometry key -> [MjModel, configured]; layout -> MjData.
    compiled: OrderedDict | None = None
    datas: dict | None = None
    spec: mujoco.MjSpec | None = None  # polygon worlds: the parsed spec, never compiled
    # Editable worlds: views of geom_size, geom_rbound, geom_aabb, bvh_aabb, body_mass and
    # body_inertia, and each body's row of bvh_aabb.
    edits: tuple | None = None
    bvh_rows: list[int] | None = None
    # What the model holds now: (settings snapshot, e, μ, derived), see _configure.
    configured: tuple | None = None
    dt: float = 0.0  # s, the time step the model holds
    normal_sign: float = 0.0  # +1/-1 once the run's first contact is read, 0 before
    last_depth: float = math.inf  # m, the previous contact step's largest penetration
    # Views of ``data`` (_use_data): qpos, qvel, xpos, xmat; the contacts (_contact_rows).
    qpos: object = None
    qvel: object = None
    xpos: object = None
    xmat: object = None
    contact_rows: object = None  # (n, 7): dist, pos, frame[:3] of each contact slot
    first_contact: object = None  # the first slot's dist, pos and frame[:3]
    first_two: object = None  # the first two slots' rows
    first_geom2: object = None  # the first slot's geom2 (1 int)
    contact_address: int = 0  # where ``contact_rows`` starts: the data's arena
    arena: object = None  # the arena as doubles, from ``contact_address``
    # Views of efc_force in ``arena`` by (ncon, nefc) (_force_view), for the data, model
    # and options held: emptied when one of them changes.
    force_views: dict = field(default_factory=dict)
    # Contact views made so far, by data (a polygon world's datas take turns).
    contact_views: dict = field(default_factory=dict)


def _use_data(world: _Model, data: mujoco.MjData) -> None:
    """Make ``world`` step ``data``, with views of its arrays made once (they live in the
    data's buffer and arena, fixed for its life; the contacts' views are made at the first
    contact the data reports, :func:`_contact_rows`)."""
    world.data = data
    world.qpos, world.qvel = data.qpos, data.qvel
    world.xpos, world.xmat = data.xpos, data.xmat
    (world.contact_rows, world.first_contact, world.first_two, world.first_geom2, world.arena,
     world.contact_address) = world.contact_views.get(id(data), (None,) * 5 + (0,))
    # Keyed by id(data): safe since world.datas holds every data for the world's life.
    if world.force_views:
        world.force_views = {}


# MuJoCo's mjContact begins with dist, pos[3] and frame[9]: the first 7 doubles (the frame's
# first row is the normal) are read as one row.
_CONTACT_HEAD = 7


def _contact_rows(world: _Model, contact) -> None:
    """Make ``world.contact_rows`` a view of the data's contacts as rows of ``dist, pos`` and
    the normal (the frame's first row), and ``world.first_geom2`` one of the first slot's
    ``geom2`` (``contact``: ``data.contact`` at a contact step).

    MuJoCo puts the contacts at the start of the data's arena (``mj_collision``; the arena
    is allocated with the data and ``mj_resetData`` points the contacts at its start), one
    fixed address for the data's life, and the bindings make new arrays of them at every
    read (with the address check); a view over every slot the arena can hold, read
    up to ``ncon``, costs one read per step. Made at the data's first contact (the fields'
    order checked) and kept by data (a polygon world's datas take turns).
    """
    distances = contact.dist
    address = distances.ctypes.data
    stride = distances.strides[0]
    if (contact.pos.ctypes.data - address, contact.frame.ctypes.data - address) != (8, 32):
        raise RuntimeError("mujoco: mjContact no longer begins with dist, pos, frame")
    rows = np.lib.stride_tricks.as_strided(
        distances, shape=(world.data.narena // stride, _CONTACT_HEAD),
        strides=(stride, 8), writeable=False)
    arena = np.lib.stride_tricks.as_strided(
        distances, shape=(world.data.narena // 8,), strides=(8,), writeable=False)
    views = (rows, rows[0], rows[:2], contact.geom2[:1], arena, address)
    world.contact_views[id(world.data)] = views
    (world.contact_rows, world.first_contact, world.first_two, world.first_geom2, world.arena,
     world.contact_address) = views


def _force_view(world: _Model, count: int, rows: int):
    """``data.efc_force`` (``rows`` long, ``count`` contacts) as a view of the arena, kept in
    ``world.force_views`` (read through the bindings, a new array each step: ~1 µs, and
    ~5 µs more for its address).

    MuJoCo allocates the constraint arrays in the arena after the contacts, in a fixed
    order of sizes that, in these planar models (dense Jacobian, one island), follow from
    the model's layout and options and the contact and row counts alone; the address is
    taken at the first step with each pair of counts, and taken again after the data, the
    model or the options change. Returns the bindings' array where the view cannot be made
    (an address off the arena's doubles).
    """
    forces = world.data.efc_force
    offset, rest = divmod(forces.ctypes.data - world.contact_address, 8)
    if rest or offset < 0 or offset + rows > len(world.arena):
        return forces
    view = world.force_views[count, rows] = world.arena[offset:offset + rows]
    return view


# Per-run constants computed once: the solve for ζ is a root search, pure in its arguments.
@functools.lru_cache(maxsize=256)
def _restitution_terms(restitution: float, time_step: float, contact_steps: float) -> tuple:
    """``(solref, ζ, restitution of ζ)`` of :func:`restitution_solref`."""
    stiffness, damping, zeta = restitution_solref(restitution, time_step, contact_steps)
    return [stiffness, damping], zeta, restitution_of_damping_ratio(zeta)


def _snapshot(settings: dict) -> dict:
    """A copy of ``settings`` that later in-place edits of its lists cannot reach."""
    return {key: list(value) if isinstance(value, list) else value
            for key, value in settings.items()}


_mj_step = mujoco.mj_step
_reset_data = mujoco.mj_resetData
_set_const = mujoco.mj_setConst


#: The accurate preset's contact duration (s): 50 steps of 1e-5 s; the accuracy bench holds it
#: while it refines the steps.
BENCH_CONTACT_DURATION_S = 5e-4


class MujocoEngine(Engine):
    name = "mujoco"
    version = mujoco.__version__
    # What the rest of the harness reads about this engine (docs/engines.md, 'The engine
    # contract'): why it lands where it does, per engine and per preset, and its plot style.
    description = (
        "MuJoCo departs because it solves no rigid-body impact law: its contact is soft, a "
        "spring–damper that cannot pull, and the bounce follows from the damping ratio "
        "alone. Under defaults (critically damped) the scenario's e is not used at all: a "
        "1 m/s drop bounces at about 0.11 m/s whatever e. Friction is soft too: its rows "
        "carry only the contact's damping, so inside the cone the slip decays at that same "
        "rate and the contact ends with about e² of the slip left; at e = 1 there is no "
        "damping and therefore no friction at all. Its second preset, matched-bounce, picks "
        "the damping from e so that the bounce is e·|v_n|; but a bounce of e·|v_n| that "
        "removes only 1 − e² of the slip is not dissipative when the normal and tangential "
        "motions are coupled (m_nt ≠ 0): it creates kinetic energy in 11.5% of random rod "
        "and box-corner impacts (46 of 400, up to +210%), and each such run is flagged "
        "energy-gain. No MuJoCo setting that keeps the bounce stops this "
        "(docs/engines.md, 'MuJoCo').")
    preset_why = {
        "defaults": ("solref [0.02, 1] (critically damped): the scenario's e is not "
                     "used (a 1 m/s drop bounces at 0.11 m/s for any e), and soft "
                     "friction turns the body over the 20-step contact."),
        "accurate": ("matched-bounce: the damping ratio is chosen from e (solref "
                     "\"restitution\") over a 50-step contact, RK4 integration, "
                     "impedance 0.9999: the bounce is e·v within 1e-4, but friction "
                     "removes only 1 − e² of the slip and none at e = 1, so with "
                     "m_nt ≠ 0 it can create energy (runs flagged energy-gain)."),
    }
    plot_style = ("#009E73", "^")
    bench_impacts = (20, 150)
    bench_impact_seconds = 8e-4
    own_law = "converged"  # a soft contact solves no rigid law: its limit is itself
    presets = PRESETS
    setting_docs = SETTING_DOCS
    # A contact at exactly zero distance gets no constraint row in MuJoCo, so the start is a
    # hair (_DETECTION_OVERLAP of a step of free flight) past the touching pose.
    timing = StepTiming(lead_steps=0.0, overlap=_DETECTION_OVERLAP)
    # The soft contact's force fades continuously and MuJoCo makes it exactly 0 once the
    # constraint is inactive: only an exact 0 counts as no impulse.
    no_impulse_relative = 0.0


    @classmethod
    def time_step_overrides(cls, role: str, time_step: float) -> dict:
        """At ``accurate`` the contact's duration is tied to steps: keep the spring at the
        preset's 0.5 ms contact, so that the time step is what changes."""
        if role != "accurate":
            return {"time_step": time_step}
        return {"time_step": time_step,
                "contact_steps": max(1, int(round(BENCH_CONTACT_DURATION_S / time_step)))}

    @classmethod
    def bench_sweep(cls, quick: bool) -> list[tuple[str, str, dict]]:
        """The settings the accuracy bench measures (harness/bench/accuracy.py)."""
        points: list[tuple[str, str, dict]] = []
        points.append(("defaults", "defaults", {}))
        for timeconst in ((0.005, 0.001) if quick else (0.01, 0.005, 0.002, 0.001)):
            dt = timeconst / 20.0
            points.append((f"solref tc={timeconst:g} dt={dt:.2g}", "defaults",
                           {"solref": [timeconst, 1.0], "time_step": dt}))
        # The accurate preset's spring-damper with the contact's duration held at 0.5 ms, so
        # only the resolution changes: contact_steps steps of 0.5 ms / contact_steps.
        contact_steps = (5, 10, 20, 50, 100) if quick else (5, 10, 20, 30, 50, 100, 200)
        for integrator in ("Euler", "RK4"):
            for count in contact_steps:
                points.append((f"{integrator} contact_steps={count}", "accurate",
                               {"integrator": integrator, "contact_steps": count,
                                "time_step": BENCH_CONTACT_DURATION_S / count}))
        points.append((BENCH_REFERENCE_LABEL, "accurate",
                       {"integrator": "RK4", "contact_steps": 400,
                        "time_step": BENCH_CONTACT_DURATION_S / 400}))
        return points

    def _validate_engine_settings(self, settings) -> None:
        name = self.name
        check_choice(name, settings, "integrator", tuple(_INTEGRATORS))
        check_choice(name, settings, "cone", tuple(_CONES))
        check_choice(name, settings, "solver", tuple(_SOLVERS))
        check_int(name, settings, "iterations", low=1)
        check_number(name, settings, "tolerance", low=0.0)
        check_int(name, settings, "ls_iterations", low=1)
        check_int(name, settings, "noslip_iterations", low=0)
        check_number(name, settings, "noslip_tolerance", low=0.0)
        check_number(name, settings, "impratio", low=0.0, strict=True)
        check_number(name, settings, "contact_steps", low=1.0)
        check_vector(name, settings, "solimp", 5)
        check_number(name, settings, "margin", low=0.0)
        solref = settings["solref"]
        if solref != "restitution":
            check_vector(name, settings, "solref", 2)
            if (solref[0] > 0) != (solref[1] > 0):
                raise EngineSettingsError(
                    f"engine {name!r}: setting 'solref' must be [timeconst > 0, dampratio > 0] "
                    f"or [-stiffness <= 0, -damping <= 0] or \"restitution\", got {solref!r} "
                    "(MuJoCo falls back to its defaults on mixed signs)"
                )

    def _world_key(self, scene: Scene, settings) -> tuple:
        return _topology(scene)

    def _build(self, scene: Scene, settings, *, contacts: bool = True) -> _Model:
        """The topology's model, compiled from ``scene`` (which it then holds)."""
        model = mujoco.MjModel.from_xml_string(_model_xml(scene))
        count = len(scene.bodies)
        body_geoms = [mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, f"g{i}")
                      for i in range(count)]
        body_ids = [mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, f"b{i}")
                    for i in range(count)]
        extents = [body_extent(b.shape) for b in scene.bodies]
        data = mujoco.MjData(model)
        world = _Model(model, data, body_geoms, body_ids, extents,
                       geometry=_geometry_key(scene))
        _use_data(world, data)
        if all(body.shape.kind in _EDITABLE_KINDS for body in scene.bodies):
            m = model
            world.edits = (m.geom_size, m.geom_rbound, m.geom_aabb, m.bvh_aabb, m.body_mass,
                           m.body_inertia)
            world.bvh_rows = [int(m.body_bvhadr[body_id]) for body_id in body_ids]
        else:
            world.compiled = OrderedDict({world.geometry: [model, None]})
            world.datas = {_layout(model): data}
        return world

    def _hold(self, world: _Model, geometry: _Geometry) -> None:
        """Make ``world`` hold ``geometry``: what a fresh compile of it gives, to the bit.

        Editable shapes: the sizes, bounding volumes, masses and inertias are written into
        the model, ``mj_setConst`` derives the rest (subtree masses, ``invweight0``,
        ``dof_M0``, ``dof_length``) and :func:`_write_statistics` the statistics
        (tests/engines/test_mujoco_geometry.py compares every array with a compile).
        Polygons: the topology's spec with the scene's values (:func:`_write_spec`),
        compiled (kept, ``_MAX_COMPILED`` at most).
        """
        if geometry.bodies is not None:
            sizes, rbounds, aabbs, bvhs, masses, inertias = world.edits
            for geom_id, body_id, bvh_row, (size, rbound, aabb, bvh, mass, inertia) in zip(
                    world.body_geoms, world.body_ids, world.bvh_rows, geometry.bodies):
                sizes[geom_id] = size
                rbounds[geom_id] = rbound
                aabbs[geom_id] = aabb
                bvhs[bvh_row] = bvh
                masses[body_id] = mass
                inertias[body_id] = inertia
            m = world.model
            _set_const(m, world.data)
            _write_statistics(m, [values[1] for values in geometry.bodies],
                              [values[4] for values in geometry.bodies], geometry.key[0])
        else:
            compiled = world.compiled
            compiled[world.geometry][1] = world.configured  # what the outgoing model holds
            entry = compiled.get(geometry.key)
            if entry is None:
                if world.spec is None:  # parsed once, from any scene of the topology
                    world.spec = mujoco.MjSpec.from_string(_model_xml(geometry.scene))
                spec = world.spec.copy()  # compiling fills a spec's mesh faces and normals
                _write_spec(spec, geometry)
                entry = compiled[geometry.key] = [spec.compile(), None]
                while len(compiled) > _MAX_COMPILED:
                    compiled.popitem(last=False)
            compiled.move_to_end(geometry.key)
            if world.force_views:  # another model, maybe other options: other places
                world.force_views = {}
            model = world.model = entry[0]
            world.configured = entry[1]
            layout = _layout(model)
            data = world.datas.get(layout)
            if data is None:
                data = world.datas[layout] = mujoco.MjData(model)
            if data is not world.data:
                _use_data(world, data)
        world.geometry = geometry.key
        world.extents = geometry.extents

    def _notes(self, scene: Scene, settings) -> tuple[str, ...]:
        if settings["solref"] != "restitution":
            return ("restitution e not used: MuJoCo's bounce comes from solref/solimp",)
        if scene.restitution < MIN_RESTITUTION:
            note = (f"e below {MIN_RESTITUTION} needs an infinite damping ratio; "
                    f"used {MIN_RESTITUTION}")
            return (note,)
        return ()

    def _prepare(self, world: _Model, scene: Scene, settings, start, weights) -> tuple:
        qpos, qvel = [], []
        for x, y, angle, vx, vy, omega in start:
            qpos += [x, y, -angle]
            qvel += [vx, vy, -omega]
        # The checks computed the inertias (a polygon's costs tens of µs): reused.
        return scene, settings, qpos, qvel, _Geometry(scene, [inertia for _, inertia in weights])

    def _reset(self, world: _Model, prepared: tuple) -> dict:
        """The scene's geometry, the run's options and contact parameters, fresh data, the
        start state."""
        scene, settings, qpos, qvel, geometry = prepared
        held = world.geometry
        if held is not geometry.key:
            if held != geometry.key:
                self._hold(world, geometry)
            world.geometry = geometry.key  # equal: the next run compares identities
        derived = self._configure(world, scene, settings)
        _reset_data(world.model, world.data)
        world.qpos[:] = qpos
        world.qvel[:] = qvel
        world.normal_sign = 0.0
        world.last_depth = math.inf
        return derived

    def _configure(self, entry: _Model, scene: Scene, settings: dict) -> dict:
        """Make the model hold every option and contact parameter of this run; its ``derived``.

        What the model already holds is not written again (compared by value, never by
        identity): the options and the settings' contact parameters when the settings are
        the same, each of the pair's ``solref``, ``condim`` and friction that ``e`` and ``μ``
        leave as they were.
        """
        e, mu = scene.restitution, scene.friction
        last = entry.configured
        if last is None or last[0] != settings:
            self._write_options(entry, settings)
            last = None
        if last is None or last[1] != e or last[2] != mu:
            entry.configured = last = (last[0] if last else _snapshot(settings), e, mu,
                                       self._write_pair(entry, scene, settings, last))
        derived = last[3]
        return {**derived, "solref": list(derived["solref"])}  # the caller's own copy

    def _write_options(self, entry: _Model, settings: dict) -> None:
        m = entry.model
        if entry.force_views:  # the constraint arrays' places may differ under others
            entry.force_views = {}
        opt = m.opt
        dt = float(settings["time_step"])
        entry.dt = dt
        opt.timestep = dt
        opt.integrator = _INTEGRATORS[settings["integrator"]]
        opt.cone = _CONES[settings["cone"]]
        opt.solver = _SOLVERS[settings["solver"]]
        opt.iterations = int(settings["iterations"])
        opt.tolerance = float(settings["tolerance"])
        opt.ls_iterations = int(settings["ls_iterations"])
        opt.noslip_iterations = int(settings["noslip_iterations"])
        opt.noslip_tolerance = float(settings["noslip_tolerance"])
        opt.impratio = float(settings["impratio"])
        m.geom_solimp[:] = [float(v) for v in settings["solimp"]]
        m.geom_margin[:] = float(settings["margin"])
        m.geom_gap[:] = 0.0

    def _write_pair(self, entry: _Model, scene: Scene, settings: dict,
                    held: tuple | None) -> dict:
        """The pair's contact parameters (from ``e``, ``μ`` and the settings); ``derived``.

        ``held``: what the model holds under the same settings (``_configure``'s record),
        whose equal values are not written again; ``None``: write every one.
        """
        m = entry.model
        derived: dict = {}
        if settings["solref"] == "restitution":
            solref, zeta, target = _restitution_terms(
                scene.restitution, float(settings["time_step"]),
                float(settings["contact_steps"]))
            derived["damping_ratio"] = zeta
            derived["restitution_target"] = target
        else:
            solref = [float(v) for v in settings["solref"]]
        derived["solref"] = solref
        mu = float(scene.friction)
        condim = 1 if mu == 0.0 else 3
        derived["condim"] = condim
        if held is None or held[3]["solref"] != solref:
            m.geom_solref[:] = solref
        if held is None or held[3]["condim"] != condim:
            m.geom_condim[:] = condim
        if held is None:
            m.geom_friction[:] = 0.0
        if held is None or float(held[2]) != mu:
            m.geom_friction[entry.body_geoms[0]] = [mu, 0.0, 0.0]
        return derived

    def _advance(self, world: _Model) -> None:
        _mj_step(world.model, world.data)

    def _step(self, world: _Model) -> RawContacts | None:
        d = world.data
        _mj_step(world.model, d)
        # Active contact constraints only: MuJoCo reports a contact at dist >= margin (its
        # "gap" zone) but gives it no constraint row.
        constraints = d.nefc
        if not constraints:
            return None
        count = d.ncon
        sign = world.normal_sign
        if sign == 0.0:  # the run's first contact
            if world.contact_rows is None:  # the data's first
                _contact_rows(world, d.contact)
            # A pair's geom order is fixed: the normal points from geom1 into geom2, and
            # body A's geom second reverses it.
            two_bodies = len(world.body_geoms) == 2
            sign = world.normal_sign = (
                -1.0 if two_bodies and world.first_geom2.item(0) == world.body_geoms[0]
                else 1.0)
        if count == 1:
            distance, x, _, z, frame_x, _, frame_z = world.first_contact.tolist()
            depth = -distance
            points = ((x, z, depth),)
        elif count == 2:  # a prism's edge (±y): a third of the contact steps, unrolled
            (distance, x, _, z, frame_x, _, frame_z), (other, other_x, _, other_z, _, _, _) = (
                world.first_two.tolist())
            depth, other = -distance, -other
            points = ((x, z, depth), (other_x, other_z, other))
            if other > depth:  # max() of the two
                depth = other
        else:
            rows = world.contact_rows[:count].tolist()
            points = tuple([(row[1], row[3], -row[0]) for row in rows])
            frame_x, frame_z = rows[0][4], rows[0][6]
            depth = max([point[2] for point in points])
        length = math.hypot(frame_x, frame_z)
        normal = (sign * frame_x / length, sign * frame_z / length)
        # No impulse vector per step (the run's comes from momentum). While the penetration
        # still grows the spring-damper pushes (k·r + b·r' > 0), so the forces are read only
        # once it shrinks: the step carries force while any constraint force is non-zero.
        growing = depth >= world.last_depth
        world.last_depth = depth
        if growing:
            return points, normal, None, None
        forces = world.force_views.get((count, constraints))
        if forces is None:
            forces = _force_view(world, count, constraints)
        return points, normal, None, sum(map(abs, forces.tolist())) * world.dt

    def _read_poses(self, world: _Model) -> tuple:
        # Python floats once (tolist): the same doubles as indexing the arrays, fewer calls.
        qpos = world.qpos.tolist()
        if len(qpos) == 3:
            return ((qpos[0], qpos[1], -qpos[2]),)
        if len(qpos) == 6:  # two bodies: unpacked, no loop (every contact step)
            x, y, angle, other_x, other_y, other_angle = qpos
            return ((x, y, -angle), (other_x, other_y, -other_angle))
        return tuple([(qpos[i], qpos[i + 1], -qpos[i + 2]) for i in range(0, len(qpos), 3)])

    def _read_velocities(self, world: _Model) -> tuple:
        qvel = world.qvel.tolist()
        if len(qvel) == 3:
            return ((qvel[0], qvel[1], -qvel[2]),)
        return tuple([(qvel[i], qvel[i + 1], -qvel[i + 2]) for i in range(0, len(qvel), 3)])

    def _out_of_plane_drift(self, world: _Model) -> float:
        """The centre's y, plus the tilt of the body's y axis times its size."""
        drift = 0.0
        xpos, xmat = world.xpos.tolist(), world.xmat.tolist()
        for body_id, extent in zip(world.body_ids, world.extents):
            rotation = xmat[body_id]  # row-major 3x3: the body's y axis is entries 1, 4, 7
            drift = max(drift,
                        abs(xpos[body_id][1]) + math.hypot(rotation[1], rotation[7]) * extent)
        return drift


ENGINE_CLASS = MujocoEngine
