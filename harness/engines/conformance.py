"""The conformance kit an adapter author runs: ``check_engine(MyEngine)`` -> ``[]`` when the
adapter keeps the engine contract (:mod:`harness.engines.contract`), else one line per
broken promise.

What it checks, on the hand-built reference scenes (:func:`harness.scene.reference_scenes`)
under each preset role:

* the class attributes the rest of the harness reads are present and well formed (name,
  version, presets with the same keys as ``setting_docs``, description, per-preset why,
  plot style, speed caps, timing, calibration knobs or why there are none);
* settings: each preset resolves and validates, also at every value of a calibration knob;
  an unknown key and a non-positive time step are refused with
  :class:`EngineSettingsError`;
* runs: every scene the engine supports ends separated (no blow-up, no missing contact, no
  step cap; a multi-contact or out-of-plane status is a finding, not a fault), reports at
  least one contact, with finite velocities; ``run_many`` of the scenes equals ``run`` of
  each bit for bit (rerun against rerun on one machine), and a second ``run`` equals the
  first (fresh per-run state); every world key is hashable;
* physics every engine keeps under every preset, rigid or soft, on a few canonical disks
  (:func:`physics_scenes`; a disk's lever arm from its centre to a ground contact does not
  turn with it, so these hold however long the contact lasts):

  - the reported normal and impulses explain the change of speeds, ``M Δu = Jᵀ P`` at the
    scene's contact point (docs/theory.md, (A22)/(A23)), within ``rounding + impulse_band·|P|``
    (the engine's traits): on body B, and with the opposite sign on body A;
  - the normal points out of the ground (two bodies: from A into B) and carries a positive
    normal impulse; the spin changes with the sign of ``r × P``, the moment of the
    tangential impulse at its offset from the centre;
  - every reported contact point lies where the scene touches body B, at the step's pose
    (the verdicts read the touching feature from it), within one step of travel, twice over,
    plus the overlap and 1 mm (the contract tests' bound);
  - friction is used: an oblique impact with μ > 0 changes the slip at the contact by at
    least half what the laws' Newton–Coulomb answer does, and with μ = 0 leaves it within
    :data:`FRICTIONLESS_SLIP` of itself;
  - the pair's μ is the one used (Coulomb): a disk sliding throughout the impact gets a
    tangential impulse of μ times the normal one, against the slip, within :data:`PAIR_BAND`
    (a μ doubled, halved or combined with the engine's own value shows here);
  - restitution is used: the separation speed of a direct impact grows with e by at least
    half the laws' growth, unless the preset declares it does not (``restitution_unused``);
    and it is the pair's e: the separation speed is the laws' within :data:`PAIR_BAND`;
  - a preset that claims a law meets it: under ``accurate``, an engine whose ``own_law`` is a
    law (:data:`harness.laws.LAW_NAMES`) departs from ``planar_impact``'s answer by at most
    :data:`OWN_LAW_DEPARTURE` on each canonical case, and it builds at least one of the
    scenes where the laws part (:data:`PARTING_SCENES`; on a disk they agree, so a claim
    checked on disks alone is no check); one whose own law is ``converged`` names its
    reference point in every bench sweep (``bench_reference``).

A scene the engine refuses with :class:`UnsupportedScene` is skipped, not failed, here and
in the contract tests alike (tests/engines/test_contract.py); the canonical disks must run.
"""

from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np

from harness.engines import load_engine
from harness.engines.contract import (
    Engine,
    EngineRun,
    Status,
    StepTiming,
    UnsupportedScene,
    ke_norm,
)
from harness.engines.settings import EngineSettingsError
from harness.laws import LAW_NAMES
from harness.scene import Body, Disk, Scene
from harness.scene.geometry import impact_problem, scene_contact
from harness.scene.reference import reference_scenes

