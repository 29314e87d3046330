"""The report's reading of a results file (harness/report/reading.py): what it takes from
the file's lines is what the records give, the records are read only when asked for, and a
report from it is the report from the records."""

from __future__ import annotations

import json
import re
import shutil
from pathlib import Path

import pytest

from harness import report
from harness.report import reading
from harness.report.figure_cache import scenario_digests
from harness.report.reading import (
    LazyResults,
    read_for_report,
    record_scenarios,
    scenarios_digest,
    source_presets,
)
from harness.report.views import engine_labels
from harness.run.records import (
    RECORDS_END,
    RECORDS_START,
    Record,
    Results,
    read_results,
    write_results,
)

ROOT = Path(__file__).resolve().parents[2]
LIBRARY = ROOT / "reports" / "results.json"  # the shipped library's results, read only
needs_library = pytest.mark.skipif(not LIBRARY.is_file(), reason="no reports/results.json")


@pytest.fixture(scope="module")
def written(tmp_path_factory) -> Path:
    """The library's results written again, as `run` writes them."""
    library = read_results(LIBRARY)
    path = tmp_path_factory.mktemp("results") / "results.json"
    return write_results(path, library.records, library.provenance, library.scenarios)


def _same_reading(lazy: LazyResults, full: Results) -> None:
    digests = scenario_digests(full)
    assert lazy.scenario_digests() == digests
    kept: dict[str, str] = {}
    assert lazy.scenario_digests(lambda key, make: kept.setdefault(key, make())) == digests
    assert len(kept) == len(digests)  # one for each scenario's exact lines
    assert lazy.scenario_digests(lambda key, make: kept[key]) == digests
    assert lazy.scenario_names() == full.scenario_names()
    assert record_scenarios(lazy) == record_scenarios(full)
    assert source_presets(lazy) == source_presets(full)
    assert lazy.provenance == full.provenance and lazy.scenarios == full.scenarios


@needs_library
def test_the_lines_give_what_the_records_give_and_the_records_wait(written):
    lazy = read_for_report(written)
    assert isinstance(lazy, LazyResults)
    full = read_results(written)
    _same_reading(lazy, full)
    assert engine_labels(lazy) == engine_labels(full)
    assert not lazy.loaded  # nothing above read a record
    assert lazy.records == full.records and lazy.loaded
    assert lazy.for_scenario(full.scenario_names()[0]) == full.for_scenario(
        full.scenario_names()[0])


def _record(scenario: str, source: str = "pymunk", preset: str | None = "defaults",
            label: str = "p") -> Record:
    return Record(scenario=scenario, point={"index": 0, "label": label}, source=source,
                  preset=preset, u_after=[1.0, 2.0, 3.0], departure={"poisson": 0.1},
                  wall_time_s=0.25, diagnostics={"engine_wall_time_s": 0.5})


@pytest.mark.parametrize("label", ["p", '"source":"x"', "back\\slash"])
def test_names_interleaved_scenarios_and_analytic_records(tmp_path, label):
    records = [_record("a.name"), _record("b_name", label=label),
               _record("a.name", source="analytic", preset=None),
               _record("plain", source="box2d", preset="accurate"),
               _record("b_name", source="mujoco"), _record("plain", source="pybullet")]
    path = write_results(tmp_path / "r.json", records, {}, {"plain": {"tags": ["t"]}})
    lazy = read_for_report(path)
    assert isinstance(lazy, LazyResults)
    _same_reading(lazy, read_results(path))
    assert source_presets(lazy) == {("pymunk", "defaults"), ("box2d", "accurate"),
                                    ("mujoco", "defaults"), ("pybullet", "defaults")}
    assert not lazy.loaded


def test_lines_the_fast_reading_cannot_tell_are_read_in_full(tmp_path):
    # A point label with braces: the file is read as read_results reads it (the same
    # records), not guessed at.
    records = [_record("a", label="{braces}"), _record("b", source="box2d", preset="accurate")]
    path = write_results(tmp_path / "r.json", records, {}, {})
    results = read_for_report(path)
    assert not isinstance(results, LazyResults)
    assert results.records == read_results(path).records


