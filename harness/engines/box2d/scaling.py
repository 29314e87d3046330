"""The velocity scaling that serves ``e`` below Box2D's restitution threshold, and the probe
run that measures the impact speed it needs.

Box2D's problem: ``b2_velocityThreshold`` (1 m/s) is compiled into pybox2d, and a contact
point slower than it gets ``e = 0``. The laws are homogeneous in lengths and velocities, so
the run is a scaled copy of the scene (package docstring, "The restitution threshold"): a
probe run measures Box2D's approach speed at the first contact (:func:`_probe`: after a
collision pass alone, else a PreSolve :class:`_SpeedProbe`), :func:`_scaled` picks the
velocity scale and the start a hair deep
from it, and :func:`_speed_class` groups the scenes of a batch likely to get one scale.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, NamedTuple

from Box2D import b2

from harness.engines.box2d.building import _extent
from harness.engines.box2d.manifold import _approach_speed, _speed_after_collide
from harness.engines.box2d.presets import (
    _BOOL_KEYS,
    MAX_ROTATION,
    MAX_TRANSLATION,
    VELOCITY_THRESHOLD,
)
from harness.engines.box2d.readout import _TOUCHING, _contact_in
from harness.scene import Scene

if TYPE_CHECKING:
    from harness.engines.box2d.world import _World

# "auto" lifts the first contact's approach speed to this multiple of the threshold: a margin
# of 2 keeps float32 rounding of the solver's own v_rel (computed anew) far from the edge.
_AUTO_MARGIN = 2.0
_MAX_AUTO_SCALE = 2.0**40  # a scene slower than 2^-39 m/s is refused rather than scaled
THRESHOLD_NOTE = "impact at or below b2_velocityThreshold (1 m/s): Box2D used e = 0"


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



def _probe(world: _World, prepared: _Prepared, starts: tuple, dt: float,
           max_steps: int) -> float | None:
    """Box2D's approach speed (m/s, scene units) at the first contact of an unscaled run."""
    world.configure(prepared.world_values, prepared.pair_values)
    world.place(starts)
    b2_world = world.world
    # The first step's collision pass alone (_speed_after_collide): a scene touching at its
    # start (the usual case) gives its speed without a listener or a solved step.
    b2_world.contactManager.Collide()
    speed = _speed_after_collide(world)
    if speed is not None:
        return speed
    probe = _SpeedProbe(world)
    b2_world.contactListener = probe
    try:
        for _ in range(max_steps):
            if probe.speed is not None:
                break
            b2_world.Step(dt, *prepared.iterations)
    finally:
        b2_world.contactListener = None
    return probe.speed



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
