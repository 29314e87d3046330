"""MuJoCo behind the engine contract: the hooks of :class:`MujocoEngine`.

What the engine does and why is told in the package's docstring (:mod:`harness.engines.mujoco`);
the model it builds, the world it keeps and the e <-> ζ map live in the package's other modules.
"""

from __future__ import annotations

import math
from collections import OrderedDict

import mujoco

from harness.engines.contract import (
    BENCH_REFERENCE_LABEL,
    Engine,
    RawContacts,
    StepTiming,
    body_extent,
)
from harness.engines.mujoco.model import (
    _EDITABLE_KINDS,
    _MAX_COMPILED,
    _Geometry,
    _geometry_key,
    _model_xml,
    _topology,
    _write_spec,
    _write_statistics,
)
from harness.engines.mujoco.presets import _CONES, _INTEGRATORS, _SOLVERS, PRESETS, SETTING_DOCS
from harness.engines.mujoco.restitution import MIN_RESTITUTION, _restitution_terms
from harness.engines.mujoco.world import _contact_rows, _force_view, _layout, _Model, _use_data
from harness.engines.settings import (
    EngineSettingsError,
    check_choice,
    check_int,
    check_number,
    check_vector,
)
from harness.scene import Scene

# Fraction of a step of free flight by which the start is past the touching pose.
_DETECTION_OVERLAP = 1e-6


def _snapshot(settings: dict) -> dict:
    """A copy of ``settings`` that later in-place edits of its lists cannot reach."""
    return {key: list(value) if isinstance(value, list) else value
            for key, value in settings.items()}



_mj_step = mujoco.mj_step
_reset_data = mujoco.mj_resetData
_set_const = mujoco.mj_setConst


#: The accurate preset's contact duration (s): 50 steps of 1e-5 s; the accuracy bench holds it
#: while it refines the steps.
BENCH_CONTACT_DURATION_S = 5e-4


