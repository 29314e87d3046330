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
contact impulses would warm-start the next run), so reruns are bit-identical.

Cost: an impact is ~2 steps of a few µs, so the per-impact path talks to Chipmunk through
pymunk's cffi ``lib`` (the C calls pymunk's wrappers make, without their ``Vec2d``,
``ContactPointSet`` and ``Space.add``/``remove`` bookkeeping), and what depends only on the
scene and the settings is computed once per (scene, settings) pair of objects.

Settings (``defaults`` | ``accurate``) are listed in :data:`SETTING_DOCS`.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import pymunk
from pymunk._chipmunk_cffi import ffi, lib

from harness.engines import (
    NO_IMPULSE_RELATIVE,
    Engine,
    EngineRun,
    _check_int,
    _check_number,
    energy_before,
    energy_weights,
    free_flight_poses,
    geometry_key,
    multi_contact_note,
    run_from_fields,
    status_from,
)
from harness.scene import Scene

# Fraction of a step by which the start pose is short of a full rewind: the first detection
# then sees an overlap of ~1e-9·|v_n|·dt (> 0, so found; too small to matter).
_DETECTION_OVERLAP = 1e-9
_GROUND_HALF_WIDTH = 1.0e3  # m; the scene is shifted so the body sits near x = 0
_MAX_PLANS = 256  # (scene, settings) pairs remembered; the cache is emptied when full

SETTING_DOCS: dict[str, str] = {
    "time_step": "s, Space.step(dt); pymunk has no default, 1/60 is its examples' value",
    "iterations": "Space.iterations, impulse solver iterations per step (default 10)",
    "collision_slop": "m, Space.collision_slop, allowed overlap (default 0.1; positions only)",
    "collision_bias": "Space.collision_bias, overlap fraction left after 1 s (default (1-0.1)^60; positions only)",
    "collision_persistence": "Space.collision_persistence, steps an arbiter is cached (default 3; >= 1, at 0 no contact is ever solved)",
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
    # scene at ~0.1 µs per extra iteration. Slop and bias move positions only.
    "accurate": dict(_DEFAULTS, iterations=100),
}


def _make_shape(pm_body: pymunk.Body, shape) -> pymunk.Shape:
    if shape.kind == "disk":
        return pymunk.Circle(pm_body, shape.radius)
    if shape.kind == "rod":
        half = shape.length / 2.0
        return pymunk.Segment(pm_body, (-half, 0.0), (half, 0.0), shape.radius)
    return pymunk.Poly(pm_body, [tuple(v) for v in shape.vertices().tolist()], radius=0.0)


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
            shapes = self.shapes
            shapes[0].elasticity, shapes[0].friction = pair_values
            if len(shapes) == 2:
                shapes[1].elasticity, shapes[1].friction = 1.0, 1.0
            self.pair_values = pair_values


def _build_space(scene: Scene, record: bool) -> _SpaceEntry:
    """A space holding the scene's ground and bodies (``record``: with the post_solve recorder)."""
    space = pymunk.Space()
    space.gravity = (0.0, 0.0)
    if scene.ground:
        w = _GROUND_HALF_WIDTH
        ground = pymunk.Poly(space.static_body, [(-w, -w), (w, -w), (w, 0.0), (-w, 0.0)], radius=0.0)
        ground.elasticity = 1.0
        ground.friction = 1.0
        space.add(ground)
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


def _start_states(scene: Scene, settings: dict) -> tuple:
    """``((x, y), θ, (v_x, v_y), ω)`` per body at the start of the run (shifted, rewound)."""
    dt = float(settings["time_step"])
    # Shift x so that the bodies sit near the origin (precision; a symmetry of the scene).
    shift_x = -sum(b.position[0] for b in scene.bodies) / len(scene.bodies)
    rewind = -(settings["approach_steps"] + 1.0 - _DETECTION_OVERLAP) * dt
    # Plain floats now, so that a value the C setters refuse (a numpy array, say) fails here,
    # before _reset has taken any shape out of the space.
    return tuple(
        (
            (float(pose[0] + shift_x), float(pose[1])),
            float(pose[2]),
            (float(body.velocity[0]), float(body.velocity[1])),
            float(body.angular_velocity),
        )
        for body, pose in zip(scene.bodies, free_flight_poses(scene, rewind))
    )


