"""Box2D (pybox2d 2.3.10) adapter.

The law Box2D solves: sequential impulses on a velocity-level Newton-Coulomb problem per
contact point, in single precision (``float32``). In a step Box2D first updates contacts at
the current positions (collision first), then integrates velocities, iterates impulses until
each point's normal velocity reaches ``-e·v_rel`` (``v_rel`` the point's normal velocity before
the step) with Coulomb friction at the end state -- ``planar_impact``'s ``"newton-lcp"`` for
one point -- and finally moves the bodies. Collision-first means ``approach_steps = 0``
starts the bodies at the scene's pose and the first step finds the contact there
(``StepTiming(lead_steps=0)``).

The restitution threshold: Box2D gives a point its bounce only when ``v_rel <
-b2_velocityThreshold`` (1 m/s, compiled in); a slower impact gets ``e = 0``. The laws are
homogeneous in lengths and velocities, so the adapter can run a scaled copy of the scene:
lengths times ``L`` (``length_scale``), velocities times ``V`` (``velocity_scale``), time times
``L/V`` (the time step passed to Box2D is ``time_step·L/V``), angular velocities times
``V/L``, inertias times ``L²``, masses unchanged, impulses times ``V``. Everything read back
is scaled back. Powers of two keep every scaling exact in binary floating point. ``"auto"``
picks the smallest power of two ``V >= 1`` that lifts the impact speed Box2D sees at the
first contact (measured once per scene and settings by a probe run in :meth:`_prepare`) to
``2 · b2_velocityThreshold``. Where the probe run would be the run's own beginning (``V = 1``
and no start depth, as under ``defaults``), the run measures that speed itself (a PreSolve
listener until the first contact), in ``run`` as in ``run_many``.

Other compiled-in limits: ``b2_maxTranslation`` (2 m per step) and ``b2_maxRotation`` (π/2
per step) clip a body's velocity for good when a step would move it further. In scene units
the caps are ``|v| <= 2 m / (L·time_step)`` and ``|ω| <= (π/2) / time_step`` (``V`` cancels):
every run reports them in ``derived`` (``speed_cap``, ``angular_speed_cap``), and a run in
which a velocity sat at a cap carries a note. Polygons carry a skin
(``b2PolygonShape::m_radius``, ``b2_polygonRadius`` = 0.01 m by default): they collide as
rounded shapes, a contact is active within the summed skins, and its point lies midway
between the skinned surfaces.

The start a hair deep: an exactly touching pose can round, in float32, to a hair apart, and
the contact is then found a step late. The adapter moves the base class's start state
``detection_overlap`` body extents further along the free flight (a time of
``overlap·extent / impact speed``), a depth in lengths, which a fraction of a step
(``StepTiming.overlap``) would not give for slow impacts.

Bodies: one ``b2World`` per geometry, length scale and skin; the ground is a static box
whose top face is ``y = 0``. A disk is a circle fixture; a box or polygon a polygon fixture;
a rod (capsule) is two circles at ``(±length/2, 0)`` with a box between them on one body (the
box's half-thickness is the cap radius less its skin, so the fixtures' union is the capsule).
Masses and inertias are set with ``b2Body::SetMassData`` (fixtures have zero density).

Pair values: Box2D mixes ``friction = sqrt(μ_A·μ_B)`` and ``restitution = max(e_A, e_B)``;
every fixture gets the pair's ``e`` and ``μ`` (``sqrt(μ·μ) == μ`` exactly in float32).

Reuse: before each run every contact is destroyed (with its warm-start impulses), the bodies
are put to sleep (zeroing their sleep timers), moved far away and back to the start state
(Box2D fits their proxies' boxes anew) and the contact manager looks for new pairs. The
proxies themselves are kept: their ids set the order in which the contacts are created and
solved, so keeping them makes reruns bit-identical whatever ran before (see
:meth:`_World.place`, :func:`_place`).

Many impacts (``run_many``): up to :data:`MANY_CHUNK` impacts share a b2World, kept apart by
collision groups, with the runs of ``run`` bit for bit (see
:meth:`Box2DEngine._build_many`).

pybox2d's ``contact.worldManifold`` returned an uninitialised normal here: the adapter
computes the world manifold itself, from the poses at the step's start (the manifold's).
Each step reads every body once (its pose then is the next step's start) and only the
touching contacts, from Box2D's structs at their addresses where their layout is the one
checked at import (see "reading Box2D's state" below): pybox2d's getters make a Python
object for every struct they return, which cost many times Box2D's own step.

Settings (``defaults`` | ``accurate``) are listed in :data:`SETTING_DOCS`.
"""

from __future__ import annotations

import ctypes
import functools
import math
import struct
from typing import NamedTuple

import Box2D
from Box2D import b2

from harness.engines.contract import (
    Engine,
    RawContacts,
    StepTiming,
    UnsupportedScene,
    body_extent,
    geometry_key,
)
from harness.engines.settings import EngineSettingsError, check_int, check_number
from harness.scene import Scene

VELOCITY_THRESHOLD = float(Box2D.b2_velocityThreshold)  # m/s (Box2D units), compiled in
MAX_TRANSLATION = float(Box2D.b2_maxTranslation)  # m per step (Box2D units), compiled in
MAX_ROTATION = float(Box2D.b2_maxRotation)  # rad per step, compiled in
POLYGON_RADIUS = float(Box2D.b2_polygonRadius)  # m (Box2D units), the default polygon skin
# "auto" lifts the first contact's approach speed to this multiple of the threshold: a margin
# of 2 keeps float32 rounding of the solver's own v_rel (computed anew) far from the edge.
_AUTO_MARGIN = 2.0
# Start depth of the accurate preset, in body extents: ~4 float32 roundings of a coordinate
# of the body's size, so that rounding cannot lift an exact touch off the ground.
DETECTION_OVERLAP = 2.0**-22
_MAX_AUTO_SCALE = 2.0**40  # a scene slower than 2^-39 m/s is refused rather than scaled
_GROUND_EXTENT_FACTOR = 8.0  # ground half-width and depth, in body extents (float32 clipping)
# A velocity Box2D clipped sits at the cap to float32 rounding: this band counts as "at".
_CAP_BAND = 1.0 - 1e-6
# Where _place moves a body for a moment (Box2D units): no proxy's fattened box reaches it.
_FAR_AWAY = (2.0**30, 2.0**30)

SETTING_DOCS: dict[str, str] = {
    "time_step": "s (scene units), b2World::Step timeStep; Box2D has no default, 1/60 is its "
    "manual's value",
    "velocity_iterations": "b2World::Step velocityIterations, impulse sweeps per step (manual: 8)",
    "position_iterations": "b2World::Step positionIterations, position-correction sweeps per "
    "step (manual: 3; positions only)",
    "warm_starting": "b2World::SetWarmStarting, start a step from the last step's impulses "
    "(default True)",
    "continuous_physics": "b2World::SetContinuousPhysics, time-of-impact sub-steps of "
    "dynamic against static bodies (default True)",
    "sub_stepping": "b2World::SetSubStepping, one time-of-impact event per step (debug; "
    "default False)",
    "allow_sleeping": "b2World::SetAllowSleeping, bodies at rest for 0.5 s sleep (default True)",
    "polygon_radius": "m (Box2D units), skin of every polygon fixture (ground, box, polygon, "
    "rod core); default b2_polygonRadius = 0.01",
    "velocity_scale": "V, velocities times V and time times 1/V in Box2D, 1 = unscaled; "
    "'auto' = smallest power of 2 >= 1 lifting the first contact's approach speed to "
    "2 x b2_velocityThreshold (1 m/s)",
    "length_scale": "L, lengths times L and time times L in Box2D (powers of 2 are exact); "
    "1 = unscaled",
    "detection_overlap": "start this fraction of the largest body extent deeper along the "
    "path than the touching pose, so that float32 rounding cannot hide the first contact "
    "(0 = start at the pose)",
    "max_steps": "step cap; reported as status no-separation when hit in contact",
    "approach_steps": "steps of free flight before first touch (0 = touching at first step)",
}

