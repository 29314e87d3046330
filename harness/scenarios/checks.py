"""Checks a scenario must pass before any engine runs: physics of every point, engine
settings, and the ``[expect]`` table against the solver.

The checks report through a :class:`harness.scenarios.table_reader.TableReader` (anything
with its ``error(key, problem, value, allowed)``), so every problem in a file is listed at
once.
"""

from __future__ import annotations

import copyreg
import json
import math
from dataclasses import dataclass
from types import MappingProxyType
from typing import Any, Mapping

import numpy as np

import planar_impact
from harness.engines import EngineNotInstalled, engine_names, load_engine
from harness.engines.facts import engine_facts
from harness.scenarios.errors import suggest
from harness.scenarios.model import Point, Scenario
from harness.scenarios.schema import LIMITS, ONE_POINT_TOLERANCE, PRESETS, SHAPE_FIELDS, limit
from harness.scenarios.table_reader import TableReader
from harness.scene import Body, Disk, Scene, geometry
from harness.scene.features import feature_points
from harness.store.cache import ResultCache
from harness.store.identity import code_version
from harness.store.passed_checks import PassedChecks


def check_engine_settings(reader: TableReader, engine: str, table: Mapping[str, Any]) -> None:
    """Check override keys and values with the engine's adapter, when it can be imported."""
    try:
        adapter = load_engine(engine)
    except EngineNotInstalled:  # the runner reports the missing engine; a bug in an adapter raises
        return
    docs = getattr(adapter, "setting_docs", {})
    known = tuple(sorted(docs))
    for key, value in table.items():
        if known and key not in docs:
            reader.error(f"engine_settings.{engine}.{key}",
                         f"unknown {engine} setting{suggest(key, known)}", value,
                         ", ".join(known))
            return
    for preset in PRESETS:
        try:
            adapter.settings(preset, dict(table))
        except ValueError as error:
            # The key the adapter rejects on its own, else (a combination) the table.
            bad = next((key for key in table if _rejects(adapter, preset, key, table[key])),
                       None)
            reader.error(f"engine_settings.{engine}" + (f".{bad}" if bad else ""),
                         f"rejected by {engine}: {error}",
                         table[bad] if bad else dict(table),
                         f"values the {engine} adapter accepts")
            return


def _rejects(adapter, preset: str, key: str, value: Any) -> bool:
    """Whether ``adapter`` rejects the override ``key = value`` alone on ``preset``."""
    try:
        adapter.settings(preset, {key: value})
    except ValueError:
        return True
    return False


def check_points(reader: TableReader, scenario: Scenario) -> None:
    """Every point must be a touching, approaching contact with e, μ in range: one point, or
    a face lying flat where the file declares ``contacts = "simultaneous"``."""
    for point in scenario.point_list():
        where = f" at sweep point {point.label}" if point.label else ""
        fixed = scenario.at(point)
        if not 0.0 <= fixed.restitution <= 1.0:
            reader.error("sweep.values", f"restitution out of range{where}", fixed.restitution,
                         "0 … 1")
            continue
        if not fixed.friction >= 0.0:
            reader.error("sweep.values", f"friction out of range{where}", fixed.friction, ">= 0")
            continue
        if fixed.system == "bodies":
            check_bodies(reader, scenario, point, fixed, where)
        else:
            check_analytic(reader, scenario, point, where)


