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


def test_speed_accuracy_covers_every_registered_engine(tmp_path, monkeypatch):
    """The coverage rule: `bench --speed-accuracy` measures every engine of the registry (the
    five shipped ones) and draws its pareto-<engine>.png, or reports it not installed with
    the reason; none is dropped. One engine is made to look missing, so both branches are
    taken wherever the test runs; the others are measured for real on two settings each."""
    from harness.engines import EngineNotInstalled, engine_class, engine_names

    hidden = engine_names()[0]
    real_load, real_sweep = bench_accuracy.load_engine, bench_accuracy.sweep

    def load(name):
        if name == hidden:
            raise EngineNotInstalled(name, "hidden by the test")
        return real_load(name)

    def two_points(name, quick):
        """The engine's two first settings (seconds, not its finest)."""
        return real_sweep(name, quick)[:2]

    for name in engine_names():  # a converged engine converges to its second, here
        try:
            if engine_class(name).own_law == "converged":
                monkeypatch.setattr(engine_class(name), "bench_reference",
                                    two_points(name, True)[1][0])
        except EngineNotInstalled:
            continue
    monkeypatch.setattr(bench_accuracy, "load_engine", load)
    monkeypatch.setattr(bench_accuracy, "sweep", two_points)
    monkeypatch.setattr(bench_accuracy, "worker_speedup",
                        lambda quick: {"skipped": "not measured by this test"})
    # an earlier run's figure of the engine now missing: not shown as this run's
    (tmp_path / f"pareto-{hidden}.png").write_bytes(b"\x89PNG\r\n\x1a\n")
    report = bench_accuracy.run(quick=True, out_dir=tmp_path)
    assert list(report["engines"]) == list(engine_names())  # the registry's order
    assert "hidden by the test" in report["engines"][hidden]["skipped"]
    assert sorted(path.name for path in tmp_path.glob("pareto-*.png")) == sorted(
        f"pareto-{name}.png" for name, entry in report["engines"].items()
        if "skipped" not in entry)
    for name, entry in report["engines"].items():
        if "skipped" in entry:
            try:  # skipped only when it is not installed (here: the one hidden)
                real_load(name)
            except EngineNotInstalled:
                continue
            assert name == hidden, entry["skipped"]
            continue
        assert entry["figure"] == f"pareto-{name}.png"
        measured = {(row["setting"], row["family"]) for row in entry["rows"]}
        assert measured == {(label, family) for label, _, _ in two_points(name, True)
                            for family in bench_accuracy.FAMILIES}
    assert f"{hidden:9} skipped: " in bench_accuracy.format_table(report)