def _reset(entry: _SpaceEntry, starts: tuple) -> None:
    """Fresh arbiters and the start state: the per-impact reset (shared with the benchmark).

    Removing a shape drops the cached arbiters that involve it (their impulses would
    warm-start this run); the same C calls as ``Space.remove``/``Space.add`` and the body
    setters, in the same order.
    """
    space_ptr = entry.space_ptr
    shape_ptrs = entry.shape_ptrs
    for shape_ptr in shape_ptrs:
        _remove_shape(space_ptr, shape_ptr)
    try:
        for body_ptr, (position, angle, velocity, angular_velocity) in zip(entry.body_ptrs, starts):
            _set_position(body_ptr, position)
            _set_angle(body_ptr, angle)
            _set_velocity(body_ptr, velocity)
            _set_angular_velocity(body_ptr, angular_velocity)
    finally:
        # Always back in: removing a shape that is not in the space makes Chipmunk abort().
        for shape_ptr in shape_ptrs:
            _add_shape(space_ptr, shape_ptr)


_remove_shape = lib.cpSpaceRemoveShape
_add_shape = lib.cpSpaceAddShape
_set_position = lib.cpBodySetPosition
_set_angle = lib.cpBodySetAngle
_set_velocity = lib.cpBodySetVelocity
_set_angular_velocity = lib.cpBodySetAngularVelocity
_space_step = lib.cpSpaceStep  # Space.step without its Python bookkeeping (no callbacks add/remove)


class _Plan:
    """Everything a run needs that depends only on the scene and the settings objects."""

    __slots__ = ("scene", "settings", "entry", "space_values", "pair_values", "starts", "dt",
                 "max_steps", "weights", "before", "body_b")

    def __init__(self, scene: Scene, settings: dict, entry: _SpaceEntry):
        self.scene = scene
        self.settings = settings
        self.entry = entry
        self.space_values = _space_values(settings)
        self.pair_values = (scene.restitution, scene.friction)
        self.starts = _start_states(scene, settings)
        self.dt = float(settings["time_step"])
        self.max_steps = int(settings["max_steps"])
        self.weights = energy_weights(scene)
        self.before = energy_before(scene)
        self.body_b = entry.body_ptrs[-1]


