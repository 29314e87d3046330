"""The faster pieces of building a run's records against what they replace, bit for bit.

* :func:`metrics.departures` (the work its laws share done once) against
  :func:`metrics.departure` law by law;
* :func:`metrics.impulse_series` (a history's impulses) against
  :func:`metrics.impulses_from_velocities`, step by step;
* :func:`records.plain_value` (flat lists and dicts taken whole) against the walk it was,
  item by item (:func:`walked_plain_value`, kept here as it was);
* the runner's ``_cached_line`` (a stored line edited to ``cached``) against
  :func:`records.record_line` of the edited record;
* a verdict handed the point's prepared terms and the impulse its record implied against
  the verdict worked out alone;
* :func:`history.contact_history` (its rows' products stacked) against the history as it
  was, row by row (:func:`stepwise_contact_history`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import numpy as np
import pytest

from harness.engines import EngineNotInstalled, load_engine
from harness.run import history, metrics, records, scenario_records, tasks, verdicts
from harness.run.records import Record, plain_value, record_line
from harness.scenarios import SCENARIO_DIR, load_scenario


def random_mass_matrix(rng, size):
    root = rng.normal(size=(size, size))
    return root @ root.T + size * np.eye(size)


def same_float(a: float, b: float) -> bool:
    """Equal bits, NaN equal to NaN."""
    return (math.isnan(a) and math.isnan(b)) or (a == b and math.copysign(1, a)
                                                  == math.copysign(1, b))


def random_speeds(rng, size):
    """Speeds, sometimes non-finite, sometimes missing, sometimes a list."""
    kind = rng.integers(10)
    if kind == 0:
        return None
    u = rng.normal(size=size) * 10.0 ** rng.integers(-3, 4)
    if kind == 3:  # near the top of the float range: differences overflow
        u *= 1.5e308 / np.max(np.abs(u))
    if kind == 1:
        u[rng.integers(size)] = rng.choice([math.nan, math.inf, -math.inf])
    return u.tolist() if kind == 2 else u


# Speeds near the float limit are among the inputs on purpose: both ways overflow there alike.
@pytest.mark.filterwarnings("ignore:overflow encountered:RuntimeWarning",
                            "ignore:invalid value encountered:RuntimeWarning")
@pytest.mark.parametrize("free_bodies", [False, True])
def test_departures_are_departure_law_by_law(free_bodies):
    rng = np.random.default_rng(11)
    for trial in range(2000):
        size = 6 if free_bodies else int(rng.choice([3, 4, 6, 9]))
        mass_matrix = random_mass_matrix(rng, size)
        u_before = (np.zeros(size) if trial % 50 == 0  # a zero scale: every departure NaN
                    else rng.normal(size=size))
        u = random_speeds(rng, size)
        law_speeds = {law: random_speeds(rng, size)
                      for law in ("newton", "poisson", "stronge", "newton-lcp")}
        found = metrics.departures(mass_matrix, u, law_speeds, u_before,
                                   free_bodies=free_bodies)
        expected = {law: metrics.departure(mass_matrix, u, u_law, u_before,
                                           free_bodies=free_bodies)
                    for law, u_law in law_speeds.items() if u_law is not None}
        assert list(found) == list(expected)
        assert all(same_float(found[law], expected[law]) for law in expected)


def test_departures_whose_difference_overflows_are_departure_law_by_law():
    mass_matrix = np.array([[2.0]])  # one speed: an infinite difference gives inf, not NaN
    u, u_before = np.array([1.5e308]), np.array([1.0])
    law_speeds = {"poisson": np.array([-1e308]), "newton": np.zeros(1)}
    with np.errstate(all="ignore"):
        found = metrics.departures(mass_matrix, u, law_speeds, u_before)
        expected = {law: metrics.departure(mass_matrix, u, u_law, u_before)
                    for law, u_law in law_speeds.items()}
    assert found == expected and found["poisson"] == math.inf


def test_departures_of_no_law_are_empty():
    mass_matrix = np.eye(3)
    assert metrics.departures(mass_matrix, [1.0, 0.0, 0.0], {}, [1.0, 1.0, 0.0]) == {}
    assert metrics.departures(mass_matrix, None, {"poisson": None}, [1.0, 1.0, 0.0]) == {}


def test_impulse_series_is_impulses_from_velocities_step_by_step():
    rng = np.random.default_rng(12)
    for _ in range(200):
        size = int(rng.choice([3, 6]))
        mass_matrix = random_mass_matrix(rng, size)
        problem = SimpleNamespace(mass_matrix=mass_matrix, u=rng.normal(size=size),
                                  wn=rng.normal(size=size), wt=rng.normal(size=size))
        speeds = [rng.normal(size=size) for _ in range(int(rng.integers(1, 8)))]
        found = metrics.impulse_series(problem, speeds)
        expected = [metrics.impulses_from_velocities(problem, u)[:2] for u in speeds]
        assert len(found) == len(expected)
        for (normal, tangential), (normal_0, tangential_0) in zip(found, expected):
            assert same_float(normal, normal_0) and same_float(tangential, tangential_0)


_PLAIN = (str, int, bool, type(None))


def walked_plain_value(value: Any) -> Any:
    """records.plain_value as it was: every item walked one call at a time."""
    kind = type(value)
    if kind is float:
        return value if math.isfinite(value) else None
    if kind in _PLAIN:
        return value
    if isinstance(value, dict):
        return {str(key): walked_plain_value(item) for key, item in value.items()}
    if isinstance(value, (list, tuple)):
        return [walked_plain_value(item) for item in value]
    if isinstance(value, str):
        return value[:]
    if hasattr(value, "tolist") and not isinstance(value, bytes):
        return walked_plain_value(value.tolist())
    if isinstance(value, float):
        return float(value) if math.isfinite(value) else None
    if isinstance(value, int) and not isinstance(value, bool):
        return int(value)
    if isinstance(value, Path):
        return value.as_posix()
    from dataclasses import asdict, is_dataclass

    if is_dataclass(value) and not isinstance(value, type):
        return walked_plain_value(asdict(value))
    return value


class Label(str):
    pass


class Count(int):
    pass


@dataclass
class Pair:
    first: Any
    second: Any


def random_value(rng, depth=0):
    """A nested value of every kind plain_value meets, flat lists and dicts most often."""
    scalars = [lambda: float(rng.normal()), lambda: math.nan, lambda: math.inf,
               lambda: -0.0, lambda: int(rng.integers(-5, 5)), lambda: bool(rng.integers(2)),
               lambda: None, lambda: "text", lambda: Label("label"), lambda: Count(3),
               lambda: np.float64(rng.normal()), lambda: np.int64(4), lambda: Path("a/b")]
    kind = rng.integers(8 if depth < 3 else 1)
    if kind == 0:
        return scalars[rng.integers(len(scalars))]()
    if kind in (1, 2):  # a flat list: floats, with a non-finite or another plain type
        items = [float(x) for x in rng.normal(size=int(rng.integers(0, 6)))]
        if items and rng.integers(3) == 0:
            items[rng.integers(len(items))] = scalars[rng.integers(len(scalars))]()
        return items if kind == 1 else tuple(items)
    if kind == 3:  # a flat dict
        keys = ["a", "b", "c", 1, None, Label("d")]
        return {keys[rng.integers(len(keys)) if rng.integers(4) == 0 else i % 3]:
                scalars[rng.integers(len(scalars))]() for i in range(int(rng.integers(0, 5)))}
    if kind == 4:
        return rng.normal(size=int(rng.integers(0, 4)))
    if kind == 5:
        return Pair(random_value(rng, depth + 1), random_value(rng, depth + 1))
    if kind == 6:
        return [random_value(rng, depth + 1) for _ in range(int(rng.integers(0, 4)))]
    return {f"k{i}": random_value(rng, depth + 1) for i in range(int(rng.integers(0, 4)))}


def plain_repr(value):
    """The value with each float's bits and each value's exact type spelled out."""
    if isinstance(value, dict):
        return ("dict", type(value), [(plain_repr(k), plain_repr(v)) for k, v in value.items()])
    if isinstance(value, list):
        return ("list", type(value), [plain_repr(item) for item in value])
    if isinstance(value, float):
        return (type(value), value.hex())
    return (type(value), value)


def test_plain_value_is_the_walk_it_was():
    rng = np.random.default_rng(13)
    for _ in range(3000):
        value = random_value(rng)
        assert plain_repr(plain_value(value)) == plain_repr(walked_plain_value(value))


def test_plain_value_copies_flat_lists_and_dicts():
    items, table = [1.0, 2.0], {"a": 1.0}
    assert plain_value(items) is not items and plain_value(table) is not table


def engine_line_record(rng, label):
    return Record(
        scenario="disk-wall", point={"index": 0, "parameter": "mu", "value": 0.2,
                                     "label": label},
        source="pymunk", preset="defaults", u_before=[1.0, -2.0, 0.0],
        u_after=rng.normal(size=3).tolist(), status="ok",
        wall_time_s=float(rng.random()), departure={"poisson": float(rng.random()),
                                                    "newton": math.nan},
        diagnostics={"notes": [label, ',"cached":false,"diagnostics":'],
                     "derived": {"cached": False}}, reasons=[{"name": "x", "fails": True}])


@pytest.mark.parametrize("label", ["μ = 0.2", ',"cached":false,"diagnostics":{',
                                   'quote " and \\ backslash', "line\nbreak"])
def test_a_cached_line_is_the_line_of_the_cached_record(label):
    rng = np.random.default_rng(14)
    for _ in range(20):
        data = engine_line_record(rng, label).as_dict()
        stored = {**data, "cached": True}
        assert scenario_records._cached_line(record_line(data), stored) == record_line(stored)


def test_a_line_of_another_layout_is_spelled_in_full():
    stored = {"scenario": "s", "cached": True}
    assert scenario_records._cached_line('{"scenario":"s"}', stored) == record_line(stored)
    assert records.record_line(stored) == '{"scenario":"s","cached":true}'


STRICT = verdicts.Tolerances(separation=1e-9, penetration=1e-3, impulse_residual=1e-12,
                             impulse=1e-12, energy=1e-15, energy_beyond_law=1e-3, cap=0.999)


@pytest.mark.parametrize("engine_name", ["pymunk", "box2d"])
def test_a_verdict_given_its_terms_and_implied_impulse_is_the_one_worked_out(engine_name):
    """engine_record hands the verdict the point's prepared terms and the impulse it already
    implied from Δu: the verdict is the one judge works out alone, bit for bit, at the
    default tolerances and at strict ones where every check fires."""
    try:
        engine = load_engine(engine_name)
    except EngineNotInstalled as error:
        pytest.skip(str(error))
    settings = engine.settings("defaults")
    judged = 0
    for path in sorted(SCENARIO_DIR.glob("*.toml"))[::3]:
        scenario = load_scenario(path)
        if scenario.analytic_only:
            continue
        point = scenario.point_list()[0]
        scene = scenario.scene(point)
        if verdicts.declared_contacts(scenario, scene) is not None:
            continue
        problem = scenario.analytic_problem(point)
        output = tasks.engine_task({"engine": engine_name, "scene": scene,
                                     "settings": settings})
        if "velocities" not in output:
            continue
        u_after = np.array([v for body in output["velocities"] for v in body], dtype=float)
        implied = metrics.impulses_from_velocities(problem, u_after,
                                                   free_bodies=not scene.ground)
        assert math.isfinite(implied[2])
        terms = verdicts.prepare(scene, problem)
        for tolerances in (verdicts.DEFAULT_TOLERANCES, STRICT):
            alone = verdicts.judge(scene, problem,
                                   verdicts.numbers_from_output(engine_name, output),
                                   tolerances=tolerances)
            given = verdicts.judge(scene, problem,
                                   verdicts.numbers_from_output(engine_name, output),
                                   tolerances=tolerances, terms=terms, implied=implied)
            assert repr(given) == repr(alone), scenario.name
        judged += 1
    assert judged > 3


def stepwise_contact_history(problem, output, scene, time_step):
    """history.contact_history as it was (its docstring aside): every row's speeds and
    products one at a time, and a pose history's impulses through impulses_from_velocities."""
    steps = output.get("contacts") or []
    normal = output.get("contact_normal")
    if not steps or normal is None or not time_step > 0:
        return None
    mass_matrix = np.asarray(problem.mass_matrix, dtype=float)
    u_before = np.asarray(problem.u, dtype=float)
    wn, wt = np.asarray(problem.wn, dtype=float), np.asarray(problem.wt, dtype=float)
    if all(step.get("impulse") is not None for step in steps):
        source = history.SOURCES[0]
        n_x, n_y = float(normal[0]), float(normal[1])
        response_n = np.linalg.solve(mass_matrix, wn)
        response_t = np.linalg.solve(mass_matrix, wt)
        total_x = total_y = 0.0
        speeds, impulses = [], []
        for step in steps:
            p_x, p_y = step["impulse"]
            total_x += p_x
            total_y += p_y
            p_n = total_x * n_x + total_y * n_y
            p_t = total_x * n_y - total_y * n_x
            speeds.append(u_before + response_n * p_n + response_t * p_t)
            impulses.append((p_n, p_t))
    elif output.get("start_offset_steps") is not None:
        source = history.SOURCES[1]
        speeds = history._from_poses(steps, scene, float(output["start_offset_steps"]),
                                     time_step)
        if speeds is None:
            return None
        impulses = [metrics.impulses_from_velocities(problem, u)[:2] for u in speeds]
    else:
        return None
    first = int(steps[0]["step"])
    rows = [(first - 1, 0.0, 0.0, u_before, 0.0)]
    for step, u, (p_n, p_t) in zip(steps, speeds, impulses):
        depth = max((point[2] for point in step["points"]), default=0.0)
        rows.append((int(step["step"]), p_n, p_t, u, max(depth, 0.0)))
    rows = history._thin(rows, history.MAX_HISTORY_STEPS + 1)
    end = np.array([v for body in output["velocities"] for v in body], dtype=float)
    mismatch = metrics.departure(mass_matrix, speeds[-1], end, u_before,
                                 free_bodies=not scene.ground)
    return {
        "source": source,
        "contact_steps": len(steps),
        "end_mismatch": float(mismatch),
        "step": [row[0] for row in rows],
        "time_ms": [1e3 * time_step * (row[0] - first + 1) for row in rows],
        "normal_impulse": [float(row[1]) for row in rows],
        "tangential_impulse": [float(row[2]) for row in rows],
        "vn": [float(wn @ row[3]) for row in rows],
        "vt": [float(wt @ row[3]) for row in rows],
        "penetration": [float(row[4]) for row in rows],
        "kinetic_energy": [0.5 * float(row[3] @ mass_matrix @ row[3]) for row in rows],
    }


