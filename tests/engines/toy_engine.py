"""A test-only engine in one module: exact Poisson impacts, to prove that an engine is one
adapter class plus a registry call (``harness.engines.register_engine``).

The toy moves the bodies in exact free flight and, at the step where they touch, applies in
that one step the impulse :mod:`planar_impact` gives for Poisson's law (Part B, the law the
harness's references solve), then lets them fly apart. It detects nothing: the contact point
and normal are the scene's (harness.scene.geometry.scene_contact), known at the touching
pose, which the base class places ``approach_steps`` steps after the start.
"""

from __future__ import annotations

import math

import numpy as np

from harness.engines.contract import Engine
from harness.scene.geometry import impact_problem, scene_contact

SETTING_DOCS = {
    "time_step": "s, the step of the free flight",
    "max_steps": "step cap; reported as status no-separation when hit in contact",
    "approach_steps": "steps of free flight before first touch (an integer: the toy applies "
                      "the impulse in the step that starts at the touch)",
}
PRESETS = {
    "defaults": {"time_step": 1.0 / 60.0, "max_steps": 100, "approach_steps": 0.0},
    "accurate": {"time_step": 1.0 / 600.0, "max_steps": 100, "approach_steps": 0.0},
}


class _World:
    """The bodies' state now, and the impact the toy applies once."""

    def __init__(self, count: int) -> None:
        self.state = np.zeros((count, 6))  # x, y, θ, v_x, v_y, ω per body
        self.dt = 0.0
        self.steps = 0
        self.impact_step = 0
        self.u_after = np.zeros(3 * count)
        self.offset = (0.0, 0.0)  # contact point from the last body's centre
        self.normal = (0.0, 1.0)
        self.mass = 1.0  # the last body's


class ToyEngine(Engine):
    name = "toy"
    version = "1"
    presets = PRESETS
    setting_docs = SETTING_DOCS
    description = "A test-only engine: exact Poisson impulses applied in one step."
    preset_why = {"defaults": "a step of 1/60 s.", "accurate": "a step of 1/600 s."}
    native_2d = True
    plot_style = ("#56B4E9", "P")
    own_law = "poisson"  # the accuracy bench measures it against Poisson's law

    def _validate_engine_settings(self, settings) -> None:
        approach = float(settings["approach_steps"])
        if approach != math.floor(approach):
            raise ValueError(f"engine 'toy': approach_steps {approach!r} is not an integer")

    def _build(self, scene, settings, *, contacts: bool = True) -> _World:
        return _World(len(scene.bodies))

    def _prepare(self, world, scene, settings, start, weights):
        contact = scene_contact(scene)
        result = impact_problem(scene, contact.point, contact.normal).solve(
            mu=scene.friction, e=scene.restitution, law="poisson")
        last = scene.bodies[-1]
        offset = (float(contact.point[0] - last.position[0]),
                  float(contact.point[1] - last.position[1]))
        normal = (float(contact.normal[0]), float(contact.normal[1]))
        return (np.array(start, dtype=float), float(settings["time_step"]),
                int(settings["approach_steps"]), np.asarray(result.u_after, dtype=float),
                offset, normal, float(weights[-1][0]))

    def _reset(self, world: _World, prepared) -> dict:
        (start, world.dt, world.impact_step, world.u_after, world.offset, world.normal,
         world.mass) = prepared
        world.state = start.copy()
        world.steps = 0
        return {}

    def _fly(self, world: _World) -> None:
        state = world.state
        state[:, 0:3] += world.dt * state[:, 3:6]

    def _advance(self, world: _World) -> None:
        self._step(world)

    def _step(self, world: _World):
        step = world.steps
        world.steps += 1
        if step != world.impact_step:
            self._fly(world)
            return None
        last = world.state[-1]
        x, y = last[0] + world.offset[0], last[1] + world.offset[1]
        velocity_before = last[3:5].copy()
        world.state[:, 3:6] = world.u_after.reshape(-1, 3)
        impulse = tuple(float(v) for v in world.mass * (world.state[-1, 3:5] - velocity_before))
        self._fly(world)
        normal_impulse = impulse[0] * world.normal[0] + impulse[1] * world.normal[1]
        return (((x, y, 0.0),), world.normal, impulse, max(normal_impulse, 0.0))

    def _read_poses(self, world: _World):
        return tuple((float(s[0]), float(s[1]), float(s[2])) for s in world.state)

    def _read_velocities(self, world: _World):
        return tuple((float(s[3]), float(s[4]), float(s[5])) for s in world.state)


ENGINE_CLASS = ToyEngine
