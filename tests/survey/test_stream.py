"""The streamed survey (harness/survey/stream.py): the same tables as the survey held in
memory, bit for bit, for any workers and on Dask; resumed from the chunks done with the same
statistics; a chunk over its time limit stopped and retried; a scene the engine cannot build
recorded skipped; progress on stderr."""

from __future__ import annotations

import json

import numpy as np
import pyarrow.parquet as pq
import pytest

from harness.cli import main
from harness.survey import cli as survey_cli
from harness.survey import stream
from harness.survey.population import resolve_populations

FAMILIES = ["spinning-disk", "disk-rod"]
SAMPLES = 20  # chunks of 8: (0, 8), (8, 16), (16, 20)
OPTIONS = ["--samples", str(SAMPLES), "--seed", "3", "--engines", "pymunk", "--no-figures"]


def _survey(out, *extra) -> int:
    return main(["survey", *FAMILIES, *OPTIONS, "--out", str(out), *extra])


def _read(path) -> dict:
    table = pq.read_table(path).to_pydict()
    if "reasons" in table:
        table["reasons"] = [",".join(item) for item in table["reasons"]]
    return table


def _same(expected: dict, found: dict) -> None:
    assert list(expected) == list(found)
    for name, values in expected.items():
        values, other = np.asarray(values), np.asarray(found[name])
        if values.dtype.kind == "f":
            assert np.array_equal(values, other, equal_nan=True), name
        else:
            assert values.astype(str).tolist() == other.astype(str).tolist(), name


@pytest.fixture(scope="module")
def in_memory():
    populations = resolve_populations(FAMILIES)
    return survey_cli.run_survey(populations, SAMPLES, 3, ["pymunk"], ["defaults", "accurate"],
                                 workers=1, echo=lambda _: None)


@pytest.fixture(scope="module")
def streamed(tmp_path_factory):
    out = tmp_path_factory.mktemp("streamed")
    assert _survey(out, "--workers", "2") == 0
    return out


def test_chunks_depend_on_the_samples_and_populations_only():
    assert stream.chunk_bounds(20, 2) == [(0, 8), (8, 16), (16, 20)]
    assert stream.chunk_bounds(3, 7) == [(0, 3)]
    big = stream.chunk_bounds(1_000_000, 7)
    assert max(end - begin for begin, end in big) * 7 <= stream.CHUNK_IMPACTS
    assert big[0][0] == 0 and big[-1][1] == 1_000_000
    assert all(a[1] == b[0] for a, b in zip(big, big[1:]))


def test_streamed_tables_equal_the_survey_held_in_memory(in_memory, streamed):
    _same(in_memory["statistics"], _read(streamed / "statistics.parquet"))
    _same(in_memory["runs"], _read(streamed / "runs.parquet"))
    _same(in_memory["samples"], _read(streamed / "samples.parquet"))
    summary = (streamed / "summary.md").read_text()
    assert "| pymunk | defaults | disk-rod | all types | 20 |" in summary


def test_the_dataset_is_partitioned_by_pair_and_read_in_one_call(streamed):
    import pyarrow.dataset as ds

    runs = ds.dataset(streamed / "dataset" / "runs", format="parquet", partitioning="hive")
    table = runs.to_table(columns=["engine", "preset", "sample"])
    assert table.num_rows == SAMPLES * len(FAMILIES) * 2
    assert sorted(path.name for path in (streamed / "dataset" / "runs").iterdir()) == \
        ["engine=pymunk"]
    metadata = json.loads(pq.read_schema(next((streamed / "dataset" / "samples").glob(
        "part-*.parquet"))).metadata[b"impact_harness"])
    assert metadata["table"] == "samples" and metadata["settings"]["samples"] == SAMPLES


