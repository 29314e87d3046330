"""pymunk (Chipmunk2D) adapter.

The law pymunk solves: sequential impulses on a velocity-level Newton-Coulomb problem. In a
step, Chipmunk first moves the bodies with their current velocities, then finds contacts,
then iterates impulses until the normal contact velocity reaches ``e·|v_n^A|`` with Coulomb
friction at the end state (``planar_impact``'s ``"newton-lcp"``). Positions-first means the
contact geometry of step k is that after moving; so ``approach_steps = 0`` places the bodies
one step (less a hair, ``_DETECTION_OVERLAP`` of the step) before the scene's pose, and the
contact is found at the scene's configuration.

Pair values: Chipmunk multiplies the shapes' ``elasticity`` and ``friction``; the partner
(ground, or ``bodies[1]``) gets 1 and ``bodies[0]``'s shape gets ``e`` and ``μ``.
Ground: a static box (top face ``y = 0``) -- a static segment gives a normal off by ~1e-12.

Reuse: one :class:`pymunk.Space` per geometry (shapes, masses, inertias). Before each run the
dynamic shapes are removed and re-added, which drops Chipmunk's cached arbiters (their
contact impulses would warm-start the next run), so reruns are bit-identical. ``run_many``
steps its batches one after the other in one space, emptied between them.

Cost: an impact is ~2 steps of a few µs, so the per-impact path talks to Chipmunk through
pymunk's cffi ``lib`` (the C calls pymunk's wrappers make, without their ``Vec2d``,
``ContactPointSet`` and ``Space.add``/``remove`` bookkeeping; a batch's bodies and shapes are
Chipmunk's own, freed by the batch), and what depends only on the scene and the settings is
computed once per (scene, settings) pair of objects.

Settings (``defaults`` | ``accurate``) are listed in :data:`SETTING_DOCS`.
"""

from __future__ import annotations

from dataclasses import dataclass

import pymunk
from pymunk._chipmunk_cffi import ffi, lib

from harness.engines.contract import Engine, RawContacts, StepTiming
from harness.engines.settings import check_int, check_number
from harness.scene import Scene

# Fraction of a step by which the start pose is short of a full rewind: the first detection
# then sees an overlap of ~1e-9·|v_n|·dt (> 0, so found; too small to matter).
_DETECTION_OVERLAP = 1e-9
_GROUND_HALF_WIDTH = 1.0e3  # m; the scene is shifted so the body sits near x = 0
#: Impacts per space in run_many. Two-body scenes: one collision category bit each (bit 31
#: is the ground's). Ground scenes: their bodies all overlap near the origin, so the
#: broad phase pairs them all (then drops the pairs by group): a space stays small.
MANY_PAIRS = 31
MANY_GROUND = 32
_GROUND_CATEGORY = 1 << 31
_GROUND_GROUP = 1  # every body of a ground scene in a batch: they never touch each other

SETTING_DOCS: dict[str, str] = {
    "time_step": "s, Space.step(dt); pymunk has no default, 1/60 is its examples' value",
    "iterations": "Space.iterations, impulse solver iterations per step (default 10)",
    "collision_slop": "m, Space.collision_slop, allowed overlap (default 0.1; positions only)",
    "collision_bias": "Space.collision_bias, overlap fraction left after 1 s "
                      "(default (1-0.1)^60; positions only)",
    "collision_persistence": "Space.collision_persistence, steps an arbiter is cached "
                             "(default 3; >= 1, at 0 no contact is ever solved)",
    "damping": "Space.damping, velocity fraction kept after 1 s (default 1 = none)",
    "max_steps": "step cap; reported as status no-separation when hit in contact",
    "approach_steps": "steps of free flight before first touch (0 = touching at first detection)",
}

