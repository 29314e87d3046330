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

Settings (``defaults`` | ``accurate``) are listed in :data:`SETTING_DOCS`.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import pymunk

from harness.engines import (
    NO_IMPULSE_RELATIVE,
    Engine,
    EngineRun,
    _check_int,
    _check_number,
    body_extent,
    decide_status,
    free_flight_poses,
)
from harness.scene import Scene

# Fraction of a step by which the start pose is short of a full rewind: the first detection
# then sees an overlap of ~1e-9·|v_n|·dt (> 0, so found; too small to matter).
_DETECTION_OVERLAP = 1e-9
_GROUND_HALF_WIDTH = 1.0e3  # m; the scene is shifted so the body sits near x = 0

SETTING_DOCS: dict[str, str] = {
    "time_step": "s, Space.step(dt); pymunk has no default, 1/60 is its examples' value",
    "iterations": "Space.iterations, impulse solver iterations per step (default 10)",
    "collision_slop": "m, Space.collision_slop, allowed overlap (default 0.1; positions only)",
    "collision_bias": "Space.collision_bias, overlap fraction left after 1 s (default (1-0.1)^60; positions only)",
    "collision_persistence": "Space.collision_persistence, steps an arbiter is cached (default 3)",
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


def _shape_key(body) -> tuple:
    shape = body.shape
    if shape.kind == "disk":
        geometry = (shape.radius,)
    elif shape.kind == "rod":
        geometry = (shape.length, shape.radius)
    else:
        geometry = tuple(map(tuple, shape.vertices().tolist()))
    return (shape.kind, geometry, float(body.mass), float(body.moment_of_inertia))


def _make_shape(pm_body: pymunk.Body, shape) -> pymunk.Shape:
    if shape.kind == "disk":
        return pymunk.Circle(pm_body, shape.radius)
    if shape.kind == "rod":
        half = shape.length / 2.0
        return pymunk.Segment(pm_body, (-half, 0.0), (half, 0.0), shape.radius)
    return pymunk.Poly(pm_body, [tuple(v) for v in shape.vertices().tolist()], radius=0.0)


class _Recorder:
    """post_solve callback state for one run (reset per run)."""

    __slots__ = ("body_b", "called", "points", "penetration", "impulse", "normal", "normal_b")

    def __init__(self):
        self.body_b = None
        self.reset_step()

    def reset_step(self):
        self.called = False
        self.points = 0
        self.penetration = 0.0
        self.impulse = (0.0, 0.0)  # on body B, world frame
        self.normal = None  # from A into B, world frame

    def __call__(self, arbiter: pymunk.Arbiter, space, data) -> None:
        point_set = arbiter.contact_point_set
        points = point_set.points
        self.called = True
        self.points = max(self.points, len(points))
        for point in points:
            if -point.distance > self.penetration:
                self.penetration = -point.distance
        impulse = arbiter.total_impulse
        normal = point_set.normal  # from shapes[0] to shapes[1]
        if arbiter.shapes[0].body is self.body_b:  # total_impulse acts on shapes[0]'s body
            self.impulse = (impulse.x, impulse.y)
            self.normal = (-normal.x, -normal.y)
        else:
            self.impulse = (-impulse.x, -impulse.y)
            self.normal = (normal.x, normal.y)


@dataclass
class _SpaceEntry:
    space: pymunk.Space
    bodies: list
    shapes: list
    recorder: _Recorder
    space_values: tuple | None = None  # Space knobs last applied
    pair_values: tuple | None = None  # (e, μ) last applied


class PymunkEngine(Engine):
    name = "pymunk"
    version = pymunk.version
    presets = PRESETS
    setting_docs = SETTING_DOCS

    def __init__(self) -> None:
        self._spaces: dict[tuple, _SpaceEntry] = {}

    def _validate_engine_settings(self, settings) -> None:
        _check_int(self.name, settings, "iterations", low=1)
        _check_number(self.name, settings, "collision_slop", low=0.0)
        _check_number(self.name, settings, "collision_bias", low=0.0, high=1.0)
        _check_int(self.name, settings, "collision_persistence", low=0)
        _check_number(self.name, settings, "damping", low=0.0, high=1.0)

    def _space_for(self, scene: Scene) -> _SpaceEntry:
        key = (scene.ground, tuple(_shape_key(body) for body in scene.bodies))
        entry = self._spaces.get(key)
        if entry is not None:
            return entry
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
            shape = _make_shape(pm_body, body.shape)
            bodies.append(pm_body)
            shapes.append(shape)
            space.add(pm_body)  # bodies stay; shapes are removed and re-added per run
        recorder = _Recorder()
        space.on_collision(post_solve=recorder)
        entry = _SpaceEntry(space, bodies, shapes, recorder)
        self._spaces[key] = entry
        return entry

    def _run(self, scene: Scene, settings: dict, preset: str | None) -> EngineRun:
        start = time.perf_counter()
        entry = self._space_for(scene)
        space, pm_bodies, shapes, recorder = entry.space, entry.bodies, entry.shapes, entry.recorder
        dt = float(settings["time_step"])
        space_values = (
            int(settings["iterations"]),
            float(settings["collision_slop"]),
            float(settings["collision_bias"]),
            int(settings["collision_persistence"]),
            float(settings["damping"]),
        )
        if entry.space_values != space_values:
            (space.iterations, space.collision_slop, space.collision_bias,
             space.collision_persistence, space.damping) = space_values
            entry.space_values = space_values

        # Fresh arbiters: removing a shape drops the cached arbiters that involve it.
        for shape in shapes:
            if shape.space is not None:
                space.remove(shape)
        e, mu = scene.restitution, scene.friction
        if entry.pair_values != (e, mu):
            shapes[0].elasticity, shapes[0].friction = e, mu
            if len(shapes) == 2:
                shapes[1].elasticity, shapes[1].friction = 1.0, 1.0
            entry.pair_values = (e, mu)
        # Shift x so that the bodies sit near the origin (precision; a symmetry of the scene).
        shift_x = -sum(b.position[0] for b in scene.bodies) / len(scene.bodies)
        rewind = -(settings["approach_steps"] + 1.0 - _DETECTION_OVERLAP) * dt
        for body, pm_body, pose in zip(scene.bodies, pm_bodies, free_flight_poses(scene, rewind)):
            pm_body.position = (pose[0] + shift_x, pose[1])
            pm_body.angle = pose[2]
            pm_body.velocity = body.velocity
            pm_body.angular_velocity = body.angular_velocity
        space.add(*shapes)
        recorder.body_b = pm_bodies[-1]

        max_steps = int(settings["max_steps"])
        steps = contact_steps = 0
        first_contact = None
        max_points = 0
        max_penetration = 0.0
        impulse_x = impulse_y = 0.0
        normal = None
        peak_normal_step = 0.0
        separated = False
        while steps < max_steps:
            recorder.reset_step()
            space.step(dt)
            steps += 1
            if recorder.called:
                contact_steps += 1
                if first_contact is None:
                    first_contact = steps
                    normal = recorder.normal
                max_points = max(max_points, recorder.points)
                max_penetration = max(max_penetration, recorder.penetration)
                impulse_x += recorder.impulse[0]
                impulse_y += recorder.impulse[1]
                step_normal = abs(recorder.impulse[0] * normal[0] + recorder.impulse[1] * normal[1])
                peak_normal_step = max(peak_normal_step, step_normal)
                if first_contact != steps and step_normal <= NO_IMPULSE_RELATIVE * peak_normal_step:
                    separated = True
                    break
            elif first_contact is not None:
                separated = True
                break

        velocities = tuple(
            (float(b.velocity.x), float(b.velocity.y), float(b.angular_velocity)) for b in pm_bodies
        )
        if normal is not None:
            n_x, n_y = normal
            normal_impulse = impulse_x * n_x + impulse_y * n_y
            tangential_impulse = impulse_x * n_y - impulse_y * n_x
            normal = (float(n_x), float(n_y))
        else:
            normal_impulse = tangential_impulse = None
        status = decide_status(
            scene,
            velocities,
            contact_seen=first_contact is not None,
            separated=separated,
            max_contact_points=max_points,
            out_of_plane_drift=None,
        )
        notes = []
        if max_points > 1:
            notes.append(f"{max_points} contact points in one step")
        return EngineRun(
            engine=self.name,
            engine_version=self.version,
            scene_name=scene.name,
            preset=preset,
            settings=settings,
            velocities=velocities,
            status=status,
            steps=steps,
            contact_steps=contact_steps,
            first_contact_step=first_contact,
            max_contact_points=max_points,
            max_penetration=float(max_penetration),
            separated=separated,
            step_cap_hit=(not separated and steps >= max_steps),
            contact_normal=normal,
            normal_impulse=normal_impulse,
            tangential_impulse=tangential_impulse,
            out_of_plane_drift=None,
            derived={},
            notes=tuple(notes),
            wall_time_s=time.perf_counter() - start,
        )

    def close(self) -> None:
        self._spaces.clear()


ENGINE_CLASS = PymunkEngine
