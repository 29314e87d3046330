"""Box2D (pybox2d 2.3.10) behind the engine contract: the hooks of :class:`Box2DEngine`.

What the engine does and why is told in the package's docstring
(:mod:`harness.engines.box2d`); the workarounds for pybox2d live in the package's other
modules.
"""

from __future__ import annotations

import Box2D

from harness.engines.box2d.batch import MANY_CHUNK, _Batch, _many_world, _ManyProbe
from harness.engines.box2d.manifold import _speed_after_collide
from harness.engines.box2d.presets import _BOOL_KEYS, PRESETS, SETTING_DOCS
from harness.engines.box2d.scaling import (
    _Prepared,
    _prepared,
    _speed_results,
    _SpeedProbe,
)
from harness.engines.box2d.world import _states_at_cap, _World
from harness.engines.contract import Engine, RawContacts, StepTiming, geometry_key
from harness.engines.settings import EngineSettingsError, check_int, check_number
from harness.scene import Scene

CLIPPED_NOTE = ("Box2D clipped a velocity (b2_maxTranslation 2 m or b2_maxRotation π/2 per "
                "step; see derived speed_cap, angular_speed_cap)")


# ---------------------------------------------------------------------- the adapter
class Box2DEngine(Engine):
    name = "box2d"
    version = Box2D.__version__
    # What the rest of the harness reads about this engine (docs/engines.md, 'The engine
    # contract'): why it lands where it does, per engine and per preset, and its plot style.
    description = (
        "Box2D solves the velocity-level law (newton-lcp) by sequential impulses, like "
        "pymunk; its measured behaviour is in docs/engines.md, 'Box2D'.")
    preset_why = {
        "defaults": ("Box2D's own defaults."),
        "accurate": ("settings under which Box2D solves its law as exactly as it can."),
    }
    rounding = 1e-6  # float32 arithmetic: a few roundings of 6e-8 (ROUNDING in the tests)
    # Under defaults the ground's skin (polygon radius) moves the point the impulse acts at
    # by ~5 mm on a 0.1 m disk: I Δω is 0.95 of r × P at the touching point (measured up to
    # 1.4e-2 of |r||P| on the reference disk, 5.9e-3 on check_engine's scenes); the verdicts'
    # impulse-residual bar.
    impulse_band = 2e-2
    # Box2D's default polygon skin (0.01 m) makes the rod's core box reach the ground beside
    # its 5 mm end cap: three contact points at once; on the ellipse's 8-gon, skins of 2 × 0.01
    # m reach past the next vertex (8 mm up): two points.
    reference_statuses = {("rod-45", "defaults"): "multi-contact",
                          ("ellipse", "defaults"): "multi-contact"}
    native_2d = True
    plot_style = ("#CC79A7", "D")
    bench_impacts = (40, 300)
    # The scale Box2D's world is built at: it moves the float32 rounding and the per-step
    # translation cap relative to the bodies (`impact-harness calibrate box2d`).
    calibration_knobs = (("length_scale", (1.0, 8.0, 64.0)),)
    presets = PRESETS
    setting_docs = SETTING_DOCS
    # Collision first: the first step finds the contact at the start pose. The start's
    # hair of overlap is a depth in lengths (detection_overlap), added in _prepare.
    timing = StepTiming(lead_steps=0.0, overlap=0.0)


    @classmethod
    def bench_sweep(cls, quick: bool) -> list[tuple[str, str, dict]]:
        """The settings the accuracy bench measures (harness/bench/accuracy.py)."""
        points: list[tuple[str, str, dict]] = []
        points.append(("defaults", "defaults", {}))
        # Box2D's own time step changes nothing for a one-step impact but the translation
        # cap; the sweeps are what converge the coupled points (float32 floor ~1e-7).
        iterations = (1, 2, 5, 8, 20, 100) if quick else (1, 2, 3, 5, 8, 10, 20, 50, 100, 200)
        for count in iterations:
            points.append((f"dt={1 / 60:.3g} it={count}", "accurate",
                           {"velocity_iterations": count}))
        return points

    def _validate_engine_settings(self, settings) -> None:
        check_int(self.name, settings, "velocity_iterations", low=1)
        check_int(self.name, settings, "position_iterations", low=0)
        for key in _BOOL_KEYS:
            if not isinstance(settings[key], bool):
                raise EngineSettingsError(
                    f"engine {self.name!r}: setting {key!r} must be true or false, "
                    f"got {settings[key]!r}")
        check_number(self.name, settings, "polygon_radius", low=0.0)
        if settings["velocity_scale"] != "auto":
            check_number(self.name, settings, "velocity_scale", low=0.0, strict=True)
        check_number(self.name, settings, "length_scale", low=0.0, strict=True)
        check_number(self.name, settings, "detection_overlap", low=0.0)

    def _world_key(self, scene: Scene, settings) -> tuple:
        return (geometry_key(scene), float(settings["length_scale"]),
                float(settings["polygon_radius"]))

    def _build(self, scene: Scene, settings, *, contacts: bool = True) -> _World:
        return _World(scene, float(settings["length_scale"]), float(settings["polygon_radius"]),
                      measures=contacts)

    def _prepare(self, world: _World | None, scene: Scene, settings, start, weights) -> _Prepared:
        # The velocity scale and start depth come from the scene (scaling.first_touch_speed);
        # the speed Box2D saw is read in the run itself (_reset).
        return _prepared(scene, settings, start)

    def _reset(self, world: _World, prepared: _Prepared) -> dict:
        world.configure(prepared.world_values, prepared.pair_values)
        world.dt, world.iterations, world.velocity = (prepared.dt, prepared.iterations,
                                                      prepared.velocity)
        world.notes = prepared.notes
        world.place(prepared.starts)
        # Already beyond a cap before the first step (place read the bodies).
        world.clipped = _states_at_cap(world.states, world.dt, 1.0)
        derived = world.derived = dict(prepared.derived)
        if world.speed_probe is not None:  # the last run met no contact
            world.world.contactListener = world.speed_probe = None
        if world.measures:
            world.restitution = prepared.pair_values[0]
            # The first step's collision pass, alone: a scene touching at its start gives its
            # speed there (_speed_after_collide); only the others need the listener.
            world.world.contactManager.Collide()
            speed = _speed_after_collide(world)
            if speed is not None:
                world.notes = _speed_results(derived, speed, world.restitution, world.notes)
            else:
                world.speed_probe = _SpeedProbe(world)
                world.world.contactListener = world.speed_probe
        return derived

    def _advance(self, world: _World) -> None:
        world.world.Step(world.dt, *world.iterations)

    def _step(self, world: _World) -> RawContacts | None:
        world.world.Step(world.dt, *world.iterations)
        probe = world.speed_probe
        if probe is not None and probe.speed is not None:  # measured in this step's PreSolve
            world.notes = _speed_results(world.derived, probe.speed, world.restitution,
                                         world.notes)
            world.world.contactListener = world.speed_probe = None
        return world.read_step()

    # ------------------------------------------------------------------ many impacts
    def _runs_alone(self, settings) -> bool:
        """With ``sub_stepping`` the impacts run one by one (:meth:`Engine.run_many`).

        Sub-stepping handles one time-of-impact event per step in the whole world and leaves
        the world's step unfinished (the next ``b2World::Step`` only resumes it): impacts
        sharing a world would steer each other.
        """
        return bool(settings["sub_stepping"])

    def _many_chunks(self, plans) -> list[list[int]]:
        """Up to :data:`MANY_CHUNK` impacts to a batch, those of one Box2D time step (the
        plans' own: ``auto`` gives each velocity scale one) together, in their order, a
        time step's impacts split evenly among its batches: a batch is one world
        (:meth:`_build_many`). Which impacts share a batch changes no run."""
        classes: dict[float, list[int]] = {}
        for index, plan in enumerate(plans):
            classes.setdefault(plan.prepared.dt, []).append(index)
        chunks = []
        for indices in classes.values():
            size = -(-len(indices) // -(-len(indices) // MANY_CHUNK))  # ceil(n / batches)
            chunks += [indices[begin:begin + size] for begin in range(0, len(indices), size)]
        return chunks

    def _build_many(self, plans) -> tuple[_Batch, list, list]:
        """b2Worlds stepping many impacts, each impact as :meth:`run` steps it alone.

        The impacts overlap in space (each at its own run-frame coordinates: moving one
        would change its float32 roundings) and are kept apart by collision filters: every
        fixture of impact k, its ground's included, is in group k+1 (always collide) with
        mask 0 (collide with no other group). Box2D solves each island (an impact's bodies
        and their touching contacts) by itself, collides contact by contact, and creates
        the contacts of new pairs in the order of the proxies' ids, which keep each impact's
        own order; time-of-impact events advance only their own bodies. So an impact's
        arithmetic is the one it has alone (the tests compare them bit for bit).

        One world per Box2D time step (the velocity scales differ: a world steps by one
        time step, and warm starting scales impulses by the ratio of consecutive steps),
        each impact built once at its run's start. The runs measure the speed Box2D sees
        themselves, as :meth:`_reset` does.
        """
        prepared = [plan.prepared for plan in plans]
        first = prepared[0]  # one settings dict for every plan
        world_values, iterations = first.world_values, first.iterations
        length = float(plans[0].settings["length_scale"])
        skin = float(plans[0].settings["polygon_radius"])
        groups: dict = {}
        for slot, one in enumerate(prepared):
            groups.setdefault(one.dt, []).append(slot)
        batch = _Batch(len(plans))
        # The plans' own derived values: run_many's plans are made for this call alone.
        derived = [one.derived for one in prepared]
        for slots in groups.values():
            dt = prepared[slots[0]].dt
            world, views = _many_world([plans[slot] for slot in slots],
                                       [prepared[slot] for slot in slots], slots, length,
                                       skin, world_values)
            for slot, view in zip(slots, views):
                view.world = len(batch.worlds)
                view.dt, view.velocity = dt, prepared[slot].velocity
                view.notes = prepared[slot].notes
                view.derived = derived[slot]
                view.clipped = _states_at_cap(view.states, dt, 1.0)  # read when placed
                batch.slots[slot] = view
            batch.worlds.append((world, dt, iterations))
            # The first step's collision pass, alone (_speed_after_collide): the impacts
            # touching at their start give their speeds there, the others through the
            # listener.
            world.contactManager.Collide()
            pending = []
            for view in views:
                speed = _speed_after_collide(view)
                if speed is None:
                    pending.append(view)
                else:
                    view.notes = _speed_results(view.derived, speed, view.restitution,
                                                view.notes)
            if pending:
                listener = _ManyProbe(pending)
                world.contactListener = listener
                batch.listeners.append((world, listener))
        return batch, batch.slots, derived

    def _step_many(self, batch: _Batch, active) -> dict:
        slots, worlds = batch.slots, batch.worlds
        if len(worlds) == 1:  # called with active impacts only
            world, dt, iterations = worlds[0]
            world.Step(dt, *iterations)
        else:
            stepping = {slots[slot].world for slot in active}
            for index, (world, dt, iterations) in enumerate(worlds):
                if index in stepping:
                    world.Step(dt, *iterations)
        contacts = {}
        for slot in active:
            view = slots[slot]
            raw = view.read_step()
            if raw is not None:
                contacts[slot] = raw
        if batch.listeners:
            batch.listeners = [(world, listener) for world, listener in batch.listeners
                               if not listener.done(world)]
        return contacts

    def _retire(self, batch: _Batch, slot: int) -> None:
        view = batch.slots[slot]
        for b2_body in view.bodies:
            b2_body.awake = False  # a sleeping impact is neither collided nor solved

    def _release_many(self, batch: _Batch) -> None:
        for world, _ in batch.listeners:
            world.contactListener = None
        batch.listeners = []
        batch.worlds = []
        batch.slots = []

    def _read_poses(self, world: _World) -> tuple:
        return world.now  # read after the step (_Readout.read)

    def _read_velocities(self, world: _World) -> tuple:
        velocity, rate = world.velocity, world.length / world.velocity
        # Read after the step (_Readout.read): the loop reads velocities only then, and
        # the batch's _finish comes before _retire stops the bodies.
        # A loop, not a comprehension (its frame): read at most steps of a run's contact.
        velocities = []
        for state in world.states:
            velocities.append((state[5] / velocity, state[6] / velocity, state[7] * rate))
        return tuple(velocities)

    def _run_notes(self, world: _World) -> tuple[str, ...]:
        if world.clipped:
            return (*world.notes, CLIPPED_NOTE)
        return world.notes



ENGINE_CLASS = Box2DEngine
