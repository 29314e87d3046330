"""Fault injection: nothing lost, nothing hangs (issue 11).

Each test reproduces one fault found by running the harness as a new user would: a kill or
a deleted cache in the middle of a run, two runs at once, a run of one file over the suite's
results, hostile scenario files, unbounded work, bad cache entries, bad command-line values.
A kill is simulated in process by an exception from the engine task (what the main process
sees when a worker dies or the user presses Ctrl-C); one test kills a real process.
"""

from __future__ import annotations

import importlib.util
import json
import math
import os
import shutil
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest

from harness import cli
from harness.run import command as run_command
from harness.run import metrics, runner
from harness.run import tasks as worker_tasks
from harness.run.records import Record, read_results, write_results
from harness.scenarios import SCENARIO_DIR, ScenarioError, load_scenario
from harness.scenarios import reader as scenario_reader
from harness.store.cache import ResultCache

# Entry files read and written by hand (shared by the cache tests).
_spec = importlib.util.spec_from_file_location(
    "cache_entries", Path(__file__).parent / "cache_entries.py")
cache_entries = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(cache_entries)
read_entry, write_entry = cache_entries.read_entry, cache_entries.write_entry

ROOT = Path(__file__).resolve().parents[2]
DISK = SCENARIO_DIR / "disk-direct.toml"
SWEEP = SCENARIO_DIR / "sweep-disk-alpha.toml"  # 9 sweep points: 9 engine runs per preset
TWO_SLED = SCENARIO_DIR / "two-sled-row2.toml"  # analytic only: no engine


def run_cli(*argv, cwd=None, env=None, timeout=120):
    """``impact-harness ARGV`` in a subprocess: (exit status, stdout, stderr)."""
    environment = dict(os.environ, PYTHONPATH=f"{ROOT / 'src'}{os.pathsep}{ROOT}")
    environment.update(env or {})
    done = subprocess.run([sys.executable, "-m", "harness.cli", *map(str, argv)], cwd=cwd,
                          env=environment, capture_output=True, text=True, timeout=timeout,
                          check=False)
    return done.returncode, done.stdout, done.stderr


def engine_outputs(outcome):
    """(scenario, point, engine.preset) -> u_after of the engine records, to compare runs."""
    return {(r.scenario, r.point["index"], r.label): r.u_after
            for r in outcome.records if r.source != "analytic"}


def sweep_run(cache, **options):
    # No time limit unless asked: the tasks then run in this process, where the tests count
    # the calls (with a limit they run in a child process, which can be stopped).
    options.setdefault("time_limit_s", None)
    return runner.run([load_scenario(SWEEP)], engines=("pymunk",), presets=("defaults",),
                      cache=cache, workers=1, log=None, **options)


# --------------------------------------------------------------------------------------------
# Finished work is kept; late failures lose nothing
# --------------------------------------------------------------------------------------------
def test_a_kill_mid_run_keeps_finished_results_and_the_rerun_recomputes_none(tmp_path,
                                                                            monkeypatch):
    """One engine run per task (``chunk_size=1``): a kill loses only the unfinished runs."""
    clean = engine_outputs(sweep_run(None))
    real_task = worker_tasks.engine_task
    calls = []

    def dies_at_the_fifth(task):
        if len(calls) == 4:
            raise KeyboardInterrupt  # the user's Ctrl-C, or a dead worker
        calls.append(task)
        return real_task(task)

    monkeypatch.setattr(worker_tasks, "engine_task", dies_at_the_fifth)
    with pytest.raises(KeyboardInterrupt):
        sweep_run(ResultCache(tmp_path), chunk_size=1)
    assert len(engine_entries(tmp_path)) == 4  # each finished run stored at once

    calls.clear()
    monkeypatch.setattr(worker_tasks, "engine_task", lambda task: (calls.append(task),
                                                             real_task(task))[1])
    rerun = sweep_run(ResultCache(tmp_path), chunk_size=1)
    assert len(calls) == 9 - 4  # nothing that had finished ran again
    assert engine_outputs(rerun) == clean  # bit-identical to an uninterrupted run