_DEFAULTS = {
    "time_step": 1.0 / 60.0,
    "iterations": 10,
    "collision_slop": 0.1,
    "collision_bias": (1.0 - 0.1) ** 60,
    "collision_persistence": 3,
    "damping": 1.0,
    "max_steps": 1000,
    "approach_steps": 0.0,
}
PRESETS: dict[str, dict] = {
    "defaults": dict(_DEFAULTS),
    # Coupled contacts (the rod) need >= 20 iterations; 100 reaches rounding on every test
    # scene, and an extra iteration costs little beside a run's fixed
    # cost (`impact-harness bench --engines` measures it). Slop and bias move positions only.
    "accurate": dict(_DEFAULTS, iterations=100),
}


def _make_shape(pm_body: pymunk.Body, shape) -> pymunk.Shape:
    if shape.kind == "ellipse":  # no ellipse in Chipmunk: its placed polygon
        shape = shape.stand_in()
    if shape.kind == "disk":
        return pymunk.Circle(pm_body, shape.radius)
    if shape.kind == "rod":
        half = shape.length / 2.0
        return pymunk.Segment(pm_body, (-half, 0.0), (half, 0.0), shape.radius)
    return pymunk.Poly(pm_body, [tuple(v) for v in shape.vertices().tolist()], radius=0.0)


def _new_shape_ptr(body_ptr, shape):
    """The C shape :func:`_make_shape` makes (the same constructor and arguments), without
    pymunk's wrapper: the caller frees it (``cpShapeFree``)."""
    if shape.kind == "ellipse":  # no ellipse in Chipmunk: its placed polygon
        shape = shape.stand_in()
    kind = shape.kind
    if kind == "disk":
        return lib.cpCircleShapeNew(body_ptr, shape.radius, (0, 0))
    if kind == "rod":
        half = shape.length / 2.0
        return lib.cpSegmentShapeNew(body_ptr, (-half, 0.0), (half, 0.0), shape.radius)
    if kind == "box":  # Box.vertices()'s values, without the array
        half_w, half_h = shape.width / 2.0, shape.height / 2.0
        vertices = [(-half_w, -half_h), (half_w, -half_h), (half_w, half_h), (-half_w, half_h)]
    elif kind == "polygon":  # Polygon.vertices() is the points as floats
        vertices = [(float(x), float(y)) for x, y in shape.points]
    else:
        vertices = [tuple(v) for v in shape.vertices().tolist()]
    return lib.cpPolyShapeNew(body_ptr, len(vertices), vertices, _IDENTITY, 0.0)


def _new_space(space_values: tuple | None = None) -> pymunk.Space:
    """An empty space without gravity; ``space_values``: :func:`_space_values` to apply."""
    space = pymunk.Space()
    space.gravity = (0.0, 0.0)
    if space_values is not None:
        (space.iterations, space.collision_slop, space.collision_bias,
         space.collision_persistence, space.damping) = space_values
    return space


def _set_pair(shape_ptrs, e: float, mu: float) -> None:
    """The pair's ``e`` and ``μ``: Chipmunk multiplies the shapes' values, so ``bodies[0]``'s
    shape gets them and the partner's (if a body) the neutral 1."""
    _set_elasticity(shape_ptrs[0], e)
    _set_friction(shape_ptrs[0], mu)
    if len(shape_ptrs) == 2:
        _set_elasticity(shape_ptrs[1], 1.0)
        _set_friction(shape_ptrs[1], 1.0)


class _Recorder:
    """post_solve callback: keeps the step's arbiter; the run reads it after the step.

    Reading after ``cpSpaceStep`` returns gives what the callback would see: post-solve is
    the step's last phase. A space holds one pair of shapes, so at most one arbiter a step.
    """

    __slots__ = ("arbiter",)

    def __init__(self):
        self.arbiter = None

    def __call__(self, arbiter: pymunk.Arbiter, space, data) -> None:
        self.arbiter = arbiter._arbiter