def test_a_killed_survey_resumes_from_the_chunks_done(streamed, tmp_path, capsys):
    out = tmp_path / "again"
    assert _survey(out, "--workers", "1") == 0
    chunks = sorted((out / "dataset" / "chunks").glob("part-*.json"))
    assert len(chunks) == 3
    # A kill after the first chunk: the others' records (written last) are missing.
    for record in chunks[1:]:
        record.unlink()
    kept = (out / "dataset" / "samples" / "part-00000.parquet").stat().st_mtime_ns
    (out / "statistics.parquet").unlink()
    capsys.readouterr()
    assert _survey(out, "--workers", "1") == 0
    assert "resuming: 1 of 3 chunks" in capsys.readouterr().out
    assert (out / "dataset" / "samples" / "part-00000.parquet").stat().st_mtime_ns == kept
    _same(_read(streamed / "statistics.parquet"), _read(out / "statistics.parquet"))
    _same(_read(streamed / "runs.parquet"), _read(out / "runs.parquet"))
    # Another plan (another seed) starts afresh: nothing of the first is reused.
    capsys.readouterr()
    assert main(["survey", *FAMILIES, *OPTIONS[:2], "--seed", "4", "--engines", "pymunk",
                 "--no-figures", "--out", str(out), "--workers", "1"]) == 0
    assert "resuming" not in capsys.readouterr().out
    assert json.loads((out / "dataset" / "plan.json").read_text())["seed"] == 4


def test_progress_goes_to_stderr_with_the_time_left(tmp_path, capsys):
    assert _survey(tmp_path / "p", "--workers", "1") == 0
    err = capsys.readouterr().err
    assert f"{SAMPLES * len(FAMILIES)}/{SAMPLES * len(FAMILIES)} impacts (100%)" in err
    assert "left" in err
    assert _survey(tmp_path / "q", "--workers", "1", "--quiet") == 0
    assert "impacts (" not in capsys.readouterr().err


def test_dask_gives_the_local_pools_statistics(streamed, tmp_path):
    pytest.importorskip("distributed")
    out = tmp_path / "dask"
    assert _survey(out, "--executor", "dask", "--workers", "2") == 0
    _same(_read(streamed / "statistics.parquet"), _read(out / "statistics.parquet"))
    _same(_read(streamed / "runs.parquet"), _read(out / "runs.parquet"))


def test_a_chunk_over_its_time_limit_is_stopped_and_run_again_later(tmp_path, capsys):
    out = tmp_path / "limited"
    code = main(["survey", "spinning-disk", "--samples", "12", "--engines", "pymunk",
                 "--preset", "defaults", "--no-figures", "--out", str(out), "--workers", "1",
                 "--task-time-limit", "1e-6"])
    assert code == 4
    err = capsys.readouterr().err
    assert "SURVEY CHUNK STOPPED: chunk 0 (samples 0-7 of every population): time limit" in err
    assert "2 of 2 chunks stopped" in err
    assert not (out / "statistics.parquet").exists()
    assert main(["survey", "spinning-disk", "--samples", "12", "--engines", "pymunk",
                 "--preset", "defaults", "--no-figures", "--out", str(out),
                 "--workers", "1"]) == 0
    assert len(_read(out / "runs.parquet")["sample"]) == 12


def test_bad_executor_options_are_refused_before_any_work(tmp_path, capsys):
    with pytest.raises(SystemExit) as stop:
        main(["survey", "--executor", "spark", "--out", str(tmp_path / "x")])
    assert stop.value.code == 2
    assert main(["survey", "--scheduler", "tcp://h:1", "--out", str(tmp_path / "x")]) == 2
    assert "--scheduler 'tcp://h:1': needs --executor dask" in capsys.readouterr().err
    assert main(["survey", "--task-time-limit", "0", "--out", str(tmp_path / "x")]) == 2
    assert not (tmp_path / "x").exists()


POLYGONS = """
name = "big-polygons"
description = "Regular polygons of 5 or 24 sides on the ground (Box2D builds 16 at most)."
restitution = 0.5
friction = 0.3
[ground]
[approach]
speed = 1.0
direction_deg = { uniform = [-30.0, 30.0] }
[[body]]
name = "polygon"
shape = "polygon"
sides = { choice = [5, 24] }
circumradius = 0.2
mass = 1.0
angle_deg = { uniform = [0.0, 360.0] }
"""