def test_a_kill_mid_run_keeps_finished_chunks(tmp_path, monkeypatch):
    """Chunks of 4 runs (``Engine.run_many``): a kill in the second keeps the first's 4."""
    clean = engine_outputs(sweep_run(None, chunk_size=1))
    real_chunk = worker_tasks.engine_chunk
    chunks = []

    def dies_in_the_second_chunk(tasks):
        if chunks:
            raise KeyboardInterrupt
        chunks.append(len(tasks))
        return real_chunk(tasks)

    monkeypatch.setattr(worker_tasks, "engine_chunk", dies_in_the_second_chunk)
    with pytest.raises(KeyboardInterrupt):
        sweep_run(ResultCache(tmp_path), chunk_size=4)
    assert chunks == [4] and len(engine_entries(tmp_path)) == 4

    chunks.clear()
    singles = []
    real_task = worker_tasks.engine_task
    monkeypatch.setattr(worker_tasks, "engine_chunk", lambda tasks: (chunks.append(len(tasks)),
                                                               real_chunk(tasks))[1])
    monkeypatch.setattr(worker_tasks, "engine_task", lambda task: (singles.append(task),
                                                             real_task(task))[1])
    rerun = sweep_run(ResultCache(tmp_path), chunk_size=4)
    # the 5 runs left, nothing that had finished: a chunk of 4, and 1 alone (no batch)
    assert chunks == [4] and len(singles) == 1
    assert engine_outputs(rerun) == clean


def engine_entries(cache_dir: Path) -> list[tuple[Path, int | None, dict]]:
    """The cache's engine-run records, single or packed (it also keeps finished points and
    references, which hold no velocities): the ones a rerun counts as ``cached`` records."""
    return cache_entries.engine_run_records(cache_dir)


def scenario_entries(cache_dir: Path) -> list[Path]:
    """The cache's entries holding a whole scenario's records (``.jsonl``)."""
    return list(cache_dir.rglob("*.jsonl"))


