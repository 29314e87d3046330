"""pybullet (Bullet) adapter.

The law Bullet solves: sequential impulses (projected Gauss-Seidel) on a velocity-level
Newton-Coulomb problem (``planar_impact``'s ``"newton-lcp"``), with two biases that its
defaults switch on: a contact is created up to ``contactBreakingThreshold`` (0.02 m) before
touch and the solver then aims at ``e·|v_n| - gap/dt``; restitution is zeroed below
``restitutionVelocityThreshold`` (0.2 m/s). ``accurate`` removes both and the position
(ERP) terms, and turns warm starting off (see :data:`PRESETS`). In a step Bullet detects
contacts at the current positions, solves velocities, then moves: ``approach_steps = 0``
starts the bodies at the scene's pose.

Planar motion: each body is a fixed-base multibody chain world -> prismatic x ->
prismatic z -> revolute y, the shape on the last link with the scene's mass and inertia,
the joints' default velocity motors off (``force=0``) and joint damping 0. The scene's
(x, y) is the engine's (x, z); the revolute joint's angle and rate are ``-θ`` and ``-ω``.
Shapes: disk -> sphere (its in-plane section is the disk; the chain keeps it planar); rod ->
capsule along the link's x; box -> box; polygon -> convex hull of the polygon extruded
along y -- pybullet 3.2.7 keeps a link's hull collision margin at 0.001 m (changeDynamics
acts on bases only), so a polygon's contacts sit 1 mm outside it: a measured, pinned
departure, noted on the run. The ground is Bullet's static plane (normal +z; the
convex-plane collider uses exact support points).

Pair values: Bullet multiplies the two restitutions and the two lateral frictions; the
partner (plane, or ``bodies[1]``) gets 1, ``bodies[0]`` gets ``e`` and ``μ``.

Reuse and determinism: one DIRECT client per (engine settings, geometry) -- at most
:data:`_MAX_WORLDS` alive, least recently used disconnected. Bullet's
``contactBreakingThreshold`` is a process-wide global read when a contact manifold is
created, so it is set again before every run. Before a run the bodies are parked far from
each other and the plane and collision detection is run once, which empties the contact
manifolds (Bullet warm-starts from them); sleeping is disabled.

Cost: an impact is ~2 steps, so what depends only on the scene and the settings (world,
start joint states, energy weights) is computed once per (scene, settings) pair of objects,
and pybullet is called with positional arguments (its keyword parsing costs ~0.2 µs a call).

Settings (``defaults`` | ``accurate``) are listed in :data:`SETTING_DOCS`; ``None`` means
"not set: Bullet's default".
"""

from __future__ import annotations

import math
import time
from collections import OrderedDict
from dataclasses import dataclass, field

import pybullet as p

from harness.engines import (
    NO_IMPULSE_RELATIVE,
    Engine,
    EngineRun,
    _check_choice,
    _check_int,
    _check_number,
    body_extent,
    count_planar_points,
    energy_before,
    energy_weights,
    free_flight_poses,
    geometry_key,
    multi_contact_note,
    run_from_fields,
    status_from,
)
from harness.scene import Scene

_MAX_WORLDS = 8
_MAX_PLANS = 256  # (scene, settings) pairs remembered; the cache is emptied when full
_PARK_HEIGHT = 1.0e3  # m, where bodies wait (far above the plane) while contacts are cleared

# setting key -> pybullet setPhysicsEngineParameter keyword
_ENGINE_PARAMETERS: dict[str, str] = {
    "time_step": "fixedTimeStep",
    "num_solver_iterations": "numSolverIterations",
    "num_sub_steps": "numSubSteps",
    "contact_breaking_threshold": "contactBreakingThreshold",
    "contact_erp": "contactERP",
    "erp": "erp",
    "friction_erp": "frictionERP",
    "contact_slop": "contactSlop",
    "restitution_velocity_threshold": "restitutionVelocityThreshold",
    "enable_cone_friction": "enableConeFriction",
    "solver_residual_threshold": "solverResidualThreshold",
    "warm_starting_factor": "warmStartingFactor",
    "global_cfm": "globalCFM",
    "use_split_impulse": "useSplitImpulse",
}

