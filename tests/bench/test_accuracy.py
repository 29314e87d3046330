"""Smoke test of the speed–accuracy benchmark (the benchmark itself lives outside the suite)."""

from __future__ import annotations

import pytest

from harness.bench import accuracy as bench_accuracy
from harness.engines import ENGINE_NAMES


@pytest.mark.parametrize("name", ENGINE_NAMES)
def test_every_sweep_point_is_a_valid_setting(name, load_or_skip):
    engine = load_or_skip(name)
    for quick in (True, False):
        points = bench_accuracy.sweep(name, quick)
        assert len({label for label, _, _ in points}) == len(points)  # labels identify points
        for _, preset, overrides in points:
            engine.settings(preset, overrides)  # raises EngineSettingsError on a bad key/value


def test_pareto_front_and_cheapest_setting():
    assert bench_accuracy.pareto_front([(3, 1e-3), (1, 1e-1), (2, 1e-1), (4, 1e-6)]) == [
        (1, 1e-1), (3, 1e-3), (4, 1e-6)]
    rows = []
    for label, time_s, error in (("slow-exact", 3.0, 1e-9), ("fast-rough", 1.0, 5e-3),
                                 ("fastest-bad", 0.5, 0.2)):
        for family in bench_accuracy.FAMILIES:
            rows.append({"setting": label, "family": family, "status": "ok",
                         "time_per_impact_s": time_s, "departure": {"own": error}})
    table = bench_accuracy.cheapest_settings({"rows": rows})
    assert table["0.01"]["setting"] == "fast-rough"
    assert table["0.001"]["setting"] == "slow-exact"
    rows = [dict(row, departure={"own": 0.5}) for row in rows]
    assert bench_accuracy.cheapest_settings({"rows": rows})["0.01"]["setting"] == "not reachable"


def test_measure_pymunk_on_two_points(monkeypatch, load_or_skip):
    load_or_skip("pymunk")
    monkeypatch.setattr(bench_accuracy, "sweep", lambda name, quick: [
        ("it=100", "accurate", {"time_step": 1e-3, "iterations": 100}),
        ("it=1", "accurate", {"time_step": 1e-3, "iterations": 1})])
    result = bench_accuracy.measure_engine("pymunk", quick=True)
    rows = {(r["setting"], r["family"]): r for r in result["rows"]}
    assert len(rows) == 2 * len(bench_accuracy.FAMILIES)
    # the accurate setting solves newton-lcp to rounding on every family (docs/engines.md,
    # 'pymunk': ~1e-12); 1e-9 leaves room for the step's position update
    for family in bench_accuracy.FAMILIES:
        assert rows[("it=100", family)]["departure"]["own"] < 1e-9, family
        assert rows[("it=100", family)]["time_per_impact_s"] > 0
    # one iteration on the coupled rod is far off (docs/engines.md, 'pymunk': 2-5 iterations
    # are badly wrong)
    assert rows[("it=1", "rod")]["departure"]["own"] > 1e-3


def test_a_converged_engine_is_measured_against_the_point_it_names(monkeypatch, toy_engine,
                                                                   tmp_path, capsys):
    # own_law "converged" used to need MuJoCo's reference label in the sweep (a StopIteration
    # otherwise); an engine names its own point (bench_reference) or bench refuses it at once.
    from harness import cli
    from tests.engines.toy_engine import ToyEngine

    monkeypatch.setattr(ToyEngine, "own_law", "converged")
    out = tmp_path / "bench"
    assert cli.main(["bench", "--speed-accuracy", "--quick", "--out", str(out)]) == 2
    error = capsys.readouterr().err
    assert "engine 'toy': own_law 'converged' needs bench_reference" in error
    assert "allowed: ['defaults', 'accurate']" in error
    assert not out.exists()  # refused before any work
    monkeypatch.setattr(ToyEngine, "bench_reference", "accurate")
    result = bench_accuracy.measure_engine(toy_engine, quick=True)
    assert result["reference_setting"] == "accurate"
    rows = [row for row in result["rows"] if row["setting"] == "accurate"]
    assert rows and all(row["departure"]["own"] == 0.0 for row in rows)  # itself
    cheapest = bench_accuracy.cheapest_settings(result)
    assert {cell["setting"] for cell in cheapest.values()} == {"defaults"}  # not the reference


def test_an_engine_claiming_any_law_of_the_registry_is_measured_from_it(monkeypatch,
                                                                         toy_engine):
    # The bench measures every engine from Poisson, Stronge and newton-lcp; an engine that
    # claims another law of the registry (here Newton's, which check_engine would hold its
    # accurate preset to) is measured from that one too.
    from tests.engines.toy_engine import ToyEngine

    monkeypatch.setattr(ToyEngine, "own_law", "newton")
    result = bench_accuracy.measure_engine(toy_engine, quick=True)
    for row in result["rows"]:
        assert set(row["departure"]) == {*bench_accuracy.BENCH_LAWS, "newton", "own"}
        assert row["departure"]["own"] == row["departure"]["newton"]
