"""pybullet (Bullet) behind the engine contract: the hooks of :class:`PybulletEngine`.

What the engine does and why is told in the package's docstring
(:mod:`harness.engines.pybullet`); the bodies it builds, the world it reads and the clients
it keeps live in the package's other modules.
"""

from __future__ import annotations

import math

from harness.engines.contract import Engine, RawContacts, body_extent, geometry_key
from harness.engines.pybullet.bodies import _add_bodies, _add_plane, _configure
from harness.engines.pybullet.clients import (
    _Batch,
    _Client,
    _connect,
    _remove_bodies,
    _reset_client,
    _settings_key,
    _slice_offsets,
)
from harness.engines.pybullet.presets import PRESETS, SETTING_DOCS
from harness.engines.pybullet.world import _contact_of, _read_joints, _set_joints, _World
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

_POLYGON_NOTE = ("polygon: pybullet keeps a link's convex-hull collision margin at 0.001 m, "
                 "so contacts sit 1 mm outside the polygon")

_get_contacts = p.getContactPoints
_step_simulation = p.stepSimulation


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
    # Under defaults the 0.04 1/s link damping also acts over the contact's steps: m Δv
    # differs from the reported impulse by up to 7.5e-4 of it on check_engine's scenes (the
    # 2 m/s sliding disk; a faster slide would show more of the damping).
    impulse_band = 1e-3
    no_calibration_knobs_why = (
        "none of Bullet's own settings is tried: its iterations, sub-steps and step converge "
        "the solve, the ERP terms, slop and contact threshold correct positions or add the "
        "biases `accurate` removes")
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
    def _many_chunks(self, plans) -> list[list[int]]:
        """Ground scenes and two-body scenes apart (a two-body world has no plane),
        :data:`MANY_IMPACTS` to a world."""
        chunks = []
        for ground in (True, False):
            rows = [index for index, plan in enumerate(plans) if plan.scene.ground == ground]
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
