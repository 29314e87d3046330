"""Box2D's settings: their docs, the defaults and the two presets, and the compiled-in
limits of pybox2d 2.3.10 that they and the workarounds refer to (read once, at import)."""

from __future__ import annotations

import Box2D

VELOCITY_THRESHOLD = float(Box2D.b2_velocityThreshold)  # m/s (Box2D units), compiled in
MAX_TRANSLATION = float(Box2D.b2_maxTranslation)  # m per step (Box2D units), compiled in
MAX_ROTATION = float(Box2D.b2_maxRotation)  # rad per step, compiled in
POLYGON_RADIUS = float(Box2D.b2_polygonRadius)  # m (Box2D units), the default polygon skin
# Start depth of the accurate preset, in body extents: ~4 float32 roundings of a coordinate
# of the body's size, so that rounding cannot lift an exact touch off the ground.
DETECTION_OVERLAP = 2.0**-22

SETTING_DOCS: dict[str, str] = {
    "time_step": "s (scene units), b2World::Step timeStep; Box2D has no default, 1/60 is its "
    "manual's value",
    "velocity_iterations": "b2World::Step velocityIterations, impulse sweeps per step (manual: 8)",
    "position_iterations": "b2World::Step positionIterations, position-correction sweeps per "
    "step (manual: 3; positions only)",
    "warm_starting": "b2World::SetWarmStarting, start a step from the last step's impulses "
    "(default True)",
    "continuous_physics": "b2World::SetContinuousPhysics, time-of-impact sub-steps of "
    "dynamic against static bodies (default True)",
    "sub_stepping": "b2World::SetSubStepping, one time-of-impact event per step (debug; "
    "default False)",
    "allow_sleeping": "b2World::SetAllowSleeping, bodies at rest for 0.5 s sleep (default True)",
    "polygon_radius": "m (Box2D units), skin of every polygon fixture (ground, box, polygon, "
    "rod core); default b2_polygonRadius = 0.01",
    "velocity_scale": "V, velocities times V and time times 1/V in Box2D, 1 = unscaled; "
    "'auto' = smallest power of 2 >= 1 lifting the first contact's approach speed to "
    "2 x b2_velocityThreshold (1 m/s)",
    "length_scale": "L, lengths times L and time times L in Box2D (powers of 2 are exact); "
    "1 = unscaled",
    "detection_overlap": "start this fraction of the largest body extent deeper along the "
    "path than the touching pose, so that float32 rounding cannot hide the first contact "
    "(0 = start at the pose)",
    "max_steps": "step cap; reported as status no-separation when hit in contact",
    "approach_steps": "steps of free flight before first touch (0 = touching at first step)",
}

_DEFAULTS = {
    "time_step": 1.0 / 60.0,
    "velocity_iterations": 8,
    "position_iterations": 3,
    "warm_starting": True,
    "continuous_physics": True,
    "sub_stepping": False,
    "allow_sleeping": True,
    "polygon_radius": POLYGON_RADIUS,
    "velocity_scale": 1.0,
    "length_scale": 1.0,
    "detection_overlap": 0.0,
    "max_steps": 1000,
    "approach_steps": 0.0,
}
PRESETS: dict[str, dict] = {
    "defaults": dict(_DEFAULTS),
    # Coupled points (rod, box corner) need more sweeps than 8; 100 reaches float32 rounding
    # on every test scene. No skin: a skinned point lies off the surface (moment arm). No
    # warm start or time-of-impact sub-step: nothing but the impact's own impulses. "auto"
    # serves e at any impact speed (the threshold would zero it at or below 1 m/s).
    "accurate": dict(
        _DEFAULTS,
        velocity_iterations=100,
        warm_starting=False,
        continuous_physics=False,
        allow_sleeping=False,
        polygon_radius=0.0,
        velocity_scale="auto",
        detection_overlap=DETECTION_OVERLAP,
    ),
}

_BOOL_KEYS = ("warm_starting", "continuous_physics", "sub_stepping", "allow_sleeping")