_DEFAULTS = {
    "time_step": 1.0 / 60.0,
    "velocity_iterations": 8,
    "position_iterations": 3,
    "warm_starting": True,
    "continuous_physics": True,
    "sub_stepping": False,
    "allow_sleeping": True,
    "polygon_radius": POLYGON_RADIUS,
    "velocity_scale": 1.0,
    "length_scale": 1.0,
    "detection_overlap": 0.0,
    "max_steps": 1000,
    "approach_steps": 0.0,
}
PRESETS: dict[str, dict] = {
    "defaults": dict(_DEFAULTS),
    # Coupled points (rod, box corner) need more sweeps than 8; 100 reaches float32 rounding
    # on every test scene. No skin: a skinned point lies off the surface (moment arm). No
    # warm start or time-of-impact sub-step: nothing but the impact's own impulses. "auto"
    # serves e at any impact speed (the threshold would zero it at or below 1 m/s).
    "accurate": dict(
        _DEFAULTS,
        velocity_iterations=100,
        warm_starting=False,
        continuous_physics=False,
        allow_sleeping=False,
        polygon_radius=0.0,
        velocity_scale="auto",
        detection_overlap=DETECTION_OVERLAP,
    ),
}

_BOOL_KEYS = ("warm_starting", "continuous_physics", "sub_stepping", "allow_sleeping")
THRESHOLD_NOTE = "impact at or below b2_velocityThreshold (1 m/s): Box2D used e = 0"
CLIPPED_NOTE = ("Box2D clipped a velocity (b2_maxTranslation 2 m or b2_maxRotation π/2 per "
                "step; see derived speed_cap, angular_speed_cap)")


# ---------------------------------------------------------------------- reading Box2D's state
# pybox2d makes a Python wrapper object for every struct a getter returns (about ten per
# contact and step), which cost the readout far more than Box2D's step. So the
# per-step readout reads Box2D's own structs at their addresses instead, one unpack each:
# b2Body (transform, sweep angle, velocities, contact list), b2ContactEdge and b2Contact with
# its b2Manifold, in the layouts of Box2D 2.3 as pybox2d 2.3.10 compiles them (64-bit).
# :func:`_layout_matches` checks every field against pybox2d's getters on a live world at
# import, following no pointer it has not checked; where they differ, the getters read the
# same values (``_READERS``). float32 fields become the same Python floats either way.
_B2 = Box2D._Box2D
_get_transform = _B2.b2Body___GetTransform
_get_position = _B2.b2Transform_position_get
_get_rotation = _B2.b2Transform_q_get
_get_angle = _B2.b2Body___GetAngle
_get_linear_velocity = _B2.b2Body___GetLinearVelocity
_get_angular_velocity = _B2.b2Body___GetAngularVelocity
_body_contacts = _B2.b2Body___GetContactList_internal
_edge_contact = _B2.b2ContactEdge_contact_get
_edge_next = _B2.b2ContactEdge_next_get
_contact_next = _B2.b2Contact___GetNext
_is_touching = _B2.b2Contact___IsTouching
_get_manifold = _B2.b2Contact___GetManifold
_get_fixture_a = _B2.b2Contact___GetFixtureA
_get_fixture_b = _B2.b2Contact___GetFixtureB
_point_count = _B2.b2Manifold_pointCount_get
_get_point = _B2.b2Manifold___GetPoint

#: A body's identity, its C++ address: poses are keyed by it (a b2Body wrapper compares
#: through a Python function, and each access to a contact's body makes a new wrapper).
_body_id = _B2.b2Body___hash__
_CIRCLES = Box2D.b2Manifold.e_circles
_FACE_A = Box2D.b2Manifold.e_faceA

_string_at = ctypes.string_at
#: b2Body: m_xf (p.x, p.y, q.s, q.c), m_sweep.a, m_linearVelocity, m_angularVelocity.
_BODY = struct.Struct("@12x4f28xf4x3f")
_BODY_CONTACTS = 136  # offset of b2Body::m_contactList
_POINTER = struct.Struct("@P")
#: b2ContactEdge: contact, next.
_EDGE = struct.Struct("@8xP8xP")
#: b2Contact: m_flags, m_next, m_fixtureA, m_fixtureB, m_manifold (both points' localPoint,
#: normalImpulse, tangentImpulse; localNormal, localPoint, type, pointCount).
_CONTACT = struct.Struct("@8xI12xP64x2P8x2f2f4x2f2f4x2f2fiI")
_TOUCHING = 0x0002  # b2Contact::e_touchingFlag


def _state_struct() -> struct.Struct:
    """:data:`_BODY` and ``m_contactList`` in one read (a body's :func:`_state_in_memory`)."""
    return _body_and_contacts(_BODY.format, _BODY_CONTACTS)


@functools.lru_cache(maxsize=4)
def _body_and_contacts(body_format: str, contacts_offset: int) -> struct.Struct:
    """:func:`_state_struct`, made once per layout (a Struct parses its format when made)."""
    return struct.Struct(f"{body_format}{contacts_offset - struct.calcsize(body_format)}xP")


# The structs are read in place, through a ctypes buffer over each (made once per address: a
# buffer costs as much as ctypes.string_at, which copies; unpacking a buffer costs a third).
def _buffer(address: int, size: int):
    """Box2D's ``size`` bytes at ``address`` as a buffer ``struct`` unpacks in place."""
    return (ctypes.c_char * size).from_address(address)


class _Memory:
    """The buffers (:func:`_buffer`) one readout reads Box2D's structs through.

    ``body``: a body's state and contact list (:func:`_state_struct`), by the body's address
    (:data:`_body_id`); ``edges``, ``contacts``: b2ContactEdge and b2Contact by address.
    Contacts come and go, but Box2D's block allocator gives a freed contact's memory only to
    another contact and keeps it until its world goes: a kept buffer reads a contact that is
    listed now (only listed addresses are read). The buffers live as long as the readout,
    which does not outlive its world's bodies.
    """

    __slots__ = ("bodies", "contacts", "edges", "state")

    def __init__(self) -> None:
        self.state = _state_struct()
        self.bodies: dict[int, object] = {}
        self.edges: dict[int, object] = {}
        self.contacts: dict[int, object] = {}

    def body(self, address: int):
        buffer = self.bodies.get(address)
        if buffer is None:
            buffer = self.bodies[address] = _buffer(address, self.state.size)
        return buffer


def _state_in_memory(body, address: int, memory: _Memory) -> tuple:
    """``(x, y, sin θ, cos θ, θ, v_x, v_y, ω, contact list)`` of a body now (its transform,
    its sweep's angle, its velocities, the address of its first b2ContactEdge), read at its
    address."""
    return memory.state.unpack_from(memory.body(address))


def _state_by_getters(body, address: int, memory: _Memory) -> tuple:
    """:func:`_state_in_memory` through pybox2d's getters (the contact list left 0)."""
    transform = _get_transform(body)
    position, rotation = _get_position(transform), _get_rotation(transform)
    velocity = _get_linear_velocity(body)
    return (position.x, position.y, rotation.s, rotation.c, _get_angle(body), velocity.x,
            velocity.y, _get_angular_velocity(body), 0)