# Statuses that break the contract on a reference scene; the others (multi-contact,
# out-of-plane) are findings about the engine that the verdicts flag, not adapter faults.
_BROKEN = (Status.BLOW_UP, Status.NO_CONTACT, Status.NO_SEPARATION)
# The preset roles every engine has (the registry's PRESET_ROLES, which imports this layer).
_ROLES = ("defaults", "accurate")
# What an engine may declare as its own law (the accuracy bench measures against it): a law
# of the registry, or "converged" (its own run at the finest settings).
_OWN_LAWS = (*LAW_NAMES, "converged")
#: Largest departure ``‖u_engine − u_law‖_M / ‖u_before‖_M`` of an ``accurate`` run from the
#: engine's own law on a canonical case (the accuracy bench's tighter threshold, 0.1%): the
#: shipped rigid engines reach 5e-8 or less (Box2D's float32), the toy 1e-16. Kind (docs/
#: verdicts.md, 'Same answers on every CPU'): a decision with a stated band on an engine's
#: accuracy (its discretisation and its solver's stopping), not a comparison of rounding.
OWN_LAW_DEPARTURE = 1e-3
#: With μ = 0 the slip at the contact may move by at most this fraction of itself (measured:
#: 9.4e-4 under pybullet's defaults, 0 for every other engine and preset).
FRICTIONLESS_SLIP = 1e-2
#: With μ > 0 (or a larger e) the slip (the separation speed) must move by at least this
#: fraction of what the laws' answer moves it by (measured on the kit's scenes: MuJoCo's
#: soft friction 0.74 under matched-bounce, every other engine and preset 0.999 to 1.034; the
#: separation speed's growth with e 0.999 to 1, MuJoCo's and Drake's defaults aside,
#: restitution_unused).
USED_FRACTION = 0.5
#: The pair gets exactly its e and μ (the contract's guarantee): a direct impact's separation
#: speed, and a sliding impact's ratio of tangential to normal impulse over μ, may depart from
#: the laws' by at most this fraction (measured: the separation speed 4.9e-3 under pybullet's
#: defaults, 1e-4 or less elsewhere, MuJoCo's and Drake's defaults aside, restitution_unused;
#: the impulse ratio 1e-6 or less for every engine and preset but Drake's defaults, 2.4e-5:
#: its regularised friction).
PAIR_BAND = 0.05


def check_engine(engine: type[Engine] | Engine | str) -> list[str]:
    """The contract's promises ``engine`` (a class, an instance or a registered name)
    breaks, one line each; an empty list when it conforms."""
    if isinstance(engine, str):
        instance = load_engine(engine)
    elif isinstance(engine, type):
        instance = engine()
    else:
        instance = engine
    failures = _attribute_failures(type(instance))
    if failures:  # runs need well-formed presets
        return failures
    failures += _settings_failures(instance)
    failures += _world_key_failures(instance)
    if failures:  # runs need settings that resolve and worlds the cache can keep
        return failures
    failures += _run_failures(instance)
    failures += _physics_failures(instance)
    return failures