def check_bodies(reader: TableReader, scenario: Scenario, point: Point, fixed: Scenario,
                 where: str) -> None:
    """The bodies' values at ``point`` (``fixed``: ``scenario.at(point)``), then their contact
    and the second-strike check."""
    for spec in fixed.bodies:
        for key, value in (("mass", spec.mass), ("inertia", spec.inertia)):
            if value is not None and not value > 0.0:
                reader.error(f"body.{spec.name}.{key}", f"must be positive{where}", value, "> 0")
                return
        for key in SHAPE_FIELDS[spec.shape.kind]:
            value = getattr(spec.shape, key, None)
            if isinstance(value, float) and not value > 0.0:
                reader.error(f"body.{spec.name}.{key}", f"must be positive{where}", value, "> 0")
                return
    scene = scenario.scene(point)  # kept with the scenario, for the run to come
    contact, exact = geometry.scene_contact_each(
        scene, (ONE_POINT_TOLERANCE, geometry.DEFAULT_TOLERANCE))
    placed = [s for s in fixed.bodies if s.position is not None]
    position_key = (f"body.{placed[-1].name}.position" if placed else "body")
    positions = [list(s.position) for s in placed]
    if abs(exact.gap) > fixed.gap_tolerance:
        state = "apart" if exact.gap > 0 else "overlapping"
        reader.error(position_key, f"bodies must touch{where}: measured gap {exact.gap:.6g} m "
                     f"({state})", positions if len(positions) > 1 else positions[0],
                     f"|gap| <= gap_tolerance = {fixed.gap_tolerance:g} m")
        return
    declared = fixed.contacts == "simultaneous"
    angles = {s.name: s.angle_deg for s in fixed.bodies}
    if contact.point_count > 1 and not declared:
        reader.error(f"body.{fixed.bodies[-1].name}.angle_deg",
                     f"{contact.point_count} contact points within {ONE_POINT_TOLERANCE:g} m"
                     f"{where} (a face lies flat on a face): outside one-point impact theory",
                     angles, "a pose with a single closest point (turn the body), or declare "
                     'the flat face with contacts = "simultaneous"')
        return
    if declared:
        check_simultaneous(reader, fixed, scene, contact.point_count, angles, where)
        return
    vn, _ = geometry.contact_velocity(scene, exact)
    if not vn < 0.0:
        reader.error(f"body.{fixed.bodies[-1].name}.velocity",
                     f"the bodies do not approach{where}: contact normal velocity v_n = "
                     f"{vn:.6g} m/s{_other_velocities(fixed)}", list(fixed.bodies[-1].velocity),
                     "velocities giving v_n < 0 along the normal "
                     f"{np.round(exact.normal, 6).tolist()} (from A into B)")
        return
    if fixed.expect_sequence:
        return
    time_step, engine = engine_time_step(fixed)
    strike = second_strike(scene, exact, SEQUENCE_HORIZON_STEPS * time_step, time_step)
    if strike is not None:
        reader.error("expect_sequence",
                     f"a second feature strikes within the impact{where}: {strike.describe()}, "
                     f"within {SEQUENCE_HORIZON_STEPS} steps of {engine} "
                     f"({time_step:.3g} s each): the engines will see a sequence of impacts, "
                     "not one", False,
                     "expect_sequence = true (the runs are then judged, docs/verdicts.md), or "
                     "a pose whose other corners/ends stay clear")


def _other_velocities(fixed: Scenario) -> str:
    """The velocities of the bodies other than the last (whose velocity an approach error
    names), which the approach depends on as well: ``" (with body.a.velocity = [1, 0])"``."""
    others = ", ".join(f"body.{spec.name}.velocity = {list(spec.velocity)}"
                       for spec in fixed.bodies[:-1])
    return f" (with {others})" if others else ""


def check_simultaneous(reader: TableReader, fixed: Scenario, scene: Scene, point_count: int,
                       angles: dict, where: str) -> None:
    """A declared flat face (``contacts = "simultaneous"``): two or more contact points within
    ONE_POINT_TOLERANCE, at least one approaching; not also a declared sequence."""
    if fixed.expect_sequence:
        reader.error("expect_sequence", 'contradicts contacts = "simultaneous"' + where, True,
                     "one of them: a flat face (simultaneous) or a tilt (a sequence)")
        return
    if point_count < 2:
        reader.error("contacts", f"declares a flat face, but a single point touches{where} "
                     f"(no second point within {ONE_POINT_TOLERANCE:g} m)", angles,
                     'a pose with a face lying flat, or contacts = "one" (the default)')
        return
    contacts = geometry.scene_contacts(scene, tolerance=ONE_POINT_TOLERANCE)
    normal_speeds = [geometry.contact_velocity(scene, c)[0] for c in contacts]
    if not min(normal_speeds) < 0.0:
        reader.error(f"body.{fixed.bodies[-1].name}.velocity",
                     f"no contact point approaches{where}: v_n = "
                     f"{[round(v, 6) for v in normal_speeds]} m/s{_other_velocities(fixed)}",
                     list(fixed.bodies[-1].velocity),
                     "velocities giving v_n < 0 at one contact point at least")


