"""Fuzzing the command line with hostile input (issue 23): mutated scenario files,
population files, command lines and results files, each through ``impact-harness``'s own
``main`` in this process.

Seeded and bounded (a fixed number of cases per kind, a time limit per case; about half a
minute on the 2-core machine). Each case must end as a clean run (exit 0 or 1) or as bad
input (exit 2, saying why on stderr): never a traceback, an internal error (exit 3) or a
hang. A failure names the seed and the case, so it can be replayed alone.
"""

from __future__ import annotations

import errno
import json
import random
import re
import signal
import time
from pathlib import Path

import pytest

from harness import cli
from harness.scenarios import SCENARIO_DIR
from harness.store.sealing import Seal

ROOT = Path(__file__).resolve().parents[1]
SEED = 20261128
#: Seconds one case may take before it counts as a hang.
CASE_LIMIT_S = 30

#: Values that broke, or could break, a reader: huge, tiny, not finite, of the wrong type,
#: nested, control characters, long.
HOSTILE_VALUES = ["1e308", "-1e308", "1e-320", "nan", "inf", "-inf", "0", "-0.0", "-1",
                  "1e12", "1000000000", "9" * 40, '"x"', '"\\u0000"', '"a\\nb"', "true", "[]",
                  "{}", "[1, 2, 3]", "[" * 70 + "]" * 70, "{ a = 1 }", '"' + "x" * 5000 + '"']
#: Scenario files whose mutants also go through ``run``: one point, quick to simulate.
CHEAP = ("disk-direct.toml", "disk-oblique.toml", "two-sled-row1.toml", "matrix-rod-45.toml",
         "rod-45-direct-plastic.toml", "disk-topspin.toml")
NUMBER = re.compile(r"(?<![\w.\"])-?\d+(?:\.\d+)?(?:[eE][-+]?\d+)?(?![\w.\"])")


class Hang(Exception):
    pass


def _alarm(signum, frame):
    raise Hang


def run_main(argv: list[str], capsys) -> tuple[int, str, str]:
    """``impact-harness ARGV`` in this process: (exit status, stdout, stderr)."""
    previous = signal.signal(signal.SIGALRM, _alarm)
    signal.setitimer(signal.ITIMER_REAL, CASE_LIMIT_S)
    try:
        try:
            status = cli.main(argv)
        except SystemExit as stop:  # argparse refusing an option
            status = stop.code if isinstance(stop.code, int) else 2
    except Hang:
        status = "hang"
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)
    said = capsys.readouterr()
    return status, said.out, said.err


def assert_clean(case: str, argv: list[str], status, out: str, err: str) -> None:
    where = f"{case}: impact-harness {' '.join(argv)[:300]}"
    assert status in (0, 1, 2), f"{where}: exit {status}\n{err[-600:]}"
    assert "Traceback" not in out + err, f"{where}: a traceback\n{err[-600:]}"
    assert "internal error" not in out + err, f"{where}: {err[-600:]}"
    if status == 2:
        assert (out + err).strip(), f"{where}: exit 2 without a word"


def mutate_text(text: str, rng: random.Random) -> str:
    """One to three edits of a TOML file's text: a number replaced by a hostile value, a line
    dropped or repeated, bytes inserted, the text cut short."""
    for _ in range(rng.randint(1, 3)):
        kind = rng.choice(["number", "number", "number", "drop", "repeat", "insert", "cut"])
        lines = text.split("\n")
        if kind == "number":
            spots = list(NUMBER.finditer(text))
            if spots:
                spot = rng.choice(spots)
                text = text[:spot.start()] + rng.choice(HOSTILE_VALUES) + text[spot.end():]
        elif kind == "drop" and len(lines) > 1:
            del lines[rng.randrange(len(lines))]
            text = "\n".join(lines)
        elif kind == "repeat":
            line = rng.randrange(len(lines))
            lines.insert(line, lines[line])
            text = "\n".join(lines)
        elif kind == "insert":
            at = rng.randrange(len(text) + 1)
            text = text[:at] + rng.choice(["\x00", "[", "]]", "=", '"', "\\", "\n[[body]]\n",
                                           "é", "\n[engine_settings.pymunk]\niterations = 0\n"]) \
                + text[at:]
        else:
            text = text[:rng.randrange(len(text) + 1)]
    return text


