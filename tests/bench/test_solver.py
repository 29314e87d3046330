"""The solver benchmark checks its own answers and measures what it says (no timing asserts)."""

import dataclasses

import numpy as np
import pytest

import planar_impact as pi
from harness.bench import solver as bench
from harness.scene.random_problems import random_problems


def test_check_against_process_accepts_the_solver():
    sample = random_problems(50, seed=11)
    for law in pi.LAWS:
        bench._check_against_process(law, sample)


def test_check_against_process_rejects_a_wrong_answer(monkeypatch):
    real = pi.solve_batch

    def wrong(*args, **kwargs):
        result = real(*args, **kwargs)
        return dataclasses.replace(result, normal_impulse=result.normal_impulse * (1 + 1e-6))

    monkeypatch.setattr(pi, "solve_batch", wrong)
    with pytest.raises(AssertionError, match="disagrees with the impulse process"):
        bench._check_against_process("poisson", random_problems(50, seed=12))


def test_output_write_covers_every_array_of_a_batch_result():
    result = pi.solve_batch([1.0, 2.0], 0.0, 1.0, -1.0, 0.5, 0.3, 0.5)
    arrays = [v for v in result.as_dict().values() if isinstance(v, np.ndarray)]
    assert len(arrays) == 14  # status + the 13 result fields
    assert sorted(map(str, bench.result_dtypes())) == sorted(str(v.dtype) for v in arrays)
    # ... which is what the solver allocates per result, from its own table.
    from planar_impact import batch
    assert sorted(map(str, bench.result_dtypes())) == sorted(
        str(np.dtype(d)) for d in batch.BATCH_DTYPES.values())
    assert bench.output_write_time(10, repeat=1) > 0


@pytest.mark.parametrize("keep", [True, False])
def test_numpy_passes_time_is_positive(keep):
    assert bench.numpy_passes_time(1000, repeat=1, keep=keep) > 0


def _bench_args(out, **sections):
    import argparse

    parser = argparse.ArgumentParser()
    bench.add_arguments(parser)
    argv = ["--out", str(out), "--quick"] + [f"--{name.replace('_', '-')}" for name in sections]
    return parser.parse_args(argv)


def test_one_section_updates_its_part_of_bench_json(tmp_path, monkeypatch):
    """``bench --solver`` replaces the solver section and keeps the survey's and the engines'
    (README tables and the bench page read the whole file)."""
    import json

    measured = {"batch": {"poisson": 1.0}}
    monkeypatch.setattr(bench, "solver_benchmark", lambda quick: measured)
    monkeypatch.setattr(bench, "print_solver", lambda results: None)
    monkeypatch.setattr(bench, "write_solver_figure", lambda results, path: None)
    earlier = {"provenance": {"format": bench.BENCH_FORMAT, "created_utc": "2026-01-01T00:00:00Z",
                              "git": {"commit": "abc"}, "versions": {"pymunk": "6.0"},
                              "machine": {"cpu_count": 64}},
               "quick": False, "solver": {"batch": {"poisson": 9.0}},
               "survey": {"ratio": 1.4}, "engines": {"pymunk": 2.0}}
    (tmp_path / "bench.json").write_text(json.dumps(earlier))
    assert bench.main(_bench_args(tmp_path, solver=True)) == 0
    table = json.loads((tmp_path / "bench.json").read_text())
    assert table["solver"] == measured
    assert table["survey"] == {"ratio": 1.4} and table["engines"] == {"pymunk": 2.0}
    assert table["measured"]["survey"] == {"created_utc": "2026-01-01T00:00:00Z",
                                           "commit": "abc", "quick": False,
                                           "versions": {"pymunk": "6.0"},
                                           "machine": {"cpu_count": 64}}
    assert table["measured"]["solver"]["quick"] is True
    # the kept sections' machine and versions are theirs, not this run's
    assert table["measured"]["solver"]["machine"] == table["provenance"]["machine"]
    assert table["measured"]["solver"]["versions"] == table["provenance"]["versions"]
    assert table["measured"]["solver"]["created_utc"] == table["provenance"]["created_utc"]
    assert set(table["measured"]) == {"solver", "survey", "engines"}


def test_a_run_into_a_new_directory_holds_its_sections_only(tmp_path, monkeypatch):
    import json

    monkeypatch.setattr(bench, "solver_benchmark", lambda quick: {"batch": {}})
    monkeypatch.setattr(bench, "print_solver", lambda results: None)
    monkeypatch.setattr(bench, "write_solver_figure", lambda results, path: None)
    assert bench.main(_bench_args(tmp_path / "new", solver=True)) == 0
    table = json.loads((tmp_path / "new" / "bench.json").read_text())
    assert set(table["measured"]) == {"solver"} and "survey" not in table
    # the digest of harness/bench/ the report compares with today's before linking the page
    from harness.report.pages import command_code_version

    assert table["provenance"]["command_code_version"] == command_code_version("bench")


def test_a_section_that_fails_leaves_the_finished_ones_in_bench_json(tmp_path, monkeypatch):
    """A fault late in the run (here the speed-accuracy section raising, after the solver's
    section finished) never throws the finished sections away: bench.json holds them."""
    import json

    from harness.bench import accuracy as bench_accuracy

    def fails(quick, out_dir):
        raise RuntimeError("a section's fault")

    monkeypatch.setattr(bench, "solver_benchmark", lambda quick: {"batch": {"poisson": 1.0}})
    monkeypatch.setattr(bench, "print_solver", lambda results: None)
    monkeypatch.setattr(bench, "write_solver_figure", lambda results, path: None)
    monkeypatch.setattr(bench_accuracy, "reference_problems", lambda quick: [])
    monkeypatch.setattr(bench_accuracy, "run", fails)
    with pytest.raises(RuntimeError, match="a section's fault"):
        bench.main(_bench_args(tmp_path, solver=True, speed_accuracy=True))
    table = json.loads((tmp_path / "bench.json").read_text())
    assert table["solver"] == {"batch": {"poisson": 1.0}} and "speed_accuracy" not in table
    assert set(table["measured"]) == {"solver"}


@pytest.mark.parametrize(("status", "complete"), [(0, True), (1, True), (4, True), (3, False)])
def test_the_executors_bench_times_a_run_whose_engine_erred(status, complete, tmp_path,
                                                            monkeypatch):
    # `run` exits 4 when an engine run ended in an error its record reports (Drake's TAMSI on
    # a perturbed rod): a complete run, timed; an internal error (3) is not
    import subprocess

    from harness.bench import executors

    monkeypatch.setattr(executors.subprocess, "run", lambda command, **_: (
        subprocess.CompletedProcess(command, status, "", "its stderr")))
    timer = executors._run_command(tmp_path, tmp_path, "local")
    if complete:
        assert timer() >= 0.0
    else:
        with pytest.raises(RuntimeError, match="exited 3: its stderr"):
            timer()