def check_analytic(reader: TableReader, scenario: Scenario, point: Point, where: str) -> None:
    try:
        problem = scenario.analytic_problem(point)
    except ImportError:  # pragma: no cover - planar_impact is part of this project
        return
    except (TypeError, ValueError) as error:
        reader.error("parameters" if scenario.system == "two-sled" else "mass_matrix",
                     f"cannot build the problem{where}: {error}")
        return
    vn = float(np.asarray(problem.wn) @ np.asarray(problem.u))
    if not vn < 0.0:
        key = "parameters.u" if scenario.system == "two-sled" else "u"
        reader.error(key, f"no approach{where}: v_n = wn·u = {vn:.6g}",
                     list(np.asarray(problem.u)), "speeds giving wn·u < 0")


def check_expectations(scenario: Scenario) -> list[str]:
    """Compare ``[expect]`` with ``planar_impact``; one message per mismatch (empty: all agree)."""
    problems = []
    where = scenario.path or scenario.name
    for point in scenario.point_list():
        at = f" at {point.label}" if point.label else ""
        fixed = scenario.at(point)
        problem = scenario.analytic_problem(point)
        wanted_laws = set(scenario.expect.collision_type) | set(scenario.expect.energy_gain)
        if scenario.expect.case is not None:
            wanted_laws.add("poisson")
        results = {}
        for law in sorted(wanted_laws):
            try:
                results[law] = problem.solve(mu=fixed.friction, e=fixed.restitution,
                                             law=law)
            except (ValueError, planar_impact.ImpactInputError) as error:
                problems.append(f"{where}: {law}{at}: the solver refused: {error}")
        for law, result in results.items():
            expected = scenario.expected_collision_type(law, point)
            if expected is not None and result.collision_type != expected:
                problems.append(f"{where}: expect.collision_type.{law}{at} = {expected}, but "
                                f"the solver gives {result.collision_type}")
            gain = scenario.expected_energy_gain(law, point)
            # The solver's decision (energy_gained): inside its rounding band either
            # expectation is right.
            if (gain is not None and not result.energy_gain_at_boundary
                    and result.energy_gained != gain):
                problems.append(f"{where}: expect.energy_gain.{law}{at} = {str(gain).lower()}, "
                                f"but the energy change is {result.energy_change:.6g} J")
        case = scenario.expected_case(point)
        if case is not None and "poisson" in results and results["poisson"].case != case:
            problems.append(f"{where}: expect.case{at} = {case}, but the solver gives "
                            f"{results['poisson'].case}")
    return problems


# --------------------------------------------------------------------------------------------
# A second feature within the impact (docs/verdicts.md, 'Sequences found before any run')
# --------------------------------------------------------------------------------------------
#: The horizon of the second-strike check, in steps of the coarsest engine time step: a
#: rigid engine's contact lasts a step or two (pymunk and pybullet on the library: one to
#: three), and what strikes later is a new impact after the run. A soft contact (MuJoCo's
#: defaults) lasts longer; its runs are judged after they ran (docs/verdicts.md).
SEQUENCE_HORIZON_STEPS = 2
#: Time step (s) assumed when no engine of the scenario can be loaded (pymunk's 1/60 s).
FALLBACK_TIME_STEP = 1.0 / 60.0
#: Samples of the post-impact free flight over the horizon (the gaps of a rotating body are
#: smooth on this scale: 48 samples of a 50 ms horizon are ~1 ms apart).
SEQUENCE_SAMPLES = 48
#: Bisections refining a strike time found between two samples.
STRIKE_BISECTIONS = 30
#: Laws whose post-impact motion is followed: the engines' own law and the reference.
SEQUENCE_LAWS = ("newton-lcp", "poisson")


@dataclass(frozen=True)
class Strike:
    """A feature other than the first contact's that reaches the partner."""

    body: str
    feature: str
    partner: str
    time_s: float  # after first touch
    motion: str  # "before the impact" or "after the impact (<law>)"

    def describe(self) -> str:
        return (f"{self.body}'s {self.feature} reaches the {self.partner} "
                f"{1e3 * self.time_s:.3g} ms after first touch, moving as {self.motion}")