class PymunkEngine(Engine):
    name = "pymunk"
    version = pymunk.version
    presets = PRESETS
    setting_docs = SETTING_DOCS

    def __init__(self) -> None:
        self._spaces: dict[tuple, _SpaceEntry] = {}
        self._plans: dict[tuple[int, int], _Plan] = {}
        self._bodies_out = ffi.new("cpBody **"), ffi.new("cpBody **")

    def _validate_engine_settings(self, settings) -> None:
        _check_int(self.name, settings, "iterations", low=1)
        _check_number(self.name, settings, "collision_slop", low=0.0)
        _check_number(self.name, settings, "collision_bias", low=0.0, high=1.0)
        # At 0 Chipmunk drops each step's own arbiter before solving it: no contact, ever.
        _check_int(self.name, settings, "collision_persistence", low=1)
        _check_number(self.name, settings, "damping", low=0.0, high=1.0)

    def _space_for(self, scene: Scene) -> _SpaceEntry:
        key = geometry_key(scene)
        entry = self._spaces.get(key)
        if entry is None:
            entry = self._spaces[key] = _build_space(scene, record=True)
        return entry

    def _plan_for(self, scene: Scene, settings: dict) -> _Plan:
        # Keyed by object identity; the plan holds both objects, so the ids stay theirs.
        key = (id(scene), id(settings))
        plan = self._plans.get(key)
        if plan is not None and plan.scene is scene and plan.settings is settings:
            return plan
        plan = _Plan(scene, settings, self._space_for(scene))
        # Remembered for a checked immutable scene and a settings dict the caller reuses.
        if scene is self._last_scene and settings is (self._last_checked or (None, None))[1]:
            if len(self._plans) >= _MAX_PLANS:
                self._plans.clear()
            self._plans[key] = plan
        return plan

    def _run(self, scene: Scene, settings: dict, preset: str | None) -> EngineRun:
        start = time.perf_counter()
        plan = self._plans.get((id(scene), id(settings)))  # _plan_for's hit, inlined
        if plan is None or plan.scene is not scene or plan.settings is not settings:
            plan = self._plan_for(scene, settings)
        entry = plan.entry
        entry.configure(plan.space_values, plan.pair_values)
        _reset(entry, plan.starts)
        recorder = entry.recorder
        recorder.arbiter = None
        space_ptr, dt, body_b = entry.space_ptr, plan.dt, plan.body_b
        out_a, out_b = self._bodies_out
        point_set_of, impulse_of, bodies_of = (
            lib.cpArbiterGetContactPointSet, lib.cpArbiterTotalImpulse, lib.cpArbiterGetBodies)

        max_steps = plan.max_steps
        steps = contact_steps = 0
        first_contact = None
        max_points = 0
        max_penetration = 0.0
        impulse_x = impulse_y = 0.0
        normal = None
        peak_normal_step = 0.0
        separated = False
        while steps < max_steps:
            _space_step(space_ptr, dt)
            steps += 1
            arbiter = recorder.arbiter
            count = 0
            if arbiter is not None:
                recorder.arbiter = None
                point_set = point_set_of(arbiter)
                # 0 points: an arbiter dropped in this step (collision_persistence 0); pymunk's
                # ContactPointSet rejects it, so the step counts as reporting no contact.
                count = point_set.count
            if count:
                contact_steps += 1
                for index in range(count):
                    depth = -point_set.points[index].distance
                    if depth > max_penetration:
                        max_penetration = depth
                if count > max_points:
                    max_points = count
                # The arbiter's shape order can change from step to step (Chipmunk swaps
                # two shapes of the same type as it finds them): read it every step.
                bodies_of(arbiter, out_a, out_b)
                b_first = out_a[0] == body_b
                if first_contact is None:
                    first_contact = steps
                    n = point_set.normal  # from the first shape into the second
                    normal = (-n.x, -n.y) if b_first else (n.x, n.y)
                impulse = impulse_of(arbiter)  # on the body of the arbiter's first shape
                if b_first:
                    step_x, step_y = impulse.x, impulse.y
                else:
                    step_x, step_y = -impulse.x, -impulse.y
                impulse_x += step_x
                impulse_y += step_y
                step_normal = abs(step_x * normal[0] + step_y * normal[1])
                if step_normal > peak_normal_step:
                    peak_normal_step = step_normal
                if first_contact != steps and step_normal <= NO_IMPULSE_RELATIVE * peak_normal_step:
                    separated = True
                    break
            elif first_contact is not None:
                separated = True
                break

        velocities = []
        for body_ptr in entry.body_ptrs:
            velocity = lib.cpBodyGetVelocity(body_ptr)
            velocities.append((velocity.x, velocity.y, lib.cpBodyGetAngularVelocity(body_ptr)))
        velocities = tuple(velocities)
        if normal is not None:
            n_x, n_y = normal
            normal_impulse = impulse_x * n_x + impulse_y * n_y
            tangential_impulse = impulse_x * n_y - impulse_y * n_x
        else:
            normal_impulse = tangential_impulse = None
        status = status_from(
            plan.weights,
            plan.before,
            velocities,
            contact_seen=first_contact is not None,
            separated=separated,
            max_contact_points=max_points,
            out_of_plane_drift=None,
        )
        return run_from_fields({
            "engine": self.name,
            "engine_version": self.version,
            "scene_name": scene.name,
            "preset": preset,
            "settings": settings,
            "velocities": velocities,
            "status": status,
            "steps": steps,
            "contact_steps": contact_steps,
            "first_contact_step": first_contact,
            "max_contact_points": max_points,
            "max_penetration": max_penetration,
            "separated": separated,
            "step_cap_hit": not separated and steps >= max_steps,
            "contact_normal": normal,
            "normal_impulse": normal_impulse,
            "tangential_impulse": tangential_impulse,
            "out_of_plane_drift": None,
            "derived": {},
            "notes": (multi_contact_note(max_points),) if max_points > 1 else (),
            "wall_time_s": time.perf_counter() - start,
        })

    def close(self) -> None:
        self._spaces.clear()
        self._plans.clear()


ENGINE_CLASS = PymunkEngine
