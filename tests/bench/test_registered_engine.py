"""A registered engine goes through `impact-harness bench` as the shipped ones do: the
test-only toy of tests/engines/toy_engine.py, the only engine listed (the ``toy_engine``
fixture of tests/conftest.py), measured by ``--engines`` and ``--survey``."""

from __future__ import annotations

import json

from harness import cli
from harness.bench import survey as bench_survey


def test_the_toy_goes_through_bench_engines_and_survey(tmp_path, monkeypatch, capsys,
                                                       toy_engine):
    monkeypatch.setattr(bench_survey, "QUICK_SAMPLES", 2)  # 14 impacts: seconds
    out = tmp_path / "bench"
    assert cli.main(["bench", "--engines", "--survey", "--quick", "--out", str(out)]) == 0
    table = json.loads((out / "bench.json").read_text(encoding="utf-8"))
    overhead = table["engines"]["engines"]
    assert list(overhead) == [toy_engine] and overhead[toy_engine]["available"]
    rows = overhead[toy_engine]["rows"]
    assert {row["preset"] for row in rows} == {"defaults", "accurate"}
    # exact impulses: every benchmarked run a single impact, rerun bit for bit
    assert all(row["verdict"] == "ok" and row["deterministic"] for row in rows)
    assert all(row["harness_us"] > 0 and row["bare_us"] > 0 for row in rows)
    survey = table["survey"]
    assert survey["engines"] == [toy_engine]
    assert set(survey["pairs"]) == {"toy.defaults", "toy.accurate"}
    assert survey["impacts"] == 2 * 7 and survey["survey_cpu_s"] > 0
    printed = capsys.readouterr().out
    assert "toy " in printed and "toy.accurate" in printed


def test_bench_engines_skips_a_scene_the_engine_refuses(monkeypatch, toy_engine):
    # UnsupportedScene is a skip everywhere (the runner, check_engine, the contract tests,
    # the bench), never a crash: the toy refusing capsules benchmarks the other scenes.
    from harness.bench import engines as bench_engines
    from harness.engines import UnsupportedScene
    from tests.engines.toy_engine import ToyEngine

    def refuse_rods(self, scene, settings, *, contacts=True):
        if any(body.shape.kind == "rod" for body in scene.bodies):
            raise UnsupportedScene("engine 'toy': no capsules (a test's refusal)")
        return original(self, scene, settings, contacts=contacts)

    original = ToyEngine._build
    monkeypatch.setattr(ToyEngine, "_build", refuse_rods)
    report = bench_engines.run_engine_overhead_benchmark(quick=True, engines=[toy_engine])
    rows = report["engines"][toy_engine]["rows"]
    skipped = [row for row in rows if "skipped" in row]
    assert {(row["scene"], row["preset"]) for row in skipped} == {
        ("rod-45", "defaults"), ("rod-45", "accurate")}
    assert all("no capsules" in row["skipped"] for row in skipped)
    assert all(row["deterministic"] for row in rows if "skipped" not in row)
    table = bench_engines.format_table(report)
    assert "rod-45      skipped: engine 'toy': no capsules" in table


def test_bench_survey_leaves_out_the_scenes_where_the_engine_raised(monkeypatch, toy_engine):
    # An engine raising on a scene (Drake's accurate failing to converge) is an error the
    # survey records; the bench times every pair on the other scenes, both sides alike.
    from harness.engines import load_engine
    from harness.survey.population import resolve_populations
    from harness.survey.sampling import sample_population
    from tests.engines.toy_engine import ToyEngine

    monkeypatch.setattr(bench_survey, "QUICK_SAMPLES", 2)
    scenes = [sample.scene for population in resolve_populations([])
              for sample in sample_population(population, 2, 0).samples]
    faulty = scenes[1]
    engine = load_engine(toy_engine)
    clean_steps = {preset: [run.steps for run in engine.run_many(scenes,
                                                                 engine.settings(preset))]
                   for preset in ("defaults", "accurate")}
    original = ToyEngine._prepare

    def prepare(self, world, scene, settings, start, weights):
        if scene is faulty or (scene.friction, scene.restitution, scene.bodies[-1].velocity) \
                == (faulty.friction, faulty.restitution, faulty.bodies[-1].velocity):
            raise RuntimeError("toy failed to converge (a test's fault)\nmore advice")
        return original(self, world, scene, settings, start, weights)

    monkeypatch.setattr(ToyEngine, "_prepare", prepare)
    report = bench_survey.run(2, engines=[toy_engine], rounds=1)
    for preset in ("defaults", "accurate"):
        entry = report["pairs"][f"toy.{preset}"]
        assert entry["errored"] == 1
        assert entry["error"] == "RuntimeError: toy failed to converge (a test's fault)"
        # the contract's run (whose steps the bare sides repeat) is of the other scenes
        assert entry["steps"] == sum(clean_steps[preset]) - clean_steps[preset][1]
    text = bench_survey.format_report(report)
    assert "toy.accurate: 1 of 14 (RuntimeError: toy failed to converge" in text