@dataclass
class _SpaceEntry:
    space: pymunk.Space
    bodies: list
    shapes: list
    recorder: _Recorder | None
    space_values: tuple | None = None  # Space knobs last applied
    pair_values: tuple | None = None  # (e, μ) last applied
    dt: float = 0.0  # s, the time step of the current run

    def __post_init__(self) -> None:
        self.space_ptr = self.space._space
        self.shape_ptrs = tuple(shape._shape for shape in self.shapes)
        self.body_ptrs = tuple(body._body for body in self.bodies)

    def configure(self, space_values: tuple, pair_values: tuple) -> None:
        """Apply the Space knobs and the pair's (e, μ) where they changed."""
        if self.space_values != space_values:
            space = self.space
            (space.iterations, space.collision_slop, space.collision_bias,
             space.collision_persistence, space.damping) = space_values
            self.space_values = space_values
        if self.pair_values != pair_values:
            _set_pair(self.shape_ptrs, *pair_values)
            self.pair_values = pair_values


def _ground_shape(space: pymunk.Space, shape_filter: pymunk.ShapeFilter | None = None):
    """The ground: a static box with top face ``y = 0`` and the partner's neutral e, μ."""
    w = _GROUND_HALF_WIDTH
    ground = pymunk.Poly(space.static_body, [(-w, -w), (w, -w), (w, 0.0), (-w, 0.0)], radius=0.0)
    ground.elasticity = 1.0
    ground.friction = 1.0
    if shape_filter is not None:
        ground.filter = shape_filter
    return ground


def _build_space(scene: Scene, record: bool) -> _SpaceEntry:
    """A space holding the scene's ground and bodies (``record``: with the post_solve recorder)."""
    space = _new_space()
    if scene.ground:
        space.add(_ground_shape(space))
    bodies, shapes = [], []
    for body in scene.bodies:
        pm_body = pymunk.Body(body.mass, body.moment_of_inertia)
        bodies.append(pm_body)
        shapes.append(_make_shape(pm_body, body.shape))
    # Added once through pymunk (its bookkeeping); each run removes and re-adds the shapes
    # through lib, which leaves pymunk's view unchanged.
    space.add(*bodies, *shapes)
    recorder = None
    if record:
        recorder = _Recorder()
        space.on_collision(post_solve=recorder)
    return _SpaceEntry(space, bodies, shapes, recorder)


def _space_values(settings: dict) -> tuple:
    return (
        int(settings["iterations"]),
        float(settings["collision_slop"]),
        float(settings["collision_bias"]),
        int(settings["collision_persistence"]),
        float(settings["damping"]),
    )


_remove_shape = lib.cpSpaceRemoveShape
_remove_body = lib.cpSpaceRemoveBody
_set_filter = lib.cpShapeSetFilter
_add_shape = lib.cpSpaceAddShape
_set_position = lib.cpBodySetPosition
_set_angle = lib.cpBodySetAngle
_set_velocity = lib.cpBodySetVelocity
_set_angular_velocity = lib.cpBodySetAngularVelocity
_get_position = lib.cpBodyGetPosition
_get_angle = lib.cpBodyGetAngle
_get_velocity = lib.cpBodyGetVelocity
_get_angular_velocity = lib.cpBodyGetAngularVelocity
_space_step = lib.cpSpaceStep  # Space.step without its Python bookkeeping (no callbacks add/remove)
_point_set_of = lib.cpArbiterGetContactPointSet
_impulse_of = lib.cpArbiterTotalImpulse
_bodies_of = lib.cpArbiterGetBodies
_set_elasticity = lib.cpShapeSetElasticity
_set_friction = lib.cpShapeSetFriction
_IDENTITY = (1.0, 0.0, 0.0, 1.0, 0.0, 0.0)  # pymunk's Transform.identity() for a Poly


