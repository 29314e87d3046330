"""One impact's b2World, kept across runs, and what the per-step readout keeps of it.

pybox2d's problems it answers: a contact's body or shape accessed through pybox2d makes a new
wrapper each time, so the readout keeps the bodies and fixtures by address and reads each body
once a step (:class:`_Readout`); and a world reused for another run would keep contacts,
warm-start impulses, sleep timers and proxies' boxes from the last one, which
:meth:`_World.place` clears while keeping the proxies' ids (reruns bit-identical).
"""

from __future__ import annotations

import math
from math import hypot as _hypot
from typing import TYPE_CHECKING

from Box2D import b2

from harness.engines.box2d.building import (
    _add_impact,
    _extent,
    _place,
    _set_pair_values,
    _set_switches,
)
from harness.engines.box2d.manifold import _contact_of
from harness.engines.box2d.presets import MAX_ROTATION, MAX_TRANSLATION
from harness.engines.box2d.readout import _READERS, _body_id, _Memory, _state_in_memory
from harness.engines.contract import RawContacts
from harness.scene import Scene

if TYPE_CHECKING:
    from harness.engines.box2d.scaling import _SpeedProbe

# A velocity Box2D clipped sits at the cap to float32 rounding: this band counts as "at".
_CAP_BAND = 1.0 - 1e-6
# The caps times the band (what read_step compares with, every step).
_TRANSLATION_BAND, _ROTATION_BAND = _CAP_BAND * MAX_TRANSLATION, _CAP_BAND * MAX_ROTATION


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
        velocity reached a cap (``clipped``, from the first step that does).

        The hot path (every step of every impact): :meth:`_take` and
        :func:`_states_at_cap` are written out here, operation for operation."""
        buffers = self.buffers
        if buffers is not None:  # _state_in_memory, on the buffers made once
            states = list(map(self.memory.state.unpack_from, buffers))
        else:
            state_of, memory = _READERS[0], self.memory
            states = [state_of(b2_body, key, memory) for b2_body, key in self.dynamic]
        # Every contact of an impact involves its body B (the ground's partner or the other
        # body, the last one); the body's list keeps the world's order of them.
        touching = _READERS[1](self.body_b, states[-1], self.memory)
        raw = _contact_of(touching, self) if touching else None
        length, start = self.length, self.start
        now = []
        clipped, dt = self.clipped, self.dt
        for key, (x, y, sin, cos, angle, v_x, v_y, omega, _) in zip(self.keys, states):
            start[key] = (x, y, cos, sin)
            now.append((x / length, y / length, angle))
            if not clipped:
                clipped = (_hypot(v_x, v_y) * dt > _TRANSLATION_BAND
                           or abs(omega) * dt > _ROTATION_BAND)
        self.now, self.states, self.clipped = tuple(now), states, clipped
        return raw

    def _take(self, states: list) -> None:
        length, start = self.length, self.start
        now = []
        for key, (x, y, sin, cos, angle, _, _, _, _) in zip(self.keys, states):
            start[key] = (x, y, cos, sin)
            now.append((x / length, y / length, angle))
        self.now, self.states = tuple(now), states



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