def engine_time_step(fixed: Scenario) -> tuple[float, str]:
    """The coarsest time step (s) of the scenario's engines over both presets, and the
    engine's name; :data:`FALLBACK_TIME_STEP` when none can be loaded."""
    best, name = 0.0, ""
    for engine in fixed.engines:
        overrides = dict(fixed.engine_settings.get(engine, {}))
        for preset in PRESETS:
            step = _preset_time_step(engine, preset, overrides)
            if step is not None and step > best:
                best, name = step, engine
    return (best, name) if best > 0 else (FALLBACK_TIME_STEP, "an engine at 1/60 s")


#: :func:`_preset_time_step` by engine, preset and overrides (a library's files share a few:
#: an adapter's settings, copied and validated, were a fifth of reading a file anew).
_TIME_STEPS: dict[tuple[str, str, str], float | None] = {}


def _preset_time_step(engine: str, preset: str, overrides: dict) -> float | None:
    """The time step (s) of ``engine`` at ``preset`` with ``overrides``; None when the engine
    is not installed or the overrides are bad (reported elsewhere)."""
    try:  # most files override nothing: no spelling for them
        key = (engine, preset, json.dumps(overrides, sort_keys=True) if overrides else "{}")
    except (TypeError, ValueError):  # a value json cannot spell: not remembered
        key = None
    if key is not None and key in _TIME_STEPS:
        return _TIME_STEPS[key]
    try:
        step = float(load_engine(engine).settings(preset, overrides)["time_step"])
    except (EngineNotInstalled, ValueError, KeyError):
        step = None
    if key is not None:
        _TIME_STEPS[key] = step
    return step


def _feature_points(body: Body) -> list[tuple[str, np.ndarray, float]]:
    """``(name, body-frame centre, radius)`` of each corner or end cap of ``body``; none
    for an ellipse, whose one contact rolls (the vertices of the polygon standing in for it
    in some engines are judged run by run: the verdicts' ``multi-contact``)."""
    if body.shape.kind == "ellipse":
        return []

    centres, radius, names = feature_points(body.shape)
    return [(name, centre, radius) for name, centre, radius in
            zip(names, centres, [radius] * len(names))]


def _feature_gap(scene: Scene, index: int, centre: np.ndarray, radius: float,
                 poses: list[tuple[float, float, float]]) -> float:
    """Signed distance (m) from a feature of body ``index`` to its partner at ``poses``."""
    x, y, angle = poses[index]
    # elementwise, the same bits on every CPU (geometry.turn; a BLAS product is not)
    world = geometry.turn(centre, angle)[0] + np.array([x, y])
    if scene.ground:
        return float(world[1]) - radius
    other = 1 - index
    partner = scene.bodies[other].moved(position=(poses[other][0], poses[other][1]),
                                        angle=poses[other][2])
    feature = Body("feature", Disk(radius), 1.0, (float(world[0]), float(world[1])))
    return geometry.body_contact(partner, feature).gap


def _ground_gap(c: float, s: float, height: float, x: float, y: float, radius: float
                ) -> float:
    """:func:`_feature_gap` above the ground: the height of the feature at body-frame ``(x,
    y)`` on a body at ``height`` turned by the angle of cosine ``c`` and sine ``s``, less its
    radius (the same sums as the rotation matrix's product)."""
    return (s * x + c * y) + height - radius


def _first_ground_touch(start: list, features: list, speeds, times: np.ndarray) -> int | None:
    """The first of ``times`` at which a feature (``(body index, name, body-frame x, y,
    radius)``) of a body starting at ``start`` poses and moving at ``speeds`` touches the
    ground, as an index, or None: the sums of :func:`_ground_gap` over arrays of times, in
    the same order (the angles' cosines and sines by :mod:`math`, as there), so the sample
    found is the one the sample-by-sample scan finds."""
    turns = []
    for i, (_, y, angle) in enumerate(start):
        angles = (angle + speeds[3 * i + 2] * times).tolist()
        turns.append((np.array([math.cos(a) for a in angles]),
                      np.array([math.sin(a) for a in angles]), y + speeds[3 * i + 1] * times))
    touched = np.zeros(len(times), dtype=bool)
    for index, _, x, y, radius in features:
        c, s, heights = turns[index]
        touched |= _ground_gap(c, s, heights, x, y, radius) <= 0.0
    hits = np.flatnonzero(touched)
    return int(hits[0]) if hits.size else None


