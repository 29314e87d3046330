"""A scene as MuJoCo builds it: the XML of a scene's topology, and the values the compiler
gives a scene's geometry (sizes, bounding volumes, masses, inertias, statistics), so that a
compiled model can be made to hold another scene of its topology without compiling again,
bit for bit what a compile gives (tests/engines/test_mujoco_geometry.py).
"""

from __future__ import annotations

import math
import struct
from fractions import Fraction

import mujoco
import numpy as np

from harness.engines.contract import body_extent
from harness.scene import Scene


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