def test_plain_lines_are_read_in_one_pass(tmp_path):
    records = [_record("a"), _record("b", source="analytic", preset=None), _record("a"),
               _record("c", source="box2d", preset="accurate")]
    data = write_results(tmp_path / "r.json", records, {}, {}).read_bytes()
    begin = data.index(RECORDS_START.encode()) + len(RECORDS_START)
    end = len(data) - len(RECORDS_END)
    found = reading._lines(data, begin, end, 4)
    assert found is not None
    assert found.pairs == {("pymunk", "defaults"), ("analytic", None), ("box2d", "accurate")}
    assert reading._lines(data, begin, end, 3) is None  # not the lines' count
    lines = data[begin:end].split(b",\n")
    starts = [begin + sum(len(line) + 2 for line in lines[:index]) for index in range(4)]
    assert found.names == ["a", "b", "a", "c"]
    assert found.segments["a"] == [(begin, begin + len(lines[0])),
                                   (starts[2], starts[2] + len(lines[2]))]
    assert found.segments["c"] == [(starts[3], end)]


def test_a_file_laid_out_otherwise_is_read_in_full(tmp_path):
    path = write_results(tmp_path / "r.json", [_record("a"), _record("b")], {}, {})
    assert isinstance(read_for_report(path), LazyResults)
    document = json.loads(path.read_text(encoding="utf-8"))
    path.write_text(json.dumps(document, indent=2), encoding="utf-8")
    results = read_for_report(path)
    assert isinstance(results, Results) and results.scenario_names() == ["a", "b"]


def test_a_record_without_its_speeds_is_refused_before_the_report(tmp_path):
    path = write_results(tmp_path / "r.json", [_record("a"), _record("b")], {}, {})
    text = path.read_text(encoding="utf-8")
    path.write_text(text.replace('"u_after":[1.0,2.0,3.0],', "", 1), encoding="utf-8")
    with pytest.raises(ValueError, match="record 0: no u_after"):
        read_for_report(path)


def test_a_file_that_is_not_results_says_so_as_before(tmp_path):
    path = tmp_path / "r.json"
    path.write_text('{"format": "something else"}\n', encoding="utf-8")
    with pytest.raises(ValueError, match="not an impact-harness results file"):
        read_for_report(path)
    with pytest.raises(FileNotFoundError):
        read_for_report(tmp_path / "absent.json")


def test_the_scenarios_digest_follows_the_scenarios(tmp_path):
    first = write_results(tmp_path / "a.json", [_record("a")], {"x": 1}, {"a": {"tags": ["t"]}})
    again = write_results(tmp_path / "b.json", [_record("a")], {"x": 2}, {"a": {"tags": ["t"]}})
    other = write_results(tmp_path / "c.json", [_record("a")], {"x": 1}, {"a": {"tags": ["u"]}})
    digests = [scenarios_digest(read_for_report(path)) for path in (first, again, other)]
    assert digests[0] == digests[1] != digests[2]  # the provenance is not the scenarios
    assert scenarios_digest(read_results(first)) == scenarios_digest(read_results(again))


def _outputs(out: Path) -> tuple[str, str]:
    page = (out / "index.html").read_text("utf-8")
    return re.sub(r"Report generated [^<]*", "", page), (out / "summary.md").read_text("utf-8")


@needs_library
@pytest.mark.parametrize("many", [False, True])
def test_a_report_from_the_lines_is_the_report_from_the_records(written, tmp_path,
                                                                monkeypatch, many):
    if many:  # the aggregated page of many scenarios
        monkeypatch.setattr(report, "MANY_SCENARIOS", 1)
    options = {"workers": 1, "scenario_figures": "none", "svg": "headline"}
    out = tmp_path / "full"
    # The shipped report's figures, of these very records: those still current for the code
    # are not drawn again (what is compared here is the page and the tables, and both
    # reports share the figures).
    if (LIBRARY.parent / "figures").is_dir():
        shutil.copytree(LIBRARY.parent / "figures", out / "figures")
    report.write_report(read_results(written), out, **options)
    expected = _outputs(out)
    # every piece computed again from the lazy results (which then read the records)
    fresh = tmp_path / "fresh"
    shutil.copytree(out / "figures", fresh / "figures")
    cold = read_for_report(written)
    report.write_report(cold, fresh, **options)
    assert _outputs(fresh) == expected and cold.loaded
    # warm: every piece from the cache, no record read
    warm = read_for_report(written)
    report.write_report(warm, fresh, **options)
    assert _outputs(fresh) == expected and not warm.loaded