class PymunkEngine(Engine):
    name = "pymunk"
    version = pymunk.version
    # What the rest of the harness reads about this engine (docs/engines.md, 'The engine
    # contract'): why it lands where it does, per engine and per preset, and its plot style.
    description = (
        "Chipmunk2D solves the engines' velocity-level law (newton-lcp): within one step it "
        "iterates impulses until the normal contact velocity is e times the approach speed, "
        "with Coulomb friction judged at the end state. Its departure from Poisson and "
        "Stronge is therefore mostly the law itself: wherever the slip stops or reverses "
        "during the impact, newton-lcp ends elsewhere (docs/engines.md, 'pymunk').")
    preset_why = {
        "defaults": ("10 solver iterations per step: exact on a lone contact, about "
                     "1e-5 off on coupled contacts (a rod or a box corner)."),
        "accurate": ("100 iterations: newton-lcp to rounding; only the iterations "
                     "differ from defaults."),
    }
    native_2d = True
    plot_style = ("#0072B2", "o")
    bench_impacts = (400, 3000)
    bench_impact_seconds = 2e-4
    no_calibration_knobs_why = (
        "no setting of pymunk's own enters its impact law beside the pair's μ and e: the "
        "iterations and the step only converge its solve, slop and bias move positions only")
    presets = PRESETS
    setting_docs = SETTING_DOCS
    # Positions first: the contact of step k is found after the move, so the bodies start
    # one step (less a hair) before the touching pose.
    timing = StepTiming(lead_steps=1.0, overlap=_DETECTION_OVERLAP, recentre_y=False)


    @classmethod
    def bench_sweep(cls, quick: bool) -> list[tuple[str, str, dict]]:
        """The settings the accuracy bench measures (harness/bench/accuracy.py)."""
        points: list[tuple[str, str, dict]] = []
        points.append(("defaults", "defaults", {}))
        steps = (1 / 60, 1e-3) if quick else (1 / 60, 1e-3, 1e-4)
        iterations = (1, 2, 5, 10, 20, 50, 100) if quick else (1, 2, 3, 5, 10, 20, 30, 50, 100, 200)
        for dt in steps:
            for count in iterations:
                points.append((f"dt={dt:.3g} it={count}", "accurate",
                               {"time_step": dt, "iterations": count}))
        return points

    def __init__(self) -> None:
        self._bodies_out = ffi.new("cpBody **"), ffi.new("cpBody **")
        self._batch_space: _BatchSpace | None = None  # run_many's space between batches

    def _validate_engine_settings(self, settings) -> None:
        check_int(self.name, settings, "iterations", low=1)
        check_number(self.name, settings, "collision_slop", low=0.0)
        check_number(self.name, settings, "collision_bias", low=0.0, high=1.0)
        # At 0 Chipmunk drops each step's own arbiter before solving it: no contact, ever.
        check_int(self.name, settings, "collision_persistence", low=1)
        check_number(self.name, settings, "damping", low=0.0, high=1.0)

    def _build(self, scene: Scene, settings, *, contacts: bool = True) -> _SpaceEntry:
        return _build_space(scene, record=contacts)

    def _prepare(self, world: _SpaceEntry, scene: Scene, settings, start, weights) -> tuple:
        starts = tuple([((x, y), angle, (vx, vy), omega)
                        for x, y, angle, vx, vy, omega in start])  # a list: no generator
        return _space_values(settings), (scene.restitution, scene.friction), starts, \
            float(settings["time_step"])

    def _reset(self, world: _SpaceEntry, prepared: tuple) -> dict:
        """Fresh arbiters and the start state.

        Removing a shape drops the cached arbiters that involve it (their impulses would
        warm-start this run); the same C calls as ``Space.remove``/``Space.add`` and the body
        setters, in the same order.
        """
        space_values, pair_values, starts, world.dt = prepared
        world.configure(space_values, pair_values)
        space_ptr = world.space_ptr
        shape_ptrs = world.shape_ptrs
        for shape_ptr in shape_ptrs:
            _remove_shape(space_ptr, shape_ptr)
        try:
            for body_ptr, (position, angle, velocity, rate) in zip(world.body_ptrs, starts):
                _set_position(body_ptr, position)
                _set_angle(body_ptr, angle)
                _set_velocity(body_ptr, velocity)
                _set_angular_velocity(body_ptr, rate)
        finally:
            # Always back in: removing a shape that is not in the space makes Chipmunk abort().
            for shape_ptr in shape_ptrs:
                _add_shape(space_ptr, shape_ptr)
        if world.recorder is not None:
            world.recorder.arbiter = None
        return {}

    def _advance(self, world: _SpaceEntry) -> None:
        _space_step(world.space_ptr, world.dt)

    def _step(self, world: _SpaceEntry) -> RawContacts | None:
        _space_step(world.space_ptr, world.dt)
        recorder = world.recorder
        arbiter = recorder.arbiter
        if arbiter is None:
            return None
        recorder.arbiter = None
        out_a, out_b = self._bodies_out
        _bodies_of(arbiter, out_a, out_b)
        return _contact_of(arbiter, out_a[0] == world.body_ptrs[-1])

    # ------------------------------------------------------------------ many impacts
    def _many_chunks(self, plans) -> list[list[int]]:
        """Ground scenes :data:`MANY_GROUND` to a space, two-body scenes :data:`MANY_PAIRS`
        (one collision category bit per pair)."""
        chunks = []
        for ground, size in ((True, MANY_GROUND), (False, MANY_PAIRS)):
            rows = [index for index, plan in enumerate(plans) if plan.scene.ground == ground]
            chunks += [rows[begin:begin + size] for begin in range(0, len(rows), size)]
        return chunks

    def _build_many(self, plans) -> tuple[_Batch, list, list]:
        """One space for many impacts, each at its own run-frame coordinates.

        The impacts overlap in space and are kept apart by shape filters: the bodies of
        ground scenes share one group (never touch each other) and touch only the ground's
        category; the bodies of the k-th two-body scene are in category ``1 << k`` only.
        They share no dynamic body, so each impact's arithmetic is the one it has alone
        (the tests compare them bit for bit).

        The bodies and shapes are Chipmunk's own (the C calls of pymunk's constructors and
        setters, in the same order, without their wrappers, which cost more than the
        impact's stepping); the
        batch owns them and :meth:`_release_many` frees them.
        """
        space_values, _, _, dt = plans[0].prepared  # one settings dict for every plan
        # The last batch's space, empty again: a new space would allocate and zero its pools
        # anew for every batch. Bodies and shapes are added in the same order,
        # so each impact's arithmetic is the same (the tests compare runs bit for bit).
        holder, self._batch_space = self._batch_space or _BatchSpace(), None
        space = holder.space
        (space.iterations, space.collision_slop, space.collision_bias,
         space.collision_persistence, space.damping) = space_values
        if not holder.ground and any(plan.scene.ground for plan in plans):
            holder.ground = True  # kept: no two-body impact's filter accepts it
            space.add(_ground_shape(space, pymunk.ShapeFilter(categories=_GROUND_CATEGORY)))
        batch = _Batch(holder, dt)
        try:
            _fill_batch(batch, plans)
        except BaseException:
            self._release_many(batch)
            raise
        return batch, batch.slots, [{} for _ in plans]

    def _step_many(self, batch: _Batch, active) -> dict:
        arbiters = batch.arbiters
        arbiters.clear()
        _space_step(batch.space_ptr, batch.dt)
        contacts = {}
        out_a, out_b = self._bodies_out
        slot_of = batch.slot_of
        for arbiter in arbiters:
            _bodies_of(arbiter, out_a, out_b)
            found = slot_of.get(out_a[0])
            if found is None:  # body a is the ground
                slot, b_first = slot_of[out_b[0]][0], False
            else:
                slot, b_first = found
            contact = _contact_of(arbiter, b_first)
            if contact is not None:
                contacts[slot] = contact
        return contacts

    def _retire(self, batch: _Batch, slot: int) -> None:
        batch.take_out(slot)

    def _release_many(self, batch: _Batch) -> None:
        batch.free()
        self._batch_space = batch.holder  # empty but for the ground: the next batch's

    def _read_poses(self, world: _SpaceEntry) -> tuple:
        return _triples(world, _get_position, _get_angle)

    def _read_velocities(self, world: _SpaceEntry) -> tuple:
        return _triples(world, _get_velocity, _get_angular_velocity)