SETTING_DOCS: dict[str, str] = {
    "time_step": "s, fixedTimeStep (default 1/240)",
    "num_solver_iterations": "numSolverIterations, PGS iterations per step (default 50)",
    "num_sub_steps": "numSubSteps, sub-steps per step (default 0 = none)",
    "contact_breaking_threshold": "m, contactBreakingThreshold: contacts exist up to this gap "
    "(default 0.02; process-wide in Bullet, set before every run)",
    "contact_erp": "contactERP, fraction of penetration corrected per step by velocity (default 0.2)",
    "erp": "erp, joint error reduction (default 0.2; the planar chain's joints are exact)",
    "friction_erp": "frictionERP (default 0.2)",
    "contact_slop": "m, contactSlop, penetration left uncorrected (default 1e-5)",
    "restitution_velocity_threshold": "m/s, restitution is 0 below this approach speed (default 0.2)",
    "enable_cone_friction": "enableConeFriction, 1 = implicit cone, 0 = two-direction box (default 1)",
    "solver_residual_threshold": "solverResidualThreshold, PGS stops below it (default 1e-7)",
    "warm_starting_factor": "warmStartingFactor, share of last step's impulse re-applied (default 0.85)",
    "global_cfm": "globalCFM, constraint force mixing (default 0)",
    "use_split_impulse": "useSplitImpulse, 1 = position correction apart (rigid bodies; default 1)",
    "linear_damping": "1/s, per-link linearDamping (Bullet's default 0.04)",
    "angular_damping": "1/s, per-link angularDamping (Bullet's default 0.04)",
    "max_steps": "step cap; reported as status no-separation when hit in contact",
    "approach_steps": "steps of free flight before first touch (0 = touching at the first step)",
}

_DEFAULTS = {key: None for key in _ENGINE_PARAMETERS}
_DEFAULTS.update(
    time_step=1.0 / 240.0,
    # Set explicitly: a process-wide global in Bullet, so "not set" would inherit another run's.
    contact_breaking_threshold=0.02,
    linear_damping=0.04,
    angular_damping=0.04,
    max_steps=1000,
    approach_steps=0.0,
)
PRESETS: dict[str, dict] = {
    "defaults": dict(_DEFAULTS),
    "accurate": dict(
        _DEFAULTS,
        # Coupled contacts (the rod) need >= 10 iterations; 100 with no early exit reaches
        # rounding on every test scene.
        num_solver_iterations=100,
        solver_residual_threshold=0.0,
        contact_breaking_threshold=1e-6,  # no early contact (and no gap/dt bias)
        contact_erp=0.0,
        friction_erp=0.0,
        contact_slop=0.0,
        restitution_velocity_threshold=0.0,
        warm_starting_factor=0.0,  # no impulse carried from a previous step
        linear_damping=0.0,
        angular_damping=0.0,
    ),
}

_RUN_ONLY = ("max_steps", "approach_steps")


def _collision_shape(client: int, shape) -> int:
    depth = 2.0 * body_extent(shape)  # out-of-plane thickness; any value works with the chain
    if shape.kind == "disk":
        return p.createCollisionShape(p.GEOM_SPHERE, radius=shape.radius, physicsClientId=client)
    if shape.kind == "rod":
        # Bullet's capsule runs along its frame's z; turn it +90° about y so z goes to x.
        return p.createCollisionShape(
            p.GEOM_CAPSULE,
            radius=shape.radius,
            height=shape.length,
            collisionFrameOrientation=p.getQuaternionFromEuler([0.0, math.pi / 2.0, 0.0]),
            physicsClientId=client,
        )
    if shape.kind == "box":
        return p.createCollisionShape(
            p.GEOM_BOX,
            halfExtents=[shape.width / 2.0, depth / 2.0, shape.height / 2.0],
            physicsClientId=client,
        )
    vertices = [[x, side * depth / 2.0, y] for x, y in shape.vertices().tolist() for side in (-1.0, 1.0)]
    return p.createCollisionShape(p.GEOM_MESH, vertices=vertices, physicsClientId=client)