def _touching_in_memory(body, state: tuple, memory: _Memory) -> list:
    """The touching contacts of a body as :data:`_CONTACT` tuples, oldest first (the order
    of pybox2d's ``body.contacts``, which reverses Box2D's list: a new contact goes to its
    head); ``state``: the body's :func:`_state_in_memory` now (its contact list)."""
    touching = []
    edges, contacts = memory.edges, memory.contacts
    edge_struct, contact_struct = _EDGE, _CONTACT
    edge = state[8]
    while edge:
        buffer = edges.get(edge)
        if buffer is None:
            buffer = edges[edge] = _buffer(edge, edge_struct.size)
        contact, edge = edge_struct.unpack_from(buffer)
        buffer = contacts.get(contact)
        if buffer is None:
            buffer = contacts[contact] = _buffer(contact, contact_struct.size)
        values = contact_struct.unpack_from(buffer)
        if values[0] & _TOUCHING:
            touching.append(values)
    touching.reverse()
    return touching


def _touching_by_getters(body, state: tuple, memory: _Memory) -> list:
    """:func:`_touching_in_memory` through pybox2d's getters."""
    touching = []
    edge = _body_contacts(body)
    while edge is not None:
        contact = _edge_contact(edge)
        if _is_touching(contact):
            touching.append(_contact_values(contact))
        edge = _edge_next(edge)
    touching.reverse()
    return touching


def _contact_values(contact) -> tuple:
    """A contact as :data:`_CONTACT` unpacks it, through pybox2d's getters (the next
    contact's address left 0, a point not in use zeros)."""
    manifold = _get_manifold(contact)
    count = _point_count(manifold)
    values = [_TOUCHING if _is_touching(contact) else 0, 0,
              int(_get_fixture_a(contact).this), int(_get_fixture_b(contact).this)]
    for index in range(2):
        if index < count:
            point = _get_point(manifold, index)
            local = point.localPoint
            values += (local.x, local.y, point.normalImpulse, point.tangentImpulse)
        else:
            values += (0.0, 0.0, 0.0, 0.0)
    normal, local = manifold.localNormal, manifold.localPoint
    values += (normal.x, normal.y, local.x, local.y, manifold.type_, count)
    return tuple(values)


def _used(values: tuple) -> tuple:
    """What the readout uses of a :data:`_CONTACT` tuple: the fixtures and the manifold's
    fields, of its points only those in use (the others hold whatever was there)."""
    count = values[17]
    return (*values[2:4], *values[4:4 + 4 * count], *values[12:])


def _layout_matches() -> bool:
    """Whether :data:`_BODY`, :data:`_EDGE` and :data:`_CONTACT` read what pybox2d's getters
    read, on a box landing nearly flat on a ground box (a manifold of two points, the
    values distinct). A pointer is followed only once it equals the getters' own."""
    world = b2.world(gravity=(0.0, 0.0), doSleep=False)
    try:
        ground = world.CreateStaticBody()
        ground.CreatePolygonFixture(vertices=[(-4.0, -1.0), (4.0, -1.0), (4.0, 0.0),
                                              (-4.0, 0.0)])
        body = world.CreateDynamicBody(position=(0.25, 0.49), angle=0.0)
        body.CreatePolygonFixture(box=(0.5, 0.5), density=1.0)
        body.linearVelocity, body.angularVelocity = (0.75, -3.0), 0.5
        world.Step(1.0 / 60.0, 8, 3)
        address = _body_id(body)
        if address != int(body.this):
            return False
        memory = _Memory()
        state = _BODY.unpack(_string_at(address, _BODY.size))
        if state != _state_by_getters(body, address, memory)[:8]:
            return False
        (edge,) = _POINTER.unpack(_string_at(address + _BODY_CONTACTS, _POINTER.size))
        first = _body_contacts(body)
        if first is None or edge != int(first.this):
            return False
        contact, next_edge = _EDGE.unpack(_string_at(edge, _EDGE.size))
        swig_contact = _edge_contact(first)
        if (contact != int(swig_contact.this) or next_edge != 0 or _edge_next(first) is not None
                or not _is_touching(swig_contact)):
            return False
        values = _CONTACT.unpack(_string_at(contact, _CONTACT.size))
        if values[1] != 0 or _contact_next(swig_contact) is not None:
            return False
        expected = _contact_values(swig_contact)
        in_place = _state_in_memory(body, address, memory)
        return (values[0] & _TOUCHING == _TOUCHING and expected[17] == 2
                and _used(values) == _used(expected)
                and in_place == (*state, edge)
                and _touching_in_memory(body, in_place, memory) == [values])
    except (ValueError, TypeError, AttributeError, IndexError, struct.error):
        return False


_IN_MEMORY = _layout_matches()
#: ``(state, touching of a body)``: the readers in use.
_READERS = ((_state_in_memory, _touching_in_memory) if _IN_MEMORY
            else (_state_by_getters, _touching_by_getters))


class _Readout:
    """What the readout keeps of one impact's bodies and fixtures (a :class:`_World`'s and
    a :class:`_Slot`'s base).

    ``start``: every body's pose ``(x, y, cos θ, sin θ)`` by :data:`_body_id` when the next
    step begins (a step's contacts are collided at its start, and their geometry needs those
    poses; the ground's, read once, never changes); ``now``: the scene's poses ``(x, y, θ)``
    now, what ``_read_poses`` returns; ``states``: every body's :func:`_state_in_memory` now.
    :meth:`read` refreshes them after placing the bodies and :meth:`read_step` after a step,
    so the bodies are read once a step (the next step starts where this one ended).
    ``fixtures``: every fixture's userData by its address; ``by_id``: every body, the
    ground's included, by :data:`_body_id`; ``memory``: the readers' buffers, ``buffers``
    the bodies' (None where the getters read); ``keys``: the bodies' :data:`_body_id`.
    ``dt``: the run's Box2D time step and ``clipped`` whether a velocity reached a cap
    (:func:`_states_at_cap`), which :meth:`read_step` checks until one has.
    """

    __slots__ = ("bodies", "body_b", "body_b_id", "buffers", "by_id", "clipped", "dt",
                 "dynamic", "fixtures", "keys", "length", "memory", "now", "start", "states")

    def __init__(self, bodies: list, static: list, fixtures: list, length: float) -> None:
        self.bodies, self.body_b, self.length = bodies, bodies[-1], length
        self.body_b_id = _body_id(self.body_b)
        self.dynamic = [(b2_body, _body_id(b2_body)) for b2_body in bodies]
        self.keys = [key for _, key in self.dynamic]
        self.by_id = {key: b2_body for b2_body, key in self.dynamic}
        self.fixtures = {int(fixture.this): fixture.userData for fixture in fixtures}
        self.memory = _Memory()
        self.start = {}
        for b2_body in static:
            key = _body_id(b2_body)
            self.by_id[key] = b2_body
            x, y, sin, cos = _READERS[0](b2_body, key, self.memory)[:4]
            self.start[key] = (x, y, cos, sin)
        self.buffers = ([self.memory.body(key) for _, key in self.dynamic]
                        if _READERS[0] is _state_in_memory else None)
        self.now: tuple = ()
        self.states: list = []
        self.dt, self.clipped = 0.0, False

    def read(self) -> None:
        """Read the bodies now (after placing them)."""
        state_of, memory = _READERS[0], self.memory
        self._take([state_of(b2_body, key, memory) for b2_body, key in self.dynamic])

    def read_step(self) -> RawContacts | None:
        """After a step: its contact (:func:`_contact_of`: body B's touching contacts, at the
        poses the step started from), then the bodies now (as :meth:`read`), and whether a
        velocity reached a cap (``clipped``, from the first step that does)."""
        buffers = self.buffers
        if buffers is not None:  # _state_in_memory, on the buffers made once
            unpack = self.memory.state.unpack_from
            states = [unpack(buffer) for buffer in buffers]
        else:
            state_of, memory = _READERS[0], self.memory
            states = [state_of(b2_body, key, memory) for b2_body, key in self.dynamic]
        # Every contact of an impact involves its body B (the ground's partner or the other
        # body, the last one); the body's list keeps the world's order of them.
        touching = _READERS[1](self.body_b, states[-1], self.memory)
        raw = _contact_of(touching, self) if touching else None
        self._take(states)
        if not self.clipped:
            self.clipped = _states_at_cap(states, self.dt, _CAP_BAND)
        return raw

    def _take(self, states: list) -> None:
        length, start = self.length, self.start
        now = []
        for key, (x, y, sin, cos, angle, _, _, _, _) in zip(self.keys, states):
            start[key] = (x, y, cos, sin)
            now.append((x / length, y / length, angle))
        self.now, self.states = tuple(now), states


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
    """A body definition, a fixture definition (density 0) and a mass record (centre at the
    origin), filled anew for every body and fixture of :func:`_add_impact`: the impacts of
    a batch share one set (each costs several µs to make, as much as a fixture)."""

    __slots__ = ("body", "fixture", "mass")

    def __init__(self) -> None:
        self.body = b2.bodyDef()
        self.fixture = b2.fixtureDef()
        self.fixture.density = 0.0
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
        fixture_definition.groupIndex = group
        fixture_definition.maskBits = 0
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