def _contact_of(arbiter, b_first: bool) -> RawContacts | None:
    """The step's contact from its arbiter (``b_first``: body B is the arbiter's body a)."""
    point_set = _point_set_of(arbiter)
    # 0 points: an arbiter dropped in this step (collision_persistence 0); pymunk's
    # ContactPointSet rejects it, so the step counts as reporting no contact.
    count = point_set.count
    if not count:
        return None
    # The arbiter's shape order can change from step to step (Chipmunk swaps two shapes of
    # the same type as it finds them): the caller reads it every step.
    n = point_set.normal  # from the first shape into the second
    impulse = _impulse_of(arbiter)  # on the body of the arbiter's first shape
    points = point_set.points
    if b_first:
        normal = (-n.x, -n.y)
        step_x, step_y = impulse.x, impulse.y
    else:
        normal = (n.x, n.y)
        step_x, step_y = -impulse.x, -impulse.y
    point = points[0]
    on_b = point.pointA if b_first else point.pointB
    contact_points = ((on_b.x, on_b.y, -point.distance),)
    for index in range(1, count):  # Chipmunk reports at most 2
        point = points[index]
        on_b = point.pointA if b_first else point.pointB
        contact_points += ((on_b.x, on_b.y, -point.distance),)
    return (
        contact_points,
        normal,
        (step_x, step_y),
        abs(step_x * normal[0] + step_y * normal[1]),
    )


