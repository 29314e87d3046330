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

Reuse and determinism: one world per (engine settings, geometry) -- at most
:data:`_MAX_WORLDS` alive, least recently used released. A world is a DIRECT client of its
own; connecting one costs ~20-50 ms, so a released world's client is emptied
(``resetSimulation``, which deletes Bullet's dynamics world and makes a new one) and kept
idle for the next world of the same engine settings (at most :data:`_MAX_IDLE` per
settings), which is then built in it in ~1 ms. Per settings only: a client keeps some
values across a reset (the time step, the sub-step count), and every value a world of the
same settings sets is the same, so a reused client equals a new one bit for bit
(tests/engines/test_pybullet.py checks runs against a fresh adapter's). Bullet's
``contactBreakingThreshold`` is a process-wide global read when a contact manifold is
created, so it is set again before every run. Before a run the bodies are parked far from
each other and the plane and collision detection is run once, which empties the contact
manifolds (Bullet warm-starts from them); sleeping is disabled.

Cost: an impact is ~2 steps, so what depends only on the scene and the settings (world,
start joint states, energy weights) is computed once per (scene, settings) pair of objects,
and pybullet is called with positional arguments (its keyword parsing costs ~0.2 µs a call).
Clients run without pybullet's TinyRenderer plugin, which meshed every new link's collision
shape for rendering (most of ``createMultiBody``'s cost for a sphere).

Many impacts (``run_many``, the survey): a new geometry needs new bodies, and
``createMultiBody`` (~0.2-0.3 ms a body) is then the cost of an impact, so many impacts
share one client (:data:`MANY_IMPACTS`, ground and two-body scenes apart) with one
``stepSimulation`` and one ``getContactPoints`` a step, instead of a client reset each.
Each impact lies in its own slice of the engine's y, the axis out of the scene's plane:
the joints' rotations about y have exact zeros off the plane and Bullet's collision and
Jacobian arithmetic works with differences of positions, so the x-z numbers are those of a
lone run at y = 0, while slices :data:`_MANY_GAP` (plus twice the contact breaking
threshold) apart never meet. The slices are laid out in bit-reversed order of making
(:func:`_slice_offsets`): made in order along the line, they made Bullet's broad-phase tree
a chain that every new, first-moved or removed body walked.
They share only the static plane, which joins no simulation islands. Finished impacts are
removed. The runs equal :meth:`run`'s bit for bit (tests/engines/test_pybullet_many.py);
moving impacts apart within the plane instead changes roundings (measured).
A batch's client is kept for the next batch of its settings and kind, with its plane, and
emptied by removing the bodies left in it: a ``resetSimulation`` (~2 ms, Bullet remakes its
dynamics world and memory pools) cost more than a batch's stepping. Bullet keeps every
collision shape made in a client (it refuses to remove one a removed body used, ~8 kB an
impact), so the client is reset after :data:`_MANY_RESET_AFTER` impacts
(tests/engines/test_pybullet_clients.py: runs keep their bits across both).
Where a batch's time goes (700 survey scenes, process CPU, measured with every pybullet call
timed): about three quarters inside pybullet -- ``createMultiBody`` a third (pybullet
serialises each new body's description and parses it back in the client, ~0.1 ms a call
whatever it creates: a ``batchPositions`` call of one body costs as much, and only its
copies of one shape share it), stepping a fifth -- and about a tenth in this module's
Python; the client's reset then costs ~15 µs per body made since the last. pybullet 3.2.7
has no call reading several bodies' joint states, ``createMultiBody`` takes no inertia, the
``changeDynamics`` folds tried change the bits (docs/engines.md; so does e and μ in the
damping call), and batch sizes 4 to 64 cost the same within the noise.

Settings (``defaults`` | ``accurate``) are listed in :data:`SETTING_DOCS`; ``None`` means
"not set: Bullet's default".
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from harness.engines.contract import Engine, RawContacts, body_extent, geometry_key
from harness.engines.quiet import import_quietly
from harness.engines.settings import check_choice, check_int, check_number
from harness.scene import Scene

p = import_quietly("pybullet")  # not `import pybullet as p`: it prints its build time

_MAX_WORLDS = 8
_MAX_IDLE = 2  # emptied clients kept per engine settings (runs of new geometries one by
# one need 1: a new geometry evicts one world and builds one)
#: Impacts per client in run_many (measured: see docs/engines.md, 'pybullet'; with the
#: batch client kept, 8 to 64 cost the same within the noise, 128 and 256 more).
MANY_IMPACTS = 32
#: Impacts built in a run_many client before it is reset (~8 kB each stays until then).
_MANY_RESET_AFTER = 1024
_MANY_GAP = 1.0  # m, between two impacts' slices of the engine's y (plus 2 x the threshold)
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
    "contact_erp": "contactERP, fraction of penetration corrected per step by velocity "
    "(default 0.2)",
    "erp": "erp, joint error reduction (default 0.2; the planar chain's joints are exact)",
    "friction_erp": "frictionERP (default 0.2)",
    "contact_slop": "m, contactSlop, penetration left uncorrected (default 1e-5)",
    "restitution_velocity_threshold": "m/s, restitution is 0 below this approach speed "
    "(default 0.2)",
    "enable_cone_friction": "enableConeFriction, 1 = implicit cone, 0 = two-direction box "
    "(default 1)",
    "solver_residual_threshold": "solverResidualThreshold, PGS stops below it (default 1e-7)",
    "warm_starting_factor": "warmStartingFactor, share of last step's impulse re-applied "
    "(default 0.85)",
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


# Bullet's capsule runs along its frame's z; turned +90° about y, z goes to x.
_CAPSULE_ALONG_X = p.getQuaternionFromEuler([0.0, math.pi / 2.0, 0.0])


def _collision_shape(client: int, shape, extent: float) -> int:
    """The shape's collision shape; ``extent`` is its :func:`body_extent`."""
    depth = 2.0 * extent  # out-of-plane thickness; any value works with the chain
    if shape.kind == "ellipse":  # Bullet's planar ellipse would be a mesh: its placed polygon
        shape = shape.stand_in()
    if shape.kind == "disk":
        return p.createCollisionShape(p.GEOM_SPHERE, radius=shape.radius, physicsClientId=client)
    if shape.kind == "rod":
        return p.createCollisionShape(
            p.GEOM_CAPSULE,
            radius=shape.radius,
            height=shape.length,
            collisionFrameOrientation=_CAPSULE_ALONG_X,
            physicsClientId=client,
        )
    if shape.kind == "box":
        return p.createCollisionShape(
            p.GEOM_BOX,
            halfExtents=[shape.width / 2.0, depth / 2.0, shape.height / 2.0],
            physicsClientId=client,
        )
    vertices = [
        [x, side * depth / 2.0, y]
        for x, y in shape.vertices().tolist()
        for side in (-1.0, 1.0)
    ]
    return p.createCollisionShape(p.GEOM_MESH, vertices=vertices, physicsClientId=client)


# createMultiBody's link arguments that every chain shares (pybullet copies them in).
_LINK_ORIGINS = [[0.0, 0.0, 0.0]] * 3
_LINK_ROTATIONS = [[0.0, 0.0, 0.0, 1.0]] * 3
_NO_VISUALS = [-1, -1, -1]
_LINK_PARENTS = [0, 1, 2]
_NO_FORCES = [0.0, 0.0, 0.0]
_JOINT_TYPES = [p.JOINT_PRISMATIC, p.JOINT_PRISMATIC, p.JOINT_REVOLUTE]
_JOINT_AXES = [[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, 1.0, 0.0]]
_ORIGIN = [0.0, 0.0, 0.0]
_NO_ROTATION = [0.0, 0.0, 0.0, 1.0]
_create_multibody = p.createMultiBody


def _planar_multibody(client: int, body, collision: int, offset: float = 0.0,
                      pair_values: tuple[float, float] | None = None) -> int:
    """The body's planar chain, its last link of shape ``collision``, its base at ``offset``
    along the engine's y (out of the plane); ``pair_values``: its (e, μ), if given."""
    mass, inertia = float(body.mass), float(body.moment_of_inertia)
    # Positional (pybullet's order; each keyword costs a lookup): baseMass,
    # baseCollisionShapeIndex, baseVisualShapeIndex, basePosition, baseOrientation,
    # baseInertialFramePosition, baseInertialFrameOrientation (their defaults), then the
    # links' masses, collision and visual shapes, positions, orientations, inertial frame
    # positions and orientations, parents, joint types and axes, useMaximalCoordinates.
    uid = _create_multibody(0.0, -1, -1, [0.0, offset, 0.0], _NO_ROTATION, _ORIGIN,
                            _NO_ROTATION, [0.0, 0.0, mass], [-1, -1, collision], _NO_VISUALS,
                            _LINK_ORIGINS, _LINK_ROTATIONS, _LINK_ORIGINS, _LINK_ROTATIONS,
                            _LINK_PARENTS, _JOINT_TYPES, _JOINT_AXES, 0, physicsClientId=client)
    # Mass and the inertia in one call (a call without mass= can zero it); e and μ in the
    # same call keep the runs' bits (tests/engines/test_pybullet_survey_identity.py).
    if pair_values is None:
        p.changeDynamics(uid, 2, mass=mass, localInertiaDiagonal=[inertia, inertia, inertia],
                         physicsClientId=client)
    else:
        p.changeDynamics(uid, 2, mass=mass, localInertiaDiagonal=[inertia, inertia, inertia],
                         restitution=pair_values[0], lateralFriction=pair_values[1],
                         physicsClientId=client)
    # The joints' default velocity motors off: no force (one call for the three joints).
    p.setJointMotorControlArray(uid, _LINK_PARENTS, p.VELOCITY_CONTROL, forces=_NO_FORCES,
                                physicsClientId=client)
    return uid


def _configure(client: int, settings) -> None:
    """No gravity and the engine settings that are set (the others stay Bullet's)."""
    p.setGravity(0.0, 0.0, 0.0, physicsClientId=client)
    parameters = {
        keyword: settings[key]
        for key, keyword in _ENGINE_PARAMETERS.items()
        if settings[key] is not None
    }
    p.setPhysicsEngineParameter(physicsClientId=client, **parameters)


def _add_plane(client: int) -> int:
    """The ground: Bullet's static plane ``z = 0``, with the partner's neutral e and μ."""
    plane_shape = p.createCollisionShape(p.GEOM_PLANE, physicsClientId=client)
    plane = p.createMultiBody(0.0, plane_shape, physicsClientId=client)
    p.changeDynamics(plane, -1, restitution=1.0, lateralFriction=1.0, physicsClientId=client)
    return plane


def _add_bodies(client: int, scene: Scene, settings, extents, offset: float = 0.0,
                pair_values: tuple[float, float] | None = None) -> list[int]:
    """The scene's bodies (``extents``: their :func:`body_extent`) as planar chains (bases at
    ``offset`` along y), damped as set, never sleeping; ``bodies[0]`` gets ``pair_values``
    (e, μ) if given (else :meth:`PybulletEngine._reset` sets them), the partner body the
    neutral e and μ."""
    bodies = []
    linear_damping = float(settings["linear_damping"])
    angular_damping = float(settings["angular_damping"])
    for body, extent in zip(scene.bodies, extents):
        collision = _collision_shape(client, body.shape, extent)
        uid = _planar_multibody(client, body, collision, offset, pair_values)
        pair_values = None  # bodies[0]'s only
        # On the shape's link only: the damping and sleeping are the multibody's, and the
        # massless links' joint damping is 0 already (the runs keep their bits: the tests).
        # A separate call from the mass's: one call with both changed the bits (measured).
        p.changeDynamics(uid, 2, linearDamping=linear_damping, angularDamping=angular_damping,
                         jointDamping=0.0, activationState=p.ACTIVATION_STATE_DISABLE_SLEEPING,
                         physicsClientId=client)
        bodies.append(uid)
    if len(bodies) == 2:
        p.changeDynamics(bodies[1], 2, restitution=1.0, lateralFriction=1.0,
                         physicsClientId=client)
    return bodies


@dataclass(slots=True)
class _World:
    client: int  # -1 once released (its client may serve another world)
    settings_key: tuple  # the engine settings (which idle clients it may take and give back)
    plane: int | None
    bodies: list[int]
    extents: tuple[float, ...]  # m, body_extent of each body (out-of-plane drift)
    scale: float  # m, size of the scene's bodies (where bodies are parked)
    pair_values: tuple | None = None  # (e, μ) last set
    dirty: bool = True  # contacts may remain from the previous run
    threshold: float = 0.02
    dt: float = 1.0 / 240.0  # s, the world's time step
    offset: float = 0.0  # m, the bases' y (run_many: each impact at its own)
    # Steps taken (one list per client use: a batch's impacts share their batch's), and the
    # velocities read with the poses at step velocities_at: the run reads the poses of a
    # contact step and then often its velocities, which one getJointStates call gives.
    clock: list = field(default_factory=lambda: [0])
    velocities_at: int = -1
    velocities: tuple = ()


_POLYGON_NOTE = ("polygon: pybullet keeps a link's convex-hull collision margin at 0.001 m, "
                 "so contacts sit 1 mm outside the polygon")

_get_contacts = p.getContactPoints
_get_states = p.getJointStates
_step_simulation = p.stepSimulation
_reset_joints = p.resetJointStatesMultiDof
_JOINTS = (0, 1, 2)


def _read_joints(world: _World) -> tuple:
    """Per body the joints' positions as the scene's ``(x, y, θ)`` (the revolute joint
    turns the other way); the rates, read in the same calls, are kept on the world as
    ``(v_x, v_y, ω)`` for :meth:`PybulletEngine._read_velocities` of the same step.

    Called at every contact step of every impact: one body and two are written out (no
    lists, no loop), the survey's only cases besides none.
    """
    client, bodies = world.client, world.bodies
    (x, v_x, _, _), (z, v_z, _, _), (angle, rate, _, _) = _get_states(bodies[0], _JOINTS,
                                                                       client)
    world.velocities_at = world.clock[0]
    if len(bodies) == 1:
        world.velocities = ((v_x, v_z, -rate),)
        return ((x, z, -angle),)
    (x_b, v_x_b, _, _), (z_b, v_z_b, _, _), (angle_b, rate_b, _, _) = _get_states(
        bodies[1], _JOINTS, client)  # a scene has one body or two
    world.velocities = ((v_x, v_z, -rate), (v_x_b, v_z_b, -rate_b))
    return ((x, z, -angle), (x_b, z_b, -angle_b))


def _set_joints(client: int, bodies, joints) -> None:
    """Every body's joint positions and rates (``_prepare``'s form), one call per body:
    the first reset of a new body's joints is costly per call where a plane is in the
    world, so all three joints go in one call."""
    for uid, (x, v_x, z, v_z, angle, rate) in zip(bodies, joints):
        # Lists: pybullet 3.2.7 crashes (segmentation fault) on tuples of values here.
        _reset_joints(uid, _JOINTS, [[x], [z], [angle]], [[v_x], [v_z], [rate]],
                      physicsClientId=client)


def _contact_of(points, body_b: int, dt: float) -> RawContacts:
    """One impact's contact from its points (``getContactPoints`` tuples, Bullet's order).

    Called at every contact step of every impact: the first point (most steps' only one)
    is written out; the sums start from ``0.0 +`` as a loop from 0.0 would (a -0.0 term
    gives 0.0).
    """
    # Force on body A: normal force along n (the normal on B, towards A) plus the two
    # lateral friction forces along their directions.
    (_, body_a, _, _, _, on_a, _, n, distance, force_n,
     friction_1, direction_1, friction_2, direction_2) = points[0]
    sign = 1.0 if body_a == body_b else -1.0
    n_x, _, n_z = n
    step_normal = 0.0 + force_n
    step_x = 0.0 + sign * (force_n * n_x + friction_1 * direction_1[0]
                           + friction_2 * direction_2[0])
    step_z = 0.0 + sign * (force_n * n_z + friction_1 * direction_1[2]
                           + friction_2 * direction_2[2])
    length = math.hypot(n_x, n_z)
    normal = (sign * n_x / length, sign * n_z / length)
    if len(points) == 1:
        return (((on_a[0], on_a[2], -distance),), normal, (step_x * dt, step_z * dt),
                step_normal * dt)
    contact_points = [(on_a[0], on_a[2], -distance)]
    for cp in points[1:]:
        (_, body_a, _, _, _, on_a, _, n, distance, force_n,
         friction_1, direction_1, friction_2, direction_2) = cp
        sign = 1.0 if body_a == body_b else -1.0
        step_normal += force_n
        step_x += sign * (force_n * n[0] + friction_1 * direction_1[0]
                          + friction_2 * direction_2[0])
        step_z += sign * (force_n * n[2] + friction_1 * direction_1[2]
                          + friction_2 * direction_2[2])
        contact_points.append((on_a[0], on_a[2], -distance))
    return (tuple(contact_points), normal, (step_x * dt, step_z * dt), step_normal * dt)


def _connect() -> int:
    """A new DIRECT client without its renderer plugin.

    pybullet's built-in TinyRenderer makes a visual mesh of every new link from its
    collision shape (for a sphere, most of a ``createMultiBody`` call); nothing
    here renders. Plugins touch no physics (the bit-identity tests pin the runs).
    """
    client = p.connect(p.DIRECT)
    renderer = p.loadPlugin("tinyRendererPlugin", physicsClientId=client)  # its id, if loaded
    if renderer >= 0:
        p.unloadPlugin(renderer, physicsClientId=client)
    return client


@dataclass
class _Client:
    """A DIRECT client and what it keeps between uses."""

    uid: int  # pybullet's physicsClientId
    plane: int | None = None  # run_many: the static plane it keeps for ground batches
    impacts: int = 0  # run_many: impacts built in it since it was last reset


def _reset_client(client: _Client) -> None:
    """Empty ``client``: Bullet deletes its dynamics world and makes a new one."""
    p.resetSimulation(physicsClientId=client.uid)
    client.plane, client.impacts = None, 0


def _remove_bodies(client: int, worlds) -> None:
    """Remove the bodies of ``worlds`` (batch impacts) from ``client``."""
    for world in worlds:
        for uid in world.bodies:
            p.removeBody(uid, physicsClientId=client)


def _slice_offsets(sizes: list[float], gap: float) -> list[float]:
    """Each batch impact's y (its bases'), for impacts of ``sizes`` (m, their largest body
    extents) made in list order: slices ``gap`` apart, laid out along y in bit-reversed
    order of making (0, n/2, n/4, 3n/4, ...).

    Bullet's broad phase keeps a bounding-volume tree that it does not rebalance as leaves
    are added or moved: slices made in order along a line make it a chain, and every body
    made, first moved (its start state) or removed then walks it (a cost that grows with
    every body already in the client). Made in bit-reversed order, each new body splits
    the longest gap so far, and the tree stays shallow.
    """
    count = len(sizes)
    bits = max(count - 1, 0).bit_length()
    # Slot order along y: by the bit reversal of the slot's index.
    along = sorted(range(count), key=lambda slot: int(format(slot, f"0{bits}b")[::-1] or "0", 2))
    offsets = [0.0] * count
    offset = previous = 0.0
    for place, slot in enumerate(along):
        size = sizes[slot]
        if place:
            offset += previous + size + gap
        previous = size
        offsets[slot] = offset
    return offsets


def _settings_key(settings) -> tuple:
    """The settings a world is built with (all but the per-run ones), as a key."""
    return tuple((k, settings[k]) for k in sorted(settings) if k not in _RUN_ONLY)


class _Batch:
    """A client holding many impacts (one :class:`_World` view each)."""

    __slots__ = ("body_b", "client", "clock", "dt", "held", "left", "pool_key", "slot_of",
                 "slots")

    def __init__(self, held: _Client, pool_key: tuple, dt: float) -> None:
        self.held, self.pool_key, self.dt = held, pool_key, dt
        self.client = held.uid  # -1 once released
        self.slots: list[_World] = []
        self.slot_of: dict[int, int | None] = {}  # body unique id -> slot (the plane: None)
        self.body_b: list[int] = []  # per slot, its body B's unique id (bodies[-1])
        self.left: set[int] = set()  # slots whose bodies are still in the client
        self.clock = [0]  # steps taken (its impacts' _World.clock)


class PybulletEngine(Engine):
    name = "pybullet"
    version = "3.2.7"
    # What the rest of the harness reads about this engine (docs/engines.md, 'The engine
    # contract'): why it lands where it does, per engine and per preset, and its plot style.
    description = (
        "Bullet also solves newton-lcp (projected Gauss–Seidel), but out of the box it adds "
        "two biases: contacts exist up to 2 cm before touch and the solver then aims at "
        "e·|v_n| − gap/dt, and restitution is cut to zero below 0.2 m/s; a default contact "
        "slop and link damping take about 0.2% more. Polygons keep a 1 mm collision margin "
        "(docs/engines.md, 'pybullet').")
    preset_why = {
        "defaults": ("Bullet's own defaults: 2 cm contact threshold, 0.2 m/s "
                     "restitution threshold, contact slop and 0.04 1/s damping, "
                     "so the bounce depends on where in a step the impact falls."),
        "accurate": ("threshold, position-error terms, warm starting and damping "
                     "off, 100 iterations: newton-lcp to rounding (polygons: the "
                     "1 mm margin remains)."),
    }
    plot_style = ("#E69F00", "s")
    bench_impacts = (200, 1000)
    bench_impact_seconds = 5e-5
    #: pybullet 3.2.7 clamps every joint's speed to its ``maxJointVelocity``, 100 by default:
    #: a disk dropped at 150 m/s enters at 100 m/s, at 10⁶ m/s it leaves at [0, 100, 0]
    #: (e = 1) (docs/verdicts.md, 'Velocity caps').
    speed_caps = (100.0, 100.0)
    presets = PRESETS
    setting_docs = SETTING_DOCS
    max_worlds = _MAX_WORLDS


    @classmethod
    def bench_sweep(cls, quick: bool) -> list[tuple[str, str, dict]]:
        """The settings the accuracy bench measures (harness/bench/accuracy.py)."""
        points: list[tuple[str, str, dict]] = []
        points.append(("defaults", "defaults", {}))
        points.append(("defaults it=200", "defaults", {"num_solver_iterations": 200}))
        iterations = (1, 2, 5, 10, 20, 50, 100) if quick else (1, 2, 3, 5, 10, 20, 30, 50, 100, 200)
        for dt in ((1 / 240,) if quick else (1 / 240, 1e-3)):
            for count in iterations:
                points.append((f"dt={dt:.3g} it={count}", "accurate",
                               {"time_step": dt, "num_solver_iterations": count}))
        for sub in ((4,) if quick else (2, 4, 8)):
            points.append((f"dt={1 / 240:.3g} it=10 sub={sub}", "accurate",
                           {"num_solver_iterations": 10, "num_sub_steps": sub}))
        return points

    def __init__(self) -> None:
        # Idle clients: ("world", settings key) -> emptied clients for run()'s worlds;
        # ("many", settings key, ground) -> run_many's, with their plane (if ground) only.
        self._idle: dict[tuple, list[_Client]] = {}
        try:  # pybullet has no __version__; its API version is a date
            from importlib.metadata import PackageNotFoundError, version

            self.version = version("pybullet")
        except PackageNotFoundError:  # pragma: no cover - metadata missing
            pass

    def _validate_engine_settings(self, settings) -> None:
        name = self.name
        check_int(name, settings, "num_solver_iterations", low=1, allow_none=True)
        check_int(name, settings, "num_sub_steps", low=0, allow_none=True)
        check_number(name, settings, "contact_breaking_threshold", low=0.0, strict=True)
        for key in ("contact_erp", "erp", "friction_erp"):
            check_number(name, settings, key, low=0.0, high=1.0, allow_none=True)
        for key in ("contact_slop", "restitution_velocity_threshold", "solver_residual_threshold",
                    "global_cfm"):
            check_number(name, settings, key, low=0.0, allow_none=True)
        check_number(name, settings, "warm_starting_factor", low=0.0, high=1.0, allow_none=True)
        check_choice(name, settings, "enable_cone_friction", (0, 1), allow_none=True)
        check_choice(name, settings, "use_split_impulse", (0, 1), allow_none=True)
        check_number(name, settings, "linear_damping", low=0.0)
        check_number(name, settings, "angular_damping", low=0.0)

    # ------------------------------------------------------------------ worlds
    def _world_key(self, scene: Scene, settings) -> tuple:
        """The engine settings a world is built with, and the geometry."""
        return (_settings_key(settings), geometry_key(scene))

    def _take_client(self, pool_key: tuple) -> _Client:
        """An idle client kept under ``pool_key``, else a new one."""
        idle = self._idle.get(pool_key)
        return idle.pop() if idle else _Client(_connect())

    def _keep_client(self, pool_key: tuple, client: _Client, limit: int, empty) -> None:
        """Keep ``client`` idle under ``pool_key`` once ``empty(client)`` has emptied it, if
        fewer than ``limit`` are kept there; else disconnect it."""
        idle = self._idle.setdefault(pool_key, [])
        try:
            if len(idle) < limit:
                empty(client)
                idle.append(client)
            else:
                p.disconnect(physicsClientId=client.uid)
        except p.error:  # pragma: no cover - already gone at interpreter exit
            pass

    def _build(self, scene: Scene, settings, *, contacts: bool = True) -> _World:
        settings_key = _settings_key(settings)
        client = self._take_client(("world", settings_key)).uid
        _configure(client, settings)
        plane = _add_plane(client) if scene.ground else None
        extents = tuple(body_extent(b.shape) for b in scene.bodies)
        bodies = _add_bodies(client, scene, settings, extents)
        # A bare-stepping world never asks for contacts, so it never knows whether the last
        # run left some: it starts clean (no collision detection has run yet) and stays so.
        return _World(client=client, settings_key=settings_key, plane=plane, bodies=bodies,
                      extents=extents,
                      scale=max(extents), dirty=contacts,
                      threshold=float(settings["contact_breaking_threshold"]),
                      dt=float(settings["time_step"]))

    def _release(self, world: _World) -> None:
        """Empty the world's client and keep it idle for its settings, or disconnect it."""
        client, world.client = world.client, -1
        if client >= 0:
            self._keep_client(("world", world.settings_key), _Client(client), _MAX_IDLE,
                              _reset_client)

    def close(self) -> None:
        """Release every cached world and plan, and disconnect the idle clients."""
        super().close()
        while self._idle:
            _, clients = self._idle.popitem()
            for client in clients:
                try:
                    p.disconnect(physicsClientId=client.uid)
                except p.error:  # pragma: no cover - already gone at interpreter exit
                    pass

    def __del__(self):  # pragma: no cover - interpreter exit
        try:
            self.close()
        except Exception:  # noqa: BLE001, S110 - nothing to report to at exit
            pass

    def _notes(self, scene: Scene, settings) -> tuple[str, ...]:
        polygon = any(body.shape.kind in ("polygon", "ellipse") for body in scene.bodies)
        return (_POLYGON_NOTE,) if polygon else ()

    # ------------------------------------------------------------------ run
    def _prepare(self, world: _World | None, scene: Scene, settings, start, weights) -> tuple:
        """The start joint states ``(x, v_x, z, v_z, -θ, -ω)`` per body and the pair's
        (e, μ); ``world`` is not needed (``None`` for :meth:`run_many`)."""
        joints = tuple(
            (x, vx, y, vy, -angle, -omega) for x, y, angle, vx, vy, omega in start
        )
        return joints, (scene.restitution, scene.friction)

    def _reset(self, world: _World, prepared: tuple) -> dict:
        """The process-wide contact threshold, empty contact manifolds where the last run
        left contacts, the pair's (e, μ) and the start joint states."""
        joints, pair_values = prepared
        client = world.client
        if world.pair_values != pair_values:
            p.changeDynamics(world.bodies[0], 2, restitution=pair_values[0],
                             lateralFriction=pair_values[1], physicsClientId=client)
            world.pair_values = pair_values
        # Process-wide in Bullet: new manifolds take the value current at their creation.
        p.setPhysicsEngineParameter(contactBreakingThreshold=world.threshold,
                                    physicsClientId=client)
        reset = p.resetJointState
        if world.dirty:
            # Empty the contact manifolds: park the bodies apart, run collision detection.
            for index, uid in enumerate(world.bodies):
                reset(uid, 0, 10.0 * index * (world.scale + 1.0), 0.0, client)
                reset(uid, 1, _PARK_HEIGHT, 0.0, client)
            p.performCollisionDetection(client)
        _set_joints(client, world.bodies, joints)
        world.velocities_at = -1
        return {}

    def _advance(self, world: _World) -> None:
        _step_simulation(world.client)
        world.clock[0] += 1

    def _step(self, world: _World) -> RawContacts | None:
        client = world.client
        _step_simulation(client)
        world.clock[0] += 1
        # No filter: Bullet's own body order (a filtered query flips the normal of a swapped
        # pair but not the friction directions). The world holds only this pair.
        # Positional: bodyA, bodyB, linkIndexA, linkIndexB at their "any" defaults.
        points = _get_contacts(-1, -1, -2, -2, client)
        world.dirty = bool(points)
        if not points:
            return None
        return _contact_of(points, world.bodies[-1], world.dt)

    # ------------------------------------------------------------------ many impacts
    def _many_chunks(self, scenes) -> list[list[int]]:
        """Ground scenes and two-body scenes apart (a two-body world has no plane),
        :data:`MANY_IMPACTS` to a world."""
        chunks = []
        for ground in (True, False):
            rows = [index for index, scene in enumerate(scenes) if scene.ground == ground]
            chunks += [rows[begin:begin + MANY_IMPACTS]
                       for begin in range(0, len(rows), MANY_IMPACTS)]
        return chunks

    def _build_many(self, plans) -> tuple[_Batch, list[_World], list[dict]]:
        """One client holding every plan's impact, each in its own slice of the engine's y.

        The scene's plane is the engine's x-z plane, so an impact moved along y keeps its
        x-z arithmetic (the rotations about y have exact zeros off the plane, and Bullet
        works with differences of positions): slices :data:`_MANY_GAP` plus twice the
        contact breaking threshold apart never meet (no contact points, no broad-phase
        pairs), and share only the static plane, which joins no islands.
        """
        settings = plans[0].settings  # one settings dict for every plan
        settings_key = _settings_key(settings)
        ground = plans[0].scene.ground
        pool_key = ("many", settings_key, ground)
        held = self._take_client(pool_key)
        client = held.uid
        if ground and held.plane is None:
            held.plane = _add_plane(client)
        plane = held.plane
        held.impacts += len(plans)
        _configure(client, settings)
        threshold = float(settings["contact_breaking_threshold"])
        p.setPhysicsEngineParameter(contactBreakingThreshold=threshold, physicsClientId=client)
        batch = _Batch(held, pool_key, float(settings["time_step"]))
        gap = _MANY_GAP + 2.0 * threshold  # contact points exist up to the threshold
        slots, slot_of, body_b, dt = batch.slots, batch.slot_of, batch.body_b, batch.dt
        if plane is not None:
            slot_of[plane] = None  # _step_many: look at the contact's other body
        every_extents = [tuple([body_extent(body.shape) for body in plan.scene.bodies])
                         for plan in plans]
        sizes = [max(extents) for extents in every_extents]
        offsets = _slice_offsets(sizes, gap)
        for slot, plan in enumerate(plans):
            scene, extents, size, offset = (plan.scene, every_extents[slot], sizes[slot],
                                            offsets[slot])
            joints, (e, mu) = plan.prepared
            bodies = _add_bodies(client, scene, settings, extents, offset, (e, mu))
            _set_joints(client, bodies, joints)
            slots.append(_World(client=client, settings_key=settings_key, plane=plane,
                                bodies=bodies, extents=extents, scale=size, pair_values=(e, mu),
                                dirty=False, threshold=threshold, dt=dt, offset=offset,
                                clock=batch.clock))
            for uid in bodies:
                slot_of[uid] = slot
            body_b.append(bodies[-1])
        batch.left.update(range(len(plans)))
        return batch, batch.slots, [{} for _ in plans]

    def _step_many(self, batch: _Batch, active) -> dict:
        client = batch.client
        _step_simulation(client)
        batch.clock[0] += 1
        points_of: dict[int, list] = {}
        slot_of = batch.slot_of  # the plane's id -> None
        for cp in _get_contacts(-1, -1, -2, -2, client):  # every pair, Bullet's order
            slot = slot_of[cp[1]]
            if slot is None:  # body A is the plane
                slot = slot_of[cp[2]]
            points = points_of.get(slot)
            if points is None:
                points_of[slot] = [cp]
            else:
                points.append(cp)
        body_b, dt = batch.body_b, batch.dt
        return {slot: _contact_of(points, body_b[slot], dt)
                for slot, points in points_of.items()}

    def _retire(self, batch: _Batch, slot: int) -> None:
        """Remove the impact's bodies: the next steps neither move nor collide them."""
        _remove_bodies(batch.client, (batch.slots[slot],))
        batch.left.discard(slot)

    def _release_many(self, batch: _Batch) -> None:
        """Keep the batch's client for the next batch of its settings and kind, emptied of
        the impacts still in it (a client reset costs more than a batch's stepping), and
        reset after :data:`_MANY_RESET_AFTER` impacts (Bullet keeps every collision shape
        made in a client, and refuses to remove one a removed body used)."""
        batch.client = -1
        left = [batch.slots[slot] for slot in sorted(batch.left)]
        batch.left.clear()
        for world in batch.slots:
            world.client = -1

        def empty(client: _Client) -> None:
            if client.impacts >= _MANY_RESET_AFTER:
                _reset_client(client)
            else:
                _remove_bodies(client.uid, left)

        self._keep_client(batch.pool_key, batch.held, 1, empty)

    def _read_poses(self, world: _World) -> tuple:
        return _read_joints(world)

    def _read_velocities(self, world: _World) -> tuple:
        if world.velocities_at != world.clock[0]:
            _read_joints(world)
        return world.velocities

    def _out_of_plane_drift(self, world: _World) -> float:
        """The centre's y, plus the tilt of the link's y axis times the body's size."""
        client, offset = world.client, world.offset
        drift = 0.0
        for uid, extent in zip(world.bodies, world.extents):
            link = p.getLinkState(uid, 2, 0, 0, client)
            qx, qy, qz, qw = link[1]  # world orientation of the link frame
            tilt_x = 2.0 * (qx * qy - qz * qw)  # components of the link's y axis off (0, 1, 0)
            tilt_z = 2.0 * (qy * qz + qx * qw)
            body_drift = abs(link[0][1] - offset) + math.hypot(tilt_x, tilt_z) * extent
            if body_drift > drift:  # noqa: PLR1730 - the loop reads better with the test
                drift = body_drift
        return drift


ENGINE_CLASS = PybulletEngine
