"""The report's Survey section (harness/report/survey.py): its table is the survey's
statistics, its figures exist and are drawn once, it says what was not run, and a report
without a survey has none; the suite's quick survey is kept while its inputs are unchanged
(harness/suite.py)."""

from __future__ import annotations

import argparse
import html
import re
import shutil
from html.parser import HTMLParser
from pathlib import Path

import numpy as np
import pytest

from harness import report, suite
from harness.engines import EngineNotInstalled
from harness.report.survey import read_columns, survey_section
from harness.report.views import fmt_departure
from harness.run import runner
from harness.run.metrics import fmt_departures
from harness.run.records import read_results, write_results
from harness.scenarios import load_scenarios
from harness.survey import cli as survey_cli
from harness.survey.population import resolve_populations

LIBRARY = Path(__file__).resolve().parents[2] / "scenarios"
SAMPLES = 3
#: The engine the survey below pretends is not installed.
MISSING = "box2d"


def section_of(page: str) -> str:
    """The HTML from the Survey heading to the next section's ("" when there is none)."""
    start = page.find("id='survey'")
    if start < 0:
        return ""
    end = page.find("<details class='fold'", start)
    return page[start:end if end >= 0 else len(page)]


class Tables(HTMLParser):
    """Each table's rows as lists of cell texts, and every image's source."""

    def __init__(self):
        super().__init__()
        self.tables, self.images, self._cell = [], [], None

    def handle_starttag(self, tag, attrs):
        if tag == "table":
            self.tables.append([])
        elif tag == "tr":
            self.tables[-1].append([])
        elif tag in ("td", "th"):
            self._cell = []
        elif tag == "img":
            self.images.append(dict(attrs)["src"])

    def handle_endtag(self, tag):
        if tag in ("td", "th"):
            self.tables[-1][-1].append("".join(self._cell).strip())
            self._cell = None

    def handle_data(self, data):
        if self._cell is not None:
            self._cell.append(data)


def parse(html: str) -> Tables:
    tables = Tables()
    tables.feed(html)
    return tables


@pytest.fixture(scope="module")
def results_path(tmp_path_factory):
    """Results of one scenario with pymunk only (what the page is built around)."""
    out = tmp_path_factory.mktemp("results")
    scenarios = load_scenarios(LIBRARY / "disk-oblique.toml")
    outcome = runner.run(scenarios, engines=("pymunk",), cache=None, workers=1, log=None)
    return write_results(out / "results.json", outcome.records, outcome.provenance,
                         outcome.scenarios)


@pytest.fixture(scope="module")
def surveyed(tmp_path_factory, results_path):
    """A report directory holding a small survey (pymunk, both presets; box2d "not
    installed") and the report written over it."""
    out = tmp_path_factory.mktemp("report")
    real_load = survey_cli.load_engine

    def load(name):
        if name == MISSING:
            raise EngineNotInstalled(MISSING, "pretended missing here")
        return real_load(name)

    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(survey_cli, "load_engine", load)
        survey = survey_cli.run_survey(resolve_populations(["spinning-disk", "disk-rod"]),
                                       SAMPLES, 3, ["pymunk", MISSING],
                                       ["defaults", "accurate"], workers=1, echo=lambda _: None)
    settings = {"samples": SAMPLES, "seed": 3, "engines": ["pymunk"],
                "presets": ["defaults", "accurate"], "skipped": survey["skipped"],
                "left_out": survey["left_out"]}
    survey_cli.write_survey(survey, out / "survey", settings, figures=False)
    written = report.write_report(read_results(results_path), out, workers=1,
                                  scenario_figures="none")
    return out, written


def test_the_table_is_the_surveys_statistics(surveyed):
    out, written = surveyed
    section = section_of(written["html"].read_text(encoding="utf-8"))
    assert section, "no Survey section"
    stats = read_columns(out / "survey" / "statistics.parquet")
    overall = np.flatnonzero(stats["poisson_type"] == 0)
    table = parse(section).tables[0]
    header, rows = table[0], table[1:]
    assert header[:6] == ["engine", "preset", "family", "n", "flagged", "gains E"]
    assert len(rows) == len(overall) == 2 * 2  # two presets, two families
    assert header[6:] == ["from Poisson, checked runs: median", "p90", "max",
                          "from Poisson, all runs: median", "p90",
                          "from Stronge, checked: median", "p90"]

    def cell(i, prefix):  # a quantile and its interval in one style (fmt_departures)
        text, low, high = fmt_departures([float(stats[prefix][i]),
                                          float(stats[f"{prefix}_low"][i]),
                                          float(stats[f"{prefix}_high"][i])])
        return text, f"[{low}, {high}]"

    def split(text):  # a cell's value, then its interval in small type (if any)
        value, _, rest = text.partition("[")
        return value.strip(), f"[{rest.strip()}" if rest else ""

    shown = {(row[2], row[3], *(split(text) for text in row[6:])) for row in rows}
    expected = {(str(stats["family"][i]), str(int(stats["n"][i])),
                 cell(i, "departure_poisson_median"), cell(i, "departure_poisson_p90"),
                 (fmt_departure(float(stats["departure_poisson_max"][i])), ""),
                 cell(i, "departure_poisson_all_median"), cell(i, "departure_poisson_all_p90"),
                 *((fmt_departure(float(stats[f"departure_stronge_{name}"][i])), "")
                   for name in ("median", "p90")))
                for i in overall}
    assert shown == expected
    assert {int(stats["n"][i]) for i in overall} == {SAMPLES}