def test_mutated_scenario_files(tmp_path, capsys):
    rng = random.Random(SEED)
    sources = sorted(SCENARIO_DIR.glob("*.toml"))
    files = []
    for number in range(200):
        source = rng.choice(sources)
        path = tmp_path / f"m{number}-{source.name}"
        text = mutate_text(source.read_text(encoding="utf-8"), rng)
        path.write_bytes(text.encode("utf-8", "surrogatepass") if rng.random() < 0.9
                         else b"\xff\xfe" + text.encode("utf-8"))
        files.append(path)
    valid = []
    for path in files:  # one by one: each its own line, or none
        argv = ["validate", str(path)]
        status, out, err = run_main(argv, capsys)
        assert_clean(f"seed {SEED}, {path.name}", argv, status, out, err)
        if status == 0:
            valid.append(path)
    # a few through `run` (the laws, one engine, no cache), those that passed `validate`
    # and some that did not: bad ones refused, good ones run
    cheap = [p for p in files if p.name.split("-", 1)[1] in CHEAP]
    small = [p for p in cheap if p in valid][:8] + [p for p in cheap if p not in valid][:4]
    for number, path in enumerate(small):
        argv = ["run", str(path), "--engines", "pymunk", "--preset", "defaults", "--no-cache",
                "--json", str(tmp_path / f"r{number}.json")]
        assert_clean(f"seed {SEED}, run {path.name}", argv, *run_main(argv, capsys))


def test_mutated_population_files(tmp_path, capsys):
    rng = random.Random(SEED + 1)
    sources = sorted((ROOT / "populations").glob("*.toml"))
    for number in range(16):
        source = rng.choice(sources)
        path = tmp_path / f"p{number}-{source.name}"
        path.write_text(mutate_text(source.read_text(encoding="utf-8"), rng), encoding="utf-8")
        argv = ["survey", str(path), "--samples", "3", "--engines", "pymunk", "--preset",
                "defaults", "--workers", "1", "--no-figures", "--out", str(tmp_path / "s")]
        assert_clean(f"seed {SEED + 1}, {path.name}", argv, *run_main(argv, capsys))


#: Options and hostile values for the command-line fuzz; a command always names one small
#: scenario or population and one engine, so a line that is accepted runs in a second.
OPTION_VALUES = {
    "--workers": ["0", "-1", "1", "2", "1e9", "x", "99999999999999999999"],
    "--chunk-size": ["0", "1", "-5", "1000000000"],
    "--task-time-limit": ["0", "-1", "nan", "inf", "1e300", "30"],
    "--set": ["pymunk.iterations=0", "pymunk.iterations=1e9", "pymunk.time_step=1e-8",
              "pymunk.max_steps=10000000", "pymunk.approach_steps=1e12", "pymunk.bogus=1",
              "bogus.x=1", "pymunk.iterations=[[[[1]]]]", "pymunk.time_step=\"x\"",
              "pymunk.iterations=20", "=", "pymunk.=1"],
    "--preset": ["defaults", "bogus", "all", ""],
    "--json": ["{tmp}/a.json", "{tmp}", "/dev/null", "/proc/x/y.json", "{tmp}/" + "a" * 300,
               "{tmp}/nested/new/r.json"],
    "--samples": ["0", "-3", "1000000000", "2", "1e3"],
    "--seed": ["-1", "0", "4294967296", "x"],
    "--out": ["{tmp}/out", "/dev/null", "{tmp}/a-file", "{tmp}/" + "b" * 300],
    "--engines": ["bogus", "pymunk", "pymunk,bogus", ""],
}
COMMAND_OPTIONS = {
    "run": ["--workers", "--chunk-size", "--task-time-limit", "--set", "--preset", "--json"],
    "survey": ["--samples", "--seed", "--workers", "--out", "--engines"],
    "validate": [],
}


def test_hostile_command_lines(tmp_path, capsys):
    rng = random.Random(SEED + 2)
    (tmp_path / "a-file").write_text("x")
    for number in range(60):
        command = rng.choice(sorted(COMMAND_OPTIONS))
        argv = [command]
        if command == "run":
            argv += [str(SCENARIO_DIR / "disk-direct.toml"), "--engines", "pymunk", "--no-cache"]
        elif command == "survey":
            argv += ["disk-disk", "--no-figures"]
        else:
            argv += [rng.choice([str(SCENARIO_DIR / "disk-direct.toml"), "/dev/zero",
                                 str(tmp_path), "/nonexistent.toml", "x" * 5000])]
        chosen = rng.sample(COMMAND_OPTIONS[command], k=min(len(COMMAND_OPTIONS[command]),
                                                            rng.randint(1, 3)))
        for option in chosen:
            argv += [option, rng.choice(OPTION_VALUES[option]).format(tmp=tmp_path)]
        if command == "run" and "--json" not in argv:
            argv += ["--json", str(tmp_path / f"run{number}.json")]
        if command == "survey":
            if "--samples" not in argv or not _small(argv):
                argv = _with(argv, "--samples", "2")
            if "--out" not in argv:
                argv += ["--out", str(tmp_path / "out")]
            if "--engines" not in argv:
                argv += ["--engines", "pymunk"]
        assert_clean(f"seed {SEED + 2}, case {number}", argv, *run_main(argv, capsys))


