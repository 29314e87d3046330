"""Box2D's state read from its structs at their addresses.

pybox2d's problem: every getter makes a Python wrapper object for the struct it returns (about
ten per contact and step), so reading a step through them costs many times Box2D's own step.
The readers here unpack Box2D 2.3's structs in place, in the layouts pybox2d 2.3.10 compiles
(64-bit), after checking them at import against the getters on a live world; where they do
not match, the getters read the same values (``_READERS``).
"""

from __future__ import annotations

import ctypes
import functools
import struct

import Box2D
from Box2D import b2

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



def _contact_in(contact) -> tuple:
    """A contact pybox2d hands over (a PreSolve's) as :data:`_CONTACT` unpacks it."""
    if _IN_MEMORY:
        return _CONTACT.unpack(_string_at(int(contact.this), _CONTACT.size))
    return _contact_values(contact)