class _Slot:
    """One impact of a batch: what ``_read_poses`` and ``_read_velocities`` read."""

    __slots__ = ("body_ptrs", "in_space", "shape_ptrs")

    def __init__(self, body_ptrs, shape_ptrs) -> None:
        self.body_ptrs, self.shape_ptrs = body_ptrs, shape_ptrs
        self.in_space = True  # not yet taken out (it may be half in while being built)


class _BatchSpace:
    """A space for batches of impacts (kept from one to the next), and the arbiters its
    last step solved (its post_solve callback's list)."""

    __slots__ = ("arbiters", "ground", "space", "space_ptr")

    def __init__(self) -> None:
        self.space = _new_space()
        self.space_ptr = self.space._space
        self.ground = False  # holds the ground
        self.arbiters: list = []
        self.space.on_collision(post_solve=self.record)

    def record(self, arbiter: pymunk.Arbiter, space, data) -> None:
        """post_solve callback: keep every arbiter of the step (one per impact at most)."""
        self.arbiters.append(arbiter._arbiter)


class _Batch:
    """Many impacts in one :class:`_BatchSpace`.

    Owns its impacts' C bodies and shapes (:meth:`free`); pymunk frees the space and the
    ground.
    """

    __slots__ = ("arbiters", "dt", "holder", "slot_of", "slots", "space_ptr")

    def __init__(self, holder: _BatchSpace, dt: float) -> None:
        self.holder, self.space_ptr, self.dt = holder, holder.space_ptr, dt
        self.arbiters = holder.arbiters
        self.slots: list[_Slot] = []
        self.slot_of: dict = {}  # body pointer -> (slot, whether it is the slot's body B)

    def take_out(self, slot: int) -> None:
        """Remove impact ``slot``'s shapes, then its bodies, from the space (as
        ``Space.remove``), once."""
        world, space_ptr = self.slots[slot], self.space_ptr
        if world.in_space:
            world.in_space = False
            for shape_ptr in world.shape_ptrs:
                _remove_shape(space_ptr, shape_ptr)
            for body_ptr in world.body_ptrs:
                _remove_body(space_ptr, body_ptr)

    def free(self) -> None:
        """Take every impact out of the space and free its C shapes and bodies (once)."""
        space_ptr = self.space_ptr
        for world in self.slots:
            if world.in_space:  # what is not in the space is skipped: Chipmunk would abort()
                world.in_space = False
                for shape_ptr in world.shape_ptrs:
                    if lib.cpSpaceContainsShape(space_ptr, shape_ptr):
                        _remove_shape(space_ptr, shape_ptr)
                for body_ptr in world.body_ptrs:
                    if lib.cpSpaceContainsBody(space_ptr, body_ptr):
                        _remove_body(space_ptr, body_ptr)
            for shape_ptr in world.shape_ptrs:
                lib.cpShapeFree(shape_ptr)
            for body_ptr in world.body_ptrs:
                lib.cpBodyFree(body_ptr)
        self.slots, self.slot_of = [], {}