def _states_at_cap(states, dt: float, band: float) -> bool:
    """Whether a body's velocity reaches ``band`` times Box2D's per-step caps (``states``:
    the bodies as :meth:`_Readout.read` reads them)."""
    for state in states:
        if math.hypot(state[5], state[6]) * dt > band * MAX_TRANSLATION:
            return True
        if abs(state[7]) * dt > band * MAX_ROTATION:
            return True
    return False


class _World(_Readout):
    """One b2World holding the scene's ground and bodies, and the current run's scales."""

    __slots__ = ("derived", "fixture_list", "iterations", "measures", "notes",
                 "pair_values", "restitution", "speed_probe", "velocity", "world",
                 "world_values")

    def __init__(self, scene: Scene, length: float, skin: float, measures: bool = True):
        self.world = b2.world(gravity=(0.0, 0.0), doSleep=True)
        # Whether a run whose probe would be its own beginning measures the first contact's
        # speed itself (not in the bare stepper: a listener costs a call per contact).
        self.measures = measures
        self.speed_probe: _SpeedProbe | None = None  # measuring the current run's speed
        self.derived: dict = {}  # the current run's derived values
        self.restitution = 0.0
        bodies, ground, self.fixture_list = _add_impact(self.world, scene, length, skin,
                                                        _extent(scene))
        super().__init__(bodies, ground, self.fixture_list, length)
        self.pair_values: tuple | None = None
        self.world_values: tuple | None = None
        # The current run's (set by _reset): Box2D time step, sweeps, velocity scale, the
        # caps in Box2D units, whether a velocity reached a cap, the run's set-up notes.
        self.iterations = (0, 0)
        self.velocity = 1.0
        self.notes: tuple[str, ...] = ()

    def configure(self, world_values: tuple, pair_values: tuple) -> None:
        """Apply the world switches and the pair's (e, μ) where they changed."""
        if self.world_values != world_values:
            _set_switches(self.world, world_values)
            self.world_values = world_values
        if self.pair_values != pair_values:
            _set_pair_values(self.fixture_list, pair_values)
            self.pair_values = pair_values

    def place(self, starts: tuple) -> None:
        """Fresh contacts and the start state ``((x, y), θ, (v_x, v_y), ω)`` (Box2D units).

        The contacts (with their warm-start impulses) are destroyed; the broad-phase proxies
        are kept. Box2D creates new contacts in the order of the proxies' ids (it sorts the
        pairs it finds), and the contacts' order is the order the sweeps solve them in, which
        moves an unconverged result (the rod under 8 sweeps). Ids come from a free list
        shared with the tree's inner nodes, so destroying and recreating proxies (as
        deactivating a body does) would change them with every run's history.
        """
        manager = self.world.contactManager
        for contact in list(self.world.contacts):
            manager.Destroy(contact)
        _place(self.bodies, starts)
        # The pairs touching at the start pose are looked up now, so that the first step's
        # collision pass already sees them.
        manager.FindNewContacts()
        self.read()


# ---------------------------------------------------------------------- contact readout
def _contact_in(contact) -> tuple:
    """A contact pybox2d hands over (a PreSolve's) as :data:`_CONTACT` unpacks it."""
    if _IN_MEMORY:
        return _CONTACT.unpack(_string_at(int(contact.this), _CONTACT.size))
    return _contact_values(contact)


def _manifold_geometry(values: tuple, pose_a: tuple, pose_b: tuple, radius_a: float,
                       radius_b: float) -> tuple[tuple[float, float], list]:
    """``(normal from fixture A to B, points (x, y, separation))`` of a contact, in world
    frame.

    b2WorldManifold::Initialize redone in Python (pybox2d's ``worldManifold`` returned an
    uninitialised normal), with the separations of the skinned shapes (Box2D's, negative
    within the summed skins). ``values``: the contact as :data:`_CONTACT` unpacks it;
    ``pose_a``, ``pose_b``: the bodies' ``(x, y, cos θ, sin θ)`` when the manifold was
    computed (the start of the step: after the step the bodies have moved, which would turn
    a circle pair's normal); ``radius_a``, ``radius_b``: the fixtures' shape radii.
    """
    pa_x, pa_y, ca, sa = pose_a
    pb_x, pb_y, cb, sb = pose_b
    kind, count = values[16], values[17]
    points = []
    if kind == _CIRCLES:
        lx, ly = values[14], values[15]  # the manifold's localPoint
        ax, ay = ca * lx - sa * ly + pa_x, sa * lx + ca * ly + pa_y
        lx, ly = values[4], values[5]  # its point's localPoint
        bx, by = cb * lx - sb * ly + pb_x, sb * lx + cb * ly + pb_y
        dx, dy = bx - ax, by - ay
        distance = math.hypot(dx, dy)
        normal = (dx / distance, dy / distance) if distance > 0.0 else (1.0, 0.0)
        c_ax, c_ay = ax + radius_a * normal[0], ay + radius_a * normal[1]
        c_bx, c_by = bx - radius_b * normal[0], by - radius_b * normal[1]
        points.append((0.5 * (c_ax + c_bx), 0.5 * (c_ay + c_by), distance - radius_a - radius_b))
        return normal, points
    face_a = kind == _FACE_A
    (c_ref, s_ref, p_ref_x, p_ref_y, r_ref) = (ca, sa, pa_x, pa_y, radius_a) if face_a else (
        cb, sb, pb_x, pb_y, radius_b)
    (c_inc, s_inc, p_inc_x, p_inc_y, r_inc) = (cb, sb, pb_x, pb_y, radius_b) if face_a else (
        ca, sa, pa_x, pa_y, radius_a)
    lx, ly = values[12], values[13]  # localNormal
    nx, ny = c_ref * lx - s_ref * ly, s_ref * lx + c_ref * ly
    lx, ly = values[14], values[15]  # localPoint
    plane_x = c_ref * lx - s_ref * ly + p_ref_x
    plane_y = s_ref * lx + c_ref * ly + p_ref_y
    for first in range(4, 4 + 4 * count, 4):
        lx, ly = values[first], values[first + 1]
        qx = c_inc * lx - s_inc * ly + p_inc_x
        qy = s_inc * lx + c_inc * ly + p_inc_y
        height = (qx - plane_x) * nx + (qy - plane_y) * ny
        c_ref_x, c_ref_y = qx + (r_ref - height) * nx, qy + (r_ref - height) * ny
        c_inc_x, c_inc_y = qx - r_inc * nx, qy - r_inc * ny
        points.append((0.5 * (c_ref_x + c_inc_x), 0.5 * (c_ref_y + c_inc_y),
                       height - r_ref - r_inc))
    if not face_a:
        nx, ny = -nx, -ny  # Box2D's normal points from fixture A to fixture B
    return (nx, ny), points