#: Relative slack of :func:`_first_body_touch`'s bound: far above the rounding of the gaps it
#: bounds (a few ulps of the coordinates), far below any gap that matters.
BOUND_SLACK = 1e-9


def _first_body_touch(scene: Scene, start: list, features: list, speeds,
                      times: np.ndarray) -> int | None:
    """The first of ``times`` (as an index) at which a feature (``(body index, name,
    body-frame centre, radius)``) of one of two bodies starting at ``start`` poses and moving
    at ``speeds`` may touch the other body, or None when none can.

    A lower bound of :func:`_feature_gap` over arrays of times: the partner's core lies
    within its extent (the farthest core point from its centre of mass) of its position, so
    the feature's gap is at least its centre's distance from that position less the extent
    and both radii. A sample where the bound exceeds :data:`BOUND_SLACK` (relative to the
    coordinates) has no touch; the sample-by-sample scan from the index returned finds what
    it finds from the first sample.
    """
    moving = []
    for i, (x, y, angle) in enumerate(start):
        moving.append((x + speeds[3 * i] * times, y + speeds[3 * i + 1] * times,
                       angle + speeds[3 * i + 2] * times))
    extents = []
    for body in scene.bodies:
        core, core_radius = geometry.local_core(body.shape)
        extents.append((float(np.max(np.hypot(core[:, 0], core[:, 1]))), core_radius))
    possible = np.zeros(len(times), dtype=bool)
    for index, _, centre, radius in features:
        x, y, angle = moving[index]
        cos, sin = np.cos(angle), np.sin(angle)
        feature_x = cos * centre[0] - sin * centre[1] + x
        feature_y = sin * centre[0] + cos * centre[1] + y
        partner_x, partner_y, _ = moving[1 - index]
        extent, partner_radius = extents[1 - index]
        reach = extent + partner_radius + radius
        bound = np.hypot(feature_x - partner_x, feature_y - partner_y) - reach
        scale = 1.0 + np.abs(feature_x) + np.abs(feature_y) + np.abs(partner_x) \
            + np.abs(partner_y) + reach
        possible |= bound <= BOUND_SLACK * scale
    hits = np.flatnonzero(possible)
    return int(hits[0]) if hits.size else None


#: :func:`_sample_times` by duration (the durations are a few engines' steps and horizons).
_SAMPLE_TIMES: dict[float, np.ndarray] = {}


def _sample_times(duration: float) -> np.ndarray:
    """The :data:`SEQUENCE_SAMPLES` sample times over ``(0, duration]`` (read-only: shared)."""
    times = _SAMPLE_TIMES.get(duration)
    if times is None:
        times = np.linspace(0.0, duration, SEQUENCE_SAMPLES + 1)[1:]
        times.flags.writeable = False
        if len(_SAMPLE_TIMES) < 64:  # durations other than the engines' are not kept
            _SAMPLE_TIMES[duration] = times
    return times


