"""A hostile environment (issue 23): the harness deletes only what it made, writes only over
regular files, never runs what it reads from disk, checks every cache entry it reads, and
its exit status says when an engine run failed."""

from __future__ import annotations

import base64
import hashlib
import importlib.util
import json
import os
import pickle
import stat
from pathlib import Path

import pytest

from harness import cli
from harness.engines import load_engine
from harness.engines.facts import ENGINE_FACTS
from harness.run import command, runner
from harness.run.records import read_results
from harness.scenarios import SCENARIO_DIR, load_scenario
from harness.store.cache import ResultCache
from harness.store.cache_directory import CACHE_MARKER, OLD_CHECKS_STORES
from harness.store.sealing import KEY_FILE, Seal

# Entry files read and written by hand (shared by the cache tests).
_spec = importlib.util.spec_from_file_location(
    "cache_entries", Path(__file__).parent / "cache_entries.py")
cache_entries = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(cache_entries)
read_entry, write_entry = cache_entries.read_entry, cache_entries.write_entry
engine_run_records, replace_record = cache_entries.engine_run_records, cache_entries.replace_record

DISK = SCENARIO_DIR / "disk-direct.toml"
SWEEP = SCENARIO_DIR / "sweep-disk-alpha.toml"  # 9 points: 9 pymunk runs with one preset


def _tree(root: Path) -> dict[str, bytes | None]:
    """Every path under ``root`` with its content (None for a directory)."""
    return {str(path.relative_to(root)): None if path.is_dir() else path.read_bytes()
            for path in sorted(root.rglob("*"))}


def _foreign_directory(tmp_path: Path) -> Path:
    """A directory the harness did not make, holding files named like cache entries too."""
    foreign = tmp_path / "mine"
    (foreign / "ab").mkdir(parents=True)
    (foreign / "ab" / ("ab" + "0" * 62 + ".json")).write_text("{}")
    (foreign / "thesis.tex").write_text("years of work")
    (foreign / "scenario-checks.pickle").write_bytes(b"not the harness's")
    return foreign