def _approach_speed(values: tuple, view: _Readout) -> float:
    """The normal approach speed at a touching contact's fastest point, computed as the
    solver computes ``v_rel`` (from the velocities before the step: call from PreSolve).
    ``values``: the contact (:func:`_contact_in`); ``view``: its impact's :class:`_Readout`
    (the fixtures and bodies)."""
    _, radius_a, body_a_id = view.fixtures[values[2]]
    _, radius_b, body_b_id = view.fixtures[values[3]]
    body_a, body_b = view.by_id[body_a_id], view.by_id[body_b_id]
    memory = view.memory
    x_a, y_a, sin_a, cos_a = _READERS[0](body_a, body_a_id, memory)[:4]  # the poses now
    x_b, y_b, sin_b, cos_b = _READERS[0](body_b, body_b_id, memory)[:4]
    normal, points = _manifold_geometry(values, (x_a, y_a, cos_a, sin_a),
                                        (x_b, y_b, cos_b, sin_b), radius_a, radius_b)
    fastest = 0.0
    for x, y, _ in points:
        va = body_a.GetLinearVelocityFromWorldPoint((x, y))
        vb = body_b.GetLinearVelocityFromWorldPoint((x, y))
        approach = -((vb[0] - va[0]) * normal[0] + (vb[1] - va[1]) * normal[1])
        fastest = max(fastest, approach)
    return fastest


class _SpeedProbe(b2.contactListener):
    """PreSolve listener of a :class:`_World`: the approach speed at the first touching
    contact (:func:`_approach_speed`)."""

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


def _box2d_starts(start, velocity: float, length: float, advance: float = 0.0) -> tuple:
    """The run-frame start states in Box2D units, ``advance`` s further along free flight."""
    return tuple(
        (
            (float((x + vx * advance) * length), float((y + vy * advance) * length)),
            float(angle + omega * advance),
            (float(vx * velocity), float(vy * velocity)),
            float(omega * velocity / length),
        )
        for x, y, angle, vx, vy, omega in start
    )


class _ProbeInputs(NamedTuple):
    """What the probe run needs, and the settings that act on its result."""

    start: tuple  # run-frame start state (contract BodyState per body)
    length: float  # length_scale
    time_step: float  # s, scene units
    max_steps: int
    velocity_scale: float | str  # the setting: a number or "auto"
    overlap: float  # detection_overlap, body extents
    extent: float  # m, the largest body extent
    restitution: float


class _Prepared:
    """A run's Box2D form: switches, pair values, sweeps, scales, start state, derived.

    ``probe``: what the probe run needs (the run-frame start state, the Box2D time step
    without velocity scale, the step cap, the settings that act on the probe's result);
    :func:`_scaled` fills in the rest from the probe's speed.
    """

    __slots__ = ("derived", "dt", "iterations", "notes", "pair_values", "probe", "starts",
                 "velocity", "world_values")

    def unprobed(self) -> _Prepared:
        """A copy of what :func:`_unprobed` sets (copy.copy costs several times more)."""
        copied = _Prepared()
        copied.world_values, copied.pair_values = self.world_values, self.pair_values
        copied.iterations, copied.probe = self.iterations, self.probe
        return copied


def _unprobed(scene: Scene, settings, start) -> _Prepared:
    """A run's :class:`_Prepared` up to the probe run."""
    prepared = _Prepared()
    length = float(settings["length_scale"])
    time_step = float(settings["time_step"])
    prepared.world_values = tuple(bool(settings[key]) for key in _BOOL_KEYS)
    prepared.pair_values = (float(scene.restitution), float(scene.friction))
    prepared.iterations = (int(settings["velocity_iterations"]),
                           int(settings["position_iterations"]))
    prepared.probe = _ProbeInputs(start, length, time_step, int(settings["max_steps"]),
                                  settings["velocity_scale"],
                                  float(settings["detection_overlap"]), _extent(scene),
                                  float(scene.restitution))
    return prepared


def _probe_starts(prepared: _Prepared) -> tuple:
    """The probe run's start state in Box2D units (unscaled velocities)."""
    return _box2d_starts(prepared.probe.start, 1.0, prepared.probe.length)


def _probe_is_run(prepared: _Prepared) -> bool:
    """Whether the probe run is the run itself up to its first contact: no velocity scale
    and no start depth that the probe's speed would set."""
    scale = prepared.probe.velocity_scale
    return scale != "auto" and float(scale) == 1.0 and prepared.probe.overlap == 0.0


def _scaled(prepared: _Prepared, probe_speed: float | None) -> _Prepared:
    """Complete ``prepared`` with the velocity scale, start state and derived values that
    Box2D's approach speed at the first contact of the probe run (``probe_speed``) sets."""
    start, length, time_step, _, scale, overlap, extent, restitution = prepared.probe
    if scale == "auto":
        scale = 1.0
        if probe_speed is not None and probe_speed > 0.0:
            target = _AUTO_MARGIN * VELOCITY_THRESHOLD
            while scale * probe_speed < target and scale < _MAX_AUTO_SCALE:
                scale *= 2.0
    velocity = prepared.velocity = float(scale)
    # The overlap as a time along the path: depth = overlap·extent at the approach speed.
    advance = 0.0
    if overlap > 0.0 and probe_speed is not None and probe_speed > 0.0:
        advance = overlap * extent / probe_speed
    prepared.starts = _box2d_starts(start, velocity, length, advance)
    prepared.dt = time_step * length / velocity
    prepared.derived = {
        "velocity_scale": velocity,
        "length_scale": length,
        "box2d_time_step": prepared.dt,
        "speed_cap": MAX_TRANSLATION / (length * time_step),
        "angular_speed_cap": MAX_ROTATION / time_step,
    }
    prepared.notes = _speed_results(prepared.derived, probe_speed, velocity, restitution)
    return prepared


def _speed_results(derived: dict, probe_speed: float | None, velocity: float,
                   restitution: float) -> tuple[str, ...]:
    """Add the impact speed Box2D saw to ``derived``; the threshold's note if it zeroed e."""
    if probe_speed is None:
        return ()
    derived["box2d_impact_speed"] = probe_speed * velocity
    cleared = probe_speed * velocity > VELOCITY_THRESHOLD
    derived["restitution_threshold_cleared"] = cleared
    if not cleared and restitution > 0.0:
        return (THRESHOLD_NOTE,)
    return ()