def _attribute_failures(cls: type[Engine]) -> list[str]:
    failures = []
    where = f"{cls.__name__}"
    if not (isinstance(cls.name, str) and cls.name):
        failures.append(f"{where}.name: a non-empty string, got {cls.name!r}")
    if not isinstance(cls.version, str):
        failures.append(f"{where}.version: a string, got {cls.version!r}")
    docs = cls.setting_docs
    if not (isinstance(docs, Mapping) and all(isinstance(v, str) and v for v in docs.values())):
        failures.append(f"{where}.setting_docs: a mapping of key -> one line of text")
    elif not {"time_step", "max_steps", "approach_steps"} <= set(docs):
        failures.append(f"{where}.setting_docs: lacks a common key "
                        "(time_step, max_steps, approach_steps)")
    presets = cls.presets
    if not isinstance(presets, Mapping) or set(presets) != set(_ROLES):
        failures.append(f"{where}.presets: exactly {list(_ROLES)}, got "
                        f"{list(presets) if isinstance(presets, Mapping) else presets!r}")
    elif isinstance(docs, Mapping):
        for role, values in presets.items():
            if set(values) != set(docs):
                failures.append(f"{where}.presets[{role!r}]: keys differ from setting_docs "
                                f"by {sorted(set(values) ^ set(docs))}")
    if not (isinstance(cls.description, str) and cls.description.strip()):
        failures.append(f"{where}.description: one paragraph of text, got {cls.description!r}")
    why = cls.preset_why
    if not (isinstance(why, Mapping) and set(why) <= set(_ROLES)
            and all(isinstance(v, str) and v for v in why.values())):
        failures.append(f"{where}.preset_why: role -> one line, roles among {list(_ROLES)}, "
                        f"got {why!r}")
    style = cls.plot_style
    if not (isinstance(style, tuple) and len(style) == 2
            and all(isinstance(v, str) and v for v in style)):
        failures.append(f"{where}.plot_style: (colour, marker) strings, got {style!r}")
    caps = cls.speed_caps
    if caps is not None and not (
            isinstance(caps, tuple) and len(caps) == 2
            and all(isinstance(v, float) and math.isfinite(v) and v > 0 for v in caps)):
        failures.append(f"{where}.speed_caps: None or (linear m/s, angular rad/s) positive "
                        f"finite floats, got {caps!r}")
    if not (isinstance(cls.rounding, float) and 0.0 < cls.rounding < 1e-3):
        failures.append(f"{where}.rounding: a float in (0, 1e-3), got {cls.rounding!r}")
    statuses = cls.reference_statuses
    if not (isinstance(statuses, Mapping) and all(
            isinstance(key, tuple) and len(key) == 2 and key[1] in _ROLES
            and value in set(Status) for key, value in statuses.items())):
        failures.append(f"{where}.reference_statuses: (scene, role) -> a status, got "
                        f"{statuses!r}")
    if not isinstance(cls.own_law, str) or cls.own_law not in _OWN_LAWS:
        failures.append(f"{where}.own_law: one of {list(_OWN_LAWS)}, got {cls.own_law!r}")
    elif cls.own_law == "converged":
        for quick in (True, False):
            labels = [label for label, _, _ in cls.bench_sweep(quick)]
            if cls.bench_reference not in labels:
                failures.append(
                    f"{where}.bench_reference: own_law 'converged' needs the label of its "
                    f"converged point in bench_sweep(quick={quick}), got "
                    f"{cls.bench_reference!r}; labels: {labels}")
    if not (isinstance(cls.impulse_band, float) and 0.0 <= cls.impulse_band < 0.1):
        failures.append(f"{where}.impulse_band: a float in [0, 0.1), got {cls.impulse_band!r}")
    if not isinstance(cls.soft_contact, bool):
        failures.append(f"{where}.soft_contact: True or False, got {cls.soft_contact!r}")
    unused = cls.restitution_unused
    if not (isinstance(unused, Mapping) and set(unused) <= set(_ROLES)
            and all(isinstance(v, str) and v for v in unused.values())):
        failures.append(f"{where}.restitution_unused: role -> why, roles among "
                        f"{list(_ROLES)}, got {unused!r}")
    left_out = cls.survey_left_out
    if not (isinstance(left_out, Mapping) and set(left_out) <= set(_ROLES)
            and all(isinstance(v, str) and v for v in left_out.values())):
        failures.append(f"{where}.survey_left_out: role -> why, roles among {list(_ROLES)}, "
                        f"got {left_out!r}")
    impacts = cls.bench_impacts
    if not (isinstance(impacts, tuple) and len(impacts) == 2
            and all(isinstance(v, int) and v > 0 for v in impacts)):
        failures.append(f"{where}.bench_impacts: (quick, full) positive ints, got {impacts!r}")
    if not isinstance(cls.timing, StepTiming):
        failures.append(f"{where}.timing: a StepTiming, got {cls.timing!r}")
    knobs = cls.calibration_knobs
    if not (isinstance(knobs, tuple) and all(
            isinstance(knob, tuple) and len(knob) == 2 and isinstance(docs, Mapping)
            and knob[0] in docs and isinstance(knob[1], tuple) and len(knob[1]) >= 2
            for knob in knobs)):
        failures.append(f"{where}.calibration_knobs: ((setting of setting_docs, (two or more "
                        f"values)), ...), got {knobs!r}")
    if not knobs and not (isinstance(cls.no_calibration_knobs_why, str)
                          and cls.no_calibration_knobs_why.strip()):
        failures.append(f"{where}.no_calibration_knobs_why: one line of text, got "
                        f"{cls.no_calibration_knobs_why!r}")
    return failures