def _planar_multibody(client: int, body) -> int:
    collision = _collision_shape(client, body.shape)
    mass, inertia = float(body.mass), float(body.moment_of_inertia)
    uid = p.createMultiBody(
        baseMass=0.0,
        baseCollisionShapeIndex=-1,
        baseVisualShapeIndex=-1,
        basePosition=[0.0, 0.0, 0.0],
        linkMasses=[0.0, 0.0, mass],
        linkCollisionShapeIndices=[-1, -1, collision],
        linkVisualShapeIndices=[-1, -1, -1],
        linkPositions=[[0.0, 0.0, 0.0]] * 3,
        linkOrientations=[[0.0, 0.0, 0.0, 1.0]] * 3,
        linkInertialFramePositions=[[0.0, 0.0, 0.0]] * 3,
        linkInertialFrameOrientations=[[0.0, 0.0, 0.0, 1.0]] * 3,
        linkParentIndices=[0, 1, 2],
        linkJointTypes=[p.JOINT_PRISMATIC, p.JOINT_PRISMATIC, p.JOINT_REVOLUTE],
        linkJointAxis=[[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, 1.0, 0.0]],
        useMaximalCoordinates=False,
        physicsClientId=client,
    )
    # Mass and the inertia in one call (a call without mass= can zero it).
    p.changeDynamics(uid, 2, mass=mass, localInertiaDiagonal=[inertia, inertia, inertia],
                     physicsClientId=client)
    for joint in range(3):
        p.setJointMotorControl2(uid, joint, p.VELOCITY_CONTROL, force=0.0, physicsClientId=client)
    return uid


@dataclass
class _World:
    client: int
    plane: int | None
    bodies: list[int]
    scale: float  # m, size of the scene's bodies (for merging contact points)
    pair_values: tuple | None = None  # (e, μ) last set
    dirty: bool = True  # contacts may remain from the previous run
    threshold: float = 0.02
    closed: bool = False  # disconnected (evicted or closed)


_POLYGON_NOTE = ("polygon: pybullet keeps a link's convex-hull collision margin at 0.001 m, "
                 "so contacts sit 1 mm outside the polygon")


def _start_states(scene: Scene, settings: dict, bodies: list[int]) -> tuple:
    """``(uid, x, v_x, z, v_z, -θ, -ω)`` per body: the joint states a run starts from."""
    # Shift the scene near the origin (a symmetry): x always, y too without ground.
    count = len(scene.bodies)
    shift_x = -sum(b.position[0] for b in scene.bodies) / count
    shift_y = 0.0 if scene.ground else -sum(b.position[1] for b in scene.bodies) / count
    rewind = -float(settings["approach_steps"]) * float(settings["time_step"])
    return tuple(
        (uid, pose[0] + shift_x, body.velocity[0], pose[1] + shift_y, body.velocity[1],
         -pose[2], -body.angular_velocity)
        for body, uid, pose in zip(scene.bodies, bodies, free_flight_poses(scene, rewind))
    )


def _reset(world: _World, starts: tuple) -> None:
    """The per-impact reset (shared with the benchmark): the process-wide contact threshold,
    empty contact manifolds where the last run left contacts, and the start joint states."""
    client = world.client
    # Process-wide in Bullet: new manifolds take the value current at their creation.
    p.setPhysicsEngineParameter(contactBreakingThreshold=world.threshold, physicsClientId=client)
    reset = p.resetJointState
    if world.dirty:
        # Empty the contact manifolds: park the bodies apart, run collision detection.
        for index, uid in enumerate(world.bodies):
            reset(uid, 0, 10.0 * index * (world.scale + 1.0), 0.0, client)
            reset(uid, 1, _PARK_HEIGHT, 0.0, client)
        p.performCollisionDetection(client)
    for uid, x, v_x, z, v_z, angle, rate in starts:
        reset(uid, 0, x, v_x, client)
        reset(uid, 1, z, v_z, client)
        reset(uid, 2, angle, rate, client)


