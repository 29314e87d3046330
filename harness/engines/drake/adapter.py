"""Drake behind the engine contract: the hooks of :class:`DrakeEngine`.

What the engine does and why is told in the package's docstring (:mod:`harness.engines.drake`);
the diagram it builds lives in :mod:`.model`, the e <-> d map in :mod:`.restitution`.
"""

from __future__ import annotations

import math
from importlib import metadata

import numpy as np

from harness.engines.contract import (
    Engine,
    RawContacts,
    StepTiming,
    geometry_key,
)
from harness.engines.drake.model import World, world_key
from harness.engines.drake.presets import APPROXIMATIONS, PRESETS, SETTING_DOCS
from harness.engines.drake.restitution import MIN_RESTITUTION, discrete_dissipation
from harness.engines.settings import EngineSettingsError, check_choice, check_int, check_number
from harness.scene import Scene
from harness.scene.geometry import contact_velocity, impact_problem, scene_contact

# Fraction of a step of free flight by which the start is past the touching pose: Drake
# reports a point pair only for an overlap.
_DETECTION_OVERLAP = 1e-6

#: The accurate preset's undamped contact duration (s): 500 steps of 1e-6 s; the accuracy
#: bench and the stress test's step sweep hold it while they change the steps.
CONTACT_DURATION_S = 5e-4

#: The label of the accuracy bench's converged point (``bench_reference``): the accurate
#: contact's 0.5 ms cut into 4000 steps (Drake has no RK4: MuJoCo's label is not its own).
BENCH_REFERENCE = "contact_steps=4000 (reference)"


def _contact_terms(scene: Scene) -> tuple[float, float]:
    """``(m_nn, v)``: the normal effective mass at the first contact point and the normal
    approach speed there (> 0), from the scene at first touch."""
    contact = scene_contact(scene)
    problem = impact_problem(scene, contact.point, contact.normal)
    wn = np.asarray(problem.wn, dtype=float)
    effective_mass = 1.0 / float(wn @ np.linalg.solve(problem.mass_matrix, wn))
    normal_speed, _ = contact_velocity(scene, contact)
    return effective_mass, -normal_speed