# ---------------------------------------------------------------------- the adapter
class Box2DEngine(Engine):
    name = "box2d"
    version = Box2D.__version__
    # What the rest of the harness reads about this engine (docs/engines.md, 'The engine
    # contract'): why it lands where it does, per engine and per preset, and its plot style.
    description = (
        "Box2D solves the velocity-level law (newton-lcp) by sequential impulses, like "
        "pymunk; its measured behaviour is in docs/engines.md, 'Box2D'.")
    preset_why = {
        "defaults": ("Box2D's own defaults."),
        "accurate": ("settings under which Box2D solves its law as exactly as it can."),
    }
    rounding = 1e-6  # float32 arithmetic: a few roundings of 6e-8 (ROUNDING in the tests)
    # Box2D's default polygon skin (0.01 m) makes the rod's core box reach the ground beside
    # its 5 mm end cap: three contact points at once; on the ellipse's 8-gon, skins of 2 × 0.01
    # m reach past the next vertex (8 mm up): two points.
    reference_statuses = {("rod-45", "defaults"): "multi-contact",
                          ("ellipse", "defaults"): "multi-contact"}
    native_2d = True
    plot_style = ("#CC79A7", "D")
    bench_impacts = (40, 300)
    presets = PRESETS
    setting_docs = SETTING_DOCS
    # Collision first: the first step finds the contact at the start pose. The start's
    # hair of overlap is a depth in lengths (detection_overlap), added in _prepare.
    timing = StepTiming(lead_steps=0.0, overlap=0.0)


    @classmethod
    def bench_sweep(cls, quick: bool) -> list[tuple[str, str, dict]]:
        """The settings the accuracy bench measures (harness/bench/accuracy.py)."""
        points: list[tuple[str, str, dict]] = []
        points.append(("defaults", "defaults", {}))
        # Box2D's own time step changes nothing for a one-step impact but the translation
        # cap; the sweeps are what converge the coupled points (float32 floor ~1e-7).
        iterations = (1, 2, 5, 8, 20, 100) if quick else (1, 2, 3, 5, 8, 10, 20, 50, 100, 200)
        for count in iterations:
            points.append((f"dt={1 / 60:.3g} it={count}", "accurate",
                           {"velocity_iterations": count}))
        return points

    def _validate_engine_settings(self, settings) -> None:
        check_int(self.name, settings, "velocity_iterations", low=1)
        check_int(self.name, settings, "position_iterations", low=0)
        for key in _BOOL_KEYS:
            if not isinstance(settings[key], bool):
                raise EngineSettingsError(
                    f"engine {self.name!r}: setting {key!r} must be true or false, "
                    f"got {settings[key]!r}")
        check_number(self.name, settings, "polygon_radius", low=0.0)
        if settings["velocity_scale"] != "auto":
            check_number(self.name, settings, "velocity_scale", low=0.0, strict=True)
        check_number(self.name, settings, "length_scale", low=0.0, strict=True)
        check_number(self.name, settings, "detection_overlap", low=0.0)

    def _world_key(self, scene: Scene, settings) -> tuple:
        return (geometry_key(scene), float(settings["length_scale"]),
                float(settings["polygon_radius"]))

    def _build(self, scene: Scene, settings, *, contacts: bool = True) -> _World:
        return _World(scene, float(settings["length_scale"]), float(settings["polygon_radius"]),
                      measures=contacts)

    def _prepare(self, world: _World | None, scene: Scene, settings, start, weights) -> _Prepared:
        prepared = _unprobed(scene, settings, start)
        if world is None:  # run_many: _build_many probes every impact of a batch at once
            return prepared
        if _probe_is_run(prepared):  # the run measures the speed itself (_reset), as in a batch
            return _scaled(prepared, None)
        # Measured for every plan: it tells whether the threshold zeroed the bounce.
        probe = prepared.probe
        probe_speed = _probe(world, prepared, _probe_starts(prepared),
                             probe.time_step * probe.length, probe.max_steps)
        return _scaled(prepared, probe_speed)

    def _reset(self, world: _World, prepared: _Prepared) -> dict:
        world.configure(prepared.world_values, prepared.pair_values)
        world.dt, world.iterations, world.velocity = (prepared.dt, prepared.iterations,
                                                      prepared.velocity)
        world.notes = prepared.notes
        world.place(prepared.starts)
        # Already beyond a cap before the first step (place read the bodies).
        world.clipped = _states_at_cap(world.states, world.dt, 1.0)
        derived = world.derived = dict(prepared.derived)
        if world.speed_probe is not None:  # the last run met no contact
            world.world.contactListener = world.speed_probe = None
        if world.measures and _probe_is_run(prepared):
            world.speed_probe = _SpeedProbe(world)
            world.world.contactListener = world.speed_probe
            world.restitution = prepared.probe.restitution
        return derived

    def _advance(self, world: _World) -> None:
        world.world.Step(world.dt, *world.iterations)

    def _step(self, world: _World) -> RawContacts | None:
        world.world.Step(world.dt, *world.iterations)
        probe = world.speed_probe
        if probe is not None and probe.speed is not None:  # measured in this step's PreSolve
            world.notes = _speed_results(world.derived, probe.speed, world.velocity,
                                         world.restitution)
            world.world.contactListener = world.speed_probe = None
        return world.read_step()

    # ------------------------------------------------------------------ many impacts
    def _runs_alone(self, settings) -> bool:
        """With ``sub_stepping`` the impacts run one by one (:meth:`Engine.run_many`).

        Sub-stepping handles one time-of-impact event per step in the whole world and leaves
        the world's step unfinished (the next ``b2World::Step`` only resumes it): impacts
        sharing a world would steer each other.
        """
        return bool(settings["sub_stepping"])

    def _many_chunks(self, scenes) -> list[list[int]]:
        """Up to :data:`MANY_CHUNK` scenes to a batch, those of one :func:`_speed_class`
        together (in their order; a class's scenes split evenly among its batches).

        ``auto`` gives each velocity scale a world of its own, and an impact outside its
        batch's probe world's group is built a second time (:meth:`_build_many`): batches
        of one class keep those few. Which scenes share a batch changes no run.
        """
        classes: dict[int, list[int]] = {}
        for index, scene in enumerate(scenes):
            classes.setdefault(_speed_class(scene), []).append(index)
        chunks = []
        for indices in classes.values():
            size = -(-len(indices) // -(-len(indices) // MANY_CHUNK))  # ceil(n / batches)
            chunks += [indices[begin:begin + size] for begin in range(0, len(indices), size)]
        return chunks

    def _build_many(self, plans) -> tuple[_Batch, list, list]:
        """b2Worlds stepping many impacts, each impact as :meth:`run` steps it alone.

        The impacts overlap in space (each at its own run-frame coordinates: moving one
        would change its float32 roundings) and are kept apart by collision filters: every
        fixture of impact k, its ground's included, is in group k+1 (always collide) with
        mask 0 (collide with no other group). Box2D solves each island (an impact's bodies
        and their touching contacts) by itself, collides contact by contact, and creates
        the contacts of new pairs in the order of the proxies' ids, which keep each impact's
        own order; time-of-impact events advance only their own bodies. So an impact's
        arithmetic is the one it has alone (the tests compare them bit for bit).

        First the probe runs of every impact in one world (unscaled, each impact put to
        sleep once its speed is known); then one world per Box2D time step (the velocity
        scales differ: a world steps by one time step, and warm starting scales impulses by
        the ratio of consecutive steps). The largest group runs in the probe's world, placed
        anew (:func:`_place` leaves nothing of the probe). When the probe run is the run's
        own beginning (no velocity scale or start depth to set), the runs measure the speed
        themselves.
        """
        prepared = [plan.prepared for plan in plans]
        first = prepared[0]  # one settings dict for every plan
        world_values, iterations = first.world_values, first.iterations
        length, time_step, max_steps = (first.probe.length, first.probe.time_step,
                                        first.probe.max_steps)
        skin = float(plans[0].settings["polygon_radius"])
        measure_in_run = _probe_is_run(first)
        probe_world = None
        if not measure_in_run:
            speeds, probe_world, probe_views = _probe_many(
                plans, prepared, length, skin, time_step * length, max_steps)
            prepared = [_scaled(one.unprobed(), speed) for one, speed in zip(prepared, speeds)]
        else:
            prepared = [_scaled(one.unprobed(), None) for one in prepared]
        groups: dict = {}
        for slot, one in enumerate(prepared):
            groups.setdefault(one.dt, []).append(slot)
        batch = _Batch(len(plans))
        # The largest group runs in the probe's world (placed anew, as run places a
        # world's bodies after its probe); the others in worlds of their own.
        for slots in sorted(groups.values(), key=len, reverse=True):
            dt = prepared[slots[0]].dt
            if probe_world is not None:
                world, views = probe_world, [probe_views[slot] for slot in slots]
                _replace(world, probe_views, set(slots), prepared)
                probe_world = None
            else:
                world, views = _many_world([plans[slot] for slot in slots],
                                           [prepared[slot] for slot in slots], slots, length,
                                           skin, world_values)
            for slot, view in zip(slots, views):
                view.world = len(batch.worlds)
                view.dt, view.velocity = dt, prepared[slot].velocity
                view.notes = prepared[slot].notes
                view.clipped = _states_at_cap(view.states, dt, 1.0)  # read when placed
                batch.slots[slot] = view
            batch.worlds.append((world, dt, iterations))
            if measure_in_run:
                listener = _ManyProbe(views, measure_run=True)
                world.contactListener = listener
                batch.listeners.append((world, listener))
        derived = [one.derived for one in prepared]
        for view, values in zip(batch.slots, derived):
            view.derived = values
        return batch, batch.slots, derived

    def _step_many(self, batch: _Batch, active) -> dict:
        slots, worlds = batch.slots, batch.worlds
        if len(worlds) == 1:  # called with active impacts only
            world, dt, iterations = worlds[0]
            world.Step(dt, *iterations)
        else:
            stepping = {slots[slot].world for slot in active}
            for index, (world, dt, iterations) in enumerate(worlds):
                if index in stepping:
                    world.Step(dt, *iterations)
        contacts = {}
        for slot in active:
            view = slots[slot]
            raw = view.read_step()
            if raw is not None:
                contacts[slot] = raw
        if batch.listeners:
            batch.listeners = [(world, listener) for world, listener in batch.listeners
                               if not listener.done(world)]
        return contacts

    def _retire(self, batch: _Batch, slot: int) -> None:
        view = batch.slots[slot]
        for b2_body in view.bodies:
            b2_body.awake = False  # a sleeping impact is neither collided nor solved

    def _release_many(self, batch: _Batch) -> None:
        for world, _ in batch.listeners:
            world.contactListener = None
        batch.listeners = []
        batch.worlds = []
        batch.slots = []

    def _read_poses(self, world: _World) -> tuple:
        return world.now  # read after the step (_Readout.read)

    def _read_velocities(self, world: _World) -> tuple:
        velocity, rate = world.velocity, world.length / world.velocity
        # Read after the step (_Readout.read): the loop reads velocities only then, and
        # the batch's _finish comes before _retire stops the bodies.
        return tuple([(state[5] / velocity, state[6] / velocity, state[7] * rate)
                      for state in world.states])

    def _run_notes(self, world: _World) -> tuple[str, ...]:
        if world.clipped:
            return (*world.notes, CLIPPED_NOTE)
        return world.notes


def _probe(world: _World, prepared: _Prepared, starts: tuple, dt: float,
           max_steps: int) -> float | None:
    """Box2D's approach speed (m/s, scene units) at the first contact of an unscaled run."""
    world.configure(prepared.world_values, prepared.pair_values)
    world.place(starts)
    probe = _SpeedProbe(world)
    b2_world = world.world
    b2_world.contactListener = probe
    try:
        for _ in range(max_steps):
            b2_world.Step(dt, *prepared.iterations)
            if probe.speed is not None:
                break
    finally:
        b2_world.contactListener = None
    return probe.speed


# ---------------------------------------------------------------------- many impacts
#: Impacts per batch in run_many (measured: see docs/engines.md, Box2D).
MANY_CHUNK = 32


def _approach_estimate(scene: Scene) -> float:
    """The normal approach speed at first touch (m/s), as the bodies' centres and a ground
    body's lowest point give it: about the speed the probe run measures (exact for a disk
    on the ground or two disks), for :func:`_speed_class`."""
    if scene.ground:
        (body,) = scene.bodies
        shape, angle = body.shape, body.angle
        cos, sin = math.cos(angle), math.sin(angle)
        if shape.kind == "disk":
            offsets = [(0.0, 0.0)]
        elif shape.kind == "rod":
            offsets = [(-shape.length / 2.0, 0.0), (shape.length / 2.0, 0.0)]
        elif shape.kind == "box":
            half_w, half_h = shape.width / 2.0, shape.height / 2.0
            offsets = [(-half_w, -half_h), (half_w, -half_h), (half_w, half_h),
                       (-half_w, half_h)]
        else:  # a polygon's points, or an ellipse's placed stand-in's
            offsets = (shape.stand_in() if shape.kind == "ellipse" else shape).points
        # The lowest point's x offset from the centre (the ground's normal is +y).
        _, lever = min((sin * x + cos * y, cos * x - sin * y) for x, y in offsets)
        return -(body.velocity[1] + body.angular_velocity * lever)
    body_a, body_b = scene.bodies
    d_x = body_b.position[0] - body_a.position[0]
    d_y = body_b.position[1] - body_a.position[1]
    distance = math.hypot(d_x, d_y)
    if distance == 0.0:
        return 0.0
    return -((body_b.velocity[0] - body_a.velocity[0]) * d_x
             + (body_b.velocity[1] - body_a.velocity[1]) * d_y) / distance


def _speed_class(scene: Scene) -> int:
    """The binary exponent of :func:`_approach_estimate` relative to the speed ``auto``
    lifts impacts to, 1 at and above it: scenes of one class likely get one ``auto``
    velocity scale."""
    speed = _approach_estimate(scene) / (_AUTO_MARGIN * VELOCITY_THRESHOLD)
    if not 0.0 < speed < 1.0 or not math.isfinite(speed):
        return 1
    return max(math.frexp(speed)[1], -64)


def _contact_of(touching: list, world) -> RawContacts | None:
    """The step's contact of one impact from its ``touching`` Box2D contacts (oldest
    first, as :data:`_CONTACT` tuples); ``world``: its :class:`_World` or :class:`_Slot`
    (scales, body B, the poses at the step's start, the fixtures).

    Each contact's geometry is :func:`_manifold_geometry`'s, written out here (the hot
    path: every step of every impact), operation for operation."""
    length, velocity, body_b = world.length, world.velocity, world.body_b_id
    poses, fixtures = world.start, world.fixtures
    step_x = step_y = 0.0
    points: list = []
    normal = None
    for values in touching:
        # Both points' localPoint and impulses (the second's unused with one point), the
        # manifold's localNormal, localPoint, type and point count.
        (_, _, fixture_a, fixture_b, l0_x, l0_y, n0, t0, l1_x, l1_y, n1, t1, normal_x,
         normal_y, local_x, local_y, kind, count) = values
        if not count:
            continue
        padding_a, radius_a, body_a_id = fixtures[fixture_a]
        padding_b, radius_b, contact_body_b = fixtures[fixture_b]
        pa_x, pa_y, ca, sa = poses[body_a_id]
        pb_x, pb_y, cb, sb = poses[contact_body_b]
        # Overlap of the scene's outlines: the skins are padding, not the bodies.
        padding = padding_a + padding_b
        # The impulse on scene body B (Box2D applies +P to fixture B's body).
        sign = 1.0 if contact_body_b == body_b else -1.0
        if kind == _CIRCLES:
            ax, ay = ca * local_x - sa * local_y + pa_x, sa * local_x + ca * local_y + pa_y
            bx, by = cb * l0_x - sb * l0_y + pb_x, sb * l0_x + cb * l0_y + pb_y
            dx, dy = bx - ax, by - ay
            distance = math.hypot(dx, dy)
            if distance > 0.0:
                n_x, n_y = dx / distance, dy / distance
            else:
                n_x, n_y = 1.0, 0.0
            c_ax, c_ay = ax + radius_a * n_x, ay + radius_a * n_y
            c_bx, c_by = bx - radius_b * n_x, by - radius_b * n_y
            points.append((0.5 * (c_ax + c_bx) / length, 0.5 * (c_ay + c_by) / length,
                           -(distance - radius_a - radius_b + padding) / length))
            # Box2D's tangent is cross(n, 1) = (n_y, -n_x).
            step_x += sign * (n0 * n_x + t0 * n_y)
            step_y += sign * (n0 * n_y - t0 * n_x)
        else:
            if kind == _FACE_A:
                c_ref, s_ref, p_ref_x, p_ref_y, r_ref = ca, sa, pa_x, pa_y, radius_a
                c_inc, s_inc, p_inc_x, p_inc_y, r_inc = cb, sb, pb_x, pb_y, radius_b
            else:
                c_ref, s_ref, p_ref_x, p_ref_y, r_ref = cb, sb, pb_x, pb_y, radius_b
                c_inc, s_inc, p_inc_x, p_inc_y, r_inc = ca, sa, pa_x, pa_y, radius_a
            n_x, n_y = c_ref * normal_x - s_ref * normal_y, s_ref * normal_x + c_ref * normal_y
            plane_x = c_ref * local_x - s_ref * local_y + p_ref_x
            plane_y = s_ref * local_x + c_ref * local_y + p_ref_y
            # Box2D's normal points from fixture A to fixture B: the impulses' normal.
            f_x, f_y = (n_x, n_y) if kind == _FACE_A else (-n_x, -n_y)
            for lx, ly, p_n, p_t in ((l0_x, l0_y, n0, t0), (l1_x, l1_y, n1, t1))[:count]:
                qx = c_inc * lx - s_inc * ly + p_inc_x
                qy = s_inc * lx + c_inc * ly + p_inc_y
                height = (qx - plane_x) * n_x + (qy - plane_y) * n_y
                c_ref_x, c_ref_y = qx + (r_ref - height) * n_x, qy + (r_ref - height) * n_y
                c_inc_x, c_inc_y = qx - r_inc * n_x, qy - r_inc * n_y
                points.append((0.5 * (c_ref_x + c_inc_x) / length,
                               0.5 * (c_ref_y + c_inc_y) / length,
                               -(height - r_ref - r_inc + padding) / length))
                step_x += sign * (p_n * f_x + p_t * f_y)
                step_y += sign * (p_n * f_y - p_t * f_x)
            n_x, n_y = f_x, f_y
        if normal is None:
            normal = (sign * n_x, sign * n_y)
    if normal is None:
        return None
    step_x, step_y = step_x / velocity, step_y / velocity
    return (tuple(points), normal, (step_x, step_y),
            abs(step_x * normal[0] + step_y * normal[1]))


class _Slot(_Readout):
    """One impact of a batch: what _read_poses, _read_velocities and _run_notes read (the
    attributes of a :class:`_World` they use)."""

    __slots__ = ("derived", "notes", "restitution", "velocity", "world")

    def __init__(self, bodies: list, ground: list, fixtures: list, length: float) -> None:
        super().__init__(bodies, ground, fixtures, length)
        self.velocity = 1.0
        self.notes: tuple[str, ...] = ()
        self.derived: dict = {}
        self.restitution = 0.0
        self.world = 0  # index of its b2World in the batch


class _Batch:
    """The b2Worlds of a batch: ``(world, dt, iterations)`` each, every impact's
    :class:`_Slot`, and the listeners still measuring approach speeds."""

    __slots__ = ("listeners", "slots", "worlds")

    def __init__(self, count: int) -> None:
        self.worlds: list = []
        self.slots: list = [None] * count
        self.listeners: list = []


def _many_world(plans, prepared, slots, length: float, skin: float, world_values: tuple,
                probe: bool = False) -> tuple:
    """A b2World holding every plan's scene at its start (``prepared``: its ``starts``, or
    the probe's with ``probe``), and one :class:`_Slot` each (bodies' userData: the slot)."""
    world = b2.world(gravity=(0.0, 0.0), doSleep=True)
    _set_switches(world, world_values)
    views = []
    definitions = _Definitions()
    for slot, plan, one in zip(slots, plans, prepared):
        bodies, ground, fixtures = _add_impact(
            world, plan.scene, length, skin, one.probe.extent,
            starts=_probe_starts(one) if probe else one.starts, group=slot + 1,
            pair_values=one.pair_values, inertias=[inertia for _, inertia in plan.weights],
            definitions=definitions)
        for b2_body in bodies:
            b2_body.userData = slot
        view = _Slot(bodies, ground, fixtures, length)
        view.restitution = one.pair_values[0]
        views.append(view)
    world.contactManager.FindNewContacts()
    if not probe:
        for view in views:
            view.read()
    return world, views


class _ManyProbe(b2.contactListener):
    """PreSolve listener of a batch world: each impact's approach speed at its first
    touching contact (:class:`_SpeedProbe` for many impacts)."""

    def __init__(self, views, measure_run: bool = False):
        super().__init__()
        self.speeds: dict[int, float] = {}
        self.views = {view.body_b.userData: view for view in views}
        # A contact's impact, by its fixture B (every fixture of an impact is its own).
        self.slots = {fixture: slot for slot, view in self.views.items()
                      for fixture in view.fixtures}
        self.measure_run = measure_run  # the runs' own speeds: into derived and notes

    def PreSolve(self, contact, old_manifold):
        values = _contact_in(contact)
        if not values[0] & _TOUCHING or not values[17]:
            return
        slot = self.slots[values[3]]
        if slot in self.speeds:
            return
        view = self.views[slot]
        speed = self.speeds[slot] = _approach_speed(values, view)
        if self.measure_run:
            view.notes = _speed_results(view.derived, speed, view.velocity, view.restitution)

    def done(self, world) -> bool:
        """Whether every impact's speed is known (the listener is then taken off)."""
        if len(self.speeds) < len(self.views):
            return False
        world.contactListener = None
        return True


def _replace(world, views, kept: set, prepared) -> None:
    """Put the impacts ``kept`` of a probe world at their run's start (``prepared``), as
    :meth:`_World.place` does; the others sleep (never collided or solved again)."""
    manager = world.contactManager
    for slot, view in enumerate(views):
        if slot in kept:
            for contact in [edge.contact for edge in view.body_b.contacts]:
                manager.Destroy(contact)
            _place(view.bodies, prepared[slot].starts)
        else:
            for b2_body in view.bodies:
                b2_body.awake = False
    manager.FindNewContacts()
    for slot in kept:
        views[slot].read()


def _probe_many(plans, prepared, length: float, skin: float, dt: float,
                max_steps: int) -> tuple[list[float | None], object, list]:
    """:func:`_probe` of every plan's scene in one world: each impact sleeps once its speed
    is known, as its probe run would stop. ``(speeds, world, slots)``."""
    slots = list(range(len(plans)))
    world, views = _many_world(plans, prepared, slots, length, skin,
                               prepared[0].world_values, probe=True)
    listener = _ManyProbe(views)
    world.contactListener = listener
    iterations = prepared[0].iterations
    asleep: set[int] = set()
    try:
        for _ in range(max_steps):
            world.Step(dt, *iterations)
            for slot in listener.speeds.keys() - asleep:
                for b2_body in views[slot].bodies:
                    b2_body.awake = False
                asleep.add(slot)
            if len(asleep) == len(views):
                break
    finally:
        world.contactListener = None
    return [listener.speeds.get(slot) for slot in slots], world, views


ENGINE_CLASS = Box2DEngine
