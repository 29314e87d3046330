"""Stress properties of the solver (hypothesis) and a smoke test of `impact-harness stress`."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st

import planar_impact as pi
from harness import stress
from harness.engines import (
    PRESET_ROLES,
    EngineNotInstalled,
    UnsupportedScene,
    engine_names,
    source_label,
)
from harness.stress import engines as stress_engines
from harness.stress import outputs as stress_outputs
from harness.stress import solver as stress_solver

LAWS = pi.LAWS
OUTPUTS = ("normal_impulse", "tangential_impulse", "vn_separation", "vt_separation",
           "energy_change")


@st.composite
def extreme_problems(draw):
    """Contact-space problems with magnitudes from 1e-30 to 1e30 and edge values of e and μ."""
    mnn = 10.0 ** draw(st.floats(-30, 30))
    mtt = mnn * 10.0 ** draw(st.floats(-12, 12))
    rho = draw(st.one_of(st.floats(-1.0, 1.0), st.sampled_from([0.0, 1.0, -1.0, 1 - 1e-15])))
    mnt = rho * math.sqrt(mnn * mtt)
    speed = 10.0 ** draw(st.floats(-30, 30))
    # |v_n|/|v_t| down to 1e-12 (grazing); the overflow at ~1e-300 is pinned below
    vn = -speed * draw(st.floats(1e-12, 1.0))
    vt = speed * draw(st.one_of(st.floats(-1e9, 1e9), st.just(0.0)))
    mu = draw(st.one_of(st.sampled_from([0.0, 10.0, 1e6]),
                        st.floats(0.0, 20.0, allow_subnormal=False)))
    e = draw(st.one_of(st.sampled_from([0.0, 1.0]), st.floats(0.0, 1.0)))
    return dict(mnn=mnn, mnt=mnt, mtt=mtt, vn=vn, vt=vt, mu=mu, e=e)


def _solve(problem, law):
    return pi.solve_batch(problem["mnn"], problem["mnt"], problem["mtt"], problem["vn"],
                          problem["vt"], problem["mu"], problem["e"], law=law)


# Found by hypothesis: the slip stops exactly at the end of compression (v_0 = 0) and the
# restitution work e²·W_c is subnormal, so the Stronge step underflowed to R/0 = inf.
SUBNORMAL_STRONGE_WORK = {"mnn": 0.1, "mnt": 0.05, "mtt": 0.1, "vn": -0.5, "vt": -0.25, "mu": 0.0,
                          "e": 3.17111423255512e-162}


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(extreme_problems())
@example(SUBNORMAL_STRONGE_WORK)
def test_extreme_magnitudes_give_a_status_or_a_finite_answer(problem):
    for law in LAWS:
        result = _solve(problem, law)
        values = [float(getattr(result, name)) for name in OUTPUTS]
        if int(result.status) == 0:
            assert all(math.isfinite(v) for v in values), (law, problem, values)
        else:  # a bad row is marked, and its outputs are NaN, never a plausible number
            assert int(result.status) in pi.STATUS_MESSAGES and all(math.isnan(v) for v in values)


@settings(max_examples=300, deadline=None)
@given(extreme_problems())
@example(SUBNORMAL_STRONGE_WORK)
def test_poisson_and_stronge_never_gain_energy_at_extreme_magnitudes(problem):
    for law in stress_solver.ENERGY_LAWS:
        result = _solve(problem, law)
        if int(result.status) != 0:
            continue
        # ΔE by (A29) sums products of size |v|·I: rounding ~1e-16 of that scale, amplified by
        # 1/c for a nearly singular M (c = Δ/(m_nn m_tt)); energy_tolerance allows both.
        scale = (abs(problem["vn"]) * float(result.normal_impulse)
                 + abs(problem["vt"] * float(result.tangential_impulse)))
        tolerance = float(stress_solver.energy_tolerance(problem["mnn"], problem["mnt"],
                                                         problem["mtt"]))
        assert float(result.energy_change) <= tolerance * scale, (law, problem)


def _not_tiny(low, high):
    """Floats in [low, high] that are 0 or at least 1e-6 in size: exact power-of-two scaling
    needs every intermediate product to stay a normal number (tiny factors make subnormals)."""
    return st.floats(low, high).filter(lambda x: x == 0.0 or abs(x) >= 1e-6)


@st.composite
def conditioned_problems(draw):
    mnn = 10.0 ** draw(st.floats(-3, 3))
    mtt = 10.0 ** draw(st.floats(-3, 3))
    mnt = draw(_not_tiny(-0.95, 0.95)) * math.sqrt(mnn * mtt)
    return dict(mnn=mnn, mnt=mnt, mtt=mtt, vn=-(10.0 ** draw(st.floats(-3, 3))),
                vt=draw(_not_tiny(-1e3, 1e3)), mu=draw(_not_tiny(0.0, 3.0)),
                e=draw(_not_tiny(0.0, 1.0)))


@settings(max_examples=200, deadline=None)
@given(conditioned_problems(), st.integers(-60, 60), st.floats(-6, 6))
def test_scaling_all_masses_by_k_scales_impulses_by_k(problem, power_of_two, log_k):
    """Masses × k ⇒ inverse-inertia terms ÷ k ⇒ impulses × k, contact velocities unchanged.

    With k a power of two every operation scales exactly: bit-identical answers. With any k,
    the answers agree to rounding (1e-9 of |I_n| + |I_t|: the closed forms lose at most a few
    digits on problems with Δ/(m_nn m_tt) ≥ 1 − 0.95²).
    """
    for law in LAWS:
        reference = _solve(problem, law)
        if int(reference.status) != 0:
            continue
        for k, exact in ((2.0**power_of_two, True), (10.0**log_k, False)):
            scaled = dict(problem, mnn=problem["mnn"] / k, mnt=problem["mnt"] / k,
                          mtt=problem["mtt"] / k)
            result = _solve(scaled, law)
            assert int(result.status) == 0
            impulses = np.array([result.normal_impulse, result.tangential_impulse]) / k
            expected = np.array([reference.normal_impulse, reference.tangential_impulse])
            # exactness needs normal numbers: a subnormal impulse has lost bits already
            if exact and np.all((expected == 0) | (np.abs(expected) > 1e-280)):
                assert np.array_equal(impulses, expected), (law, k)
                assert float(result.vt_separation) == float(reference.vt_separation)
            elif not exact:
                size = float(np.sum(np.abs(expected)))
                assert np.all(np.abs(impulses - expected) <= 1e-9 * size), (
                    law, k, impulses, expected)


@pytest.mark.parametrize("law", pi.LAWS)
def test_overflowing_alpha_is_not_a_silent_inf(law):
    """Found by the stress run: α = v_t/|v_n| ≈ 1e300 used to overflow (25) to I_n = inf
    with status 0. The closed forms now use α|v_n^A| = v_t^A; every law answers finitely or
    flags the row."""
    result = pi.solve_batch(1e9, 5e8, 1e9, -1e-300, 1.0, 10.0, 0.0, law=law)
    assert int(result.status) != 0 or np.isfinite(result.normal_impulse)


def test_boundaries_are_continuous_to_rounding():
    for boundary in stress_solver.BOUNDARIES:
        entry = stress_solver.boundary_jumps(boundary, "poisson", count=30, seed=1, ulps=2,
                                             deltas=np.array([1e-12, 1e-4]))
        assert entry["rows_solved_on_both_sides"] > 0, boundary.name
        # across a few ulps the impulses move by rounding only (≲1e-13 measured; 1e-9 flags)
        assert entry["max_ulp_jump"] < stress_solver.ULP_JUMP_TOLERANCE, (
            boundary.name, entry["max_ulp_jump"])
        # continuity: the change shrinks with the distance δ (1e-12 vs 1e-4)
        small, large = entry["max_jump_at_delta"]
        assert small <= max(1e-9, 1e-3 * large), (boundary.name, small, large)


def test_solver_families_have_no_silent_nan():
    for family, (_, problems) in stress_solver.solver_families(count=5, seed=3).items():
        for law in LAWS:
            summary = stress_solver.check_rows(stress_solver.solve_all(problems, law), problems)
            assert summary["silent_non_finite"] == 0, (family, law)
            if law in stress_solver.ENERGY_LAWS:
                assert summary["energy_gain_rows"] == 0, (family, law)


def test_engine_case_smoke():
    pytest.importorskip("pymunk", reason="pymunk is not installed")
    cases = {case["label"] + case["shape"]: case
             for case in stress_engines.engine_cases(quick=True)}
    record = stress_engines.run_engine_case({"case": cases["referencedisk"], "engine": "pymunk",
                                             "preset": "accurate"})
    assert record["outcome"] == "ok" and len(record["u_after"]) == 3
    record = stress_engines.run_engine_case({"case": cases["time_step=0.1rod"],
                                             "engine": "pymunk", "preset": "accurate"})
    assert record["outcome"] in stress_engines.OUTCOMES


def test_run_solver_only_writes_the_report(tmp_path, monkeypatch):
    monkeypatch.setattr(stress, "solver_stress", lambda quick: _tiny_solver_report())
    (tmp_path / "engine-grid.png").write_bytes(b"\x89PNG\r\n\x1a\n")  # an earlier run's
    report = stress.run(quick=True, out_dir=tmp_path, engines=False)
    assert not (tmp_path / "engine-grid.png").exists()  # no engine ran: no grid shown
    for name in ("stress.md", "stress.json", "stress-engines.csv", "solver-boundary-jumps.png",
                 "solver-energy.png"):
        assert (tmp_path / name).exists(), name
    assert report["solver"]["totals"]["silent_non_finite"] == 0


def _tiny_solver_report() -> dict:
    report = {"families": {}, "boundaries": []}
    for family, (_parameter, problems) in stress_solver.solver_families(count=2, seed=0).items():
        report["families"][family] = {}
        for law in LAWS:
            summary = stress_solver.check_rows(stress_solver.solve_all(problems, law), problems)
            summary["max_relative_energy_change_by_parameter"] = {"1.0": 0.0}
            report["families"][family][law] = summary
    report["boundaries"].append(stress_solver.boundary_jumps(
        stress_solver.BOUNDARIES[0], "poisson", 10, 0, ulps=1, deltas=np.array([1e-8])))
    report["scalar_api"] = stress_solver.scalar_api_checks(quick=True, seed=0)
    report["totals"] = {"silent_non_finite": 0, "energy_gain_poisson_stronge": 0,
                        "scalar_silent_non_finite": report["scalar_api"]["silent_non_finite"]}
    return report


def test_a_registered_engine_goes_through_impact_harness_stress(tmp_path, monkeypatch,
                                                                 toy_engine):
    """The test-only toy (tests/engines/toy_engine.py), registered and no other engine
    listed: `impact-harness stress` runs it on every case and reports it (the solver's part
    kept tiny, its figures not drawn: test_run_solver_only_writes_the_report draws them)."""
    from harness import cli

    monkeypatch.setattr(stress, "solver_stress", lambda quick: _tiny_solver_report())
    monkeypatch.setattr(stress, "boundary_jumps_figure", lambda solver, path: None)
    monkeypatch.setattr(stress, "energy_figure", lambda solver, path: None)
    out = tmp_path / "stress"
    assert cli.main(["stress", "--quick", "--out", str(out), "--no-cache", "--workers", "1"]) == 0
    report = json.loads((out / "stress.json").read_text(encoding="utf-8"))
    engines = report["engines"]
    assert set(engines["versions"]) == {toy_engine} and not engines["skipped"]
    cases = len(stress_engines.engine_cases(quick=True))
    # both presets, quick or not; exact impulses: every run a single impact
    assert engines["counts"] == {f"toy.{role}": {**dict.fromkeys(stress_engines.OUTCOMES, 0),
                                                 "ok": cases} for role in PRESET_ROLES}
    rows = (out / "stress-engines.csv").read_text(encoding="utf-8").splitlines()[1:]
    assert len(rows) == 2 * cases
    assert {row.split(",")[1] for row in rows} == set(PRESET_ROLES)
    assert "toy" in (out / "stress.md").read_text(encoding="utf-8")
    assert (out / "engine-grid.png").stat().st_size > 0


ENGINE_CASES = stress_engines.engine_cases  # the real ones, before a test replaces them


def _two_cases(quick: bool) -> list[dict]:
    """The reference disk and the 1e-4 m rod (Box2D refuses it: ``unsupported``)."""
    return [case for case in ENGINE_CASES(quick)
            if (case["shape"], case["label"]) in {("disk", "reference"), ("rod", "size=0.0001")}]


def test_every_registered_engine_is_stressed_or_reported_not_installed(tmp_path, monkeypatch):
    """The coverage rule: every engine of the registry (the five shipped ones) runs every
    case under both presets, or is listed as not installed with the reason; none is dropped.
    One engine is made to look missing here, so both branches are taken wherever the test
    runs; the others run for real on two cases."""
    hidden = engine_names()[-1]
    real_load = stress_engines.load_engine

    def load(name):
        if name == hidden:
            raise EngineNotInstalled(name, "hidden by the test")
        return real_load(name)

    monkeypatch.setattr(stress_engines, "load_engine", load)
    monkeypatch.setattr(stress_engines, "engine_cases", _two_cases)
    report = stress_engines.engine_stress(quick=True, workers=1, use_cache=False,
                                          cache_root=tmp_path / "cache")
    assert set(report["versions"]) | set(report["skipped"]) == set(engine_names())
    assert not set(report["versions"]) & set(report["skipped"])
    assert "hidden by the test" in report["skipped"][hidden]
    ran = {(r["engine"], r["preset"], r["shape"], r["label"]) for r in report["runs"]}
    assert ran == {(name, role, case["shape"], case["label"]) for name in report["versions"]
                   for role in PRESET_ROLES for case in _two_cases(True)}
    assert all(r["outcome"] in stress_engines.OUTCOMES for r in report["runs"])
    # what the outputs show of it: a row per engine and preset, one for the missing engine
    rows = [label for label, _ in stress_outputs.grid_rows(report)]
    assert rows[-1] == f"{hidden}: not installed" and len(rows) == 2 * len(report["versions"]) + 1
    text = stress_outputs.stress_markdown({"quick": True, "solver": _tiny_solver_report(),
                                           "engines": report,
                                           "provenance": {"created_utc": "now"},
                                           "timings": {"solver_s": 0.0, "engines_s": 0.0}})
    assert f"- **{hidden}**: engine {hidden!r} is not installed" in text
    for name in report["versions"]:
        assert all(f"| {source_label(name, role)} |" in text for role in PRESET_ROLES)


def test_box2d_refusing_a_tiny_body_is_reported_as_unsupported(load_or_skip):
    # Box2D's polygons have an area floor (b2_epsilon): the adapter refuses the 1e-4 m rod
    # (UnsupportedScene), an engine's stated limit, not a crash of the run
    load_or_skip("box2d")
    case = next(c for c in _two_cases(True) if c["shape"] == "rod")
    record = stress_engines.run_engine_case({"case": case, "engine": "box2d",
                                             "preset": "accurate"})
    assert record["outcome"] == "unsupported" and "b2_epsilon" in record["error"]


def test_an_engine_that_raises_refuses_or_dies_is_reported(tmp_path, monkeypatch, toy_engine):
    """An exception is ``error``, a refusal ``unsupported``, a worker that dies ``stopped``
    (the other runs go on, each with its outcome); none is dropped, and the stopped run is
    not cached, so a rerun tries it again."""
    import os

    from tests.engines.toy_engine import ToyEngine

    def faulty(self, scene, settings):
        speed = abs(scene.bodies[0].velocity[0])
        if math.isclose(speed, 100.0 / math.sqrt(2.0)):
            raise UnsupportedScene("engine 'toy': too fast (a test's refusal)")
        if math.isclose(speed, 1e-3 / math.sqrt(2.0)):
            raise RuntimeError("a test's blow-up")
        if math.isclose(speed, 1e4 / math.sqrt(2.0)):
            os._exit(3)  # the worker dies, as an engine crashing in C would take it
        return original(self, scene, settings)

    original = ToyEngine.run
    monkeypatch.setattr(ToyEngine, "run", faulty)
    monkeypatch.setattr(stress_engines, "engine_cases", lambda quick: [
        case for case in ENGINE_CASES(quick) if case["shape"] == "disk"
        and case["family"] in ("reference", "speed")])
    report = stress_engines.engine_stress(quick=True, workers=2, use_cache=True,
                                          cache_root=tmp_path / "cache")
    outcomes = {(r["preset"], r["label"]): r["outcome"] for r in report["runs"]}
    for role in PRESET_ROLES:
        assert outcomes[(role, "speed=100")] == "unsupported"
        assert outcomes[(role, "speed=0.001")] == "error"
        assert outcomes[(role, "speed=10000")] == "stopped"
        assert outcomes[(role, "reference")] == outcomes[(role, "speed=1e-06")] == "ok"
    stopped = next(r for r in report["runs"] if r["outcome"] == "stopped")
    assert "died" in stopped["error"] or "exit" in stopped["error"], stopped["error"]
    again = stress_engines.engine_stress(quick=True, workers=1, use_cache=True,
                                         cache_root=tmp_path / "cache")
    assert again["tasks_run"] == len(PRESET_ROLES)  # the stopped runs only
    # another harness/stress/ (how a run is judged) names every run anew: none is reused
    monkeypatch.setattr(stress_engines, "COMMAND_CODE_VERSION", "another stress code")
    anew = stress_engines.engine_stress(quick=True, workers=1, use_cache=True,
                                        cache_root=tmp_path / "cache")
    assert anew["tasks_run"] == len(anew["runs"]) == 2 * 5


def test_a_case_or_message_with_a_bar_stays_in_its_cell():
    # |v_n|/|v_t| (the grazing cases) and an engine's message may hold "|", which would
    # split the Markdown row the stress page is made of
    record = {"engine": "pymunk", "preset": "accurate", "shape": "disk", "family": "grazing",
              "label": "grazing=0.001", "value": 0.001, "outcome": "no-contact",
              "status": "no-contact", "energy_ratio": 1.0, "max_penetration_relative": 0.0,
              "error": "a | b"}
    engines = {"runs": [record], "skipped": {}, "cache": {"hits": 0, "misses": 1},
               "tasks_run": 1,
               "counts": {"pymunk.accurate": {**dict.fromkeys(stress_engines.OUTCOMES, 0),
                                              "no-contact": 1}}}
    text = stress_outputs.stress_markdown({"quick": True, "solver": _tiny_solver_report(),
                                           "engines": engines,
                                           "provenance": {"created_utc": "now"},
                                           "timings": {"solver_s": 0.0, "engines_s": 0.0}})
    lines = text.splitlines()
    header = lines.index("Runs not ok:") + 2
    row = next(line for line in lines[header:] if line.startswith("| pymunk.accurate"))
    assert row.count("|") == lines[header].count("|") == 8
    assert "disk: ∣v_n∣/∣v_t∣ 0.001" in row and "a ∣ b" in row