class _Plan:
    """Everything a run needs that depends only on the scene and the settings objects."""

    __slots__ = ("scene", "settings", "world", "world_key", "pair_values", "starts", "dt",
                 "max_steps", "weights", "before", "extents", "speed_scale", "notes")

    def __init__(self, scene: Scene, settings: dict, world: _World, world_key: tuple):
        self.scene = scene
        self.settings = settings
        self.world = world
        self.world_key = world_key
        self.pair_values = (scene.restitution, scene.friction)
        self.starts = _start_states(scene, settings, world.bodies)
        self.dt = float(settings["time_step"])
        self.max_steps = int(settings["max_steps"])
        self.weights = energy_weights(scene)
        self.before = energy_before(scene)
        self.extents = tuple(body_extent(body.shape) for body in scene.bodies)
        self.speed_scale = float(max(1e-300, max(abs(v) for v in scene.state())))
        polygon = any(body.shape.kind == "polygon" for body in scene.bodies)
        self.notes = (_POLYGON_NOTE,) if polygon else ()


class PybulletEngine(Engine):
    name = "pybullet"
    version = "3.2.7"
    presets = PRESETS
    setting_docs = SETTING_DOCS

    def __init__(self) -> None:
        self._worlds: OrderedDict[tuple, _World] = OrderedDict()
        self._plans: dict[tuple[int, int], _Plan] = {}
        try:  # pybullet has no __version__; its API version is a date
            from importlib.metadata import version

            self.version = version("pybullet")
        except Exception:  # pragma: no cover - metadata missing
            pass

    def _validate_engine_settings(self, settings) -> None:
        name = self.name
        _check_int(name, settings, "num_solver_iterations", low=1, allow_none=True)
        _check_int(name, settings, "num_sub_steps", low=0, allow_none=True)
        _check_number(name, settings, "contact_breaking_threshold", low=0.0, strict=True)
        for key in ("contact_erp", "erp", "friction_erp"):
            _check_number(name, settings, key, low=0.0, high=1.0, allow_none=True)
        for key in ("contact_slop", "restitution_velocity_threshold", "solver_residual_threshold",
                    "global_cfm"):
            _check_number(name, settings, key, low=0.0, allow_none=True)
        _check_number(name, settings, "warm_starting_factor", low=0.0, high=1.0, allow_none=True)
        _check_choice(name, settings, "enable_cone_friction", (0, 1), allow_none=True)
        _check_choice(name, settings, "use_split_impulse", (0, 1), allow_none=True)
        _check_number(name, settings, "linear_damping", low=0.0)
        _check_number(name, settings, "angular_damping", low=0.0)

    # ------------------------------------------------------------------ worlds
    def _world_for(self, scene: Scene, settings: dict) -> tuple[_World, tuple]:
        """The world for this geometry and these engine settings, and its cache key."""
        key = (
            tuple((k, settings[k]) for k in sorted(settings) if k not in _RUN_ONLY),
            geometry_key(scene),
        )
        world = self._worlds.get(key)
        if world is not None:
            self._worlds.move_to_end(key)
            return world, key
        client = p.connect(p.DIRECT)
        p.setGravity(0.0, 0.0, 0.0, physicsClientId=client)
        parameters = {
            keyword: settings[key]
            for key, keyword in _ENGINE_PARAMETERS.items()
            if settings[key] is not None
        }
        p.setPhysicsEngineParameter(physicsClientId=client, **parameters)
        plane = None
        if scene.ground:
            plane_shape = p.createCollisionShape(p.GEOM_PLANE, physicsClientId=client)
            plane = p.createMultiBody(0.0, plane_shape, physicsClientId=client)
            p.changeDynamics(plane, -1, restitution=1.0, lateralFriction=1.0, physicsClientId=client)
        bodies = []
        for body in scene.bodies:
            uid = _planar_multibody(client, body)
            for link in range(-1, 3):
                p.changeDynamics(
                    uid,
                    link,
                    linearDamping=float(settings["linear_damping"]),
                    angularDamping=float(settings["angular_damping"]),
                    jointDamping=0.0,
                    activationState=p.ACTIVATION_STATE_DISABLE_SLEEPING,
                    physicsClientId=client,
                )
            bodies.append(uid)
        if len(bodies) == 2:
            p.changeDynamics(bodies[1], 2, restitution=1.0, lateralFriction=1.0, physicsClientId=client)
        world = _World(
            client=client,
            plane=plane,
            bodies=bodies,
            scale=max(body_extent(b.shape) for b in scene.bodies),
            threshold=float(settings["contact_breaking_threshold"]),
        )
        self._worlds[key] = world
        while len(self._worlds) > _MAX_WORLDS:
            _, old = self._worlds.popitem(last=False)
            old.closed = True
            p.disconnect(physicsClientId=old.client)
        return world, key

    def _plan_for(self, scene: Scene, settings: dict) -> _Plan:
        # Keyed by object identity; the plan holds both objects, so the ids stay theirs.
        key = (id(scene), id(settings))
        plan = self._plans.get(key)
        if plan is not None and plan.scene is scene and plan.settings is settings and not plan.world.closed:
            self._worlds.move_to_end(plan.world_key)  # least recently used goes first
            return plan
        plan = _Plan(scene, settings, *self._world_for(scene, settings))
        # Remembered for a checked immutable scene and a settings dict the caller reuses.
        if scene is self._last_scene and settings is (self._last_checked or (None, None))[1]:
            if len(self._plans) >= _MAX_PLANS:
                self._plans.clear()
            self._plans[key] = plan
        return plan

    def close(self) -> None:
        self._plans.clear()
        while self._worlds:
            _, world = self._worlds.popitem()
            world.closed = True
            try:
                p.disconnect(physicsClientId=world.client)
            except Exception:  # pragma: no cover - already gone at exit
                pass

    def __del__(self):  # pragma: no cover - interpreter exit
        try:
            self.close()
        except Exception:
            pass

    @staticmethod
    def _approaching(states, bodies, points, body_b, speed_scale) -> bool:
        """Whether any contact point still closes (relative normal velocity < 0).

        Called on a step without impulse: a contact found early (before touch) carries no
        impulse while the bodies still approach, so that step is not a separation.
        ``states``: the bodies' joint states now.
        """
        for cp in points:
            sign = 1.0 if cp[1] == body_b else -1.0
            n_x, n_z = sign * cp[7][0], sign * cp[7][2]  # into body_b
            point_x, point_z = cp[5][0], cp[5][2]
            relative = 0.0
            for uid, state in zip(bodies, states):
                (x, vx), (z, vz), (_, rate) = ((s[0], s[1]) for s in state)
                omega = -rate  # revolute y turns clockwise in the x-z view
                vpx = vx - omega * (point_z - z)
                vpz = vz + omega * (point_x - x)
                weight = 1.0 if uid == body_b else -1.0
                relative += weight * (vpx * n_x + vpz * n_z)
            if relative < -1e-9 * speed_scale:
                return True
        return False

    # ------------------------------------------------------------------ run
    def _run(self, scene: Scene, settings: dict, preset: str | None) -> EngineRun:
        start = time.perf_counter()
        plan = self._plans.get((id(scene), id(settings)))  # _plan_for's hit, inlined
        if (plan is None or plan.scene is not scene or plan.settings is not settings
                or plan.world.closed):
            plan = self._plan_for(scene, settings)
        else:
            self._worlds.move_to_end(plan.world_key)  # least recently used goes first
        world = plan.world
        client, bodies = world.client, world.bodies
        dt = plan.dt
        pair_values = plan.pair_values
        if world.pair_values != pair_values:
            p.changeDynamics(bodies[0], 2, restitution=pair_values[0], lateralFriction=pair_values[1],
                             physicsClientId=client)
            world.pair_values = pair_values
        _reset(world, plan.starts)

        body_b = bodies[-1]
        get_contacts, get_states = p.getContactPoints, p.getJointStates
        step = p.stepSimulation
        states = None
        max_steps = plan.max_steps
        steps = contact_steps = 0
        first_contact = None
        max_points = 0
        max_penetration = 0.0
        impulse_x = impulse_z = 0.0
        normal = None
        peak_normal_step = 0.0
        separated = False
        last_points = ()
        while steps < max_steps:
            step(client)
            steps += 1
            # No filter: Bullet's own body order (a filtered query flips the normal of a
            # swapped pair but not the friction directions). The world holds only this pair.
            # Positional: bodyA, bodyB, linkIndexA, linkIndexB at their "any" defaults.
            points = get_contacts(-1, -1, -2, -2, client)
            last_points = points
            if not points:
                if first_contact is not None:
                    separated = True
                    break
                continue
            contact_steps += 1
            step_x = step_z = 0.0
            step_normal = 0.0
            for cp in points:
                # Force on body A: normal force along n (the normal on B, towards A) plus
                # the two lateral friction forces along their directions.
                (_, body_a, _, _, _, _, _, n, distance, force_n,
                 friction_1, direction_1, friction_2, direction_2) = cp
                sign = 1.0 if body_a == body_b else -1.0
                step_normal += force_n
                step_x += sign * (force_n * n[0] + friction_1 * direction_1[0] + friction_2 * direction_2[0])
                step_z += sign * (force_n * n[2] + friction_1 * direction_1[2] + friction_2 * direction_2[2])
                if -distance > max_penetration:
                    max_penetration = -distance
            if first_contact is None:
                first_contact = steps
                cp = points[0]
                sign = 1.0 if cp[1] == body_b else -1.0
                length = math.hypot(cp[7][0], cp[7][2])
                normal = (sign * cp[7][0] / length, sign * cp[7][2] / length)
            if len(points) > 1:
                planar = count_planar_points(((cp[6][0], cp[6][2]) for cp in points), world.scale)
            else:
                planar = 1
            if planar > max_points:
                max_points = planar
            impulse_x += step_x * dt
            impulse_z += step_z * dt
            step_normal *= dt
            if step_normal > peak_normal_step:
                peak_normal_step = step_normal
            if step_normal <= NO_IMPULSE_RELATIVE * peak_normal_step:
                states = [get_states(uid, (0, 1, 2), client) for uid in bodies]
                if not self._approaching(states, bodies, points, body_b, plan.speed_scale):
                    separated = True
                    break
            states = None
        world.dirty = bool(last_points)

        velocities = []
        drift = 0.0
        get_link = p.getLinkState
        if states is None:  # else read at the separation test, in this very state
            states = [get_states(uid, (0, 1, 2), client) for uid in bodies]
        for uid, extent, state in zip(bodies, plan.extents, states):
            velocities.append((state[0][1], state[1][1], -state[2][1]))
            link = get_link(uid, 2, 0, 0, client)
            # Out of plane: the centre's y, plus the tilt of the link's y axis times its size.
            qx, qy, qz, qw = link[1]  # world orientation of the link frame
            tilt_x = 2.0 * (qx * qy - qz * qw)  # components of the link's y axis off (0, 1, 0)
            tilt_z = 2.0 * (qy * qz + qx * qw)
            body_drift = abs(link[0][1]) + math.hypot(tilt_x, tilt_z) * extent
            if body_drift > drift:
                drift = body_drift
        velocities = tuple(velocities)
        if normal is not None:
            n_x, n_y = normal
            normal_impulse = impulse_x * n_x + impulse_z * n_y
            tangential_impulse = impulse_x * n_y - impulse_z * n_x
        else:
            normal_impulse = tangential_impulse = None
        status = status_from(
            plan.weights,
            plan.before,
            velocities,
            contact_seen=first_contact is not None,
            separated=separated,
            max_contact_points=max_points,
            out_of_plane_drift=drift,
        )
        notes = plan.notes
        if max_points > 1:
            notes += (multi_contact_note(max_points),)
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
            "out_of_plane_drift": drift,
            "derived": {},
            "notes": notes,
            "wall_time_s": time.perf_counter() - start,
        })


ENGINE_CLASS = PybulletEngine