def _small(argv: list[str]) -> bool:
    """Whether the ``--samples`` of a survey's command line is refused or small."""
    text = argv[argv.index("--samples") + 1]
    try:
        return not 100 < float(text) <= 1_000_000  # 1e3 is read as 1000 samples
    except ValueError:
        return True


def _with(argv: list[str], option: str, value: str) -> list[str]:
    if option in argv:
        at = argv.index(option)
        return argv[:at] + [option, value] + argv[at + 2:]
    return argv + [option, value]


HOSTILE_JSON = [None, True, -1, 1e308, "x", "", [], {}, [[[[[]]]]], {"a": {"b": {}}},
                "\u0000", 10**30]


def mutate_json(document, rng: random.Random):
    """A copy of a results file's document with one to three leaves or keys damaged."""
    document = json.loads(json.dumps(document))
    for _ in range(rng.randint(1, 3)):
        parent, key = None, None
        node = document
        for _ in range(rng.randint(1, 6)):  # walk down to a random place
            if isinstance(node, dict) and node:
                key = rng.choice(sorted(node))
            elif isinstance(node, list) and node:
                key = rng.randrange(len(node))
            else:
                break
            parent, node = node, node[key]
        if parent is None:
            continue
        if isinstance(parent, dict) and rng.random() < 0.3:
            del parent[key]
        else:
            parent[key] = rng.choice(HOSTILE_JSON)
    return document


def test_mutated_results_files(tmp_path, capsys):
    good = tmp_path / "good.json"
    argv = ["run", str(SCENARIO_DIR / "disk-direct.toml"), "--engines", "pymunk", "--preset",
            "defaults", "--no-cache", "--json", str(good)]
    assert run_main(argv, capsys)[0] == 0
    document = json.loads(good.read_text(encoding="utf-8"))
    rng = random.Random(SEED + 3)
    for number in range(60):
        path = tmp_path / f"bad{number}.json"
        choice = rng.random()
        if choice < 0.8:
            path.write_text(json.dumps(mutate_json(document, rng)), encoding="utf-8")
        elif choice < 0.9:
            text = good.read_text(encoding="utf-8")
            path.write_text(text[:rng.randrange(len(text))], encoding="utf-8")
        else:
            path.write_text("[" * 100_000 + "]" * 100_000, encoding="utf-8")
        argv = ["compare", str(good), str(path), "--csv", str(tmp_path / "c.csv")]
        assert_clean(f"seed {SEED + 3}, case {number}", argv, *run_main(argv, capsys))
        argv = ["export", str(path), "--out", str(tmp_path / "e.csv")]
        assert_clean(f"seed {SEED + 3}, export case {number}", argv, *run_main(argv, capsys))


# --------------------------------------------------------------------------------------------
# Issue 37 (second round): the fuzzer's findings, each a clean refusal (exit 2) in a second or
# so, nothing outside the named outputs changed
# --------------------------------------------------------------------------------------------
#: Seconds of CPU one case of the corpus may take (the dotted key took 40-66 s before).
CORPUS_CPU_S = 5.0
DISK_TEXT = (SCENARIO_DIR / "disk-direct.toml").read_text(encoding="utf-8")
POPULATION_TEXT = (ROOT / "populations" / "disk-disk.toml").read_text(encoding="utf-8")

#: Scenario or population files: (name, text); each must be refused by `validate`.
HOSTILE_FILES = {
    "dotted-key-120kB.toml": DISK_TEXT + "\na" + ".a" * 60_000 + " = 1\n",
    "dotted-header.toml": DISK_TEXT + "\n[a" + ".a" * 60_000 + "]\n",
    "integer-5000-digits.toml": DISK_TEXT.replace("mass = 1.0", "mass = " + "9" * 5000),
    "engines-empty.toml": DISK_TEXT.replace("[ground]", 'engines = []\n\n[ground]', 1),
    "laws-empty.toml": DISK_TEXT.replace("[ground]", 'laws = []\n\n[ground]', 1),
    "bidi-description.toml": DISK_TEXT.replace('description = "', 'description = "\u202e', 1),
    "long-name.toml": DISK_TEXT.replace('name = "disk-direct"', f'name = "{"n" * 243}"'),
    "population-attempts.toml": POPULATION_TEXT + "\nmax_attempts = 1e12\n",
    "population-attempts-fraction.toml": POPULATION_TEXT + "\nmax_attempts = 2.5\n",
    "population-speed.toml": POPULATION_TEXT.replace(
        "speed = { log_uniform = [0.3, 3.0] }", "speed = 1e6"),
    "population-radius.toml": POPULATION_TEXT.replace(
        "radius = { uniform = [0.05, 0.3] }", "radius = 1e-6", 1),
    "population-mass-ratio.toml": POPULATION_TEXT.replace(
        "mass_ratio = { log_uniform = [0.1, 10.0] }", "mass_ratio = 1e-10"),
}