def test_a_real_kill_leaves_a_usable_cache(tmp_path):
    """SIGKILL a real run part way, then rerun: the rerun's results equal a clean run's."""
    cache_dir = tmp_path / "cache"
    args = ("run", SWEEP, "--engines", "pymunk,pybullet", "--preset", "accurate",
            "--workers", "1", "--cache-dir", cache_dir)
    process = subprocess.Popen(
        [sys.executable, "-m", "harness.cli", *map(str, args), "--json", tmp_path / "a.json"],
        env=dict(os.environ, PYTHONPATH=f"{ROOT / 'src'}{os.pathsep}{ROOT}"),
        stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline and process.poll() is None:
        if len(engine_entries(cache_dir)) >= 3:
            break
        time.sleep(0.02)
    process.send_signal(signal.SIGKILL)
    process.wait()
    kept = len(engine_entries(cache_dir))
    assert kept >= 3  # written while the run was going, not at its end
    (cache_dir / "ab").mkdir(exist_ok=True)
    stale = cache_dir / "ab" / ".abcdef12-left-by-a-kill.tmp"
    stale.write_bytes(b"")
    os.utime(stale, (time.time() - 3600, time.time() - 3600))

    status, _, err = run_cli(*args, "--json", tmp_path / "b.json")
    assert status == 0, err
    assert not stale.exists()  # the zero-size temporary of a killed writer is cleaned up
    status, _, err = run_cli(*args[:-2], "--no-cache", "--json", tmp_path / "c.json")
    assert status == 0, err
    rerun, fresh = read_results(tmp_path / "b.json"), read_results(tmp_path / "c.json")
    assert sum(r.cached for r in rerun.records) >= kept
    assert [r.u_after for r in rerun.records] == [r.u_after for r in fresh.records]


def test_deleting_the_cache_mid_run_the_run_completes(tmp_path, monkeypatch):
    clean = engine_outputs(sweep_run(None))
    real_task = worker_tasks.engine_task
    cache_dir = tmp_path / "cache"
    calls = []

    def deletes_the_cache(task):
        calls.append(task)
        if len(calls) in (3, 6):
            shutil.rmtree(cache_dir, ignore_errors=True)  # rm -rf by hand, twice
        return real_task(task)

    monkeypatch.setattr(worker_tasks, "engine_task", deletes_the_cache)
    outcome = sweep_run(ResultCache(cache_dir), chunk_size=1)
    assert len(calls) == 9 and engine_outputs(outcome) == clean


def test_deleting_the_cache_between_chunks_the_run_completes(tmp_path, monkeypatch):
    clean = engine_outputs(sweep_run(None))
    real_chunk = worker_tasks.engine_chunk
    cache_dir = tmp_path / "cache"
    chunks = []

    def deletes_the_cache(tasks):
        chunks.append(len(tasks))
        if len(chunks) == 2:
            shutil.rmtree(cache_dir, ignore_errors=True)
        return real_chunk(tasks)

    monkeypatch.setattr(worker_tasks, "engine_chunk", deletes_the_cache)
    outcome = sweep_run(ResultCache(cache_dir), chunk_size=3)
    assert chunks == [3, 3, 3] and engine_outputs(outcome) == clean


def test_a_shard_removed_between_mkdir_and_the_write_is_made_again(tmp_path, monkeypatch):
    """The race of `rm -rf` during a run: the directory vanishes after put's mkdir."""
    real_makedirs = os.makedirs
    removed = []

    def made_then_removed(name, *args, **kwargs):
        real_makedirs(name, *args, **kwargs)
        if not removed and os.path.basename(name) == key[:2]:  # the shard, made
            removed.append(name)
            shutil.rmtree(tmp_path / "cache")

    cache = ResultCache(tmp_path / "cache")
    key = cache.key({"n": 1})
    monkeypatch.setattr(os, "makedirs", made_then_removed)
    cache.put(key, {"status": "ok"})
    assert removed and cache.get(key) == {"status": "ok"}


def test_a_cache_that_cannot_be_written_costs_the_cache_not_the_run(tmp_path, monkeypatch):
    def refuse(self, path, parts, key):  # every write: single entries, packs, scenarios
        raise PermissionError(13, "Permission denied", str(self.root))

    monkeypatch.setattr(ResultCache, "_write", refuse)
    outcome = sweep_run(ResultCache(tmp_path))
    assert len(engine_outputs(outcome)) == 9
    assert outcome.warnings and "Permission denied" in outcome.warnings[0]


def test_an_internal_error_in_one_point_keeps_every_other_record(monkeypatch):
    real = metrics.departures
    calls = []

    def breaks_once(*args, **kwargs):
        calls.append(1)
        if len(calls) == 2:
            raise ZeroDivisionError("injected")
        return real(*args, **kwargs)

    monkeypatch.setattr(metrics, "departures", breaks_once)
    outcome = sweep_run(None)
    errors = [r for r in outcome.records if r.status.startswith("error: internal")]
    assert len(errors) >= 1 and "ZeroDivisionError: injected" in errors[0].status
    assert len(outcome.records) == 9 * (len(load_scenario(SWEEP).laws) + 1)
    assert outcome.internal_errors


# --------------------------------------------------------------------------------------------
# Results files
# --------------------------------------------------------------------------------------------
def test_two_writers_of_one_results_file_both_succeed_and_it_stays_valid(tmp_path):
    path = tmp_path / "results.json"
    records = [Record(scenario=f"s{i}", point={"index": 0, "parameter": None, "value": None,
                                              "label": ""}, source="analytic", law="newton")
               for i in range(500)]  # each write spans many of the threads' switches (5 ms)
    failures = []

    def writer():
        try:
            for _ in range(10):
                write_results(path, records, {"who": threading.get_ident()})
        except Exception as error:  # noqa: BLE001 - every failure is the finding
            failures.append(error)

    threads = [threading.Thread(target=writer) for _ in range(4)]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    assert failures == []
    assert len(read_results(path).records) == 500
    assert not list(tmp_path.glob("*.tmp"))


def test_run_of_one_file_does_not_replace_the_suites_results(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    status, _, err = run_cli("run", "--tags", "quick", "--engines", "pymunk", "--preset",
                             "defaults", "--no-cache", cwd=tmp_path)
    assert status == 0, err
    suite_results = tmp_path / "reports" / "results.json"
    before = suite_results.read_bytes()
    status, _, err = run_cli("run", DISK, "--engines", "pymunk", "--no-cache", cwd=tmp_path)
    assert status == 2
    assert "reports/results.json" in err and "--json" in err and err.count("\n") == 1
    assert suite_results.read_bytes() == before
    status, _, err = run_cli("run", DISK, "--engines", "pymunk", "--no-cache", "--json",
                             tmp_path / "mine.json", cwd=tmp_path)
    assert status == 0, err
    assert suite_results.read_bytes() == before


def test_report_never_deletes_what_it_did_not_write(tmp_path, monkeypatch):
    """The report removes the figures it wrote before and no longer draws, never a file
    that only looks like one of its own. Its headline figures are stand-in files here: the
    thing tested is what it removes."""
    from harness import report

    def stand_in(path, *_):
        path.write_bytes(b"a figure")
        return path

    monkeypatch.setattr(report, "split_figure", lambda rows, path, tag: stand_in(path))
    monkeypatch.setattr(report, "heatmap_figure",
                        lambda results, path, tag, groups: stand_in(path))
    monkeypatch.setattr(report, "table3_figure", stand_in)
    results_path = tmp_path / "results.json"
    outcome = runner.run([load_scenario(TWO_SLED)], log=None, workers=1)
    write_results(results_path, outcome.records, outcome.provenance, outcome.scenarios)
    figures = tmp_path / "figures"
    figures.mkdir()
    foreign = figures / "impulse-someone-elses.png"
    foreign.write_bytes(b"not ours")
    report.write_report(read_results(results_path), tmp_path)
    assert foreign.read_bytes() == b"not ours"


def test_report_on_a_broken_results_file_names_it(tmp_path):
    broken = tmp_path / "broken.json"
    broken.write_text('{"format": "impact-harness-results", "records": [', encoding="utf-8")
    status, _, err = run_cli("report", "--results", broken, "--out", tmp_path / "out")
    assert status == 2
    assert str(broken) in err and "Traceback" not in err


def test_summary_escapes_markdown_in_names_and_statuses(tmp_path):
    from harness.report.summary import write_summary
    from harness.run.records import Results

    point = {"index": 0, "parameter": None, "value": None, "label": ""}
    records = [Record(scenario="my_odd_name", point=point, source="pymunk", preset="defaults",
                      status="error: a | b *c* <x>")]
    text = write_summary(Results(records=records), tmp_path).read_text(encoding="utf-8")
    line = next(line for line in text.splitlines() if line.startswith("- my"))
    assert r"my\_odd\_name" in line and r"a \| b \*c\* &lt;x&gt;" in line


# --------------------------------------------------------------------------------------------
# Hostile scenario files: one line each, exit 2, the other files still processed
# --------------------------------------------------------------------------------------------
HOSTILE = {  # file name -> (replace this line of disk-direct.toml, by this, key named)
    "mass-huge-int": ("mass = 1.0", "mass = 1" + "0" * 400, "body.disk.mass"),
    "friction-huge-int": ("friction = 0.3", "friction = 1" + "0" * 400, "friction"),
    "restitution-huge-int": ("restitution = 0.5", "restitution = 1" + "0" * 400,
                             "restitution"),
    "angle-huge-int": ("mass = 1.0", "mass = 1.0\nangle_deg = 1" + "0" * 400,
                       "body.disk.angle_deg"),
    "gate-huge-int": ("[expect]", ('[expect]\ngate."pymunk.accurate" = { law = "poisson", '
                                   'max_departure = 1' + "0" * 400 + " }"),
                      "expect.gate.pymunk.accurate.max_departure"),
    "radius-huge": ("radius = 0.1", "radius = 1e300", "body.disk.radius"),
    "mass-huge": ("mass = 1.0", "mass = 1e300", "body.disk.mass"),
    "radius-tiny": ("radius = 0.1", "radius = 1e-300", "body.disk.radius"),
    "mass-subnormal": ("mass = 1.0", "mass = 5e-324", "body.disk.mass"),
    "velocity-huge": ("velocity = [0.0, -1.0]", "velocity = [0.0, -1e300]",
                      "body.disk.velocity[1]"),
    "sweep-1e8": ("[expect]", ("[sweep]\nparameter = \"friction\"\n"
                               "values = { start = 0.0, stop = 1.0, num = 100000000 }\n[expect]"),
                  "sweep.values.num"),
    "sweep-listed": ("[expect]", "[sweep]\nparameter = \"friction\"\nvalues = ["
                     + ", ".join(str(i / 200000) for i in range(200000)) + "]\n[expect]",
                     "sweep.values"),
    "steps-forever": ("[expect]", ("[engine_settings.pymunk]\nmax_steps = 1000000000\n"
                                   "time_step = 1e-300\n[expect]"), "engine_settings.pymunk."),
}


def hostile_file(directory: Path, name: str) -> Path:
    old, new, _ = HOSTILE[name]
    text = DISK.read_text(encoding="utf-8")
    assert old in text
    text = text.replace(old, new, 1).replace('name = "disk-direct"', f'name = "{name}"')
    path = directory / f"{name}.toml"
    path.write_text(text, encoding="utf-8")
    return path


@pytest.mark.parametrize("name", sorted(HOSTILE))
def test_a_hostile_file_is_one_line_naming_file_key_value_and_what_is_allowed(tmp_path, name,
                                                                               monkeypatch):
    path = hostile_file(tmp_path, name)

    def work_started(*args, **kwargs):
        raise AssertionError("the scenario's points were built: refused after the work")

    # refused before the work, not after (checked by what ran, not by a clock)
    monkeypatch.setattr(scenario_reader, "check_points", work_started)
    with pytest.raises(ScenarioError) as raised:
        load_scenario(path)
    errors = raised.value.errors
    for error in errors:
        text = str(error)
        assert "\n" not in text and str(path) in text and "allowed:" in text
    assert errors[0].key.startswith(HOSTILE[name][2])


def test_a_non_utf8_file_is_one_line_naming_it(tmp_path):
    bad = tmp_path / "latin1.toml"
    bad.write_bytes(DISK.read_bytes().replace(b"Disk (r", b"Disque \xe9 (r"))
    shutil.copy(SCENARIO_DIR / "disk-oblique.toml", tmp_path)
    from harness.scenarios.library import load_scenarios_reporting

    scenarios, errors = load_scenarios_reporting([tmp_path])
    assert [s.name for s in scenarios] == ["disk-oblique"]
    assert len(errors) == 1 and str(bad) in str(errors[0]) and "UTF-8" in str(errors[0])


@pytest.mark.parametrize("command", ["validate", "run"])
def test_hostile_files_exit_2_and_the_good_ones_are_still_processed(tmp_path, command):
    for name in ("mass-huge-int", "mass-subnormal", "radius-huge"):
        hostile_file(tmp_path, name)
    (tmp_path / "latin1.toml").write_bytes(b'name = "x\xe9"\n')
    shutil.copy(SCENARIO_DIR / "disk-oblique.toml", tmp_path)
    extra = ("--engines", "pymunk", "--preset", "defaults", "--no-cache", "--json",
             tmp_path / "r.json") if command == "run" else ()
    status, out, err = run_cli(command, tmp_path, *extra)
    assert status == 2, out + err
    assert "Traceback" not in out + err
    lines = [line for line in (out + err).splitlines() if "allowed" in line]
    assert len(lines) == 4
    if command == "run":
        assert read_results(tmp_path / "r.json").scenario_names() == ["disk-oblique"]
    else:
        assert "disk-oblique" in out


# --------------------------------------------------------------------------------------------
# Cache entries and the cache's home
# --------------------------------------------------------------------------------------------
@pytest.mark.parametrize("damage", ["velocities-not-a-list", "four-components", "nan-ok",
                                    "status-only", "not-json"])
def test_a_bad_cache_entry_is_a_reported_miss(tmp_path, damage):
    cache = ResultCache(tmp_path)
    clean = engine_outputs(sweep_run(cache))
    # an engine run's record, not a finished point's
    entry, index, record = min(engine_entries(tmp_path), key=lambda found: found[:2])
    if damage == "velocities-not-a-list":
        record["velocities"] = "oops"
    elif damage == "four-components":
        record["velocities"][0].append(0.0)
    elif damage == "nan-ok":
        record["status"], record["velocities"][0][0] = "ok", math.nan
    elif damage == "status-only":
        record = {"status": "ok"}
    # signed anew: a whole entry whose content the run's check rejects
    body = b'{"key": "' if damage == "not-json" else json.dumps(record).encode()
    cache_entries.replace_record(entry, index, body)
    # A rerun of the same selection reads the scenario's finished records, kept whole
    # (test_scenario_records_cache damages that entry); without it, the engine runs' entries.
    for whole in scenario_entries(tmp_path):
        whole.unlink()
    again = ResultCache(tmp_path)
    outcome = sweep_run(again)
    assert engine_outputs(outcome) == clean
    assert sum(not r.cached for r in outcome.records if r.source != "analytic") == 1
    assert len(again.rejected) == 1 and str(entry) in again.rejected[0]
    assert any(str(entry) in warning for warning in outcome.warnings)


def test_the_cache_has_one_home_whatever_the_working_directory(tmp_path, monkeypatch):
    from harness.store.cache_directory import default_cache_dir

    monkeypatch.delenv("IMPACT_HARNESS_CACHE_DIR", raising=False)
    monkeypatch.chdir(tmp_path)
    home = default_cache_dir()
    assert home.is_absolute() and tmp_path not in home.parents
    assert ResultCache().root == home
    monkeypatch.setenv("IMPACT_HARNESS_CACHE_DIR", str(tmp_path / "elsewhere"))
    assert default_cache_dir() == tmp_path / "elsewhere"


def test_make_clean_removes_the_cache():
    makefile = (ROOT / "Makefile").read_text(encoding="utf-8")
    clean = makefile.split("\nclean:", 1)[1].split("\n\n", 1)[0]
    assert ".cache" in clean


def test_cache_prune_removes_entries_of_other_code_and_old_ones(tmp_path):
    old_code = ResultCache(tmp_path, version="old")
    old_code.put(old_code.key({"n": 1}), {"status": "ok"})
    current = ResultCache(tmp_path, version="new")
    current.put(current.key({"n": 1}), {"status": "ok"})
    aged = current.key({"n": 2})
    current.put(aged, {"status": "ok"})
    os.utime(current.path(aged), (time.time() - 40 * 86400, time.time() - 40 * 86400))
    assert current.info()["entries"] == 3
    removed = current.prune(max_age_days=30)
    assert removed["entries"] == 2
    assert current.info()["entries"] == 1
    current.clear()
    assert current.info()["entries"] == 0


def test_cache_command_info_prune_clear(tmp_path):
    cache = ResultCache(tmp_path, version="other")
    cache.put(cache.key({"n": 1}), {"status": "ok"})
    status, out, _ = run_cli("cache", "info", "--cache-dir", tmp_path)
    assert status == 0 and str(tmp_path) in out and "1 entr" in out
    status, out, _ = run_cli("cache", "prune", "--cache-dir", tmp_path)
    assert status == 0 and not list(tmp_path.rglob("*.json"))


# --------------------------------------------------------------------------------------------
# Bounds on work
# --------------------------------------------------------------------------------------------
class StuckInC:
    """An engine whose step never returns to Python: a regular expression backtracking
    exponentially runs in C, where no signal handler (``SIGALRM``) ever runs."""

    version = "stuck"

    def run(self, scene, settings):
        import re

        re.match(r"(a+)+$", "a" * 60 + "b")

    run_many = None


@pytest.mark.parametrize("workers", [1, 2])
def test_an_engine_task_stuck_in_c_is_stopped_and_the_run_goes_on(monkeypatch, workers):
    import harness.engines as engines_module

    real = engines_module.load_engine
    monkeypatch.setattr(engines_module, "load_engine",
                        lambda name: StuckInC() if name == "stuck" else real(name))
    scene = load_scenario(DISK).scene(load_scenario(DISK).point_list()[0])
    settings = real("pymunk").settings("defaults", {})
    tasks = [{"engine": "pymunk", "settings": settings, "scene": scene, "time_limit_s": 30.0},
             {"engine": "stuck", "settings": {}, "scene": scene, "time_limit_s": 1.0},
             {"engine": "pymunk", "settings": settings, "scene": scene, "time_limit_s": 30.0}]
    begin = time.monotonic()
    outputs = worker_tasks.run_engine_tasks(tasks, executor="local", workers=workers,
                                            scheduler=None, log=None)
    assert time.monotonic() - begin < 20  # the stuck one alone would run for hours
    assert outputs[1]["status"] == "error: time limit: stopped after 1 s (--task-time-limit)"
    assert outputs[0]["status"] == outputs[2]["status"] == "ok"  # the others ran
    assert outputs[0]["velocities"] == outputs[2]["velocities"]


def test_a_runaway_engine_is_stopped_within_seconds_of_its_limit(tmp_path):
    """The issue's reproducer: pymunk with a billion solver iterations (beyond the bound,
    raised for the test), a 3 s limit."""
    begin = time.monotonic()
    status, _, err = run_cli("run", DISK, "--engines", "pymunk", "--preset", "defaults",
                             "--no-cache", "--set", "pymunk.iterations=1000000000",
                             "--task-time-limit", "3", "--json", tmp_path / "r.json",
                             env={"IMPACT_HARNESS_MAX_SOLVER_ITERATIONS": "1e10"})
    assert time.monotonic() - begin < 30, err
    records = read_results(tmp_path / "r.json").records
    engine = [r for r in records if r.source != "analytic"]
    assert [r.status for r in engine] == [
        "error: time limit: stopped after 3 s (--task-time-limit)"]
    assert all(r.status == "ok" for r in records if r.source == "analytic")


def test_a_worker_that_dies_costs_its_task_only(monkeypatch):
    import harness.engines as engines_module

    class Crashes:
        version = "crash"
        run_many = None

        def run(self, scene, settings):
            os._exit(7)  # as an engine's segmentation fault ends the process

    real = engines_module.load_engine
    monkeypatch.setattr(engines_module, "load_engine",
                        lambda name: Crashes() if name == "crash" else real(name))
    scene = load_scenario(DISK).scene(load_scenario(DISK).point_list()[0])
    settings = real("pymunk").settings("defaults", {})
    tasks = [{"engine": name, "settings": settings, "scene": scene, "time_limit_s": 30.0}
             for name in ("pymunk", "crash", "pymunk")]
    outputs = worker_tasks.run_engine_tasks(tasks, executor="local", workers=2, scheduler=None,
                                            log=None)
    assert outputs[1]["status"] == "error: worker died (exit code 7)"
    assert outputs[0]["status"] == outputs[2]["status"] == "ok"


# --------------------------------------------------------------------------------------------
# Command-line values checked before any work; distinct exit codes
# --------------------------------------------------------------------------------------------
BAD_ARGUMENTS = {
    "workers-zero": ("--workers", "0"),
    "workers-negative": ("--workers", "-3"),
    "chunk-size-zero": ("--chunk-size", "0"),
    "scheduler-without-dask": ("--scheduler", "tcp://127.0.0.1:1"),
    "json-in-proc": ("--json", "/proc/x/r.json"),
    "json-is-a-directory": ("--json", "{tmp}"),
    "cache-dir-in-proc": ("--cache-dir", "/proc/x"),
    "cache-dir-is-a-file": ("--cache-dir", "{file}"),
}


@pytest.mark.parametrize("case", sorted(BAD_ARGUMENTS))
def test_bad_arguments_are_one_line_and_exit_2_before_any_work(tmp_path, monkeypatch, capsys,
                                                               case):
    a_file = tmp_path / "a-file"
    a_file.write_text("x")
    option, value = BAD_ARGUMENTS[case]
    value = value.format(tmp=tmp_path, file=a_file)

    def no_work(*args, **kwargs):
        raise AssertionError("scenarios loaded before the arguments were checked")

    monkeypatch.setattr(run_command, "load_scenarios_reporting", no_work)
    extra = () if option == "--json" else ("--json", str(tmp_path / "r.json"))
    try:
        status = cli.main(["run", str(DISK), option, value, *extra])
    except SystemExit as refused:  # a numeric option, refused by its argparse type
        status = refused.code
    err = capsys.readouterr().err
    assert status == 2
    assert err.count("\n") == 1 and option in err, err


def test_an_internal_error_exits_3_with_one_line(tmp_path, monkeypatch, capsys):
    def broken(*args, **kwargs):
        raise RuntimeError("injected bug")

    monkeypatch.setattr(runner, "run", broken)
    status = cli.main(["run", str(DISK), "--json", str(tmp_path / "r.json"), "--no-cache"])
    err = capsys.readouterr().err
    assert status == 3
    assert "internal error" in err and "injected bug" in err and "Traceback" not in err


def test_exit_codes_are_documented_in_the_help():
    parser = cli.build_parser(None)
    for code in ("0", "1", "2", "3"):
        assert f"  {code} " in parser.epilog
    assert "exit" in (cli.__doc__ or "").lower()