def random_history_case(rng, poses: bool):
    """A problem, an engine output with contact steps (impulses, or poses only) and a scene
    of ``bodies`` bodies, some runs longer than the stored history."""
    bodies = int(rng.integers(1, 3))
    size = 3 * bodies
    problem = SimpleNamespace(mass_matrix=random_mass_matrix(rng, size),
                              u=rng.normal(size=size), wn=rng.normal(size=size),
                              wt=rng.normal(size=size))
    count = int(rng.choice([1, 2, 7, 40, 450]))
    first = int(rng.integers(1, 20))
    steps = []
    for index in range(count):
        step = {"step": first + index,
                "points": [tuple(rng.normal(size=3)) for _ in range(int(rng.integers(0, 3)))],
                "bodies": [tuple(rng.normal(size=3)) for _ in range(bodies)]}
        if not poses:
            step["impulse"] = tuple(rng.normal(size=2) * 1e-3)
        steps.append(step)
    scene = SimpleNamespace(ground=bodies == 1, bodies=[SimpleNamespace(
        position=tuple(rng.normal(size=2)), velocity=tuple(rng.normal(size=2)),
        angle=float(rng.normal()), angular_velocity=float(rng.normal()))
        for _ in range(bodies)])
    output = {"contacts": steps, "contact_normal": tuple(rng.normal(size=2)),
              "velocities": [tuple(rng.normal(size=3)) for _ in range(bodies)],
              "start_offset_steps": 2.0 if poses else None}
    return problem, output, scene


@pytest.mark.parametrize("poses", [False, True])
def test_contact_history_is_the_stepwise_one(poses):
    rng = np.random.default_rng(15 + poses)
    for _ in range(60):
        problem, output, scene = random_history_case(rng, poses)
        time_step = float(rng.choice([1e-3, 1 / 240]))
        found = history.contact_history(problem, output, scene, time_step)
        expected = stepwise_contact_history(problem, output, scene, time_step)
        assert found.keys() == expected.keys()
        assert plain_repr(found) == plain_repr(expected)


def test_a_dict_field_holding_the_cached_key_is_spelled_in_full():
    """A key ``cached`` inside ``point`` (before the field in the line) matches the marker
    too: the line is then spelled in full, not edited at the wrong place."""
    rng = np.random.default_rng(15)
    data = engine_line_record(rng, "label").as_dict()
    data["point"] = {"a": 1, "cached": False, "diagnostics": 1}
    stored = {**data, "cached": True}
    assert scenario_records._cached_line(record_line(data), stored) == record_line(stored)