def _cpu_limited(case: str, argv: list[str], capsys) -> tuple:
    started = time.process_time()
    said = run_main(argv, capsys)
    spent = time.process_time() - started
    assert spent < CORPUS_CPU_S, f"{case}: {spent:.1f} s of CPU"
    return said


@pytest.mark.parametrize("name", sorted(HOSTILE_FILES))
def test_second_round_files_are_refused_fast(tmp_path, capsys, name):
    path = tmp_path / name
    path.write_text(HOSTILE_FILES[name], encoding="utf-8")
    assert HOSTILE_FILES[name] != (DISK_TEXT if "population" not in name else POPULATION_TEXT)
    argv = ["validate", str(path)]
    status, out, err = _cpu_limited(name, argv, capsys)
    assert_clean(name, argv, status, out, err)
    assert status == 2, f"{name}: exit {status}: {out[-300:]}{err[-300:]}"


def _command_lines(tmp_path) -> dict[str, list[str]]:
    loop = tmp_path / "loop.toml"
    loop.symlink_to(tmp_path / "loop2.toml")
    (tmp_path / "loop2.toml").symlink_to(loop)
    disk = str(SCENARIO_DIR / "disk-direct.toml")
    json_out = str(tmp_path / "r.json")
    return {
        "symlink loop as a scenario": ["run", str(loop), "--no-cache", "--json", json_out],
        "findings --count -1": ["findings", "--count", "-1"],
        "stress --workers 0": ["stress", "--workers", "0"],
        "a bad --scheduler": ["run", disk, "--executor", "dask", "--scheduler", "bogus",
                              "--no-cache", "--json", json_out],
        "report --workers 0": ["report", "--workers", "0", "--out", str(tmp_path / "rep")],
        "compare --show -1": ["compare", json_out, json_out, "--show", "-1"],
        "compare --fail-above 5": ["compare", json_out, json_out, "--fail-above", "5"],
        "compare --fail-above abc": ["compare", json_out, json_out, "--fail-above", "abc"],
        "--engines ''": ["run", disk, "--engines", "", "--no-cache", "--json", json_out],
        "survey --engines ''": ["survey", "disk-disk", "--engines", "", "--samples", "2",
                                "--out", str(tmp_path / "s")],
        "a 5000-digit --workers": ["run", disk, "--workers", "9" * 5000, "--json", json_out],
        "--set box2d.length_scale=1e300": ["run", disk, "--engines", "box2d", "--set",
                                           "box2d.length_scale=1e300", "--json", json_out],
        "--set mujoco.solimp=[2,2,2,2,2]": ["run", disk, "--engines", "mujoco", "--set",
                                            "mujoco.solimp=[2,2,2,2,2]", "--json", json_out],
        "--set nested 30,000 deep": ["run", disk, "--engines", "pymunk", "--set",
                                     "pymunk.iterations=" + "[" * 30_000 + "]" * 30_000,
                                     "--json", json_out],
        "stress: a bad --scheduler": ["stress", "--executor", "dask", "--scheduler", "bogus",
                                      "--solver-only", "--out", str(tmp_path / "st")],
        "cache info, a --cache-dir too long": ["cache", "info", "--cache-dir",
                                               str(tmp_path / ("x" * 300))],
        "cache clear, a --cache-dir a file": ["cache", "clear", "--cache-dir",
                                              str(SCENARIO_DIR / "disk-direct.toml")],
        "cache prune --older-than nan": ["cache", "prune", "--older-than", "nan",
                                         "--cache-dir", str(tmp_path / "c")],
    }


def test_second_round_command_lines_are_refused_before_any_work(tmp_path, capsys):
    lines = _command_lines(tmp_path)
    before = sorted(p.name for p in tmp_path.iterdir())
    for case, argv in lines.items():
        status, out, err = _cpu_limited(case, argv, capsys)
        assert_clean(case, argv, status, out, err)
        assert status == 2, f"{case}: exit {status}: {out[-300:]}{err[-300:]}"
        assert len(err.strip().splitlines()) == 1, f"{case}: {err}"
    assert sorted(p.name for p in tmp_path.iterdir()) == before  # nothing written