def test_the_section_says_what_was_surveyed_and_what_was_not(surveyed):
    out, written = surveyed
    section = section_of(written["html"].read_text(encoding="utf-8"))
    text = html.unescape(re.sub(r"<[^>]+>", "", section))
    assert f"{SAMPLES} random impacts from each of the 2 populations" in text
    assert "spinning-disk" in text and "disk-rod" in text and "seed 3" in text
    assert f"{MISSING} not installed (engine '{MISSING}' is not installed (pretended " \
        "missing here)" in text
    assert "A quick look." in text and "impact-harness survey" in text
    assert "href='survey/summary.md'" in section and "href='survey/runs.parquet'" in section
    assert f"Not installed: {MISSING}" in (out / "survey" / "summary.md").read_text("utf-8")


def test_every_figure_it_shows_exists(surveyed):
    out, written = surveyed
    images = parse(section_of(written["html"].read_text(encoding="utf-8"))).images
    assert sorted(Path(src).name for src in images) == ["survey-cdf-pymunk.png",
                                                        "survey-map-pymunk.png"]
    for src in images:
        assert (out / src).is_file() and (out / src).with_suffix(".svg").is_file()
        assert out / src in written["figures"]


def test_a_warm_report_draws_no_survey_figure_and_a_changed_survey_redraws(
        surveyed, results_path, tmp_path):
    out, _ = surveyed
    copy = tmp_path / "report"
    shutil.copytree(out, copy)
    figures = sorted((copy / "figures").glob("survey-*"))
    assert len(figures) == 4  # map and CDF, PNG and SVG
    before = {path: path.stat().st_mtime_ns for path in figures}
    report.write_report(read_results(results_path), copy, workers=1, scenario_figures="none")
    assert {path: path.stat().st_mtime_ns for path in figures} == before
    # other runs: every survey figure is drawn again (its digest is the runs table's)
    runs = read_columns(copy / "survey" / "runs.parquet")
    runs["departure_poisson"] = runs["departure_poisson"] * 2.0
    from harness.survey.outputs import write_parquet

    write_parquet(runs, copy / "survey" / "runs.parquet")
    report.write_report(read_results(results_path), copy, workers=1, scenario_figures="none")
    assert all(path.stat().st_mtime_ns != before[path] for path in figures)


def test_no_survey_no_section_and_its_figures_go(surveyed, results_path, tmp_path):
    out, _ = surveyed
    copy = tmp_path / "report"
    shutil.copytree(out, copy)
    shutil.rmtree(copy / "survey")
    written = report.write_report(read_results(results_path), copy, workers=1,
                                  scenario_figures="none")
    page = written["html"].read_text(encoding="utf-8")
    assert "id='survey'" not in page and "#survey" not in page
    assert not list((copy / "figures").glob("survey-*"))  # the report wrote them: removed


def test_a_survey_without_engine_runs_has_a_section_without_table(tmp_path):
    """The section itself (the page places it, test_the_table_is_the_surveys_statistics)."""
    survey = survey_cli.run_survey(resolve_populations(["spinning-disk"]), 2, 0, [],
                                   ["defaults"], workers=1, echo=lambda _: None)
    survey_cli.write_survey(survey, tmp_path / "survey",
                            {"samples": 2, "seed": 0, "engines": [], "presets": ["defaults"]},
                            figures=False)
    section = survey_section(tmp_path / "survey", {})
    assert "No engine ran in this survey" in section and "<table" not in section
    assert "not selected" in section  # every engine, none asked for