def _settings_failures(engine: Engine) -> list[str]:
    failures = []
    for role in _ROLES:
        try:
            resolved = engine.settings(role)
            engine.validate_settings(resolved)
        except (ValueError, TypeError) as error:
            failures.append(f"settings({role!r}) fails: {error}")
            continue
        for bad, what in (({"no-such-setting": 1}, "an unknown key"),
                          ({"time_step": -1.0}, "a negative time_step")):
            try:
                engine.settings(role, bad)
            except EngineSettingsError:
                continue
            except Exception as error:  # noqa: BLE001 - the kit reports any wrong exception
                failures.append(f"settings({role!r}, {bad}) raises {type(error).__name__}, "
                                "not EngineSettingsError")
                continue
            failures.append(f"settings({role!r}, {bad}) accepts {what}")
        for knob, values in engine.calibration_knobs:  # every value calibrate may try
            for value in values:
                try:
                    engine.validate_settings(engine.settings(role, {knob: value}))
                except (ValueError, TypeError) as error:
                    failures.append(f"calibration_knobs: settings({role!r}, {{{knob!r}: "
                                    f"{value!r}}}) fails: {error}")
    return failures


def _world_key_failures(engine: Engine) -> list[str]:
    """The world cache is a dict: ``_world_key`` must hash for every scene and preset."""
    scenes = [scene for scene, _, _ in reference_scenes().values()]
    scenes += physics_scenes().values()
    for role in _ROLES:
        settings = engine.settings(role)
        for scene in scenes:
            try:
                hash(engine._world_key(scene, settings))
            except TypeError as error:
                return [f"_world_key({scene.name!r}, preset {role!r}) returns an unhashable "
                        f"key ({error}); a world key is a dict key (a tuple of numbers and "
                        "strings), for every scene"]
    return []


def _run_failures(engine: Engine) -> list[str]:
    failures = []
    scenes = [scene for scene, _, _ in reference_scenes().values()]
    for role in _ROLES:
        settings = engine.settings(role)
        runs, supported = [], []
        for scene in scenes:
            label = f"run({scene.name!r}, preset {role!r})"
            try:
                run = engine.run(scene, settings)
            except UnsupportedScene:
                continue
            except Exception as error:  # noqa: BLE001 - the kit reports, it does not stop
                failures.append(f"{label} raises {type(error).__name__}: {error}")
                continue
            supported.append(scene)
            runs.append(run)
            if run.status in _BROKEN or not run.separated:
                failures.append(f"{label}: status {run.status} ({run.status_reason}), "
                                f"separated {run.separated}; expected a separation")
            if not run.contacts:
                failures.append(f"{label}: no contact reported")
            if (run.out_of_plane_drift is None) is not engine.native_2d:
                failures.append(f"{label}: out_of_plane_drift {run.out_of_plane_drift!r} "
                                f"but native_2d is {engine.native_2d}")
            if not all(math.isfinite(v) for body in run.velocities for v in body):
                failures.append(f"{label}: non-finite velocities {run.velocities}")
            if engine.run(scene, settings) != run:
                failures.append(f"{label}: a second run differs from the first")
        if not supported:
            failures.append(f"preset {role!r}: the engine supports none of the reference "
                            "scenes")
            continue
        try:
            batched = engine.run_many(supported, settings)
        except Exception as error:  # noqa: BLE001
            failures.append(f"run_many(preset {role!r}) raises {type(error).__name__}: {error}")
            continue
        for scene, one, many in zip(supported, runs, batched, strict=True):
            if one != many:
                failures.append(f"run_many(preset {role!r}): scene {scene.name!r} differs "
                                "from run() (not bit for bit)")
    return failures


