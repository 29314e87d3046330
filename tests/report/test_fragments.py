"""The report's per-scenario pieces kept between reports (harness/report/fragments.py): a
piece read back is the piece computed, and a piece is computed again when, and only when,
what it reads changes."""

from __future__ import annotations

import copy
import json
import math
import re
from pathlib import Path

import pytest

from harness import report
from harness.report import fragments
from harness.report.html import write_html
from harness.report.summary import write_summary
from harness.report.views import (
    HEADLINE_LAWS,
    departure_cell,
    departure_grid,
    engine_labels,
    engine_scenarios,
    label_records,
    split_rows,
)
from harness.run.records import Results, read_results

ROOT = Path(__file__).resolve().parents[2]
LIBRARY = ROOT / "reports" / "results.json"  # the shipped library's results, read only
pytestmark = pytest.mark.skipif(not LIBRARY.is_file(), reason="no reports/results.json")


@pytest.fixture(scope="module")
def library() -> Results:
    return read_results(LIBRARY)


def _figures(results: Results, many: bool) -> dict:
    """The report's figure slots with nothing drawn (many: the page folded per family)."""
    names = results.scenario_names()
    return {"impulse": {}, "sweep": {}, "svg": set(), "many": many,
            "groups": report.scenario_groups(results, names) if many else {},
            "scenario_figures": "none" if many else "all"}


def _json(value) -> str:
    """Views compared as JSON: their NaN (a cell without a value) is never equal to itself."""
    return json.dumps(value, sort_keys=True)


def _page(results: Results, out: Path, prepared, many: bool) -> tuple[str, str]:
    """index.html (without the time it was generated) and summary.md."""
    out.mkdir(exist_ok=True)
    page = write_html(results, out, _figures(results, many), {}, prepared).read_text("utf-8")
    summary = write_summary(results, out, prepared).read_text("utf-8")
    return re.sub(r"Report generated [^<]*", "", page), summary


@pytest.mark.parametrize("many", [False, True])
def test_a_page_from_the_cache_is_the_page_computed_afresh(library, tmp_path, many):
    fresh = _page(library, tmp_path / "fresh", fragments.prepare(library), many)
    out = tmp_path / "cached"
    out.mkdir()
    first = fragments.prepare(library, out)
    assert first.cache.computed == len(library.scenario_names())  # every view computed
    assert _page(library, out, first, many) == fresh
    first.cache.save()
    second = fragments.prepare(library, out)
    assert second.cache.computed == 0 and _json(second.views) == _json(first.views)
    assert _page(library, out, second, many) == fresh
    assert second.cache.computed == 0  # sections and tables read back too


def test_a_changed_record_recomputes_its_scenarios_pieces_only(library, tmp_path):
    out = tmp_path / "report"
    first = fragments.prepare(library, out)
    _page(library, out, first, many=True)
    first.cache.save()
    # Its file edited (what its digest follows, not its floats' bits: tests/report/
    # test_figure_digests.py), and a departure with it.
    changed = Results(copy.deepcopy(library.records), library.provenance,
                      copy.deepcopy(library.scenarios))
    name = engine_scenarios(changed)[0]
    changed.scenarios[name]["definition"] = "an edited file"
    run = next(r for r in changed.for_scenario(name) if r.source != "analytic" and r.ok)
    run.departure["poisson"] = 0.4321
    second = fragments.prepare(changed, out)
    assert second.cache.computed == 1  # its view
    assert "43.2%" in json.dumps(second.views[name])
    _page(changed, out, second, many=True)
    # and its section, its family's table and the six pieces made of every record (the
    # engines' notes, the split table, the page's counts, the several-contacts section,
    # summary.md's several-contacts tables and its runs)
    assert second.cache.computed == 9
    assert _page(changed, tmp_path / "fresh", fragments.prepare(changed), many=True) == \
        _page(changed, out, second, many=True)


def test_a_broken_or_foreign_cache_file_is_computed_afresh(library, tmp_path):
    cache_file = tmp_path / fragments.CACHE_FILE
    count = len(library.scenario_names())
    for text in ["not json\n", '{"context": "another code", "entries": {}, "texts": {}}\n',
                 json.dumps({"context": fragments.cache_context(engine_labels(library)),
                             "entries": {}, "texts": {"x": "no span"}}) + "\n"]:
        cache_file.write_text(text, encoding="utf-8")
        prepared = fragments.prepare(library, tmp_path)
        assert prepared.cache.computed == count
        assert _json(prepared.views) == _json(fragments.prepare(library).views)


def test_the_views_are_the_headline_cells_and_the_split_rows(library):
    """scenario_view and split_view against the functions the figures use."""
    prepared = fragments.prepare(library)
    labels = engine_labels(library)
    assert labels == library.engine_labels()
    names = library.scenario_names()
    assert [n for n in names if prepared.views[n]["engine"]] == engine_scenarios(library)
    for law in HEADLINE_LAWS:
        _, values, flagged, skipped = departure_grid(library, law, labels, names)
        for i, name in enumerate(names):
            grouped = label_records(library.for_scenario(name))
            for j, label in enumerate(labels):
                value, is_flagged, is_skipped, text = prepared.views[name][law][j]
                assert (math.isnan(value) and math.isnan(values[i, j])) or value == values[i, j]
                assert (is_flagged, is_skipped) == (flagged[i, j], skipped[i, j])
                assert text == departure_cell(grouped.get(label, []), law)
    rows = split_rows(library)
    assert rows  # the library has engine runs beside newton-lcp
    scenarios, row_labels = fragments.split_order(library)
    assert scenarios == list(dict.fromkeys(row["scenario"] for row in rows))
    assert row_labels == list(dict.fromkeys(row["label"] for row in rows))
    for name in scenarios:
        split = prepared.views[name]["split"]
        mine = [row for row in rows if row["scenario"] == name]
        parts = [row["law_part"] for row in mine if math.isfinite(row["law_part"])]
        assert split["law_part"] == (max(parts) if parts else None)
        for label in dict.fromkeys(row["label"] for row in mine):
            solves = [row["solve_part"] for row in mine
                      if row["label"] == label and math.isfinite(row["solve_part"])]
            assert split["solve"][label] == (max(solves) if solves else None)
    without = [n for n in names if n not in scenarios]
    assert all(prepared.views[n]["split"] == {} for n in without)