class MujocoEngine(Engine):
    name = "mujoco"
    version = mujoco.__version__
    # What the rest of the harness reads about this engine (docs/engines.md, 'The engine
    # contract'): why it lands where it does, per engine and per preset, and its plot style.
    description = (
        "MuJoCo departs because it solves no rigid-body impact law: its contact is soft, a "
        "spring–damper that cannot pull, and the bounce follows from the damping ratio "
        "alone. Under defaults (critically damped) the scenario's e is not used at all: a "
        "1 m/s drop bounces at about 0.11 m/s whatever e. Friction is soft too: its rows "
        "carry only the contact's damping, so inside the cone the slip decays at that same "
        "rate and the contact ends with about e² of the slip left; at e = 1 there is no "
        "damping and therefore no friction at all. Its second preset, matched-bounce, picks "
        "the damping from e so that the bounce is e·|v_n|; but a bounce of e·|v_n| that "
        "removes only 1 − e² of the slip is not dissipative when the normal and tangential "
        "motions are coupled (m_nt ≠ 0): it creates kinetic energy in 11.5% of random rod "
        "and box-corner impacts (46 of 400, up to +210%), and each such run is flagged "
        "energy-gain. No MuJoCo setting that keeps the bounce stops this "
        "(docs/engines.md, 'MuJoCo').")
    preset_why = {
        "defaults": ("solref [0.02, 1] (critically damped): the scenario's e is not "
                     "used (a 1 m/s drop bounces at 0.11 m/s for any e), and soft "
                     "friction turns the body over the 20-step contact."),
        "accurate": ("matched-bounce: the damping ratio is chosen from e (solref "
                     "\"restitution\") over a 50-step contact, RK4 integration, "
                     "impedance 0.9999: the bounce is e·v within 1e-4, but friction "
                     "removes only 1 − e² of the slip and none at e = 1, so with "
                     "m_nt ≠ 0 it can create energy (runs flagged energy-gain)."),
    }
    plot_style = ("#009E73", "^")
    bench_impacts = (20, 150)
    bench_impact_seconds = 8e-4
    own_law = "converged"  # a soft contact solves no rigid law: its limit is itself
    bench_reference = BENCH_REFERENCE_LABEL  # the last point of bench_sweep, quick or full
    # A soft contact over ~20 (defaults) to ~50 (matched-bounce) steps: the point and the
    # lever arm move while it pushes (measured up to 1.3e-2 of |r||P| on the kit's scenes under
    # defaults, 4e-4 under matched-bounce); the verdicts' impulse-residual bar.
    impulse_band = 2e-2
    soft_contact = True
    restitution_unused = {"defaults": "MuJoCo has no restitution coefficient: the default "
                                      "solref [0.02, 1] sets the bounce (0.11 of a 1 m/s drop "
                                      "for any e)"}
    # matched-bounce steps a stiff soft contact for hundreds of steps: more bare stepping per
    # impact than every other pair together (`impact-harness bench --survey` measures it), so
    # a default survey of thousands of impacts per family runs MuJoCo at `defaults` only.
    survey_left_out = {"accurate": "more stepping per impact than every other pair together"}
    # The soft contact's damping ratio (solref's second entry) at its 0.02 s time constant:
    # what sets MuJoCo's bounce in place of e (`impact-harness calibrate mujoco`).
    calibration_knobs = (("solref", ([0.02, 0.5], [0.02, 1.0], [0.02, 2.0])),)
    presets = PRESETS
    setting_docs = SETTING_DOCS
    # A contact at exactly zero distance gets no constraint row in MuJoCo, so the start is a
    # hair (_DETECTION_OVERLAP of a step of free flight) past the touching pose.
    timing = StepTiming(lead_steps=0.0, overlap=_DETECTION_OVERLAP)
    # The soft contact's force fades continuously and MuJoCo makes it exactly 0 once the
    # constraint is inactive: only an exact 0 counts as no impulse.
    no_impulse_relative = 0.0


    @classmethod
    def time_step_overrides(cls, role: str, time_step: float) -> dict:
        """At ``accurate`` the contact's duration is tied to steps: keep the spring at the
        preset's 0.5 ms contact, so that the time step is what changes."""
        if role != "accurate":
            return {"time_step": time_step}
        return {"time_step": time_step,
                "contact_steps": max(1, int(round(BENCH_CONTACT_DURATION_S / time_step)))}

    @classmethod
    def bench_sweep(cls, quick: bool) -> list[tuple[str, str, dict]]:
        """The settings the accuracy bench measures (harness/bench/accuracy.py)."""
        points: list[tuple[str, str, dict]] = []
        points.append(("defaults", "defaults", {}))
        for timeconst in ((0.005, 0.001) if quick else (0.01, 0.005, 0.002, 0.001)):
            dt = timeconst / 20.0
            points.append((f"solref tc={timeconst:g} dt={dt:.2g}", "defaults",
                           {"solref": [timeconst, 1.0], "time_step": dt}))
        # The accurate preset's spring-damper with the contact's duration held at 0.5 ms, so
        # only the resolution changes: contact_steps steps of 0.5 ms / contact_steps.
        contact_steps = (5, 10, 20, 50, 100) if quick else (5, 10, 20, 30, 50, 100, 200)
        for integrator in ("Euler", "RK4"):
            for count in contact_steps:
                points.append((f"{integrator} contact_steps={count}", "accurate",
                               {"integrator": integrator, "contact_steps": count,
                                "time_step": BENCH_CONTACT_DURATION_S / count}))
        points.append((BENCH_REFERENCE_LABEL, "accurate",
                       {"integrator": "RK4", "contact_steps": 400,
                        "time_step": BENCH_CONTACT_DURATION_S / 400}))
        return points

    def _validate_engine_settings(self, settings) -> None:
        name = self.name
        check_choice(name, settings, "integrator", tuple(_INTEGRATORS))
        check_choice(name, settings, "cone", tuple(_CONES))
        check_choice(name, settings, "solver", tuple(_SOLVERS))
        check_int(name, settings, "iterations", low=1)
        check_number(name, settings, "tolerance", low=0.0)
        check_int(name, settings, "ls_iterations", low=1)
        check_int(name, settings, "noslip_iterations", low=0)
        check_number(name, settings, "noslip_tolerance", low=0.0)
        check_number(name, settings, "impratio", low=0.0, strict=True)
        check_number(name, settings, "contact_steps", low=1.0)
        check_vector(name, settings, "solimp", 5)
        check_number(name, settings, "margin", low=0.0)
        solref = settings["solref"]
        if solref != "restitution":
            check_vector(name, settings, "solref", 2)
            if (solref[0] > 0) != (solref[1] > 0):
                raise EngineSettingsError(
                    f"engine {name!r}: setting 'solref' must be [timeconst > 0, dampratio > 0] "
                    f"or [-stiffness <= 0, -damping <= 0] or \"restitution\", got {solref!r} "
                    "(MuJoCo falls back to its defaults on mixed signs)"
                )

    def _world_key(self, scene: Scene, settings) -> tuple:
        return _topology(scene)

    def _build(self, scene: Scene, settings, *, contacts: bool = True) -> _Model:
        """The topology's model, compiled from ``scene`` (which it then holds)."""
        model = mujoco.MjModel.from_xml_string(_model_xml(scene))
        count = len(scene.bodies)
        body_geoms = [mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, f"g{i}")
                      for i in range(count)]
        body_ids = [mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, f"b{i}")
                    for i in range(count)]
        extents = [body_extent(b.shape) for b in scene.bodies]
        data = mujoco.MjData(model)
        world = _Model(model, data, body_geoms, body_ids, extents,
                       geometry=_geometry_key(scene))
        _use_data(world, data)
        if all(body.shape.kind in _EDITABLE_KINDS for body in scene.bodies):
            m = model
            world.edits = (m.geom_size, m.geom_rbound, m.geom_aabb, m.bvh_aabb, m.body_mass,
                           m.body_inertia)
            world.bvh_rows = [int(m.body_bvhadr[body_id]) for body_id in body_ids]
        else:
            world.compiled = OrderedDict({world.geometry: [model, None]})
            world.datas = {_layout(model): data}
        return world

    def _hold(self, world: _Model, geometry: _Geometry) -> None:
        """Make ``world`` hold ``geometry``: what a fresh compile of it gives, to the bit.

        Editable shapes: the sizes, bounding volumes, masses and inertias are written into
        the model, ``mj_setConst`` derives the rest (subtree masses, ``invweight0``,
        ``dof_M0``, ``dof_length``) and :func:`_write_statistics` the statistics
        (tests/engines/test_mujoco_geometry.py compares every array with a compile).
        Polygons: the topology's spec with the scene's values (:func:`_write_spec`),
        compiled (kept, ``_MAX_COMPILED`` at most).
        """
        if geometry.bodies is not None:
            sizes, rbounds, aabbs, bvhs, masses, inertias = world.edits
            for geom_id, body_id, bvh_row, (size, rbound, aabb, bvh, mass, inertia) in zip(
                    world.body_geoms, world.body_ids, world.bvh_rows, geometry.bodies):
                sizes[geom_id] = size
                rbounds[geom_id] = rbound
                aabbs[geom_id] = aabb
                bvhs[bvh_row] = bvh
                masses[body_id] = mass
                inertias[body_id] = inertia
            m = world.model
            _set_const(m, world.data)
            _write_statistics(m, [values[1] for values in geometry.bodies],
                              [values[4] for values in geometry.bodies], geometry.key[0])
        else:
            compiled = world.compiled
            compiled[world.geometry][1] = world.configured  # what the outgoing model holds
            entry = compiled.get(geometry.key)
            if entry is None:
                if world.spec is None:  # parsed once, from any scene of the topology
                    world.spec = mujoco.MjSpec.from_string(_model_xml(geometry.scene))
                spec = world.spec.copy()  # compiling fills a spec's mesh faces and normals
                _write_spec(spec, geometry)
                entry = compiled[geometry.key] = [spec.compile(), None]
                while len(compiled) > _MAX_COMPILED:
                    compiled.popitem(last=False)
            compiled.move_to_end(geometry.key)
            if world.force_views:  # another model, maybe other options: other places
                world.force_views = {}
            model = world.model = entry[0]
            world.configured = entry[1]
            layout = _layout(model)
            data = world.datas.get(layout)
            if data is None:
                data = world.datas[layout] = mujoco.MjData(model)
            if data is not world.data:
                _use_data(world, data)
        world.geometry = geometry.key
        world.extents = geometry.extents

    def _notes(self, scene: Scene, settings) -> tuple[str, ...]:
        if settings["solref"] != "restitution":
            return ("restitution e not used: MuJoCo's bounce comes from solref/solimp",)
        if scene.restitution < MIN_RESTITUTION:
            note = (f"e below {MIN_RESTITUTION} needs an infinite damping ratio; "
                    f"used {MIN_RESTITUTION}")
            return (note,)
        return ()

    def _prepare(self, world: _Model, scene: Scene, settings, start, weights) -> tuple:
        qpos, qvel = [], []
        for x, y, angle, vx, vy, omega in start:
            qpos += [x, y, -angle]
            qvel += [vx, vy, -omega]
        # The checks computed the inertias (a polygon's costs tens of µs): reused.
        return scene, settings, qpos, qvel, _Geometry(scene, [inertia for _, inertia in weights])

    def _reset(self, world: _Model, prepared: tuple) -> dict:
        """The scene's geometry, the run's options and contact parameters, fresh data, the
        start state."""
        scene, settings, qpos, qvel, geometry = prepared
        held = world.geometry
        if held is not geometry.key:
            if held != geometry.key:
                self._hold(world, geometry)
            world.geometry = geometry.key  # equal: the next run compares identities
        derived = self._configure(world, scene, settings)
        _reset_data(world.model, world.data)
        world.qpos[:] = qpos
        world.qvel[:] = qvel
        world.normal_sign = 0.0
        world.last_depth = math.inf
        return derived

    def _configure(self, entry: _Model, scene: Scene, settings: dict) -> dict:
        """Make the model hold every option and contact parameter of this run; its ``derived``.

        What the model already holds is not written again (compared by value, never by
        identity): the options and the settings' contact parameters when the settings are
        the same, each of the pair's ``solref``, ``condim`` and friction that ``e`` and ``μ``
        leave as they were.
        """
        e, mu = scene.restitution, scene.friction
        last = entry.configured
        if last is None or last[0] != settings:
            self._write_options(entry, settings)
            last = None
        if last is None or last[1] != e or last[2] != mu:
            entry.configured = last = (last[0] if last else _snapshot(settings), e, mu,
                                       self._write_pair(entry, scene, settings, last))
        derived = last[3]
        return {**derived, "solref": list(derived["solref"])}  # the caller's own copy

    def _write_options(self, entry: _Model, settings: dict) -> None:
        m = entry.model
        if entry.force_views:  # the constraint arrays' places may differ under others
            entry.force_views = {}
        opt = m.opt
        dt = float(settings["time_step"])
        entry.dt = dt
        opt.timestep = dt
        opt.integrator = _INTEGRATORS[settings["integrator"]]
        opt.cone = _CONES[settings["cone"]]
        opt.solver = _SOLVERS[settings["solver"]]
        opt.iterations = int(settings["iterations"])
        opt.tolerance = float(settings["tolerance"])
        opt.ls_iterations = int(settings["ls_iterations"])
        opt.noslip_iterations = int(settings["noslip_iterations"])
        opt.noslip_tolerance = float(settings["noslip_tolerance"])
        opt.impratio = float(settings["impratio"])
        m.geom_solimp[:] = [float(v) for v in settings["solimp"]]
        m.geom_margin[:] = float(settings["margin"])
        m.geom_gap[:] = 0.0

    def _write_pair(self, entry: _Model, scene: Scene, settings: dict,
                    held: tuple | None) -> dict:
        """The pair's contact parameters (from ``e``, ``μ`` and the settings); ``derived``.

        ``held``: what the model holds under the same settings (``_configure``'s record),
        whose equal values are not written again; ``None``: write every one.
        """
        m = entry.model
        derived: dict = {}
        if settings["solref"] == "restitution":
            solref, zeta, target = _restitution_terms(
                scene.restitution, float(settings["time_step"]),
                float(settings["contact_steps"]))
            derived["damping_ratio"] = zeta
            derived["restitution_target"] = target
        else:
            solref = [float(v) for v in settings["solref"]]
        derived["solref"] = solref
        mu = float(scene.friction)
        condim = 1 if mu == 0.0 else 3
        derived["condim"] = condim
        if held is None or held[3]["solref"] != solref:
            m.geom_solref[:] = solref
        if held is None or held[3]["condim"] != condim:
            m.geom_condim[:] = condim
        if held is None:
            m.geom_friction[:] = 0.0
        if held is None or float(held[2]) != mu:
            m.geom_friction[entry.body_geoms[0]] = [mu, 0.0, 0.0]
        return derived

    def _advance(self, world: _Model) -> None:
        _mj_step(world.model, world.data)

    def _step(self, world: _Model) -> RawContacts | None:
        d = world.data
        _mj_step(world.model, d)
        # Active contact constraints only: MuJoCo reports a contact at dist >= margin (its
        # "gap" zone) but gives it no constraint row.
        constraints = d.nefc
        if not constraints:
            return None
        count = d.ncon
        sign = world.normal_sign
        if sign == 0.0:  # the run's first contact
            if world.contact_rows is None:  # the data's first
                _contact_rows(world, d.contact)
            # A pair's geom order is fixed: the normal points from geom1 into geom2, and
            # body A's geom second reverses it.
            two_bodies = len(world.body_geoms) == 2
            sign = world.normal_sign = (
                -1.0 if two_bodies and world.first_geom2.item(0) == world.body_geoms[0]
                else 1.0)
        if count == 1:
            distance, x, _, z, frame_x, _, frame_z = world.first_contact.tolist()
            depth = -distance
            points = ((x, z, depth),)
        elif count == 2:  # a prism's edge (±y): a third of the contact steps, unrolled
            (distance, x, _, z, frame_x, _, frame_z), (other, other_x, _, other_z, _, _, _) = (
                world.first_two.tolist())
            depth, other = -distance, -other
            points = ((x, z, depth), (other_x, other_z, other))
            if other > depth:  # max() of the two
                depth = other
        else:
            rows = world.contact_rows[:count].tolist()
            points = tuple([(row[1], row[3], -row[0]) for row in rows])
            frame_x, frame_z = rows[0][4], rows[0][6]
            depth = max([point[2] for point in points])
        length = math.hypot(frame_x, frame_z)
        normal = (sign * frame_x / length, sign * frame_z / length)
        # No impulse vector per step (the run's comes from momentum). While the penetration
        # still grows the spring-damper pushes (k·r + b·r' > 0), so the forces are read only
        # once it shrinks: the step carries force while any constraint force is non-zero.
        growing = depth >= world.last_depth
        world.last_depth = depth
        if growing:
            return points, normal, None, None
        forces = world.force_views.get((count, constraints))
        if forces is None:
            forces = _force_view(world, count, constraints)
        return points, normal, None, sum(map(abs, forces.tolist())) * world.dt

    def _read_poses(self, world: _Model) -> tuple:
        # Python floats once (tolist): the same doubles as indexing the arrays, fewer calls.
        qpos = world.qpos.tolist()
        if len(qpos) == 3:
            return ((qpos[0], qpos[1], -qpos[2]),)
        if len(qpos) == 6:  # two bodies: unpacked, no loop (every contact step)
            x, y, angle, other_x, other_y, other_angle = qpos
            return ((x, y, -angle), (other_x, other_y, -other_angle))
        return tuple([(qpos[i], qpos[i + 1], -qpos[i + 2]) for i in range(0, len(qpos), 3)])

    def _read_velocities(self, world: _Model) -> tuple:
        qvel = world.qvel.tolist()
        if len(qvel) == 3:
            return ((qvel[0], qvel[1], -qvel[2]),)
        return tuple([(qvel[i], qvel[i + 1], -qvel[i + 2]) for i in range(0, len(qvel), 3)])

    def _out_of_plane_drift(self, world: _Model) -> float:
        """The centre's y, plus the tilt of the body's y axis times its size."""
        drift = 0.0
        xpos, xmat = world.xpos.tolist(), world.xmat.tolist()
        for body_id, extent in zip(world.body_ids, world.extents):
            rotation = xmat[body_id]  # row-major 3x3: the body's y axis is entries 1, 4, 7
            drift = max(drift,
                        abs(xpos[body_id][1]) + math.hypot(rotation[1], rotation[7]) * extent)
        return drift



ENGINE_CLASS = MujocoEngine