def test_a_full_disk_is_one_line_exit_2_not_an_internal_error(tmp_path, capsys, monkeypatch):
    from harness.report import export

    def full(*args, **kwargs):
        raise OSError(errno.ENOSPC, "No space left on device", str(tmp_path / "x.csv"))

    good = tmp_path / "good.json"
    argv = ["run", str(SCENARIO_DIR / "disk-direct.toml"), "--engines", "pymunk", "--preset",
            "defaults", "--no-cache", "--json", str(good)]
    assert run_main(argv, capsys)[0] == 0
    monkeypatch.setattr(export, "write_long", full)
    argv = ["export", str(good), "--out", str(tmp_path / "x.csv")]
    status, out, err = run_main(argv, capsys)
    assert_clean("disk full", argv, status, out, err)
    assert status == 2 and "No space left on device" in err and "x.csv" in err


@pytest.mark.parametrize("damage", ["departure-a-list", "diagnostics-a-number"])
def test_export_of_a_malformed_record_is_bad_input(tmp_path, capsys, damage):
    good = tmp_path / "good.json"
    argv = ["run", str(SCENARIO_DIR / "disk-direct.toml"), "--engines", "pymunk", "--preset",
            "defaults", "--no-cache", "--json", str(good)]
    assert run_main(argv, capsys)[0] == 0
    document = json.loads(good.read_text(encoding="utf-8"))
    record = document["records"][-1]
    if damage == "departure-a-list":
        record["departure"] = {"poisson": [1.0]}
    else:
        record["diagnostics"] = 7
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps(document), encoding="utf-8")
    argv = ["export", str(bad), "--out", str(tmp_path / "e.csv")]
    status, out, err = run_main(argv, capsys)
    assert_clean(damage, argv, status, out, err)
    assert status == 2 and "record" in err and not (tmp_path / "e.csv").exists()


@pytest.mark.parametrize("damage", ["gates-a-string", "cached-a-string", "speed-a-string",
                                    "scenario-info-a-list"])
def test_report_of_values_of_the_wrong_type_is_refused_before_any_work(tmp_path, capsys,
                                                                         damage):
    """read_results checks every value a report reads (was: exit 3 half-way through)."""
    good = tmp_path / "good.json"
    argv = ["run", str(SCENARIO_DIR / "disk-direct.toml"), "--engines", "pymunk", "--preset",
            "defaults", "--no-cache", "--json", str(good)]
    assert run_main(argv, capsys)[0] == 0
    document = json.loads(good.read_text(encoding="utf-8"))
    if damage == "gates-a-string":
        document["provenance"]["gates"] = "x"
    elif damage == "cached-a-string":
        document["records"][-1]["cached"] = "\u0000"
    elif damage == "speed-a-string":
        document["records"][-1]["u_after"][0] = "fast"
    else:
        document["scenarios"]["disk-direct"] = []
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps(document), encoding="utf-8")
    argv = ["report", "--results", str(bad), "--out", str(tmp_path / "rep")]
    status, out, err = run_main(argv, capsys)
    assert_clean(damage, argv, status, out, err)
    assert status == 2 and str(bad) in err and not (tmp_path / "rep").exists()


@pytest.mark.parametrize("variable,value", [("IMPACT_HARNESS_MAX_INPUT_BYTES", "1e300"),
                                            ("IMPACT_HARNESS_MAX_INPUT_BYTES", "abc"),
                                            ("IMPACT_HARNESS_MIN_TIME_STEP", "nan"),
                                            ("IMPACT_HARNESS_MAX_SWEEP_POINTS", "-5")])
def test_a_limit_set_in_the_environment_out_of_its_range_is_bad_input(capsys, monkeypatch,
                                                                      variable, value):
    monkeypatch.setenv(variable, value)
    argv = ["validate", str(SCENARIO_DIR / "disk-direct.toml")]
    status, out, err = run_main(argv, capsys)
    assert_clean(variable, argv, status, out, err)
    assert status == 2 and variable in err and err.count("\n") == 1


def _good_results(tmp_path, capsys) -> Path:
    good = tmp_path / "good.json"
    argv = ["run", str(SCENARIO_DIR / "disk-direct.toml"), "--engines", "pymunk", "--preset",
            "defaults", "--no-cache", "--json", str(good)]
    assert run_main(argv, capsys)[0] == 0
    return good


@pytest.mark.parametrize("name", ["index.html", "summary.md", ".report-fragments.json",
                                  ".report-digests.json"])
def test_report_refuses_a_link_at_its_own_files_before_any_work(tmp_path, capsys, name):
    """Third round: a symbolic link at out/index.html ended in exit 3 after the work, and
    one at out/.report-fragments.json to /dev/zero was read until memory ran out (24 GB)."""
    good = _good_results(tmp_path, capsys)
    out = tmp_path / "rep"
    out.mkdir()
    (out / name).symlink_to(tmp_path / "elsewhere")
    argv = ["report", "--results", str(good), "--out", str(out), "--workers", "1",
            "--scenario-figures", "none"]
    status, out_text, err = _cpu_limited(name, argv, capsys)
    assert_clean(name, argv, status, out_text, err)
    assert status == 2 and name in err and "symbolic link" in err
    assert sorted(p.name for p in out.iterdir()) == [name]  # nothing written
    assert not (tmp_path / "elsewhere").exists()