def _fill_batch(batch: _Batch, plans) -> None:
    """Every plan's bodies and shapes, at their start states, into ``batch``'s space.

    The C calls (and their order) of the pymunk objects of an impact's own space:
    ``Body(mass, inertia)`` and its setters, the shape's constructor and filter, ``e`` and
    ``μ``, then ``Space.add`` (bodies first). Each object belongs to the batch as soon as
    it exists, so that :meth:`_Batch.free` frees a half-built batch too.
    """
    space_ptr = batch.space_ptr
    ground_filter = (_GROUND_GROUP, _GROUND_CATEGORY, _GROUND_CATEGORY)
    pair = 0
    for slot, plan in enumerate(plans):
        scene = plan.scene
        if scene.ground:
            shape_filter = ground_filter
        else:
            shape_filter = (0, 1 << pair, 1 << pair)  # (group, categories, mask)
            pair += 1
        _, (e, mu), starts, _ = plan.prepared
        body_ptrs, shape_ptrs = [], []
        world = _Slot(body_ptrs, shape_ptrs)
        batch.slots.append(world)
        for body, (mass, inertia), (position, angle, velocity, rate) in zip(
                scene.bodies, plan.weights, starts):
            body_ptr = lib.cpBodyNew(mass, inertia)
            body_ptrs.append(body_ptr)
            _set_position(body_ptr, position)
            _set_angle(body_ptr, angle)
            _set_velocity(body_ptr, velocity)
            _set_angular_velocity(body_ptr, rate)
            shape_ptr = _new_shape_ptr(body_ptr, body.shape)
            shape_ptrs.append(shape_ptr)
            _set_filter(shape_ptr, shape_filter)
        _set_pair(shape_ptrs, e, mu)
        for body_ptr in body_ptrs:
            lib.cpSpaceAddBody(space_ptr, body_ptr)
            batch.slot_of[body_ptr] = (slot, body_ptr is body_ptrs[-1])
        for shape_ptr in shape_ptrs:
            _add_shape(space_ptr, shape_ptr)
        world.body_ptrs, world.shape_ptrs = tuple(body_ptrs), tuple(shape_ptrs)


def _triples(world: _SpaceEntry, vector_of, scalar_of) -> tuple:
    """Per body ``(vector.x, vector.y, scalar)``: the pose or the velocities (a scene has
    one or two bodies; unrolled, this is read at every contact step)."""
    body_ptrs = world.body_ptrs
    body_ptr = body_ptrs[0]
    vector = vector_of(body_ptr)
    first = (vector.x, vector.y, scalar_of(body_ptr))
    if len(body_ptrs) == 1:
        return (first,)
    body_ptr = body_ptrs[1]
    vector = vector_of(body_ptr)
    return (first, (vector.x, vector.y, scalar_of(body_ptr)))


ENGINE_CLASS = PymunkEngine
