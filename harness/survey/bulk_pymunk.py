"""Many independent pymunk impacts in one space: the adapter's answer at a fraction of its cost.

Measured first (harness/survey/engines.py, ``impact-harness survey --bare``): with a new
geometry for every sample, the adapter builds one ``pymunk.Space`` per geometry and that
build, not the ~2 steps of a few µs, is most of its time per impact.

Here one space holds up to :data:`CHUNK` impacts, all at their own (identical) coordinates:

* ground scenes share one static ground (the adapter's box, top face ``y = 0``); every body
  is in one non-zero ``ShapeFilter.group``, so the bodies never touch each other;
* two-body scenes get one category bit per pair (``categories = mask = 1 << k``), so a body
  only touches its partner: 32 pairs per space at most.

Everything else is the adapter's (harness/engines/pymunk_engine.py), imported, not copied:
the shapes (``_make_shape``), the start states (``_start_states``: same shift and rewind),
the pair values (first body ``e``, ``μ``; partner 1, 1), the space knobs, and the stopping
rule -- an impact ends one step after contact began in which it has no arbiter, or its
normal impulse is below ``NO_IMPULSE_RELATIVE`` of its largest step's, and its velocities
are read at that step. Its shapes then leave the space. Impacts in one space share no
dynamic body and the static body's velocity stays zero, so each impact's arithmetic is the
one it has alone; :func:`compare_with_adapter` checks it.
"""

from __future__ import annotations

import time

import numpy as np
import pymunk
from pymunk._chipmunk_cffi import ffi, lib

from harness.engines import NO_IMPULSE_RELATIVE, energy_before, energy_weights, status_from
from harness.engines.pymunk_engine import (
    _GROUND_HALF_WIDTH,
    _make_shape,
    _space_values,
    _start_states,
)
from harness.survey.laws import WIDTH

CHUNK = 32  # impacts per space: the category bits of a ShapeFilter for two-body scenes
_BODY_GROUP = 1  # the ShapeFilter group of every body of a ground chunk


class _Impact:
    """Per-impact bookkeeping, the adapter's per-run locals."""

    __slots__ = ("bodies", "body_b", "done", "first_contact", "max_points", "normal", "peak",
                 "row", "scene", "seen", "separated", "shapes", "steps", "velocities")

    def __init__(self, row, scene, bodies, shapes):
        self.row, self.scene, self.bodies, self.shapes = row, scene, bodies, shapes
        self.body_b = bodies[-1]._body
        self.first_contact = None
        self.peak = 0.0
        self.normal = None
        self.separated = False
        self.max_points = 0
        self.done = False
        self.steps = 0
        self.velocities = None
        self.seen = False


def _space(settings: dict, ground: bool) -> pymunk.Space:
    space = pymunk.Space()
    space.gravity = (0.0, 0.0)
    (space.iterations, space.collision_slop, space.collision_bias,
     space.collision_persistence, space.damping) = _space_values(settings)
    if ground:
        w = _GROUND_HALF_WIDTH
        floor = pymunk.Poly(space.static_body, [(-w, -w), (w, -w), (w, 0.0), (-w, 0.0)],
                            radius=0.0)
        floor.elasticity = floor.friction = 1.0
        space.add(floor)
    return space