class DrakeEngine(Engine):
    name = "drake"
    version = metadata.version("drake")  # pydrake itself carries no __version__
    description = (
        "Drake departs because its point contact is compliant: a Hunt–Crossley force "
        "k·x·(1 + d·ẋ) that cannot pull, with regularised friction, stepped implicitly. "
        "Under defaults the stiffness and dissipation are Drake's estimates from a 1 mm "
        "penetration allowance and the scenario's e is not used: a 1 m/s drop leaves at "
        "0.02 m/s. Under accurate the stiffness is set from the contact's normal effective "
        "mass so that a contact lasts 500 steps and d is chosen from e and the approach "
        "speed through the discrete contact's own map, so a central drop bounces at e·v "
        "(within 1% at e = 1, where the implicit step's own loss remains); where rotation "
        "couples to the normal, the compliance gives a departure of its own, closer to "
        "Stronge than to Poisson on rods and box corners.")
    preset_why = {
        "defaults": ("MultibodyPlantConfig's defaults (1 ms steps, SAP lagged, stiffness "
                     "and dissipation from a 1 mm penetration allowance): e is not used and "
                     "a 1 m/s drop bounces at about 0.02 m/s."),
        "accurate": ("stiffness from the normal effective mass over a 500-step contact of "
                     "1 µs steps, Hunt–Crossley d from e and the approach speed through "
                     "the discrete contact's map, TAMSI (as exact as SAP here and 2.8x "
                     "cheaper): a central drop bounces at e·v."),
    }
    plot_style = ("#D55E00", "v")  # Okabe–Ito vermillion; the others are taken
    bench_impacts = (10, 60)
    bench_impact_seconds = 1.2e-2
    own_law = "converged"  # a compliant contact solves no rigid law: its limit is itself
    bench_reference = BENCH_REFERENCE  # the last point of bench_sweep, quick or full
    # A compliant contact over 5-23 (defaults, 1 ms) to 500-630 (accurate, 1 µs) steps with
    # the bodies overlapping up to 0.4 mm: the force acts inside the overlap, so the lever
    # arm is shorter than the scene's first-touch point's by up to about half the depth.
    # The impulse vector is from momentum (exact); the spin's residual about the scene's
    # point was measured up to 3.2e-4 of |r||P| on the kit's scenes and 1.5e-3 on the
    # reference scenes (box corner under defaults; 9.8e-4 the ellipse under accurate).
    impulse_band = 2e-3
    soft_contact = True
    restitution_unused = {"defaults": "Drake's defaults have no restitution coefficient: the "
                                      "stiffness and Hunt–Crossley dissipation from a 1 mm "
                                      "penetration allowance set the bounce (0.02 m/s of a "
                                      "1 or 3 m/s drop for any e)"}
    # A 500-step contact at ~15-20 µs a step (Python drives every step and reads its contact):
    # the slowest pair by far, so a default survey runs Drake at defaults only
    # (`impact-harness bench --survey`; docs/populations.md).
    survey_left_out = {"accurate": "hundreds of Python-driven steps per impact: the slowest "
                                   "pair by far"}
    # Hunt–Crossley's dissipation d (s/m) as a number, what sets Drake's bounce in place of
    # e (e ≈ 0.87 / 0.5 / 0.1 at 1 m/s for these; `impact-harness calibrate drake`).
    calibration_knobs = (("hunt_crossley_dissipation", (0.2, 1.4, 10.0)),)
    presets = PRESETS
    setting_docs = SETTING_DOCS
    # Drake finds contacts from the state at the start of a step: the bodies start a hair
    # past the touching pose so that the first step sees an overlap.
    timing = StepTiming(lead_steps=0.0, overlap=_DETECTION_OVERLAP)
    max_worlds = 16  # a world per geometry and plant configuration; ~1 ms to build

    @classmethod
    def time_step_overrides(cls, role: str, time_step: float) -> dict:
        """At ``accurate`` the stiffness is tied to steps: keep the preset's 0.5 ms contact, so
        that the time step is what changes."""
        if role != "accurate":
            return {"time_step": time_step}
        return {"time_step": time_step,
                "contact_steps": max(1, int(round(CONTACT_DURATION_S / time_step)))}

    @classmethod
    def bench_sweep(cls, quick: bool) -> list[tuple[str, str, dict]]:
        """The settings the accuracy bench measures: the accurate contact's 0.5 ms cut into
        more and more steps (a longer contact would also sink deeper and move the lever
        arms: another impact, not a finer one)."""
        points: list[tuple[str, str, dict]] = [("defaults", "defaults", {})]
        for count in ((50, 100, 500) if quick else (25, 50, 100, 200, 500, 1000)):
            points.append((f"contact_steps={count}", "accurate",
                           {"contact_steps": count, "time_step": CONTACT_DURATION_S / count}))
        # the converged run the bench measures "own" against (bench_reference)
        points.append((BENCH_REFERENCE, "accurate",
                       {"contact_steps": 4000, "time_step": CONTACT_DURATION_S / 4000}))
        return points

    def _validate_engine_settings(self, settings) -> None:
        name = self.name
        check_choice(name, settings, "discrete_contact_approximation", APPROXIMATIONS)
        check_number(name, settings, "penetration_allowance", low=0.0, strict=True)
        check_number(name, settings, "stiction_tolerance", low=0.0, strict=True)
        check_number(name, settings, "contact_steps", low=1.0, allow_none=True)
        dissipation = settings["hunt_crossley_dissipation"]
        if dissipation == "restitution":
            if settings["contact_steps"] is None:
                raise EngineSettingsError(
                    f"engine {name!r}: setting 'hunt_crossley_dissipation' = \"restitution\" "
                    "needs 'contact_steps' (the discrete map depends on them), got null")
        else:
            check_number(name, settings, "hunt_crossley_dissipation", low=0.0,
                         allow_none=True)
        check_int(name, settings, "max_steps", low=1)

    def _world_key(self, scene: Scene, settings) -> tuple:
        return world_key(scene, settings, geometry_key(scene))

    def _build(self, scene: Scene, settings, *, contacts: bool = True) -> World:
        return World(scene, settings)

    def _notes(self, scene: Scene, settings) -> tuple[str, ...]:
        if settings["hunt_crossley_dissipation"] != "restitution":
            return ("restitution e not used: Drake's bounce comes from its stiffness and "
                    "Hunt–Crossley dissipation",)
        if scene.restitution < MIN_RESTITUTION:
            return (f"e below {MIN_RESTITUTION} needs an infinite dissipation; used "
                    f"{MIN_RESTITUTION}",)
        return ()

    def _prepare(self, world, scene: Scene, settings, start, weights) -> tuple:
        qs, vs = [], []
        for x, y, angle, vx, vy, omega in start:
            qs.append((x, y, angle))
            vs.append((vx, vy, omega))
        stiffness = dissipation = None
        derived: dict = {}
        steps = settings["contact_steps"]
        if steps is not None or settings["hunt_crossley_dissipation"] == "restitution":
            effective_mass, speed = _contact_terms(scene)
        if steps is not None:
            omega = math.pi / (float(steps) * float(settings["time_step"]))
            stiffness = effective_mass * omega * omega
            derived["point_contact_stiffness"] = stiffness
        chosen = settings["hunt_crossley_dissipation"]
        if chosen == "restitution":
            a = discrete_dissipation(float(scene.restitution), float(steps))
            # a scene that does not approach (no impact to come) gets no dissipation
            dissipation = a / speed if speed > 0.0 else 0.0
            derived["hunt_crossley_dissipation"] = dissipation
        elif chosen is not None:
            dissipation = float(chosen)
        # Each geometry gets 2k: Drake's series combination gives the pair k.
        per_geometry = None if stiffness is None else 2.0 * stiffness
        properties = (per_geometry, dissipation, float(scene.friction))
        return tuple(qs), tuple(vs), properties, derived

    def _reset(self, world: World, prepared: tuple) -> dict:
        qs, vs, properties, derived = prepared
        world.hold_properties(properties)
        context, plant_context = world.context, world.plant_context
        context.SetTime(0.0)
        for joint, q, v in zip(world.joints, qs, vs):
            joint.set_translation(plant_context, q[:2])
            joint.set_rotation(plant_context, q[2])
            joint.set_translational_velocity(plant_context, v[:2])
            joint.set_angular_velocity(plant_context, v[2])
        world.simulator.Initialize()
        world.steps = 0
        world.sign = None
        return dict(derived)

    def _advance(self, world: World) -> None:
        world.steps += 1
        world.advance_to(world.steps * world.time_step)

    def _step(self, world: World) -> RawContacts | None:
        world.steps += 1
        world.advance_to(world.steps * world.time_step)
        # Sampled output port: the contact the step just taken solved (from its start state)
        world.update_contact_results()
        results = world.results
        if results is None:  # the world's first step with a read-out
            results = world.results = world.contact_results()
        count = results.num_point_pair_contacts()
        if count != 1:
            return self._several_pairs(world, results, count) if count else None
        # One point pair, the scene's two geometries (the ground and a body, or two bodies):
        # the fewest binding calls, every value as the general read-out below reads it.
        info = results.point_pair_contact_info(0)
        pair = info.point_pair()
        sign = world.sign
        if sign is None:  # the run's first contact: which of the pair is the scene's B
            sign = world.sign = 1.0 if pair.id_B == world.geometry_b else -1.0
        force_x, force_y, _ = info.contact_force().tolist()  # on Drake's body B
        n_x, n_y, _ = pair.nhat_BA_W.tolist()  # from Drake's body B into its body A
        point_x, point_y, _ = info.contact_point().tolist()
        h = world.time_step
        normal = (-sign * n_x, -sign * n_y)
        impulse_x = 0.0 + sign * force_x * h  # the general read-out's sum, from 0.0
        impulse_y = 0.0 + sign * force_y * h
        normal_impulse = abs(impulse_x * normal[0] + impulse_y * normal[1])
        return ((point_x, point_y, pair.depth),), normal, None, normal_impulse

    def _several_pairs(self, world: World, results, count: int) -> RawContacts:
        """The contact of a step with ``count`` point pairs (not met with one pair of
        geometries a scene; kept general)."""
        points = []
        impulse_x = impulse_y = 0.0
        normal = None
        h = world.time_step
        geometry_b = world.geometry_b
        # Vectors read as lists of floats: one call each, and float arithmetic (the same
        # IEEE operations as numpy's scalars, without their per-operation cost).
        for index in range(count):
            info = results.point_pair_contact_info(index)
            pair = info.point_pair()
            force_x, force_y, _ = info.contact_force().tolist()  # on Drake's body B
            if pair.id_B == geometry_b:
                sign = 1.0
            else:  # Drake's B is the scene's A (or the world): the other way round
                sign = -1.0
            if normal is None:
                n_ba = pair.nhat_BA_W.tolist()  # from Drake's body B into its body A
                normal = (-sign * n_ba[0], -sign * n_ba[1])
            impulse_x += sign * force_x * h
            impulse_y += sign * force_y * h
            point_x, point_y, _ = info.contact_point().tolist()
            points.append((point_x, point_y, pair.depth))
        normal_impulse = abs(impulse_x * normal[0] + impulse_y * normal[1])
        # The impulse vector is left to momentum (m_B·Δv_B, exact here): SAP's reported
        # contact forces agree with the velocity update only to its solver tolerance
        # (~1e-8 N s a step on the reference pair); the normal impulse still tells a step
        # that pushes from one that does not (exactly 0 once the force is gone).
        return tuple(points), normal, None, normal_impulse

    def _read_poses(self, world: World) -> tuple:
        x = world.state.tolist()  # [q; v], q and v (x, y, θ) and (v_x, v_y, ω) per body
        if world.positions_count == 3:  # one body (on the ground): the loop's hot path
            return ((x[0], x[1], x[2]),)
        return tuple([(x[i], x[i + 1], x[i + 2]) for i in range(0, world.positions_count, 3)])

    def _read_velocities(self, world: World) -> tuple:
        x = world.state.tolist()
        return tuple([(x[i], x[i + 1], x[i + 2])
                      for i in range(world.positions_count, len(x), 3)])

    def _out_of_plane_drift(self, world: World) -> float:
        """The body origin's z plus the tilt of its z axis times its size (0 by the joint)."""
        drift = 0.0
        for body, extent in zip(world.bodies, world.extents):
            pose = world.plant.EvalBodyPoseInWorld(world.plant_context, body)
            z_axis = pose.rotation().matrix()[:, 2]
            drift = max(drift, abs(pose.translation()[2])
                        + math.hypot(z_axis[0], z_axis[1]) * extent)
        return drift


ENGINE_CLASS = DrakeEngine
