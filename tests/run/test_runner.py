"""The runner: records, departures, the split, gates, skipped engines, cache, results file."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

import harness.engines as engines_module
from harness.engines import ENGINE_NAMES, EngineNotInstalled, UnsupportedScene, engine_names
from harness.run import metrics, plan, runner, tasks
from harness.run.records import ANALYTIC, read_results, write_results
from harness.scenarios import SCENARIO_DIR, load_scenario
from harness.store.cache import ResultCache

ROD = load_scenario(SCENARIO_DIR / "rod-45-slip-reversal.toml")
TWO_SLED = load_scenario(SCENARIO_DIR / "two-sled-row2.toml")
DISK_SWEEP = load_scenario(SCENARIO_DIR / "sweep-disk-alpha.toml")
# Engines that solve newton-lcp exactly under `accurate` reach it to round-off
# (docs/engines.md, 'pymunk' and 'pybullet': about 1e-12); the tests allow 1e-9 relative
# in the kinetic-energy norm.
EXACT = 1e-9


def quiet_run(scenarios, **options):
    options.setdefault("cache", None)
    options.setdefault("workers", 1)
    return runner.run(scenarios, log=None, **options)


def by_label(records):
    return {r.label: r for r in records}


def test_one_record_per_scenario_point_and_source():
    outcome = quiet_run([ROD, DISK_SWEEP])
    for scenario in (ROD, DISK_SWEEP):
        records = [r for r in outcome.records if r.scenario == scenario.name]
        points = len(scenario.point_list())
        assert len(records) == points * (len(scenario.laws) + len(ENGINE_NAMES) * 2)
        keys = {(r.point["index"], r.label) for r in records}
        assert len(keys) == len(records)


def test_analytic_only_systems_never_start_an_engine(monkeypatch):
    def refuse(name):
        raise AssertionError(f"engine {name} loaded for an analytic-only scenario")

    monkeypatch.setattr(engines_module, "load_engine", refuse)
    outcome = quiet_run([TWO_SLED])
    assert {r.source for r in outcome.records} == {ANALYTIC}
    assert len(outcome.records[0].u_after) == 4  # the system's own speeds u1, u3, u4, u6


def test_law_records_match_planar_impact():
    records = by_label(quiet_run([ROD]).records)
    for law in ROD.laws:
        expected = ROD.solve(law=law)
        record = records[law]
        assert record.u_after == expected.u_after.tolist()  # the same computation, exact
        assert record.collision_type == expected.collision_type
        assert record.departure[law] == 0.0


def test_departure_is_the_relative_kinetic_energy_norm():
    records = by_label(quiet_run([ROD]).records)
    problem = ROD.analytic_problem()
    mass = problem.mass_matrix
    engine = records["mujoco.defaults"]
    poisson = np.array(records["poisson"].u_after)
    u = np.array(engine.u_after)
    by_hand = math.sqrt((u - poisson) @ mass @ (u - poisson)) / math.sqrt(
        problem.u @ mass @ problem.u)
    assert engine.departure["poisson"] == pytest.approx(by_hand, rel=1e-14)  # same formula


def test_engine_contact_velocities_and_impulses_come_from_its_speeds():
    records = by_label(quiet_run([ROD]).records)
    lcp = records["newton-lcp"]
    for label in ("pymunk.accurate", "pybullet.accurate"):
        engine = records[label]
        assert engine.departure["newton-lcp"] < EXACT
        scale = abs(lcp.vn_approach)
        assert abs(engine.vn_separation - lcp.vn_separation) < EXACT * scale
        assert abs(engine.vt_separation - lcp.vt_separation) < EXACT * scale
        assert engine.collision_type == lcp.collision_type  # end-state numbering, like the law
        derived = engine.diagnostics["impulse_from_velocities"]
        assert derived[0] == pytest.approx(lcp.normal_impulse, rel=EXACT)
        assert derived[1] == pytest.approx(lcp.tangential_impulse, rel=EXACT)
        for key in ("steps", "max_contact_points", "max_penetration", "separated"):
            assert key in engine.diagnostics


def test_the_split_of_a_departure():
    records = by_label(quiet_run([ROD]).records)
    for label in ("pymunk.defaults", "pybullet.defaults", "mujoco.matched-bounce"):
        split = metrics.departure_split(records[label].departure, records["newton-lcp"].departure)
        assert split["law_part"] == records["newton-lcp"].departure["poisson"]
        # triangle inequality of the norm; 1e-12 absorbs round-off of the three norms
        assert split["total"] <= split["law_part"] + split["solve_part"] + 1e-12
    # On this rod the law itself is ~20% from Poisson, the exact engines ~0
    # (docs/engines.md, 'The reference scenes').
    assert records["newton-lcp"].departure["poisson"] > 0.15
    assert records["pymunk.accurate"].departure["newton-lcp"] < EXACT


def test_classify_end_state():
    assert metrics.classify_end_state(1.0, 0.0, -1.0) == 1
    assert metrics.classify_end_state(1.0, 0.5, -1.0) == 3
    assert metrics.classify_end_state(1.0, -0.5, -1.0) == 2
    assert metrics.classify_end_state(0.0, -0.5, -1.0) == 3  # no initial slip: forward
    assert metrics.classify_end_state(1.0, float("nan"), -1.0) is None


def test_missing_engine_is_skipped_with_the_reason(monkeypatch):
    real = engines_module.load_engine

    def without_mujoco(name):
        if name == "mujoco":
            raise EngineNotInstalled("mujoco", "test: pretend it is missing")
        return real(name)

    monkeypatch.setattr(engines_module, "load_engine", without_mujoco)
    outcome = quiet_run([ROD])
    mujoco = [r for r in outcome.records if r.source == "mujoco"]
    assert len(mujoco) == 2
    for record in mujoco:
        assert record.status.startswith("skipped: ") and "pip install mujoco" in record.status
        assert record.departure == {} and record.u_after is None
    assert by_label(outcome.records)["pymunk.accurate"].ok
    assert "mujoco" in outcome.provenance["engines_missing"]
    # the gates of a skipped engine are not checked, never failed
    assert not outcome.failed_gates


def test_engine_that_cannot_build_the_scene_is_skipped(monkeypatch):
    class Refusing:
        def run(self, scene, settings):
            raise UnsupportedScene("test: no such shape here")

    monkeypatch.setattr(engines_module, "load_engine", lambda name: Refusing())
    output = tasks.engine_task({"engine": "pymunk", "settings": {}, "scene": ROD.scene()})
    assert output["status"] == "skipped: engine cannot build the scene: test: no such shape here"


def test_gates_pass_and_fail(tmp_path):
    assert ROD.expect.gates and all(g.status == "pass" for g in quiet_run([ROD]).gates)
    strict = tmp_path / "strict.toml"
    strict.write_text(
        (SCENARIO_DIR / "rod-45-slip-reversal.toml").read_text().replace(
            'name = "rod-45-slip-reversal"', 'name = "strict-rod"')
        + '"mujoco.defaults" = { law = "poisson", max_departure = 1e-3 }\n')
    outcome = quiet_run([load_scenario(strict)])
    failed = outcome.failed_gates
    assert [g.gate for g in failed] == ["mujoco.defaults"]
    assert "strict-rod" in failed[0].describe() and "mujoco.defaults" in failed[0].describe()


def test_cache_hits_give_the_same_records(tmp_path):
    cold = quiet_run([ROD], cache=ResultCache(tmp_path / "cache"))
    cache = ResultCache(tmp_path / "cache")
    warm = quiet_run([ROD], cache=cache)
    assert cache.misses == 0 and cache.hits == len(ENGINE_NAMES) * 2  # two presets
    assert warm.provenance["cache"]["simulated"] == 0

    def strip(record):
        return {k: v for k, v in record.as_dict().items() if k not in ("wall_time_s", "cached")}

    for a, b in zip(cold.records, warm.records):
        da, db = strip(a), strip(b)
        for d in (da, db):
            if d["diagnostics"]:
                d["diagnostics"].pop("engine_wall_time_s", None)
        assert da == db


def test_parallel_executor_gives_identical_records():
    inline = quiet_run([DISK_SWEEP], workers=1)
    pooled = quiet_run([DISK_SWEEP], workers=2)
    assert [r.u_after for r in inline.records] == [r.u_after for r in pooled.records]
    assert [r.status for r in inline.records] == [r.status for r in pooled.records]


def test_results_file_round_trip_and_provenance(tmp_path):
    outcome = quiet_run([ROD])
    path = write_results(tmp_path / "r.json", outcome.records, outcome.provenance,
                         outcome.scenarios)
    loaded = read_results(path)
    assert [r.as_dict() for r in loaded.records] == [r.as_dict() for r in outcome.records]
    prov = loaded.provenance
    for package in ("numpy", "pymunk", "pybullet", "mujoco", "box2d"):
        assert prov["versions"][package]
    assert set(prov["engine_settings"]) == set(ENGINE_NAMES)
    assert set(prov["engine_settings"]["pymunk"]) == {"defaults", "accurate"}
    for key in ("git", "machine", "created_utc", "code_version", "cache", "gates"):
        assert key in prov
    assert loaded.scenarios["rod-45-slip-reversal"]["speed_labels"][0] == "rod.v_x [m/s]"
    document = json.loads(path.read_text())
    assert document["format"] == "impact-harness-results" and document["format_version"] == 1


def test_non_finite_engine_numbers_are_written_as_null(tmp_path):
    record = quiet_run([ROD]).records[-1]
    record.u_after = [float("nan"), 1.0, float("inf")]
    path = write_results(tmp_path / "r.json", [record], {})
    assert read_results(path).records[0].u_after == [None, 1.0, None]


def test_parse_options():
    assert plan.parse_engines("pymunk, mujoco") == ("pymunk", "mujoco")
    # as experiments --engines all takes it
    assert plan.parse_engines("all") == plan.parse_engines(None) == engine_names()
    assert plan.parse_presets("all") == ("defaults", "accurate")
    with pytest.raises(ValueError, match="unknown engine"):
        plan.parse_engines("bullet")
