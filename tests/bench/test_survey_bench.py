"""``impact-harness bench --survey``: both sides measured on the same impacts and processes."""

from __future__ import annotations

import pytest

from harness.bench import survey as bench_survey


def test_survey_bench_times_the_survey_and_the_bare_stepping_of_its_impacts():
    pytest.importorskip("pymunk")
    report = bench_survey.run(3, engines=("pymunk",), rounds=2)
    assert report["impacts"] == 3 * 7  # every population
    assert report["rounds"] == 2 and report["workers"] == 1
    assert set(report["pairs"]) == {"pymunk.defaults", "pymunk.accurate"}
    assert len(report["survey_cpu_rounds"]) == len(report["bare_cpu_rounds"]) == 2
    assert 0 < report["bare_cpu_s"] and 0 < report["survey_cpu_s"]
    assert report["ratio"] == pytest.approx(report["survey_cpu_s"] / report["bare_cpu_s"])
    for entry in report["pairs"].values():
        assert 0 < entry["bare_s"] < entry["bare_world_s"]
        assert entry["steps"] >= report["impacts"]  # at least one step per impact
        assert entry["contract_ratio"] == pytest.approx(entry["contract_s"] / entry["bare_s"])
        assert entry["world_ratio"] == pytest.approx(entry["contract_s"]
                                                     / entry["bare_world_s"])
        assert entry["judged_ratio"] == pytest.approx(entry["judged_s"] / entry["bare_s"])
    text = bench_survey.format_report(report)
    assert "ratio" in text and "pymunk.accurate" in text


def test_survey_bench_splits_the_bare_stepping_over_as_many_processes_as_the_survey():
    pytest.importorskip("pymunk")
    report = bench_survey.run(2, engines=("pymunk",), presets=("accurate",), rounds=1,
                              workers=2)
    assert report["workers"] == 2
    # the workers' CPU time is counted on both sides (forked, waited for)
    assert 0 < report["bare_cpu_s"] and 0 < report["survey_cpu_s"]
    assert "2 processes each" in bench_survey.format_report(report)


def test_survey_bench_measures_the_peak_memory_of_two_survey_sizes():
    pytest.importorskip("pymunk")
    report = bench_survey.memory((8, 40))
    assert report["sizes"] == [8, 40]
    # A Python with numpy, pyarrow and an engine: tens of MB, never the benchmark's own
    # peak (a process forked from it would keep that until its exec).
    assert all(30_000 < peak < 1_000_000 for peak in report["peak_kb"])
    assert report["ratio"] == pytest.approx(report["peak_kb"][1] / report["peak_kb"][0])
    assert "ratio" in bench_survey.format_memory(report)


def test_survey_bench_reports_targets_and_the_tripwire():
    pytest.importorskip("pymunk")
    report = bench_survey.run(2, engines=("pymunk",), presets=("defaults",), rounds=1)
    text = bench_survey.format_report(report)
    assert f"target <= {bench_survey.END_TO_END_TARGET}" in text
    assert f"tripwire at {bench_survey.CONTRACT_TRIPWIRE}" in text
    entry = report["pairs"]["pymunk.defaults"]
    assert entry["bare_s"] < entry["bare_world_s"]  # the user's loop builds worlds too


def test_a_users_loop_times_the_world_built_not_the_harness_preparing_the_run(monkeypatch):
    # A user's own loop knows its settings: the harness's preparation of a run (its checks,
    # start state and, under Box2D's ``accurate``, the first-touch speed that sets the
    # velocity scale; once a second simulation, the speed probe) must not count as its time.
    pytest.importorskip("Box2D")
    import time

    from harness.engines import load_engine
    from harness.scene.reference import reference_scenes

    engine = load_engine("box2d")
    settings = engine.settings("accurate")
    scenes = [reference_scenes()[name][0] for name in ("disk", "rod-45")]
    ticks = [0.0]

    def clock() -> float:  # one second per reading, a thousand per preparation
        ticks[0] += 1.0
        return ticks[0]

    preparations = []
    original = type(engine)._prepare

    def prepare(self, *args):
        preparations.append(args[0] is not None)  # with a world: the stepper's, probed
        ticks[0] += 1000.0
        return original(self, *args)

    monkeypatch.setattr(time, "process_time", clock)
    monkeypatch.setattr(type(engine), "_prepare", prepare)
    stepping, with_world = bench_survey._bare_cpu(engine, settings, scenes, [3, 3])
    assert preparations == [True, True]
    assert 0 < stepping < with_world < 100  # a few clock readings, no preparation


def test_the_end_to_end_is_the_survey_a_user_runs_of_its_own_size():
    # With the default presets a survey leaves out the pairs an engine names in
    # survey_left_out (MuJoCo's matched-bounce), so the end to end does too, and says so;
    # its size is its own (end_to_end_samples), the per-pair comparisons keep theirs.
    pytest.importorskip("mujoco")
    from harness.engines import load_engine

    left = load_engine("mujoco").survey_left_out
    assert "accurate" in left
    report = bench_survey.run(2, engines=("mujoco",), rounds=1, end_to_end_samples=3)
    assert set(report["pairs"]) == {"mujoco.defaults", "mujoco.matched-bounce"}
    assert report["end_to_end_pairs"] == ["mujoco.defaults"]
    assert list(report["end_to_end_left_out"]) == ["mujoco.matched-bounce"]
    assert report["impacts"] == 2 * 7 and report["end_to_end_impacts"] == 3 * 7
    text = bench_survey.format_report(report)
    assert "3 samples x 7 populations = 21 impacts, the survey's 1 pair:" in text
    assert "left out as a default survey leaves it out: mujoco.matched-bounce" in text
    # Naming presets leaves no pair out, as `impact-harness survey --preset` does.
    named = bench_survey.run(2, engines=("mujoco",), presets=("accurate",), rounds=1)
    assert named["end_to_end_pairs"] == ["mujoco.matched-bounce"]
    assert named["end_to_end_left_out"] == {} and named["end_to_end_impacts"] == 2 * 7


def test_naming_the_default_presets_leaves_no_pair_out():
    # `impact-harness survey --preset defaults,accurate` runs every pair (naming presets at
    # all leaves none out, survey/cli.py); so does the bench called with those presets named.
    pytest.importorskip("mujoco")
    named = bench_survey.run(1, engines=("mujoco",), presets=("defaults", "accurate"),
                             rounds=1)
    assert named["end_to_end_pairs"] == ["mujoco.defaults", "mujoco.matched-bounce"]
    assert named["end_to_end_left_out"] == {}