def test_a_polygon_box2d_cannot_build_is_recorded_skipped(tmp_path):
    pytest.importorskip("Box2D")
    population = tmp_path / "big-polygons.toml"
    population.write_text(POLYGONS)
    out = tmp_path / "box2d"
    assert main(["survey", str(population), "--samples", "12", "--engines", "box2d",
                 "--preset", "defaults", "--no-figures", "--out", str(out),
                 "--workers", "1"]) == 0
    samples = _read(out / "samples.parquet")
    runs = _read(out / "runs.parquet")
    big = np.asarray(samples["polygon.sides"]) == 24
    assert 0 < big.sum() < len(big)
    assert (np.asarray(runs["status"])[big] == "skipped").all()
    assert (np.asarray(runs["status"])[~big] != "skipped").all()
    stats = _read(out / "statistics.parquet")
    every = stats["poisson_type"].index(0)
    assert stats["n"][every] == (~big).sum() and stats["n_skipped"][every] == big.sum()
    summary = (out / "summary.md").read_text()
    assert "## Skipped runs (the engine cannot build the scene)" in summary
    assert f"| box2d defaults | big-polygons | {big.sum()} | engine cannot build" in summary


def test_bare_stepping_is_timed_chunk_by_chunk(tmp_path):
    out = tmp_path / "bare"
    assert main(["survey", "spinning-disk", "--samples", "10", "--engines", "pymunk",
                 "--preset", "defaults", "--bare", "--no-figures", "--quiet", "--out",
                 str(out), "--workers", "1"]) == 0
    summary = (out / "summary.md").read_text()
    assert "| bare pymunk defaults (steps only) |" in summary
    assert "| bare pymunk defaults (reset + steps) |" in summary
    records = stream.chunk_records(out / "dataset")
    assert all("bare pymunk defaults (steps only)" in record["timings"] for record in records)


def test_the_survey_held_in_memory_lists_skipped_runs_alike(tmp_path):
    pytest.importorskip("Box2D")
    from harness.survey.population import load_population

    population = tmp_path / "big-polygons.toml"
    population.write_text(POLYGONS)
    survey = survey_cli.run_survey([load_population(population)], 12, 0, ["box2d"],
                                   ["defaults"], workers=1, echo=lambda _: None)
    found = survey_cli.skipped_in_memory(survey)
    (counts, why), = found.values()
    assert counts["big-polygons"] == int(np.sum(survey["runs"]["status"] == "skipped")) > 0
    assert why.startswith("engine cannot build the scene")


def test_a_survey_killed_for_real_resumes_to_the_same_tables(tmp_path, capsys):
    import signal
    import subprocess
    import sys
    import time

    out = tmp_path / "killed"
    command = [sys.executable, "-m", "harness.cli", "survey", "spinning-disk", "--samples",
               "2000", "--engines", "pymunk", "--preset", "defaults", "--workers", "1",
               "--quiet", "--no-figures", "--out", str(out)]
    process = subprocess.Popen(command, stdout=subprocess.DEVNULL)
    chunks = out / "dataset" / "chunks"
    try:
        deadline = time.monotonic() + 120
        while time.monotonic() < deadline and not list(chunks.glob("part-*.json")):
            time.sleep(0.005)
    finally:
        process.send_signal(signal.SIGKILL)
        process.wait()
    done = len(list(chunks.glob("part-*.json")))
    assert 1 <= done < len(stream.chunk_bounds(2000, 1))
    assert not (out / "statistics.parquet").exists()
    capsys.readouterr()
    assert main(command[3:]) == 0
    assert f"resuming: {done} of 16 chunks" in capsys.readouterr().out
    fresh = tmp_path / "fresh"
    assert main([*command[3:-1], str(fresh)]) == 0
    for table in ("statistics.parquet", "runs.parquet", "samples.parquet"):
        _same(_read(fresh / table), _read(out / table))