# ---------------------------------------------------------------------- physics
#: The canonical cases: a uniform disk (r 0.1 m, 1 kg) on the ground, oblique (1, -2) m/s with
#: μ 0.3 (it sticks under Newton–Coulomb: the slip of 1 m/s stops) and μ 0, and direct at
#: 3 m/s (above Box2D's 1 m/s and pybullet's 0.2 m/s restitution thresholds) with e 0.2 and
#: 0.8; and the reference pair of disks (two free bodies, normal along 30°). Every law gives
#: the disks one answer; the own-law check adds the reference 45° rod and box corner under
#: ``accurate``, where they part (:data:`PARTING_SCENES`; slip reversal under Poisson:
#: docs/theory.md, 'The velocity-level law (newton-lcp)'). Besides, a 2 kg disk sliding
#: throughout, (2, -2) m/s with μ 0.1 and e 0.5 (Coulomb's bound takes 0.9 m/s of its 2 m/s
#: slip; slower than would show pybullet's link damping under defaults beyond its
#: impulse_band): its friction impulse is μ times the normal one, and its mass, other than
#: 1 kg, shows a reported impulse that is Δv, not m Δv, on an engine of the ground only.
RESTITUTIONS = (0.2, 0.8)
#: The reference scenes where the laws part, against which the own-law check holds a claim:
#: the 45° rod and the box on a corner (any two laws differ there by 0.7% or more, above
#: OWN_LAW_DEPARTURE), each where the engine builds it; one of them must run.
PARTING_SCENES = ("rod-45", "box-corner")


def physics_scenes() -> dict[str, Scene]:
    """The scenes of the kit's physics checks, by name (see :data:`RESTITUTIONS`)."""
    def disk(name, velocity, e, mu, mass=1.0):
        body = Body("disk", Disk(0.1), mass, (0.0, 0.1), 0.0, velocity, 0.0)
        return Scene((body,), e, mu, ground=True, name=f"kit-{name}")

    low, high = RESTITUTIONS
    return {"oblique": disk("oblique", (1.0, -2.0), 0.5, 0.3),
            "frictionless": disk("frictionless", (1.0, -2.0), 0.5, 0.0),
            "direct-low-e": disk("direct-low-e", (0.0, -3.0), low, 0.3),
            "direct-high-e": disk("direct-high-e", (0.0, -3.0), high, 0.3),
            "sliding": disk("sliding", (2.0, -2.0), 0.5, 0.1, mass=2.0),
            "two-disks": reference_scenes()["two-disks"][0]}


def _slip(scene: Scene, velocities) -> float:
    """Tangential speed of the disk's lowest point (+x), ``v_x + r ω``."""
    (v_x, _, omega), = velocities
    return v_x + scene.bodies[0].shape.radius * omega


def _law_answer(scene: Scene, law: str) -> np.ndarray:
    contact = scene_contact(scene)
    problem = impact_problem(scene, contact.point, contact.normal)
    return np.asarray(problem.solve(mu=scene.friction, e=scene.restitution, law=law).u_after,
                      dtype=float)


