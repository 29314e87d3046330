"""Many impacts in one b2World (``run_many``), each run as ``run`` runs it alone.

What it answers: an impact alone pays pybox2d's Python calls for a world and its steps; up
to :data:`MANY_CHUNK` impacts sharing a world, kept apart by collision groups, take about
half the time (docs/engines.md, 'Box2D'). ``Box2DEngine._build_many`` (:mod:`.adapter`)
says why each impact's arithmetic stays its own.
"""

from __future__ import annotations

from Box2D import b2

from harness.engines.box2d.building import _add_impact, _Definitions, _set_switches
from harness.engines.box2d.manifold import _approach_speed
from harness.engines.box2d.readout import _TOUCHING, _contact_in
from harness.engines.box2d.scaling import _speed_results
from harness.engines.box2d.world import _Readout

# ---------------------------------------------------------------------- many impacts
#: Impacts per batch in run_many (measured: see docs/engines.md, Box2D).
MANY_CHUNK = 16


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


def _many_world(plans, prepared, slots, length: float, skin: float,
                world_values: tuple) -> tuple:
    """A b2World holding every plan's scene at its start (``prepared``: its ``starts``),
    and one :class:`_Slot` each (bodies' userData: the slot), each read at its start."""
    world = b2.world(gravity=(0.0, 0.0), doSleep=True)
    _set_switches(world, world_values)
    views = []
    definitions = _Definitions()
    for slot, plan, one in zip(slots, plans, prepared):
        bodies, ground, fixtures = _add_impact(
            world, plan.scene, length, skin, one.extent, starts=one.starts, group=slot + 1,
            pair_values=one.pair_values, inertias=[inertia for _, inertia in plan.weights],
            definitions=definitions)
        for b2_body in bodies:
            b2_body.userData = slot
        view = _Slot(bodies, ground, fixtures, length)
        view.restitution = one.pair_values[0]
        views.append(view)
    world.contactManager.FindNewContacts()
    for view in views:
        view.read()
    return world, views


class _ManyProbe(b2.contactListener):
    """PreSolve listener of a batch world: each impact's approach speed at its first
    touching contact (:class:`_SpeedProbe` for many impacts), for the impacts of ``views``
    (those a collision pass alone left unmeasured: :func:`_speed_after_collide`), into their
    derived values and notes."""

    def __init__(self, views):
        super().__init__()
        self.speeds: dict[int, float] = {}
        self.views = {view.body_b.userData: view for view in views}
        # A contact's impact, by its fixture B (every fixture of an impact is its own).
        self.slots = {fixture: slot for slot, view in self.views.items()
                      for fixture in view.fixtures}

    def PreSolve(self, contact, old_manifold):
        values = _contact_in(contact)
        if not values[0] & _TOUCHING or not values[17]:
            return
        slot = self.slots.get(values[3])
        if slot is None or slot in self.speeds:  # not measured here, or measured already
            return
        view = self.views[slot]
        speed = self.speeds[slot] = _approach_speed(values, view)
        view.notes = _speed_results(view.derived, speed, view.restitution, view.notes)

    def done(self, world) -> bool:
        """Whether every impact's speed is known (the listener is then taken off)."""
        if len(self.speeds) < len(self.views):
            return False
        world.contactListener = None
        return True
