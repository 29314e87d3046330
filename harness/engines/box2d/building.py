"""An impact's ground, bodies and fixtures in a b2World.

pybox2d's problem: its keyword constructors (``CreateBody``, ``CreateFixture``, shapes made
anew) cost several µs each, more than the rest of the build. Bodies and fixtures are made here
through definitions filled field by field and two shapes refilled for every fixture (a fixture
copies its shape), with the calls pybox2d itself makes once its arguments are checked; and
:func:`_place` puts bodies at a start state with nothing kept from an earlier run.
"""

from __future__ import annotations

import Box2D
from Box2D import b2

from harness.engines.box2d.presets import POLYGON_RADIUS
from harness.engines.box2d.readout import _B2, _body_id
from harness.engines.contract import UnsupportedScene, body_extent
from harness.scene import Scene

_GROUND_EXTENT_FACTOR = 8.0  # ground half-width and depth, in body extents (float32 clipping)
# Where _place moves a body for a moment (Box2D units): no proxy's fattened box reaches it.
_FAR_AWAY = (2.0**30, 2.0**30)

# ---------------------------------------------------------------------- world building
# A fixture copies its shape (b2Fixture::Create clones it), so one shape of each kind is filled
# anew for every fixture: making a shape through pybox2d costs several µs, refilling it a
# fraction (pybox2d's vertices setter, unrolled below, makes the same calls).
_POLYGON = b2.polygonShape()
_CIRCLE = b2.circleShape()
_set_vertex = _B2.b2PolygonShape_set_vertex
_set_vertex_count = _B2.b2PolygonShape_vertexCount_set
_set_vertices = _B2.b2PolygonShape___set_vertices_internal  # b2PolygonShape::Set
# What b2World.CreateBody and b2Body.CreateFixture call once they have checked their
# arguments and found no fixtures or shapes to add (a definition is always given here).
_create_body = _B2.b2World___CreateBody
_create_fixture = _B2.b2Body___CreateFixture
# A fixture definition's filter fields, set in place (pybox2d's groupIndex and maskBits
# properties fetch a new filter wrapper on every set).
_set_group_index = _B2.b2Filter_groupIndex_set
_set_mask_bits = _B2.b2Filter_maskBits_set


def _polygon_shape(vertices, radius: float):
    """The shared b2PolygonShape set on ``vertices`` with skin ``radius`` (until the next
    call: a fixture made of it keeps a copy)."""
    shape = _POLYGON
    try:
        if not 2 <= len(vertices) <= Box2D.b2_maxPolygonVertices:
            raise ValueError(f"{len(vertices)} vertices, at most "
                             f"{Box2D.b2_maxPolygonVertices}")
        for index, (x, y) in enumerate(vertices):
            _set_vertex(shape, index, x, y)
        _set_vertex_count(shape, len(vertices))
        _set_vertices(shape)
    except (AssertionError, ValueError, RuntimeError, TypeError) as error:
        raise UnsupportedScene(
            f"engine 'box2d': polygon {vertices!r} refused by b2PolygonShape::Set ({error}); "
            "try a larger length_scale") from error
    if shape.vertexCount != len(vertices):
        raise UnsupportedScene(
            f"engine 'box2d': b2PolygonShape::Set kept {shape.vertexCount} of "
            f"{len(vertices)} vertices (it welds near vertices); try a larger length_scale")
    shape.radius = radius
    return shape


def _circle_shape(radius: float, x: float = 0.0):
    """The shared b2CircleShape set to ``radius``, centred at ``(x, 0)`` on its body (until
    the next call: a fixture made of it keeps a copy)."""
    shape = _CIRCLE
    shape.radius = radius
    shape.pos = (x, 0.0)
    return shape


class _Definitions:
    """A body definition, a fixture definition (density 0) and its filter, and a mass record
    (centre at the origin), filled anew for every body and fixture of :func:`_add_impact`:
    the impacts of a batch share one set (each costs several µs to make, as much as a
    fixture)."""

    __slots__ = ("body", "filter", "fixture", "mass")

    def __init__(self) -> None:
        self.body = b2.bodyDef()
        self.fixture = b2.fixtureDef()
        self.fixture.density = 0.0
        self.filter = self.fixture.filter  # the definition's own (a pointer into it)
        self.mass = b2.massData()
        self.mass.center = (0.0, 0.0)


