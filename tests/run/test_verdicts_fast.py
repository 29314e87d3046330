"""The verdicts' fast path against the judge it replaced (harness/run/verdicts/).

The survey judges thousands of engine runs, so the verdicts work out what a scene alone
determines once (``prepare``) and place every contact point of a run against every feature at
once (``ContactTrack``). Neither may change a verdict: every reason, in the same order, with
the same numbers, bit for bit. The judge as it was before (the per-run ``judge`` with one
``feature_at`` per point and body, and the ``numbers_from_*`` that built one record per step)
is kept below as the reference, copied verbatim but for its docstrings (the helpers it shares
with the fast path, which it did not change, are imported). Both judge the same runs: every
engine and preset, over scenes sampled from every population and over every point of the
library scenarios, by the survey's path (``EngineRun`` -> ``numbers_from_run``) and by the
runner's (task output -> ``numbers_from_output``, declared flat faces through
``judge_declared``), at the default tolerances and at strict ones that make every check fire.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
import pytest

from harness import engines as engines_module
from harness.engines import (
    ENGINE_NAMES,
    PRESET_ROLES,
    UnsupportedScene,
    body_extent,
)
from harness.run import metrics, tasks, verdicts
from harness.run.verdicts import (
    DEFAULT_TOLERANCES,
    ENGINE_LAW,
    ENGINE_STATUS_REASONS,
    NEWTON_COULOMB,
    REASONS,
    REMARKS,
    RUN_CAP_BAND,
    Reason,
    RunNumbers,
    SceneScales,
    StepContacts,
    Tolerances,
    Verdict,
    declared_impulses,
)
from harness.run.verdicts.checks import (
    clipped_reasons,
    impulse_mismatch_reasons,
    penetration_reasons,
    reported_caps,
)
from harness.run.verdicts.declared import _declared_separation
from harness.scenarios import SCENARIO_DIR, load_scenario
from harness.scene import features as scene_features
from harness.scene import geometry
from harness.scene.features import feature_points
from harness.survey import laws as survey_laws
from harness.survey.engines import run_engine
from harness.survey.population import resolve_populations
from harness.survey.sampling import sample_population

PAIRS = [(engine, preset) for engine in ENGINE_NAMES for preset in PRESET_ROLES]


def overrides_of(engine, preset) -> dict:
    """Drake's accurate contact lasts 500 steps, and the reference judge below walks every
    step in Python (ten times MuJoCo's 50): Drake is judged on 50 steps of the same 0.5 ms
    contact (its own ``time_step_overrides``), through the same verdict paths."""
    if engine.name == "drake" and preset == "accurate":
        return engine.time_step_overrides(preset, 1e-5)
    return {}
SAMPLES = 8  # per population
#: Every bound tight enough that every check fires on some run (and multi-contact's reach
#: small, so a point counts at a feature only very near it).
STRICT = Tolerances(separation=1e-9, penetration=1e-3, impulse_residual=1e-12, impulse=1e-12,
                    energy=1e-15, energy_beyond_law=1e-3, cap=0.999)
#: A wide reach: points count at a feature far from it, so more runs touch a second one.
WIDE = Tolerances(penetration=0.5)
TOLERANCES = (DEFAULT_TOLERANCES, STRICT, WIDE)


def reference_numbers_from_output(engine: str, output: Mapping[str, Any]) -> RunNumbers:
    contacts = output.get("contacts")
    steps = None
    if contacts is not None:
        steps = tuple(StepContacts(int(c["step"]), tuple(tuple(p) for p in c["points"]),
                                   tuple(tuple(b) for b in c["bodies"])) for c in contacts)
    normal = output.get("contact_normal")
    return RunNumbers(
        engine=engine, status=str(output["status"]),
        u_after=np.array([v for body in output["velocities"] for v in body], dtype=float),
        max_penetration=output.get("max_penetration"),
        normal_impulse=output.get("engine_normal_impulse"),
        tangential_impulse=output.get("engine_tangential_impulse"),
        impulse_source=output.get("impulse_source"),
        contact_normal=None if normal is None else tuple(normal),
        contacts=steps, notes=tuple(output.get("notes") or ()),
        speed_caps=reported_caps(output.get("derived") or {}))


def reference_numbers_from_run(run) -> RunNumbers:
    return RunNumbers(
        engine=run.engine, status=str(run.status), u_after=np.asarray(run.u_after, dtype=float),
        max_penetration=run.max_penetration, normal_impulse=run.normal_impulse,
        tangential_impulse=run.tangential_impulse, impulse_source=run.impulse_source,
        contact_normal=run.contact_normal,
        contacts=tuple(StepContacts(step.step, tuple(step.points), step.poses)
                       for step in run.contacts),
        notes=tuple(run.notes), speed_caps=reported_caps(run.derived or {}))


def scene_scales(scene, problem) -> SceneScales:
    vn_approach, _ = metrics.contact_velocities(problem, problem.u)
    mnn, _, _ = metrics.delassus(problem)
    speed_norm = metrics.frame_free_scale(problem.mass_matrix, problem.u,
                                          free_bodies=not scene.ground)
    return SceneScales(approach_speed=abs(vn_approach), impulse=abs(vn_approach) / mnn,
                       speed_norm=speed_norm, energy=0.5 * speed_norm**2,
                       size=min(body_extent(body.shape) for body in scene.bodies))


def reference_judge(scene, problem, run: RunNumbers, *,
                    law_energy_change: float | None = None,
                    tolerances: Tolerances = DEFAULT_TOLERANCES, contacts=None) -> Verdict:
    if contacts is not None:
        return reference_judge_declared(scene, problem, run, contacts,
                                        law_energy_change=law_energy_change,
                                        tolerances=tolerances)
    reasons: list[Reason] = []
    if run.status == "multi-contact" and (run.contacts is not None or _one_feature(scene)):
        pass  # judged below from the features touched, not from a count of points
    elif run.status in ENGINE_STATUS_REASONS:
        reasons.append(Reason(run.status, None, None, f"the engine's status: {run.status}"))
    elif run.status != "ok":  # skipped or error: nothing to judge
        return Verdict(tuple(reasons))
    u_after = run.u_after
    if not np.all(np.isfinite(u_after)):
        if run.status != "blow-up":
            reasons.append(Reason("blow-up", None, None, "non-finite velocities"))
        return Verdict(tuple(reasons))
    scales = scene_scales(scene, problem)
    if run.speed_caps is not None:
        reasons += _clipped_magnitudes(run.engine, run.speed_caps, problem.u, u_after,
                                       tolerances)
    else:
        reasons += clipped_reasons(run.engine, problem.u, u_after, tolerances)
    if run.contacts is not None:
        reasons += _second_features(scene, run.contacts, tolerances)
    vn_after, _ = metrics.contact_velocities(problem, u_after)
    bound = tolerances.separation * scales.approach_speed
    if vn_after < -bound:
        reasons.append(Reason("not-separated", vn_after, -bound,
                              f"v_n^S = {vn_after:.4g} m/s < -{bound:.3g} m/s "
                              f"({tolerances.separation:g}·|v_n^A|)"))
    reasons += penetration_reasons(run, scales, tolerances)
    implied_n, implied_t, residual = impulse_from_velocities(problem, u_after,
                                                             scales.speed_norm)
    if residual > tolerances.impulse_residual:
        reasons.append(Reason("impulse-residual", residual, tolerances.impulse_residual,
                              f"‖Δu − M⁻¹(w_n I_n + w_t I_t)‖_M = {residual:.3g} of the "
                              f"frame-free speed norm"))
    reasons += impulse_mismatch_reasons(run, implied_n, implied_t, scales, tolerances,
                                        engine="(I_n, I_t)", implied="by Δu",
                                        scale="|v_n^A|/m_nn")
    reasons += _energy_gain(problem, u_after, scales, law_energy_change, tolerances,
                            law=ENGINE_LAW)
    order = list(REASONS)
    reasons.sort(key=lambda r: order.index(r.name))
    return Verdict(tuple(reasons))


def _energy_gain(problem, u_after, scales: SceneScales, law_energy_change: float | None,
                 tolerances: Tolerances, *, law: str) -> list[Reason]:
    gain = metrics.energy_change(problem.mass_matrix, problem.u, u_after)
    bound = tolerances.energy * scales.energy
    if gain <= bound:
        return []
    by_law = (law_energy_change is not None and law_energy_change > bound
              and gain <= law_energy_change + tolerances.energy_beyond_law * scales.energy)
    return [Reason(
        "energy-gain", gain, bound,
        f"ΔE = +{gain:.4g} J ({gain / scales.energy:.3g} of the frame-free kinetic energy); "
        + (f"{law} gains {law_energy_change:.4g} J on this problem" if by_law
           else f"{law} does not gain energy here" if not law_energy_change
           or law_energy_change <= bound
           else f"beyond {law}'s own gain of {law_energy_change:.4g} J"),
        attribution="law" if by_law else "numerics", fails=not by_law)]


def impulse_from_velocities(problem, u_after, speed_norm: float) -> tuple[float, float, float]:
    normal, tangential, _ = metrics.impulses_from_velocities(problem, u_after)
    delta_u = np.asarray(u_after, dtype=float) - problem.u
    explained = np.linalg.solve(problem.mass_matrix,
                                problem.wn * normal + problem.wt * tangential)
    rest = metrics.ke_norm(problem.mass_matrix, delta_u - explained)
    return normal, tangential, (rest / speed_norm if speed_norm > 0 else math.nan)


def _clipped_magnitudes(engine: str, caps: tuple[float, float], u_before: np.ndarray,
                        u_after: np.ndarray, tolerances: Tolerances) -> list[Reason]:
    band = 1.0 - max(tolerances.cap, RUN_CAP_BAND)
    speed_cap, rate_cap = caps
    found = []
    for when, u in (("before", u_before), ("after", u_after)):
        for body in range(len(u) // 3):
            vx, vy, omega = (float(v) for v in u[3 * body : 3 * body + 3])
            if math.hypot(vx, vy) >= band * speed_cap:
                found.append((when, body, "|v|", math.hypot(vx, vy), speed_cap, "m/s"))
            if abs(omega) >= band * rate_cap:
                found.append((when, body, "|ω|", abs(omega), rate_cap, "rad/s"))
    if not found:
        return []
    when, body, name, value, cap, unit = found[0]
    more = f" (and {len(found) - 1} more)" if len(found) > 1 else ""
    return [Reason("clipped", value, cap,
                   f"body {body} {name} {when} = {value:.6g} {unit}, at {engine}'s cap "
                   f"{cap:.6g} {unit} for this run's settings{more}")]


def feature_at(shape, state: Sequence[float], point: Sequence[float],
               reach: float) -> int | None:
    centres, radius, _ = feature_points(shape)
    if not len(centres):
        return None
    x, y, angle = state[0], state[1], state[2]
    c, s = math.cos(angle), math.sin(angle)
    world = centres @ np.array([[c, s], [-s, c]]) + np.array([x, y])
    distances = np.hypot(world[:, 0] - point[0], world[:, 1] - point[1]) - radius
    nearest = int(np.argmin(distances))
    return nearest if distances[nearest] <= reach else None


def _one_feature(scene) -> bool:
    return all(body.shape.kind == "disk" for body in scene.bodies)


def _second_features(scene, contacts: Sequence[StepContacts],
                     tolerances: Tolerances) -> list[Reason]:
    # the features at the scene's contact point in its pose are the contact's too
    point = geometry.scene_contact(scene).point
    at_contact = [feature_at(body.shape, (*body.position, body.angle), point,
                             tolerances.penetration * body_extent(body.shape))
                  for body in scene.bodies]
    first = None
    for record in contacts:
        for point in record.points:
            features = []
            for body, state in zip(scene.bodies, record.bodies):
                reach = tolerances.penetration * body_extent(body.shape) + max(point[2], 0.0)
                features.append(feature_at(body.shape, state, point[:2], reach))
            if first is None:
                first = features
                continue
            for index, (now, then) in enumerate(zip(features, first)):
                if now is not None and now != then and now != at_contact[index]:
                    body = scene.bodies[index]
                    names = feature_points(body.shape)[2]
                    return [Reason("multi-contact", float(record.step), None,
                                   f"{body.name}'s {names[now]} touched at step "
                                   f"{record.step} (the first contact was at "
                                   + (names[then] if then is not None else "a face")
                                   + ")")]
    return []


def _staggered(scene, contacts, records: Sequence[StepContacts],
               tolerances: Tolerances) -> list[Reason]:
    """``not-simultaneous``, one point at a time: each point belongs to the first declared
    contact whose feature it touches on some body, else to the nearest declared point."""
    declared = [[feature_at(body.shape, (*body.position, body.angle), contact.point,
                            tolerances.penetration * body_extent(body.shape))
                 for body in scene.bodies] for contact in contacts]
    firsts: dict[int, int] = {}
    for record in records:
        for point in record.points:
            owner = None
            for index, features in enumerate(declared):
                for body, state, feature in zip(scene.bodies, record.bodies, features):
                    reach = tolerances.penetration * body_extent(body.shape) + max(point[2], 0)
                    now = feature_at(body.shape, state, point[:2], reach)
                    if now is not None and now == feature:
                        owner = index
                        break
                if owner is not None:
                    break
            if owner is None:
                owner = min(range(len(contacts)), key=lambda i: math.hypot(
                    point[0] - contacts[i].point[0], point[1] - contacts[i].point[1]))
            firsts.setdefault(owner, record.step)
            firsts[owner] = min(firsts[owner], record.step)
    if len(set(firsts.values())) < 2:
        return []
    (early, first), (late, last) = min((v, k) for k, v in firsts.items()), max(
        (v, k) for k, v in firsts.items())
    return [Reason("not-simultaneous", float(late - early), 0.0,
                   f"{_contact_name(contacts, first)} first struck at step {early}, "
                   f"{_contact_name(contacts, last)} at step {late}: a sequence of impacts, "
                   "not the simultaneous impact declared")]


def _contact_name(contacts, index: int) -> str:
    x, y = (float(v) for v in contacts[index].point)
    return f"contact {index + 1} of {len(contacts)} at ({x:.4g}, {y:.4g}) m"


def reference_judge_declared(scene, problem, run: RunNumbers, contacts, *,
                             law_energy_change: float | None = None,
                             tolerances: Tolerances = DEFAULT_TOLERANCES) -> Verdict:
    from harness.scene import geometry

    reasons: list[Reason] = []
    if run.status in ENGINE_STATUS_REASONS and run.status != "multi-contact":
        reasons.append(Reason(run.status, None, None, f"the engine's status: {run.status}"))
    elif run.status not in ("ok", "multi-contact"):  # skipped or error: nothing to judge
        return Verdict(tuple(reasons))
    u_after = run.u_after
    if not np.all(np.isfinite(u_after)):
        if run.status != "blow-up":
            reasons.append(Reason("blow-up", None, None, "non-finite velocities"))
        return Verdict(tuple(reasons))
    wn, wt = geometry.contact_rows(scene, contacts)
    scales = declared_scales(scene, problem, wn)
    if run.speed_caps is not None:
        reasons += _clipped_magnitudes(run.engine, run.speed_caps, problem.u, u_after,
                                       tolerances)
    else:
        reasons += clipped_reasons(run.engine, problem.u, u_after, tolerances)
    if run.contacts is not None:
        reasons += _undeclared_features(scene, contacts, run.contacts, tolerances)
        reasons += _staggered(scene, contacts, run.contacts, tolerances)
    reasons += _declared_separation(contacts, wn @ u_after, scales, tolerances)
    reasons += penetration_reasons(run, scales, tolerances)
    impulses, residual = declared_impulses(problem.mass_matrix, wn, wt, problem.u, u_after,
                                           scales.speed_norm)
    if residual > tolerances.impulse_residual:
        reasons.append(Reason("impulse-residual", residual, tolerances.impulse_residual,
                              f"‖Δu − M⁻¹Σ_i(w_n^(i) I_n^(i) + w_t^(i) I_t^(i))‖_M = "
                              f"{residual:.3g} of the frame-free speed norm, over the "
                              f"{len(contacts)} declared contacts"))
    reasons += impulse_mismatch_reasons(
        run, float(np.sum(impulses[0])), float(np.sum(impulses[1])), scales, tolerances,
        engine="(ΣI_n, ΣI_t)", implied=f"by Δu over the {len(contacts)} declared contacts",
        scale="max_i |v_n^A(i)|/m_nn(i)")
    reasons += _energy_gain(problem, u_after, scales, law_energy_change, tolerances,
                            law=NEWTON_COULOMB)
    order = list(REASONS)
    reasons.sort(key=lambda r: order.index(r.name))
    return Verdict(tuple(reasons))


def declared_scales(scene, problem, wn: np.ndarray) -> SceneScales:
    single = scene_scales(scene, problem)
    approach = np.abs(wn @ problem.u)
    mnn = np.einsum("ij,ij->i", wn, np.linalg.solve(problem.mass_matrix, wn.T).T)
    return SceneScales(approach_speed=float(approach.max()),
                       impulse=float(np.max(approach / mnn)),
                       speed_norm=single.speed_norm, energy=single.energy, size=single.size)


def _undeclared_features(scene, contacts, records: Sequence[StepContacts],
                         tolerances: Tolerances) -> list[Reason]:
    def features_at(states, point, depth):
        return tuple(feature_at(body.shape, state, point,
                                tolerances.penetration * body_extent(body.shape)
                                + max(depth, 0.0))
                     for body, state in zip(scene.bodies, states))

    poses = [(*body.position, body.angle) for body in scene.bodies]
    declared = [features_at(poses, contact.point, 0.0) for contact in contacts]
    for record in records:
        for point in record.points:
            features = features_at(record.bodies, point[:2], point[2])
            if any(all(now is None or now == then for now, then in zip(features, allowed))
                   for allowed in declared):
                continue
            index = next(k for k, now in enumerate(features) if now is not None
                         and any(now != allowed[k] for allowed in declared))
            body = scene.bodies[index]
            names = feature_points(body.shape)[2]
            held = sorted({allowed[index] for allowed in declared},
                          key=lambda f: -1 if f is None else f)
            listed = ", ".join("a face" if f is None else names[f] for f in held)
            return [Reason("multi-contact", float(record.step), None,
                           f"{body.name}'s {names[features[index]]} touched at step "
                           f"{record.step}, outside the {len(contacts)} declared contacts "
                           f"({listed})")]
    return []



# --------------------------------------------------------------------------------------------
# The comparisons
# --------------------------------------------------------------------------------------------
def same(new: Verdict, old: Verdict) -> bool:
    """Every reason equal, floats bit for bit (``repr`` tells every float apart but NaNs,
    which compare unequal to themselves). The reference implementation predates the
    ``at-boundary`` remarks (never failures): they are left out of the comparison."""
    kept = Verdict(tuple(r for r in new.reasons if r.name not in REMARKS))
    return repr(kept) == repr(old)


@pytest.fixture(scope="module")
def survey_scenes():
    """Scenes of every population, their impacts and newton-lcp's energy changes."""
    samples = [sample for population in resolve_populations([])
               for sample in sample_population(population, SAMPLES, 0).samples]
    terms = survey_laws.contact_terms(samples)
    lcp = survey_laws.solve_laws(terms)["newton-lcp"].batch.energy_change
    return [sample.scene for sample in samples], terms.problems, np.asarray(lcp)


@pytest.mark.parametrize(("engine_name", "preset"), PAIRS)
def test_survey_runs_get_the_reference_verdicts(engine_name, preset, survey_scenes,
                                                load_or_skip):
    engine = load_or_skip(engine_name)
    scenes, problems, lcp = survey_scenes
    runs = engine.run_many(scenes, engine.settings(preset, overrides_of(engine, preset)))
    prepared = verdicts.prepare_many(scenes, problems)
    seen, placed = set(), 0
    for row, run in enumerate(runs):
        numbers = verdicts.numbers_from_run(run)
        if not prepared[row].one_feature:
            placed += len(numbers.contacts.points)
        for tolerances in TOLERANCES:
            for gain in (float(lcp[row]), None):
                old = reference_judge(scenes[row], problems[row],
                                      reference_numbers_from_run(run),
                                      law_energy_change=gain, tolerances=tolerances)
                for terms in (prepared[row], None):
                    new = verdicts.judge(scenes[row], problems[row], numbers,
                                         law_energy_change=gain, tolerances=tolerances,
                                         terms=terms)
                    assert same(new, old), (row, scenes[row].name)
                seen.update(reason.name for reason in old.reasons)
    # the runs exercise what was rewritten: points placed at corners and end caps (more than
    # one per run), the implied impulse
    assert placed > len(runs) and "impulse-residual" in seen, (placed, seen)


@pytest.mark.parametrize(("engine_name", "preset"), PAIRS)
def test_the_survey_columns_are_the_reference_verdicts(engine_name, preset, survey_scenes,
                                                       load_or_skip):
    """``run_engine``'s status and reasons, judged with the scene terms it works out or is
    given (as the survey's parts give them), are those of the reference (runs are deterministic:
    ``run_many`` again)."""
    engine = load_or_skip(engine_name)
    scenes, problems, lcp = survey_scenes
    overrides = overrides_of(engine, preset)
    results = run_engine(engine_name, preset, scenes, problems, lcp, overrides=overrides)
    again = run_engine(engine_name, preset, scenes, problems, lcp,
                       verdicts.prepare_many(scenes, problems), overrides=overrides)
    runs = engine.run_many(scenes, engine.settings(preset, overrides))
    for row, run in enumerate(runs):
        old = reference_judge(scenes[row], problems[row], reference_numbers_from_run(run),
                              law_energy_change=float(lcp[row]))
        for result in (results, again):
            assert result.status[row] == old.status(run.status.value)
            assert result.reasons[row] == ",".join(old.names)


class Replay:
    """An engine whose ``run`` returns a run already made (so the runner's task output and
    the run itself come from one simulation)."""

    def __init__(self, engine, run):
        self.timing, self.recorded = engine.timing, run

    def run(self, scene, settings):
        return self.recorded


def library_points():
    for path in sorted(SCENARIO_DIR.glob("*.toml")):
        scenario = load_scenario(path)
        if scenario.analytic_only:
            continue
        for point in scenario.point_list():
            yield scenario, point


@pytest.mark.slow
@pytest.mark.parametrize(("engine_name", "preset"), PAIRS)
def test_library_runs_get_the_reference_verdicts(engine_name, preset, monkeypatch,
                                                 load_or_skip):
    engine = load_or_skip(engine_name)
    settings = engine.settings(preset, overrides_of(engine, preset))
    judged = declared_judged = 0
    for scenario, point in library_points():
        scene = scenario.scene(point)
        problem = scenario.analytic_problem(point)
        try:
            run = engine.run(scene, settings)
        except UnsupportedScene:
            continue
        monkeypatch.setattr(engines_module, "load_engine", lambda name, run=run: Replay(
            engine, run))
        output = tasks.engine_task({"engine": engine_name, "scene": scene,
                                     "settings": settings})
        assert output["status"] == run.status
        declared = verdicts.declared_contacts(scenario, scene)
        try:
            lcp = problem.solve(mu=scene.friction, e=scene.restitution,
                                law="newton-lcp").energy_change
        except ValueError:
            lcp = None
        for tolerances in TOLERANCES:
            for gain in {lcp, None}:
                for new_numbers, old_numbers in (
                        (verdicts.numbers_from_run(run), reference_numbers_from_run(run)),
                        (verdicts.numbers_from_output(engine_name, output),
                         reference_numbers_from_output(engine_name, output))):
                    old = reference_judge(scene, problem, old_numbers, law_energy_change=gain,
                                          tolerances=tolerances, contacts=declared)
                    new = verdicts.judge(scene, problem, new_numbers, law_energy_change=gain,
                                         tolerances=tolerances, contacts=declared)
                    assert same(new, old), (scenario.name, point)
        judged += 1
        declared_judged += declared is not None
    assert judged and declared_judged, (judged, declared_judged)


@pytest.mark.parametrize("shape", ["box", "rod", "disk"])
def test_feature_at_is_the_reference_one_point_at_a_time(shape):
    """The public one-point ``feature_at`` against the reference, at points all around the
    body in many poses and reaches (near corners and end caps, on faces, far away)."""
    from harness.scene import Box, Disk, Rod

    body = {"box": Box(0.3, 0.1), "rod": Rod(0.4, 0.02), "disk": Disk(0.1)}[shape]
    rng = np.random.default_rng(7)
    centres = feature_points(body)[0]
    found = set()
    for _ in range(400):
        state = (*rng.normal(size=2), rng.uniform(-7, 7))
        near = (centres[rng.integers(len(centres))] if len(centres) else np.zeros(2))
        c, s = math.cos(state[2]), math.sin(state[2])
        point = (near @ np.array([[c, s], [-s, c]]) + state[:2]
                 + rng.normal(scale=rng.choice([1e-4, 1e-2, 0.2]), size=2))
        reach = float(rng.choice([0.0, 1e-3, 0.02, 0.5]))
        expected = feature_at(body, state, point, reach)
        assert scene_features.feature_at(body, state, point, reach) == expected
        found.add(expected)
    assert len(found) == (1 if shape == "disk" else len(centres) + 1)  # every one, and None