def test_report_fragments_are_read_bounded_never_from_a_device(tmp_path):
    """The report's own cache in its directory is read as a regular file of bounded size:
    a FIFO or a device there is a cache to compute anew, never read (nor waited on)."""
    import os

    from harness.report.fragments import FragmentCache

    fifo = tmp_path / "fragments.json"
    os.mkfifo(fifo)
    previous = signal.signal(signal.SIGALRM, _alarm)
    signal.setitimer(signal.ITIMER_REAL, 5)
    try:
        assert FragmentCache(fifo, "context").stored == {}
    except Hang:
        pytest.fail("waited on a FIFO for its content")
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)
    big = tmp_path / "big.json"
    seal = Seal(tmp_path)
    kept = FragmentCache(big, "context", seal)
    kept.get("a", lambda: 1)
    kept.get("b", lambda: "x" * 100)
    kept.save()
    assert FragmentCache(big, "context", seal).stored == {"a": 1, "b": "x" * 100}


def test_report_fragments_edited_or_unsealed_are_computed_anew(tmp_path, capsys):
    """Fourth round: whoever could write the report's directory could edit
    .report-fragments.json and get their HTML into index.html (only a hash of the code
    guarded it). The file is sealed under a key kept apart (the result cache's); an edited,
    unsealed or otherwise sealed file is not believed, said in one line."""
    from harness.report.fragments import FragmentCache

    (tmp_path / "key-home").mkdir()
    seal = Seal(tmp_path / "key-home")
    path = tmp_path / ".report-fragments.json"
    kept = FragmentCache(path, "context", seal)
    kept.get("section", lambda: "<p>computed</p>")
    kept.get("view", lambda: {"cells": [1.5, None]})
    kept.save()
    assert capsys.readouterr().err == ""
    assert FragmentCache(path, "context", seal).stored == {"section": "<p>computed</p>",
                                                           "view": {"cells": [1.5, None]}}
    assert capsys.readouterr().err == ""
    sealed = path.read_bytes()
    header, rest = sealed.split(b"\n", 1)
    other = Seal(tmp_path / "other")
    (tmp_path / "other").mkdir()
    forged_header = json.dumps(other.sealed(json.loads(header))).encode()
    unsealed = {key: value for key, value in json.loads(header).items() if key != "mac"}
    for case, text in (
            ("a section edited", sealed.replace(b"computed", b"<script>x</script>")),
            ("sealed by another key", forged_header + b"\n" + rest),
            ("unsealed", json.dumps(unsealed).encode() + b"\n" + rest),
            ("the old format", b'{"context": "context", "entries": {}, "texts": '
                               b'{"section": [0, 17]}}\n<script>x</script>')):
        path.write_bytes(text)
        cache = FragmentCache(path, "context", seal)
        assert cache.stored == {}, case
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and "not believed" in err and str(path) in err, case
        assert cache.get("section", lambda: "<p>computed</p>") == "<p>computed</p>"


def test_a_figure_replaced_by_a_fifo_is_redrawn_not_waited_on(tmp_path):
    import os

    from harness.report.figure_cache import png_tag

    os.mkfifo(tmp_path / "heatmap.png")
    previous = signal.signal(signal.SIGALRM, _alarm)
    signal.setitimer(signal.ITIMER_REAL, 5)
    try:
        assert png_tag(tmp_path / "heatmap.png") is None
    except Hang:
        pytest.fail("waited on a FIFO for its content")
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)


@pytest.mark.parametrize("damage", ["departure-400-digits", "speed-400-digits",
                                    "speeds-gone"])
def test_compare_of_a_huge_integer_or_a_result_gone_is_refused_or_a_change(tmp_path, capsys,
                                                                           damage):
    """A 400-digit integer as a departure ended in an OverflowError (exit 3); speeds null in
    one file only compared as "0 changed" (exit 0)."""
    good = _good_results(tmp_path, capsys)
    text = good.read_text(encoding="utf-8")
    document = json.loads(text)
    record = document["records"][-1]
    if damage == "speeds-gone":
        record["u_after"] = None
        bad_text = json.dumps(document)
    else:
        field = "departure" if damage.startswith("departure") else "u_after"
        marker = 123.25
        if field == "departure":
            record["departure"]["poisson"] = marker
        else:
            record["u_after"][0] = marker
        bad_text = json.dumps(document).replace("123.25", "9" * 400)
    bad = tmp_path / "bad.json"
    bad.write_text(bad_text, encoding="utf-8")
    argv = ["compare", str(good), str(bad)]
    status, out, err = run_main(argv, capsys)
    assert_clean(damage, argv, status, out, err)
    if damage == "speeds-gone":
        assert status == 1 and "speeds gone" in out
    else:
        assert status == 2 and str(bad) in err and "not" in err