def _add_impact(world, scene: Scene, length: float, skin: float, extent: float, *,
                starts: tuple | None = None, group: int = 0, pair_values: tuple | None = None,
                inertias=None, definitions: _Definitions | None = None
                ) -> tuple[list, list, list]:
    """``(bodies, ground, fixtures)``: the scene's ground and bodies in ``world``, the
    bodies at ``starts`` (:func:`_place`'s form; None: at rest at the origin, for
    :func:`_place` to move), the fixtures with the pair's ``(e, μ)`` (None: Box2D's
    defaults, for :meth:`_World.configure` to set) in collision group ``group`` with mask
    0 (0: no group, every fixture collides). ``inertias``: the bodies' moments of inertia
    in scene units when already known (a polygon's is computed); None: the scene's.
    ``definitions``: the :class:`_Definitions` to fill (None: new ones).

    Every fixture's userData is ``(padding, radius, body)``: how far it pads the scene's
    outline, its shape's radius as Box2D holds it (float32) and its body's
    :data:`_body_id`, which the readout takes in one call (a fixture's ``body`` or
    ``shape`` would make a new wrapper each time).

    The objects are made through definitions filled field by field (pybox2d's keyword
    constructors cost more than the rest of the build). A body's skins are set before its
    fixtures are made, so their proxies' boxes are the ones :func:`_place` fits; the
    ground's skin is set after (its proxy's box is the default skin's, as it always was: a
    static body is never placed anew, and the box decides when contacts are created).
    """
    if definitions is None:
        definitions = _Definitions()
    fixture_definition, body_definition = definitions.fixture, definitions.body
    if pair_values is not None:
        fixture_definition.restitution, fixture_definition.friction = pair_values
    if group:
        _set_group_index(definitions.filter, group)
        _set_mask_bits(definitions.filter, 0)
    fixtures = []
    body_id = 0

    def add(body, shape, padding: float) -> None:
        fixture_definition.shape = shape
        fixture = _create_fixture(body, fixture_definition)  # copies the definition, shape
        fixture.userData = (padding, shape.radius, body_id)
        fixtures.append(fixture)

    ground = []
    if scene.ground:  # a static body at the origin (the definition may hold the last body)
        body_definition.type = b2.staticBody
        body_definition.position, body_definition.angle = (0.0, 0.0), 0.0
        ground_body = _create_body(world, body_definition)
        body_id = _body_id(ground_body)
        add(ground_body, _polygon_shape(_ground_vertices(extent, length), POLYGON_RADIUS),
            skin)
        ground_shape = fixtures[-1].shape
        ground_shape.radius = skin
        fixtures[-1].userData = (skin, ground_shape.radius, body_id)
        ground.append(ground_body)
    body_definition.type = b2.dynamicBody
    mass_data = definitions.mass
    bodies = []
    for index, body in enumerate(scene.bodies):
        if starts is not None:
            body_definition.position, body_definition.angle = starts[index][:2]
        b2_body = _create_body(world, body_definition)
        body_id = _body_id(b2_body)
        shape = body.shape
        if shape.kind == "disk":
            add(b2_body, _circle_shape(shape.radius * length), 0.0)  # the disk's own radius
        elif shape.kind == "rod":
            half, radius = shape.length / 2.0 * length, shape.radius * length
            for x in (-half, half):
                add(b2_body, _circle_shape(radius, x), 0.0)
            # Core box inset by its skin: its rounded outline stays inside the capsule
            # (padding 0: its skin lies inside the capsule's outline).
            core_skin = min(skin, radius / 2.0)
            thickness = radius - core_skin
            add(b2_body, _polygon_shape([(-half, -thickness), (half, -thickness),
                                         (half, thickness), (-half, thickness)], core_skin), 0.0)
        else:
            vertices = [(x * length, y * length) for x, y in _outline(shape)]
            # The skin pads the scene's outline: a contact's overlap of the scene's bodies
            # is its separation plus the skins.
            add(b2_body, _polygon_shape(vertices, skin), skin)
        mass_data.mass = body.mass
        inertia = body.moment_of_inertia if inertias is None else inertias[index]
        mass_data.I = inertia * length * length
        b2_body.massData = mass_data
        if starts is not None:
            _, _, b2_body.linearVelocity, b2_body.angularVelocity = starts[index]
        bodies.append(b2_body)
    return bodies, ground, fixtures


def _outline(shape) -> list:
    """A box's or polygon's vertices as ``shape.vertices()`` gives them, as Python floats
    (without the numpy array, which costs more than the rest of the body); an ellipse's
    placed stand-in polygon's (Box2D has no ellipse)."""
    if shape.kind == "ellipse":
        shape = shape.stand_in()
    if shape.kind == "box":
        half_w, half_h = shape.width / 2.0, shape.height / 2.0
        return [(-half_w, -half_h), (half_w, -half_h), (half_w, half_h), (-half_w, half_h)]
    return [(float(x), float(y)) for x, y in shape.points]


def _ground_vertices(extent: float, length: float) -> list:
    """The ground box (top face ``y = 0``): half-width a few body extents (float32 clipping
    against a far ground vertex loses ~|vertex|·1e-7 m)."""
    width = _GROUND_EXTENT_FACTOR * extent * length
    return [(-width, -width), (width, -width), (width, 0.0), (-width, 0.0)]


def _extent(scene: Scene) -> float:
    return max(body_extent(body.shape) for body in scene.bodies)


def _set_pair_values(fixtures, pair_values: tuple) -> None:
    restitution, friction = pair_values
    for fixture in fixtures:
        fixture.restitution = restitution
        fixture.friction = friction


def _set_switches(world, world_values: tuple) -> None:
    (world.warmStarting, world.continuousPhysics, world.subStepping,
     world.allowSleeping) = world_values


def _place(bodies, starts: tuple) -> None:
    """Put ``bodies`` at the start state ``((x, y), θ, (v_x, v_y), ω)`` (Box2D units), with
    nothing kept from what they did before (their contacts must be gone already).

    Two things of a body outlive a run and would steer the next: its sleep timer (reset by
    putting it to sleep) and its proxies' fattened boxes, which decide which contacts exist
    at the start and so the order Box2D creates and solves them in. Moving the body far away
    and back makes Box2D fit every box anew around the start pose, as in a fresh world. The
    proxies themselves, and so their ids, are kept (see :meth:`_World.place`).
    """
    for b2_body, (position, angle, velocity, angular_velocity) in zip(bodies, starts):
        b2_body.awake = False  # also zeroes the sleep timer
        b2_body.transform = (_FAR_AWAY, angle)
        b2_body.transform = (position, angle)
        b2_body.linearVelocity = velocity
        b2_body.angularVelocity = angular_velocity
        b2_body.awake = True