def _momentum_failures(engine: Engine, scene: Scene, run: EngineRun,
                       where: str) -> list[tuple[str, str]]:
    """``M Δu = Jᵀ P``: the reported impulse on body B (and its opposite on body A) at the
    scene's contact point, against each body's change of momentum."""
    n_x, n_y = run.contact_normal
    t_x, t_y = n_y, -n_x  # the contract's t
    p_x = run.normal_impulse * n_x + run.tangential_impulse * t_x
    p_y = run.normal_impulse * n_y + run.tangential_impulse * t_y
    size = math.hypot(p_x, p_y)
    tolerance = engine.rounding + engine.impulse_band * size
    point = scene_contact(scene).point
    failures = []  # (promise, sentence)
    bodies = scene.bodies
    for index, (body, (v_x, v_y, omega)) in enumerate(zip(bodies, run.velocities)):
        sign = 1.0 if index == len(bodies) - 1 else -1.0  # body A takes the opposite impulse
        which = "body B" if sign > 0 else "body A"
        momentum = (body.mass * (v_x - body.velocity[0]), body.mass * (v_y - body.velocity[1]))
        if math.hypot(momentum[0] - sign * p_x, momentum[1] - sign * p_y) > tolerance:
            failures.append(("momentum",
                f"{where}: the reported impulse does not explain the change of momentum of "
                f"{which}: m Δv = ({momentum[0]:.6g}, {momentum[1]:.6g}) N s but the normal "
                f"and impulses reported give ({sign * p_x:.6g}, {sign * p_y:.6g}) N s "
                f"(allowed {tolerance:.3g}: rounding + impulse_band·|P|)"))
            continue
        lever = (float(point[0]) - body.position[0], float(point[1]) - body.position[1])
        moment = sign * (lever[0] * p_y - lever[1] * p_x)  # r × P
        spin = body.moment_of_inertia * (omega - body.angular_velocity)
        arm = math.hypot(*lever)
        allowed = arm * tolerance
        if abs(moment) > allowed and spin * moment < 0:
            failures.append(("spin sign",
                f"{where}: the spin of {which} turns against the moment of the impulse: "
                f"I Δω = {spin:.6g} N m s but r × P = {moment:.6g} N m s (a tangential impulse "
                "at an offset from the centre turns the body its way: a sign flipped?)"))
        elif abs(spin - moment) > allowed:
            failures.append(("moment",
                f"{where}: the reported impulse does not explain the change of spin of "
                f"{which}: I Δω = {spin:.6g} N m s but r × P = {moment:.6g} N m s at the "
                f"contact point (allowed {allowed:.3g}: |r|·(rounding + impulse_band·|P|))"))
    return failures


def _normal_failures(scene: Scene, run: EngineRun, where: str) -> list[tuple[str, str]]:
    n_x, n_y = run.contact_normal
    if scene.ground:
        outward, what = (0.0, 1.0), "out of the ground (+y)"
    else:
        a, b = scene.bodies
        outward = (b.position[0] - a.position[0], b.position[1] - a.position[1])
        what = "from body A into body B"
    failures = []
    if n_x * outward[0] + n_y * outward[1] <= 0.0:
        failures.append(("normal", f"{where}: the contact normal ({n_x:.6g}, {n_y:.6g}) does "
                                   f"not point {what}: a normal flipped?"))
    elif not run.normal_impulse > 0.0:
        failures.append(("normal impulse", f"{where}: the normal impulse "
                         f"{run.normal_impulse!r} N s is not positive: a contact pushes the "
                         "bodies apart"))
    return failures


def _point_failures(scene: Scene, run: EngineRun, where: str) -> list[tuple[str, str]]:
    """Each reported point where the scene touches body B at the step's reported pose: a
    disk's lowest point stays its lowest, so on the ground every step's; two disks' line of
    centres turns as they roll on each other during a soft contact, so there the first
    step's. Allowed: the pose is read after the step, and an engine may report the point
    before the step moves the bodies or anywhere across the overlap, so twice one step of
    body B's travel, plus the run's largest overlap and 1 mm (the contract tests' bound; the
    shipped engines reach 0.4 of it at most, pybullet's and Box2D's direct impacts)."""
    body = scene.bodies[-1]
    point = scene_contact(scene).point
    offset = (float(point[0]) - body.position[0], float(point[1]) - body.position[1])
    speed = max(math.hypot(*body.velocity), math.hypot(*run.velocities[-1][:2]))
    reach = 2.0 * float(run.settings["time_step"]) * speed + run.max_penetration + 1e-3
    steps = run.contacts if scene.ground else run.contacts[:1]
    for step in steps:
        x, y, _ = step.poses[-1]
        for found in step.points:
            miss = math.hypot(found.x - x - offset[0], found.y - y - offset[1])
            if not miss <= reach:
                return [("point",
                    f"{where}: the reported contact point ({found.x:.6g}, {found.y:.6g}) of step "
                    f"{step.step} is {miss:.3g} m from where the scene touches body B (its "
                    f"centre ({x:.6g}, {y:.6g}) + ({offset[0]:.6g}, {offset[1]:.6g})), more "
                    f"than two steps of travel plus the overlap ({reach:.3g} m): a point on "
                    "the wrong body, side or frame?")]
    return []