def test_the_quick_survey_is_kept_while_its_inputs_are_unchanged(tmp_path, monkeypatch):
    monkeypatch.setattr(suite, "SURVEY_SAMPLES", 2)
    args = argparse.Namespace(engines="pymunk", preset="accurate")
    out = tmp_path / "survey"
    summary, surveyed = suite.quick_survey(args, out)
    assert surveyed and summary.is_file()
    tables = {path.name: path.read_bytes() for path in out.glob("*.parquet")}
    assert suite.quick_survey(args, out)[1] is False  # same inputs: kept
    assert {path.name: path.read_bytes() for path in out.glob("*.parquet")} == tables
    _nudge_floats(out / "runs.parquet")  # results a last bit apart (another CPU): still kept
    assert (out / "runs.parquet").read_bytes() != tables["runs.parquet"]
    assert suite.quick_survey(args, out)[1] is False
    monkeypatch.setattr(suite, "SURVEY_SAMPLES", 3)  # other inputs: surveyed again
    assert suite.quick_survey(args, out)[1] is True
    assert len(read_columns(out / "runs.parquet")["sample"]) == 3 * len(resolve_populations())
    (out / "runs.parquet").unlink()  # a table missing: surveyed again
    assert suite.quick_survey(args, out)[1] is True and (out / "runs.parquet").is_file()
    args.engines = "pymunk,box2d"  # other engines: surveyed again
    assert suite.quick_survey(args, out)[1] is True


def _nudge_floats(path: Path) -> None:
    """Every float of the parquet table at ``path`` one unit in the last place up."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    table = pq.read_table(path)
    for index, field in enumerate(table.schema):
        if pa.types.is_float64(field.type):
            values = table.column(index).to_numpy(zero_copy_only=False)
            table = table.set_column(index, field, pa.array(np.nextafter(values, np.inf)))
    pq.write_table(table, path)


def test_the_quick_surveys_digest_is_the_same_under_other_kernels():
    """Of inputs and code only: a process with another OpenBLAS kernel and numpy's SIMD
    dispatch off (tests/other_kernels.py) works out the same digest."""
    import importlib.util
    import subprocess
    import sys

    spec = importlib.util.spec_from_file_location(
        "other_kernels", Path(__file__).parent.parent / "other_kernels.py")
    other_kernels = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(other_kernels)
    environment, _ = other_kernels.kernel_environment()
    script = ("from harness import suite\n"
              "from harness.survey.population import resolve_populations\n"
              "print(suite.survey_inputs(resolve_populations([]), ['pymunk'], ['accurate']))")
    there = subprocess.run([sys.executable, "-c", script], env=environment, check=True,
                           capture_output=True, text=True).stdout.split()[-1]
    assert there == suite.survey_inputs(resolve_populations([]), ["pymunk"], ["accurate"])


def test_the_quick_surveys_digest_follows_its_files_versions_and_code(tmp_path, monkeypatch):
    from harness.survey.population import load_population, population_files

    shipped = population_files()[0]
    copy = tmp_path / shipped.name
    copy.write_text(shipped.read_text(encoding="utf-8"), encoding="utf-8")
    engines, presets = ["pymunk"], ["accurate"]
    before = suite.survey_inputs([load_population(copy)], engines, presets)
    assert suite.survey_inputs([load_population(copy)], engines, presets) == before
    copy.write_text(shipped.read_text(encoding="utf-8") + "\n# edited\n", encoding="utf-8")
    assert suite.survey_inputs([load_population(copy)], engines, presets) != before
    copy.write_text(shipped.read_text(encoding="utf-8"), encoding="utf-8")
    versions = suite.package_versions  # harness.run.provenance's, as the suite reads it
    monkeypatch.setattr(suite, "package_versions",
                        lambda names: {**versions(names), "pymunk": "0.0-other"})
    assert suite.survey_inputs([load_population(copy)], engines, presets) != before
    monkeypatch.undo()
    monkeypatch.setattr(suite, "code_version_of", lambda sources: "other code")
    assert suite.survey_inputs([load_population(copy)], engines, presets) != before


def test_a_settings_file_that_is_not_an_object_reruns_the_survey(tmp_path, monkeypatch):
    monkeypatch.setattr(suite, "SURVEY_SAMPLES", 2)
    args = argparse.Namespace(engines="pymunk", preset="accurate")
    out = tmp_path / "survey"
    suite.quick_survey(args, out)
    (out / survey_cli.SETTINGS_FILE).write_text("[1]", encoding="utf-8")
    assert suite.quick_survey(args, out)[1] is True  # not a crash: surveyed again


def test_a_survey_without_engines_removes_an_earlier_surveys_tables(tmp_path):
    out = tmp_path / "survey"
    for engines in (["pymunk"], []):
        survey = survey_cli.run_survey(resolve_populations(["spinning-disk"]), 2, 0, engines,
                                       ["accurate"], workers=1, echo=lambda _: None)
        survey_cli.write_survey(survey, out, {"samples": 2, "seed": 0, "engines": engines,
                                              "presets": ["accurate"]}, figures=False)
        assert (out / "statistics.parquet").exists() == bool(engines)
    assert "<table" not in survey_section(out, {})