# --------------------------------------------------------------------------------------------
# Item 1: only what the harness made is deleted
# --------------------------------------------------------------------------------------------
@pytest.mark.parametrize("action", ["clear", "prune"])
def test_cache_clear_or_prune_of_a_foreign_directory_refuses_and_changes_nothing(
        tmp_path, capsys, action):
    foreign = _foreign_directory(tmp_path)
    before = _tree(foreign)
    assert cli.main(["cache", action, "--cache-dir", str(foreign)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and str(foreign) in err and CACHE_MARKER in err
    assert _tree(foreign) == before


def test_a_run_refuses_a_foreign_cache_directory_before_any_work(tmp_path, capsys):
    foreign = _foreign_directory(tmp_path)
    before = _tree(foreign)
    status = cli.main(["run", str(DISK), "--engines", "pymunk", "--cache-dir", str(foreign),
                       "--json", str(tmp_path / "r.json")])
    err = capsys.readouterr().err
    assert status == 2 and err.count("\n") == 1 and "--cache-dir" in err
    assert _tree(foreign) == before and not (tmp_path / "r.json").exists()


def test_cache_clear_removes_only_the_entries_of_a_cache_it_made(tmp_path, capsys):
    root = tmp_path / "cache"  # made (and marked) by the run
    assert cli.main(["run", str(DISK), "--engines", "pymunk", "--cache-dir", str(root),
                     "--json", str(tmp_path / "r.json"), "--workers", "1"]) == 0
    assert (root / CACHE_MARKER).is_file()
    entries = ResultCache(root).info()["entries"]
    assert entries > 3
    (root / "notes.txt").write_text("the user's")  # put there by someone else
    shard = next(path for path in root.iterdir() if path.is_dir())
    (shard / "notes.txt").write_text("the user's too")
    capsys.readouterr()
    assert cli.main(["cache", "clear", "--cache-dir", str(root)]) == 0
    assert f"removed {entries} entries" in capsys.readouterr().out
    assert sorted(str(p.relative_to(root)) for p in root.rglob("*")) == sorted(
        [CACHE_MARKER, KEY_FILE, "notes.txt", shard.name, f"{shard.name}/notes.txt"])


# --------------------------------------------------------------------------------------------
# Item 3: nothing read from the cache is unpickled, evaluated or imported
# --------------------------------------------------------------------------------------------
class _Payload:
    """Unpickling one makes the directory ``path`` (the proof that code ran)."""

    def __init__(self, path: Path):
        self.path = str(path)

    def __reduce__(self):
        return (os.mkdir, (self.path,))


def test_a_crafted_pickle_in_the_cache_runs_no_code(tmp_path):
    root, ran = tmp_path / "cache", tmp_path / "code-ran"
    argv = ["run", str(DISK), "--engines", "pymunk", "--cache-dir", str(root), "--json",
            str(tmp_path / "r.json"), "--workers", "1"]
    assert cli.main(argv) == 0
    crafted = pickle.dumps(_Payload(ran))
    for name in OLD_CHECKS_STORES:  # the stores' old names, a pickle among them
        (root / name).write_bytes(crafted)
    # an engine-facts entry holding a base64 pickle, whole (its checksum signed anew)
    for path in root.glob("??/*.json"):
        header, record = read_entry(path)
        if record.get("kind") == ENGINE_FACTS:
            write_entry(path, header, {**record, "pickled": base64.b64encode(crafted).decode()})
    assert cli.main(argv) == 0  # a warm run
    assert cli.main(["cache", "info", "--cache-dir", str(root)]) == 0
    assert cli.main(["cache", "prune", "--cache-dir", str(root)]) == 0
    assert not ran.exists()
    # never read, and never removed by their name alone (no seal of the key over them)
    assert all((root / name).read_bytes() == crafted for name in OLD_CHECKS_STORES)
    assert not list(tmp_path.glob("*.pickle"))  # and the results are JSON alone


# --------------------------------------------------------------------------------------------
# Item 9: every entry read is checked against its checksum
# --------------------------------------------------------------------------------------------
def test_velocities_edited_in_the_cache_are_detected_and_recomputed(tmp_path):
    def run(cache):
        return runner.run([load_scenario(SWEEP)], engines=("pymunk",), presets=("defaults",),
                          cache=cache, workers=1, log=None)

    clean = run(ResultCache(tmp_path))
    for whole in tmp_path.glob("??/*.jsonl"):  # the scenario's records kept whole aside
        whole.unlink()
    edited = engine_run_records(tmp_path)
    assert len(edited) == 9
    for path, index, record in edited:  # valid JSON, every speed ×1.5, the checksum as written
        record["velocities"] = [[1.5 * v for v in body] for body in record["velocities"]]
        replace_record(path, index, json.dumps(record).encode(), sign=False)
    again = ResultCache(tmp_path)
    outcome = run(again)
    assert [r.u_after for r in outcome.records] == [r.u_after for r in clean.records]
    assert outcome.provenance["cache"]["simulated"] == 9  # each recomputed
    assert len(again.rejected) == 9 and all("checksum differs" in r for r in again.rejected)
    assert sum("cache entry rejected" in warning for warning in outcome.warnings) == 9


def test_an_entry_is_its_checksummed_payload(tmp_path):
    cache = ResultCache(tmp_path, version="v")
    key = cache.key({"n": 1})
    cache.put(key, {"velocities": [[0.1, 0.2, 0.3]], "status": "ok"})
    header, _ = read_entry(cache.path(key))
    body = cache.path(key).read_bytes().partition(b"\n")[2]
    assert header == {"key": key, "code_version": "v",
                      "sha256": hashlib.sha256(body).hexdigest(), "mac": header["mac"]}
    Seal(tmp_path).check(header)  # sealed with the cache's key (tests/store/test_sealing.py)
    assert cache.get(key) == {"velocities": [[0.1, 0.2, 0.3]], "status": "ok"}


# --------------------------------------------------------------------------------------------
# Item 2 and 10: outputs over regular files only, with the umask's mode
# --------------------------------------------------------------------------------------------
@pytest.mark.parametrize("target", ["device", "pipe", "directory", "link", "missing/r.json"])
def test_run_json_refuses_anything_but_a_regular_file_before_any_work(tmp_path, capsys,
                                                                      target):
    (tmp_path / "directory").mkdir()
    (tmp_path / "theirs").write_text("theirs")
    (tmp_path / "link").symlink_to(tmp_path / "theirs")
    os.mkfifo(tmp_path / "pipe")
    try:  # a character device of /dev/null's numbers, where this user may make one
        os.mknod(tmp_path / "device", stat.S_IFCHR | 0o666, os.makedev(1, 3))
    except PermissionError:
        os.mkfifo(tmp_path / "device")
    before = {name: os.lstat(tmp_path / name).st_mode for name in
              ("device", "pipe", "directory", "link")}
    status = cli.main(["run", str(DISK), "--no-cache", "--json", str(tmp_path / target)])
    err = capsys.readouterr().err
    assert status == 2 and err.count("\n") == 1 and "--json" in err
    assert (tmp_path / "theirs").read_text() == "theirs"
    assert {name: os.lstat(tmp_path / name).st_mode for name in before} == before
    assert not (tmp_path / "missing").exists() and not list(tmp_path.glob("*.pickle"))


def test_the_results_file_has_the_mode_the_umask_gives(tmp_path):
    previous = os.umask(0o022)
    try:
        assert cli.main(["run", str(DISK), "--engines", "pymunk", "--no-cache", "--json",
                         str(tmp_path / "r.json"), "--workers", "1"]) == 0
    finally:
        os.umask(previous)
    assert (tmp_path / "r.json").stat().st_mode & 0o777 == 0o644


def test_a_link_planted_at_a_report_output_is_not_written_through(tmp_path):
    from matplotlib.figure import Figure

    from harness.plotting import save_png

    theirs = tmp_path / "theirs.png"
    theirs.write_bytes(b"theirs")
    planted = tmp_path / "figure.png"
    planted.symlink_to(theirs)
    figure = Figure()
    figure.add_subplot().plot([0, 1], [0, 1])
    with pytest.raises(OSError, match="symbolic link"):
        save_png(figure, planted)
    assert theirs.read_bytes() == b"theirs" and planted.is_symlink()


@pytest.mark.parametrize("damage", ["format_version", "u_after"])
def test_compare_and_report_refuse_results_not_of_this_format(tmp_path, capsys, damage):
    path = tmp_path / "r.json"
    assert cli.main(["run", str(DISK), "--engines", "pymunk", "--no-cache", "--json",
                     str(path), "--workers", "1"]) == 0
    document = json.loads(path.read_text(encoding="utf-8"))
    if damage == "format_version":
        document["format_version"] = 99
    else:
        del document["records"][-1]["u_after"]
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps(document), encoding="utf-8")
    capsys.readouterr()
    assert cli.main(["compare", str(path), str(bad)]) == 2
    err = capsys.readouterr().err  # bad input: one line on stderr, as every command's
    assert err.count("\n") == 1 and str(bad) in err
    assert cli.main(["report", "--results", str(bad), "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and str(bad) in err and not (tmp_path / "out").exists()


# --------------------------------------------------------------------------------------------
# Item 6: an engine error is never exit 0
# --------------------------------------------------------------------------------------------
def test_an_engine_error_exits_4_and_the_results_are_written(tmp_path, monkeypatch, capsys):
    adapter = type(load_engine("pymunk"))

    def broken(self, *args, **kwargs):
        raise TypeError("injected engine failure")

    monkeypatch.setattr(adapter, "run", broken)
    monkeypatch.setattr(adapter, "run_many", broken)
    path = tmp_path / "r.json"
    status = cli.main(["run", str(DISK), "--engines", "pymunk", "--no-cache", "--json",
                       str(path), "--workers", "1"])
    err = capsys.readouterr().err
    assert status == command.EXIT_ENGINE_ERROR == 4
    engine_records = [r for r in read_results(path).records if r.source == "pymunk"]
    assert engine_records and all(r.status.startswith("error: TypeError") for r in engine_records)
    assert err.count("ENGINE ERROR:") == len(engine_records)
    assert "  4 " in cli.build_parser(None).epilog