def _physics_failures(engine: Engine) -> list[str]:
    scenes = physics_scenes()
    failures = []
    for role in _ROLES:
        settings = engine.settings(role)
        runs: dict[str, EngineRun] = {}
        broken: dict[str, list[str]] = {}  # promise -> its sentences, one per scene
        for key, scene in scenes.items():
            where = f"physics, preset {role!r}, scene {scene.name!r}"
            try:
                run = engine.run(scene, settings)
            except UnsupportedScene as error:
                if key == "two-disks":  # an engine of one body against the ground
                    continue
                failures.append(f"{where}: the engine refuses a disk on the ground ({error}); "
                                "the kit cannot check its physics")
                continue
            except Exception as error:  # noqa: BLE001 - the kit reports, it does not stop
                failures.append(f"{where}: raises {type(error).__name__}: {error}")
                continue
            if run.contact_normal is None or run.normal_impulse is None or not all(
                    math.isfinite(v) for body in run.velocities for v in body):
                failures.append(f"{where}: no contact or non-finite speeds (status "
                                f"{run.status}): the physics cannot be checked")
                continue
            found = (_normal_failures(scene, run, where)
                     + _momentum_failures(engine, scene, run, where)
                     + _point_failures(scene, run, where))
            for promise, sentence in found:
                broken.setdefault(promise, []).append(sentence)
            if not found:  # the checks below read speeds the impulse explains
                runs[key] = run
        for sentences in broken.values():  # one sentence per broken promise
            more = len(sentences) - 1
            failures.append(sentences[0] + (f" (and {more} more like it under this preset)"
                                            if more else ""))
        failures += _friction_failures(scenes, runs, role)
        failures += _coulomb_failures(scenes, runs, role)
        failures += _restitution_failures(engine, scenes, runs, role)
        if role == "accurate":
            failures += _own_law_failures(engine, scenes, runs)
    return failures


def _friction_failures(scenes, runs, role: str) -> list[str]:
    failures = []
    if "oblique" in runs:
        scene = scenes["oblique"]
        before = _slip(scene, [scene.bodies[0].state()])
        change = _slip(scene, runs["oblique"].velocities) - before
        expected = _slip(scene, [_law_answer(scene, "newton-lcp")]) - before
        if abs(change) < USED_FRACTION * abs(expected) or change * expected < 0:
            failures.append(
                f"preset {role!r}: friction is not used: with μ = {scene.friction:g} the "
                f"oblique impact changes the slip by {change:.4g} m/s where the laws change "
                f"it by {expected:.4g} m/s (at least {USED_FRACTION:g} of it expected)")
    if "frictionless" in runs:
        scene = scenes["frictionless"]
        before = _slip(scene, [scene.bodies[0].state()])
        change = _slip(scene, runs["frictionless"].velocities) - before
        if abs(change) > FRICTIONLESS_SLIP * abs(before):
            failures.append(
                f"preset {role!r}: friction acts at μ = 0: the oblique impact changes the slip "
                f"by {change:.4g} m/s (at most {FRICTIONLESS_SLIP:g} of {before:g} m/s)")
    return failures


def _coulomb_failures(scenes, runs, role: str) -> list[str]:
    """A disk sliding throughout: the reported friction impulse is μ times the normal one,
    against the slip (Coulomb's law at sliding, which every law and engine shares)."""
    if "sliding" not in runs:
        return []
    scene, run = scenes["sliding"], runs["sliding"]
    # t = +x on the ground; the slip is +x, so friction's impulse is along -t.
    ratio = -run.tangential_impulse / (scene.friction * run.normal_impulse)
    if abs(ratio - 1.0) <= PAIR_BAND:
        return []
    return [f"preset {role!r}: the pair's μ is not the one used: a disk sliding at "
            f"{scene.bodies[0].velocity[0]:g} m/s with μ = {scene.friction:g} gets a friction "
            f"impulse of {-run.tangential_impulse:.4g} N s against the slip for a normal "
            f"impulse of {run.normal_impulse:.4g} N s, an effective μ of "
            f"{ratio * scene.friction:.4g} (Coulomb: μ times it, within {PAIR_BAND:g}; a μ "
            "scaled, or combined with the engine's own value?)"]