def _run_chunk(rows, scenes, settings, out_velocities, out_status, out_steps) -> None:
    ground = scenes[rows[0]].ground
    space = _space(settings, ground)
    impacts, by_body = [], {}
    for slot, row in enumerate(rows):
        scene = scenes[row]
        shape_filter = (pymunk.ShapeFilter(group=_BODY_GROUP) if ground else
                        pymunk.ShapeFilter(categories=1 << slot, mask=1 << slot))
        bodies, shapes = [], []
        for body, (position, angle, velocity, spin) in zip(scene.bodies,
                                                           _start_states(scene, settings)):
            pm_body = pymunk.Body(body.mass, body.moment_of_inertia)
            pm_body.position, pm_body.angle = position, angle
            pm_body.velocity, pm_body.angular_velocity = velocity, spin
            shape = _make_shape(pm_body, body.shape)
            shape.filter = shape_filter
            bodies.append(pm_body)
            shapes.append(shape)
        shapes[0].elasticity, shapes[0].friction = scene.restitution, scene.friction
        if len(shapes) == 2:
            shapes[1].elasticity = shapes[1].friction = 1.0
        space.add(*bodies, *shapes)
        impact = _Impact(row, scene, bodies, shapes)
        impacts.append(impact)
        for pm_body in bodies:
            by_body[pm_body._body] = impact

    arbiters: list = []
    space.on_collision(post_solve=lambda arbiter, _space, _data: arbiters.append(
        arbiter._arbiter))
    space_ptr, dt = space._space, float(settings["time_step"])
    max_steps = int(settings["max_steps"])
    out_a, out_b = ffi.new("cpBody **"), ffi.new("cpBody **")
    active = list(impacts)
    step = 0
    while active and step < max_steps:
        arbiters.clear()
        lib.cpSpaceStep(space_ptr, dt)
        step += 1
        for impact in active:
            impact.seen = False
        for arbiter in arbiters:
            point_set = lib.cpArbiterGetContactPointSet(arbiter)
            count = point_set.count
            if not count:  # an arbiter dropped this step: no contact (as the adapter)
                continue
            lib.cpArbiterGetBodies(arbiter, out_a, out_b)
            impact = by_body.get(out_a[0]) or by_body[out_b[0]]  # a may be the ground
            if impact.done:
                continue
            impact.seen = True
            impact.max_points = max(impact.max_points, count)
            b_first = out_a[0] == impact.body_b
            if impact.first_contact is None:
                impact.first_contact = step
                n = point_set.normal
                impact.normal = (-n.x, -n.y) if b_first else (n.x, n.y)
            total = lib.cpArbiterTotalImpulse(arbiter)
            sign = 1.0 if b_first else -1.0
            step_normal = abs(sign * (total.x * impact.normal[0] + total.y * impact.normal[1]))
            impact.peak = max(impact.peak, step_normal)
            if impact.first_contact != step and step_normal <= NO_IMPULSE_RELATIVE * impact.peak:
                impact.separated = True
        still = []
        for impact in active:
            if not impact.seen and impact.first_contact is not None:
                impact.separated = True
            if impact.separated or step >= max_steps:
                impact.done, impact.steps = True, step
                impact.velocities = tuple((b.velocity.x, b.velocity.y, b.angular_velocity)
                                          for b in impact.bodies)
                space.remove(*impact.shapes, *impact.bodies)
            else:
                still.append(impact)
        active = still
    for impact in impacts:
        if impact.velocities is None:  # the cap hit before any contact
            impact.steps = step
            impact.velocities = tuple((b.velocity.x, b.velocity.y, b.angular_velocity)
                                      for b in impact.bodies)
        row, scene = impact.row, impact.scene
        out_velocities[row, :3 * len(scene.bodies)] = [v for body in impact.velocities
                                                       for v in body]
        out_steps[row] = impact.steps
        out_status[row] = status_from(
            energy_weights(scene), energy_before(scene), impact.velocities,
            contact_seen=impact.first_contact is not None, separated=impact.separated,
            max_contact_points=impact.max_points, out_of_plane_drift=None)


def run_bulk(scenes, settings: dict, chunk: int = CHUNK):
    """``(velocities (n, 6), status (n,), steps (n,), wall seconds)`` for every scene."""
    if not 1 <= chunk <= CHUNK:
        raise ValueError(f"chunk must be 1 … {CHUNK} (one category bit per impact), got {chunk}")
    start = time.perf_counter()
    count = len(scenes)
    velocities = np.zeros((count, WIDTH))
    status = np.empty(count, dtype=object)
    steps = np.zeros(count, dtype=np.int64)
    for ground in (True, False):
        rows = [row for row, scene in enumerate(scenes) if scene.ground == ground]
        for begin in range(0, len(rows), chunk):
            _run_chunk(rows[begin:begin + chunk], scenes, settings, velocities, status, steps)
    return velocities, status.astype(str), steps, time.perf_counter() - start


def compare_with_adapter(scenes, preset: str = "accurate") -> dict:
    """Run ``scenes`` through the adapter one by one and in bulk; the largest difference.

    Returns ``{"max_abs_difference", "bit_identical", "same_status", "same_steps",
    "adapter_s", "bulk_s", "impacts"}`` (velocity differences in the scenes' units).
    """
    from harness.survey.engines import run_engine

    single = run_engine("pymunk", preset, scenes)
    from harness.engines import load_engine

    settings = load_engine("pymunk").settings(preset)
    velocities, status, steps, wall = run_bulk(scenes, settings)
    difference = np.abs(velocities - single.velocities)
    return {
        "max_abs_difference": float(difference.max()) if difference.size else 0.0,
        "bit_identical": bool(np.array_equal(velocities, single.velocities)),
        "same_status": bool(np.array_equal(status, single.status)),
        "same_steps": bool(np.array_equal(steps, single.steps)),
        "adapter_s": single.wall_s,
        "bulk_s": wall,
        "impacts": len(scenes),
    }
