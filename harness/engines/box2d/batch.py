"""Many impacts in one b2World (``run_many``), each run as ``run`` runs it alone.

What it answers: an impact alone pays pybox2d's Python calls for a world, its probe run and
its steps; up to :data:`MANY_CHUNK` impacts sharing a world, kept apart by collision groups,
take about half the time (docs/engines.md, 'Box2D'). ``Box2DEngine._build_many``
(:mod:`.adapter`) says why each impact's arithmetic stays its own.
"""

from __future__ import annotations

from Box2D import b2

from harness.engines.box2d.building import _add_impact, _Definitions, _place, _set_switches
from harness.engines.box2d.manifold import _approach_speed, _speed_after_collide
from harness.engines.box2d.readout import _TOUCHING, _contact_in
from harness.engines.box2d.scaling import _probe_starts, _speed_results
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
    touching contact (:class:`_SpeedProbe` for many impacts), for the impacts of ``views``
    (those a collision pass alone left unmeasured: :func:`_speed_after_collide`)."""

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
        slot = self.slots.get(values[3])
        if slot is None or slot in self.speeds:  # not measured here, or measured already
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
    iterations = prepared[0].iterations
    # The first step's collision pass alone (_speed_after_collide): most impacts touch at
    # their start, and their speeds are known without a listener or a solved step.
    world.contactManager.Collide()
    speeds: dict[int, float] = {}
    for slot, view in enumerate(views):
        speed = _speed_after_collide(view)
        if speed is not None:
            speeds[slot] = speed
    pending = [view for slot, view in enumerate(views) if slot not in speeds]
    if pending:
        listener = _ManyProbe(pending)
        listener.speeds = speeds  # the measured ones asleep, the others measured here
        world.contactListener = listener
    asleep: set[int] = set()
    try:
        steps = 0
        while True:
            for slot in speeds.keys() - asleep:
                for b2_body in views[slot].bodies:
                    b2_body.awake = False
                asleep.add(slot)
            if len(asleep) == len(views) or steps == max_steps:
                break
            world.Step(dt, *iterations)
            steps += 1
    finally:
        world.contactListener = None
    return [speeds.get(slot) for slot in slots], world, views
