"""``impact-harness run``, ``report``, ``suite`` and ``paper`` through the real dispatcher."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest

import harness.engines as engines_module
from harness.cli import main
from harness.engines import EngineNotInstalled
from harness.scenarios import SCENARIO_DIR

ROD = SCENARIO_DIR / "rod-45-slip-reversal.toml"
TWO_SLED = SCENARIO_DIR / "two-sled-row1.toml"


def cli(capsys, *argv):
    code = main(list(map(str, argv)))
    out, err = capsys.readouterr()
    return code, out, err


def test_run_writes_results_and_shows_progress(capsys, tmp_path):
    results = tmp_path / "r.json"
    code, _, err = cli(capsys, "run", ROD, TWO_SLED, "--json", results,
                       "--cache-dir", tmp_path / "cache")
    assert code == 0
    assert "[1/2] rod-45-slip-reversal" in err and "[2/2] two-sled-row1" in err
    document = json.loads(results.read_text())
    sources = {(r["scenario"], r["source"]) for r in document["records"]}
    assert ("two-sled-row1", "analytic") in sources
    assert ("rod-45-slip-reversal", "mujoco") in sources
    assert not any(s == "two-sled-row1" and src != "analytic" for s, src in sources)


def test_run_selects_engines_presets_and_tags(capsys, tmp_path):
    results = tmp_path / "r.json"
    code, _, _ = cli(capsys, "run", "--tags", "quick", "--engines", "pymunk", "--preset",
                     "accurate", "--json", results, "--no-cache")
    assert code == 0
    records = json.loads(results.read_text())["records"]
    engine = [r for r in records if r["source"] != "analytic"]
    assert engine and {(r["source"], r["preset"]) for r in engine} == {("pymunk", "accurate")}
    assert {r["scenario"] for r in records} >= {"rod-45-slip-reversal", "two-sled-row1"}


def test_run_fails_on_a_failing_gate_and_names_it(capsys, tmp_path):
    strict = tmp_path / "strict.toml"
    strict.write_text(ROD.read_text().replace('name = "rod-45-slip-reversal"', 'name = "strict"')
                      + '"mujoco.defaults" = { law = "poisson", max_departure = 1e-3 }\n')
    code, _, err = cli(capsys, "run", strict, "--json", tmp_path / "r.json", "--no-cache")
    assert code == 1
    assert "GATE FAILED" in err and '"mujoco.defaults"' in err and "'strict'" in err
    # in percent as the report shows it, and the limit also as the file writes it
    assert "vs max 0.1% (max_departure = 0.001)" in err
    assert re.search(r"departure from poisson \d[\d.e+-]*% vs", err), err
    assert "records from 1 scenario;" in err


def test_run_skips_a_missing_engine_with_the_reason(capsys, tmp_path, monkeypatch):
    real = engines_module.load_engine

    def without_pybullet(name):
        if name == "pybullet":
            raise EngineNotInstalled("pybullet", "test: pretend it is missing")
        return real(name)

    monkeypatch.setattr(engines_module, "load_engine", without_pybullet)
    results = tmp_path / "r.json"
    code, _, err = cli(capsys, "run", ROD, "--json", results, "--no-cache")
    assert code == 0  # a missing engine never fails the run
    assert "skipped engine pybullet" in err
    records = [r for r in json.loads(results.read_text())["records"] if r["source"] == "pybullet"]
    assert len(records) == 2
    assert all(r["status"].startswith("skipped: ") and "pip install pybullet" in r["status"]
               for r in records)


@pytest.mark.parametrize("argv, message", [
    (["--engines", "bullet"], "unknown engine"),
    (["--tags", "no-such-tag"], "no scenario has this tag"),
])
def test_run_bad_options(capsys, tmp_path, argv, message):
    code, _, err = cli(capsys, "run", *argv, "--json", tmp_path / "r.json", "--no-cache")
    assert code == 2 and message in err


def test_run_a_bad_file(capsys, tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text(ROD.read_text().replace("mass = 1.0", "mass = -1.0"))
    code, _, err = cli(capsys, "run", bad, "--json", tmp_path / "r.json", "--no-cache")
    assert code == 2 and "bad.toml" in err and "mass" in err


def test_report_command(capsys, tmp_path):
    results = tmp_path / "r.json"
    assert cli(capsys, "run", ROD, "--json", results, "--no-cache")[0] == 0
    code, out, _ = cli(capsys, "report", "--results", results, "--out", tmp_path / "out")
    assert code == 0 and "index.html" in out
    assert (tmp_path / "out" / "index.html").is_file()
    assert (tmp_path / "out" / "summary.md").is_file()
    assert (tmp_path / "out" / "figures" / "impulse-rod-45-slip-reversal.png").is_file()


def test_report_without_results(capsys, tmp_path):
    code, _, err = cli(capsys, "report", "--results", tmp_path / "none.json", "--out", tmp_path)
    assert code == 2 and "no results file" in err


def test_suite_quick(capsys, tmp_path):
    out = tmp_path / "reports"
    code, _, err = cli(capsys, "suite", "--tags", "quick", "--out", out,
                       "--cache-dir", tmp_path / "cache")
    assert code == 0, err
    survey = Path("survey", "summary.md")
    for name in ("paper-table3.md", "paper-table3.png", "results.json", "index.html",
                 "summary.md", survey, "survey/statistics.parquet"):
        assert (out / name).is_file(), name
    assert "[1/4] Table 3" in err and "[3/4] survey" in err and "[4/4] report" in err
    assert "all gates passed" in err
    page = (out / "index.html").read_text(encoding="utf-8")
    assert "Table 3 of Djerassi" in page  # the paper's table embedded in the page
    assert f"href='{survey.as_posix()}'" in page
    assert "<div class='folded' id='survey'>" in page and "figures/survey-map-pymunk.png" in page
    assert (out / "figures" / "survey-map-pymunk.png").is_file()
    table = (out / survey).read_text(encoding="utf-8")
    assert "| pymunk | accurate | rod-ground | all types | 20 |" in table  # SURVEY_SAMPLES each
    # a warm rerun simulates nothing and keeps the survey
    code, _, err = cli(capsys, "suite", "--tags", "quick", "--out", out,
                       "--cache-dir", tmp_path / "cache")
    assert code == 0 and "0 engine runs simulated" in err
    assert "survey/summary.md (unchanged" in err


def test_paper_command(capsys, tmp_path):
    code, out, _ = cli(capsys, "paper", "--out", tmp_path)
    assert code == 0 and "printed cells reproduced" in out
    assert (tmp_path / "paper-table3.md").is_file() and (tmp_path / "paper-table3.png").is_file()


def _library_report(directory: Path) -> Path:
    """A stand-in for the library's report in ``directory/reports``."""
    (directory / "reports").mkdir()
    index = directory / "reports" / "index.html"
    index.write_text("the library's report")
    return index