def test_the_cache_never_writes_through_a_linked_shard_directory(tmp_path, capsys):
    """A shard directory of the cache replaced by a link to elsewhere: the run goes on
    without the cache, nothing lands where the link points."""
    cache = tmp_path / "cache"
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    argv = ["run", str(SCENARIO_DIR / "disk-direct.toml"), "--engines", "pymunk", "--preset",
            "defaults", "--workers", "1", "--cache-dir", str(cache), "--json",
            str(tmp_path / "r.json"), "--force"]
    assert run_main(argv, capsys)[0] == 0
    shards = [p for p in cache.iterdir() if p.is_dir()]
    assert shards
    for shard in shards:  # every entry gone, every directory a link: each put is refused
        for entry in shard.iterdir():
            entry.unlink()
        shard.rmdir()
        shard.symlink_to(elsewhere)
    status, out, err = run_main(argv, capsys)
    assert_clean("linked shard", argv, status, out, err)
    assert status == 0 and "symbolic link" in err
    assert list(elsewhere.iterdir()) == []


@pytest.mark.parametrize("name", ["disk\u202egnp.exe", "a\u0000b", "n" * 300, "../../x",
                                  '=HYPERLINK("http://x")', "disk-direct\n"])
def test_a_results_file_with_a_name_no_scenario_file_takes_is_refused(tmp_path, capsys, name):
    """A scenario's name in a results file obeys the scenario file's rule: a 300-character
    one ended compare in exit 3 (a file name too long), a bidi control or a NUL went into
    the report's page and figures."""
    good = _good_results(tmp_path, capsys)
    document = json.loads(good.read_text(encoding="utf-8"))
    for record in document["records"]:
        record["scenario"] = name
    document["scenarios"] = {name: next(iter(document["scenarios"].values()))}
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps(document), encoding="utf-8")
    for argv in (["compare", str(bad), str(bad)], ["export", str(bad), "--out",
                                                   str(tmp_path / "e.csv")],
                 ["report", "--results", str(bad), "--out", str(tmp_path / "rep")]):
        status, out, err = run_main(argv, capsys)
        assert_clean(name, argv, status, out, err)
        assert status == 2 and "not a scenario's name" in err, err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bad.json", "good.json"]


@pytest.mark.parametrize("field", ["name", "tag"])
def test_a_name_or_tag_ending_in_a_newline_is_refused(tmp_path, capsys, field):
    """``$`` in the name's pattern matched before a final newline: "disk-direct\\n" was a
    valid name (and a file name, an HTML anchor, a table cell with a line break)."""
    text = DISK_TEXT.replace('name = "disk-direct"', 'name = "disk-direct\\n"', 1) \
        if field == "name" else DISK_TEXT.replace('"quick"', '"quick\\n"', 1)
    assert text != DISK_TEXT
    path = tmp_path / "s.toml"
    path.write_text(text, encoding="utf-8")
    status, out, err = run_main(["validate", "--no-solve", str(path)], capsys)
    assert status == 2 and "\\n" in out + err


def test_export_replaces_its_own_file(tmp_path, capsys):
    """`export --out FILE` a second time was refused: FILE "is not a directory"."""
    good = _good_results(tmp_path, capsys)
    argv = ["export", str(good), "--out", str(tmp_path / "e.csv")]
    assert run_main(argv, capsys)[0] == 0
    status, out, err = run_main(argv, capsys)
    assert status == 0, err


def test_a_file_of_100_000_unknown_tables_prints_a_bounded_list(tmp_path, capsys):
    """Each unknown key is an error; 100,000 of them printed 100,000 lines."""
    path = tmp_path / "tables.toml"
    path.write_text(DISK_TEXT + "".join(f"\n[t{i}]\n" for i in range(2000)), encoding="utf-8")
    argv = ["validate", "--no-solve", str(path)]
    status, out, err = _cpu_limited("tables", argv, capsys)
    assert_clean("tables", argv, status, out, err)
    assert status == 2 and "1980 more errors not shown" in out
    assert len((out + err).splitlines()) < 30


def test_compare_never_writes_its_table_over_a_file_it_compares(tmp_path, capsys):
    """`compare a.json b.json --csv b.json` replaced b.json by the table (exit 0)."""
    good = _good_results(tmp_path, capsys)
    text = good.read_text(encoding="utf-8")
    for option in ("--csv", "--html"):
        argv = ["compare", str(good), str(good), option, str(good)]
        status, out, err = run_main(argv, capsys)
        assert_clean(option, argv, status, out, err)
        assert status == 2 and "being compared" in err
    assert good.read_text(encoding="utf-8") == text