def _restitution_failures(engine: Engine, scenes, runs, role: str) -> list[str]:
    if role in engine.restitution_unused or not {"direct-low-e", "direct-high-e"} <= set(runs):
        return []
    low, high = scenes["direct-low-e"], scenes["direct-high-e"]
    separation = [runs[key].velocities[0][1] for key in ("direct-low-e", "direct-high-e")]
    expected = [float(_law_answer(scene, "poisson")[1]) for scene in (low, high)]
    growth, law_growth = separation[1] - separation[0], expected[1] - expected[0]
    if growth < USED_FRACTION * law_growth:
        return [f"preset {role!r}: restitution is not used: a direct impact at "
                f"{-low.bodies[0].velocity[1]:g} m/s separates at {separation[0]:.4g} m/s with "
                f"e = {low.restitution:g} and {separation[1]:.4g} m/s with e = "
                f"{high.restitution:g} (the laws: {expected[0]:.4g} and {expected[1]:.4g}); a "
                "preset that ignores e by design says so in restitution_unused"]
    for scene, speed, law in zip((low, high), separation, expected, strict=True):
        if abs(speed - law) > PAIR_BAND * law:
            return [f"preset {role!r}: the pair's e is not the one used: a direct impact at "
                    f"{-scene.bodies[0].velocity[1]:g} m/s with e = {scene.restitution:g} "
                    f"separates at {speed:.4g} m/s where the laws give {law:.4g} m/s (within "
                    f"{PAIR_BAND:g} of it), an effective e of "
                    f"{speed / -scene.bodies[0].velocity[1]:.4g} (e scaled, or combined with "
                    "the engine's own value?)"]
    return []


def _own_law_failures(engine: Engine, scenes, runs) -> list[str]:
    law = engine.own_law
    if law not in LAW_NAMES:  # "converged": its reference is checked with the attributes
        return []
    cases = [(scenes[key], run) for key, run in runs.items()]
    parting = 0  # the cases where the laws part: every law gives the disks one answer
    for name in PARTING_SCENES:
        scene = reference_scenes()[name][0]
        try:
            cases.append((scene, engine.run(scene, engine.settings("accurate"))))
        except UnsupportedScene:
            continue  # a shape the engine cannot build
        except Exception as error:  # noqa: BLE001 - the kit reports, it does not stop
            return [f"physics, preset 'accurate', scene {scene.name!r}: raises "
                    f"{type(error).__name__}: {error}"]
        parting += 1
    failures = []
    if not parting:
        failures.append(
            f"preset 'accurate': own_law {law!r} cannot be checked: the engine refuses "
            f"{' and '.join(map(repr, PARTING_SCENES))}, where the laws part (on the disks "
            "every law gives one answer); claim 'converged' (with bench_reference) instead")
    for scene, run in cases:
        answer = _law_answer(scene, law)
        departure = ke_norm(scene, run.u_after - answer) / ke_norm(scene, scene.state())
        if not departure <= OWN_LAW_DEPARTURE:
            failures.append(
                f"preset 'accurate' does not meet its own law {law!r} (own_law) on the "
                f"canonical case {scene.name!r}: departure {departure:.3g} > "
                f"{OWN_LAW_DEPARTURE:g} from planar_impact's answer")
    return failures


__all__ = ["FRICTIONLESS_SLIP", "OWN_LAW_DEPARTURE", "PAIR_BAND", "PARTING_SCENES", "USED_FRACTION",
           "check_engine", "physics_scenes"]