def second_strike(scene: Scene, contact, horizon_s: float, step_s: float) -> Strike | None:
    """The first feature other than the touching one to reach the partner within the impact.

    The bodies move freely from the touching pose: with their approach speeds for one engine
    step (an engine resolves the contact after it has found it), and with the post-impact
    speeds of each of :data:`SEQUENCE_LAWS` for ``horizon_s``. A corner or end cap touching
    at the start (gap within ``ONE_POINT_TOLERANCE``) is the first contact's and is skipped.
    """
    problem = geometry.impact_problem(scene, contact.point, contact.normal)
    motions = [("before the impact", problem.u, step_s)]
    solve_law = problem.law_solver(mu=scene.friction, e=scene.restitution)  # checked once
    for law in SEQUENCE_LAWS:
        try:
            result = solve_law(law)
        except (ValueError, planar_impact.ImpactInputError):
            continue
        motions.append((f"after the impact ({law})", result.u_after, horizon_s))
    start = [(b.position[0], b.position[1], b.angle) for b in scene.bodies]
    features = []
    for index, body in enumerate(scene.bodies):
        for name, centre, radius in _feature_points(body):
            if _feature_gap(scene, index, centre, radius, start) > ONE_POINT_TOLERANCE:
                features.append((index, name, centre, radius))
    if not features:
        return None
    # On the ground (most files) a feature's gap is its height: plain floats, no arrays.
    ground_features = [(index, name, float(centre[0]), float(centre[1]), radius)
                       for index, name, centre, radius in features]

    def poses_at(speeds, time_s):
        return [(x + speeds[3 * i] * time_s, y + speeds[3 * i + 1] * time_s,
                 angle + speeds[3 * i + 2] * time_s) for i, (x, y, angle) in enumerate(start)]

    def touching(speeds, time_s):
        poses = poses_at(speeds, time_s)
        if scene.ground:
            turns = [(math.cos(angle), math.sin(angle), y) for _, y, angle in poses]
            for index, name, x, y, radius in ground_features:
                c, s, height = turns[index]
                if _ground_gap(c, s, height, x, y, radius) <= 0.0:
                    return index, name
            return None
        return next(((index, name) for index, name, centre, radius in features
                     if _feature_gap(scene, index, centre, radius, poses) <= 0.0), None)

    earliest: Strike | None = None
    for motion, speeds, duration in motions:
        times = _sample_times(duration)
        # The samples before the first (possible) touch skipped in one pass of arrays.
        if scene.ground:
            first = _first_ground_touch(start, ground_features, speeds, times)
        else:
            first = _first_body_touch(scene, start, features, speeds, times)
        if first is None:
            continue
        previous = 0.0 if first == 0 else float(times[first - 1])
        for time_s in times[first:]:
            if earliest is not None and previous >= earliest.time_s:
                break
            hit = touching(speeds, time_s)
            if hit is not None:
                low, high = previous, float(time_s)
                for _ in range(STRIKE_BISECTIONS):  # the strike time, to 2^-30 of a sample
                    middle = 0.5 * (low + high)
                    found = touching(speeds, middle)
                    if found is None:
                        low = middle
                    else:
                        high, hit = middle, found
                index, name = hit
                partner = "ground" if scene.ground else scene.bodies[1 - index].name
                if earliest is None or high < earliest.time_s:
                    earliest = Strike(scene.bodies[index].name, name, partner, high, motion)
                break
            previous = float(time_s)
    return earliest


# --------------------------------------------------------------------------------------------
# Checks passed, remembered by content (a warm run re-reads files, it need not re-check them)
# --------------------------------------------------------------------------------------------
def _reduce_proxy(proxy: MappingProxyType):
    """A read-only mapping (the scenario model's) as its items, read-only again: the outcome
    of a scenario check travels from a forked worker back to the run through the pool's
    pipe, which plain pickling of a ``mappingproxy`` refuses."""
    return _read_only, (dict(proxy),)


def _read_only(items: dict) -> MappingProxyType:
    return MappingProxyType(items)


# For the process pool's own transport only (harness/scenarios/library.py): nothing is ever
# unpickled from a file.
copyreg.pickle(MappingProxyType, _reduce_proxy)


def _checks_context(root=None) -> str:
    """What a check's outcome depends on besides the file's text
    (:class:`harness.store.passed_checks.PassedChecks`): the code (the scenarios, the scene
    and the engines, which :func:`harness.store.identity.code_version` covers), the limits of
    :data:`LIMITS` and which of the registered engines are installed
    (:func:`engine_time_step`; those registered at run time too), read from the
    result cache at ``root`` where it is kept (:mod:`harness.engines.facts`: no engine is
    imported for it on a warm run)."""
    installed = list(engine_facts(engine_names(), None if root is None else ResultCache(root))
                     .versions)
    return json.dumps({"code": code_version(), "limits": {k: limit(k) for k in sorted(LIMITS)},
                       "engines": installed}, sort_keys=True)


#: The store :func:`harness.scenarios.reader.load_scenario` consults (disabled by default).
passed_checks = PassedChecks()


def use_passed_checks(root=None) -> PassedChecks:
    """Make ``root`` (None: disabled) the store of passed checks; returns it."""
    global passed_checks
    passed_checks = PassedChecks(root, context=_checks_context)
    return passed_checks