def test_report_refuses_to_replace_the_library_report(capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    index = _library_report(tmp_path)
    mine = tmp_path / "my.json"
    mine.write_text("{}")
    code, _, err = cli(capsys, "report", "--results", mine)
    assert code == 2
    assert "reports/" in err and "--out" in err and "--force" in err
    assert index.read_text() == "the library's report"


@pytest.mark.parametrize("argv", [
    ["--results", "reports/results.json"],  # the results the report was made from
    ["--results", "reports/../reports/results.json"],  # the same file by another path
    ["--results", "my.json", "--force"],
    ["--results", "my.json", "--out", "reports"],  # the directory named: as asked
])
def test_report_replaces_the_library_report_when_expected(capsys, tmp_path, monkeypatch, argv):
    monkeypatch.chdir(tmp_path)
    _library_report(tmp_path)
    # No results file: the refusal would come first, so this error says it was passed.
    code, _, err = cli(capsys, "report", *argv)
    assert code == 2 and "no results file" in err and "--force" not in err


def test_report_into_reports_without_a_report_there(capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    code, _, err = cli(capsys, "report", "--results", "my.json")
    assert code == 2 and "no results file" in err


@pytest.mark.parametrize("command, default", [("bench", "reports/bench"),
                                              ("stress", "reports/stress")])
def test_help_gives_the_default_output_directory(capsys, command, default):
    with pytest.raises(SystemExit):
        main([command, "--help"])
    help_text = " ".join(capsys.readouterr().out.split())
    assert f"--out OUT output directory (default: {default}" in help_text


@pytest.mark.parametrize(("command", "one", "four"), [
    ("run", "a gate of a scenario", True), ("paper", "Table 3", False),
    ("cache", None, False), ("new", "the file exists", False)])
def test_each_command_lists_the_exit_statuses_it_returns(capsys, command, one, four):
    with pytest.raises(SystemExit):
        main([command, "--help"])
    text = capsys.readouterr().out
    epilogue = text[text.index("exit status:"):]
    assert ("\n  1 " in epilogue) == (one is not None)
    if one is not None:
        assert one in epilogue.split("\n  1 ")[1].split("\n  2 ")[0]
    assert ("\n  4 " in epilogue) == four
    assert "\n  2 bad input" in epilogue and "\n  3 internal error" in epilogue


def test_a_failed_gate_just_above_its_limit_never_reads_as_equal_to_it():
    from harness.run.gates import GateResult

    gate = GateResult("s", "pymunk", "poisson", 0.001, "", "pymunk.defaults", 0.0010004, "FAIL")
    text = gate.describe()
    value = text.split("departure from poisson ")[1].split(" vs max ")[0]
    limit = text.split(" vs max ")[1].split(" (")[0]
    assert value != limit and value.endswith("%") and limit.endswith("%"), text