def test_compare_of_a_departure_gone_is_a_change(tmp_path, capsys):
    """An engine record whose departures vanished in B compared as "0 changed", exit 0."""
    good = _good_results(tmp_path, capsys)
    document = json.loads(good.read_text(encoding="utf-8"))
    document["records"][-1]["departure"] = {}
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps(document), encoding="utf-8")
    status, out, err = run_main(["compare", str(good), str(bad)], capsys)
    assert status == 1 and "gone" in out, out + err
    status, out, err = run_main(["compare", str(bad), str(good)], capsys)  # a law added
    assert status == 0, out + err


@pytest.mark.parametrize("name", ["summary.md", "runs.parquet", ".written-by-survey.json"])
def test_survey_refuses_a_link_at_its_own_files_before_any_work(tmp_path, capsys, name):
    """A link at the survey's own summary.md was found by the write after the work (exit 3)."""
    out = tmp_path / "survey"
    out.mkdir()
    (out / name).symlink_to(tmp_path / "elsewhere")
    argv = ["survey", "disk-disk", "--samples", "2", "--engines", "pymunk", "--preset",
            "defaults", "--workers", "1", "--no-figures", "--out", str(out)]
    status, out_text, err = _cpu_limited(name, argv, capsys)
    assert_clean(name, argv, status, out_text, err)
    assert status == 2 and name in err and "symbolic link" in err
    assert sorted(p.name for p in out.iterdir()) == [name]
    assert not (tmp_path / "elsewhere").exists()


def test_cache_clear_under_a_planted_marker_removes_only_what_the_key_sealed(tmp_path,
                                                                            capsys):
    """Fourth round: a marker file planted in a directory of files named like cache entries
    got them all removed by `cache clear`; only entries the cache's key sealed are, and
    what is left is counted."""
    from harness.store.cache import ResultCache
    from harness.store.cache_directory import CACHE_MARKER

    planted = tmp_path / "theirs"
    (planted / "ab").mkdir(parents=True)
    (planted / CACHE_MARKER).write_text("planted")
    users = [planted / "ab" / f"{'ab' + '0' * 62}.json", planted / "passed-checks.json"]
    for path in users:
        path.write_text('{"key": "mine", "sha256": "0"}\nthe user\'s own\n')
    for action in ("prune", "clear"):
        argv = ["cache", action, "--cache-dir", str(planted)]
        status, out, err = run_main(argv, capsys)
        assert_clean("planted marker", argv, status, out, err)
        assert status == 0 and "removed 0 entries" in out and "left 2 files" in out, out + err
    assert all(path.read_text().endswith("the user's own\n") for path in users)
    # the cache's own entries, sealed by its key, are removed; a forged one beside them stays
    cache = ResultCache(tmp_path / "cache", version="v")
    key = cache.key({"a": 1})
    cache.put(key, {"status": "ok"})
    cache.put_lines(cache.key({"b": 2}), ['{"x": 1}'])
    forged = cache.path(cache.key({"c": 3}))
    forged.parent.mkdir(exist_ok=True)
    forged.write_bytes(cache.path(key).read_bytes())  # a sealed header, not its name
    argv = ["cache", "clear", "--cache-dir", str(cache.root)]
    status, out, err = run_main(argv, capsys)
    assert status == 0 and "removed 2 entries" in out and "left 1 files" in out, out + err
    assert forged.exists() and not cache.path(key).exists()


def test_a_report_never_shows_html_planted_in_its_cached_pieces(tmp_path, capsys,
                                                                monkeypatch):
    """Fourth round, end to end: an edited .report-fragments.json put its HTML into
    index.html. The edited file is not believed (one warning line), the page is computed
    anew, and the next report is warm again without a word."""
    monkeypatch.setenv("IMPACT_HARNESS_CACHE_DIR", str(tmp_path / "cache"))
    good = _good_results(tmp_path, capsys)
    out = tmp_path / "rep"
    argv = ["report", "--results", str(good), "--out", str(out), "--workers", "1",
            "--scenario-figures", "none"]
    assert run_main(argv, capsys)[0] == 0
    pieces = out / ".report-fragments.json"
    text = pieces.read_bytes()
    assert b"disk-direct" in text and b"<script>" not in text
    pieces.write_bytes(text.replace(b"disk-direct", b"<script>alert(1)</script>", 1))
    status, _, err = run_main(argv, capsys)
    assert status == 0 and err.count("not believed") == 1 and str(pieces) in err, err
    assert "<script>alert(1)</script>" not in (out / "index.html").read_text(encoding="utf-8")
    status, _, err = run_main(argv, capsys)
    assert status == 0 and "not believed" not in err, err
