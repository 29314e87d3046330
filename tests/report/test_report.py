"""Report generation: the files, every image the HTML references, no external assets."""

from __future__ import annotations

import re
from html.parser import HTMLParser

import pytest

from harness import report
from harness.report import html, views
from harness.run import runner
from harness.run.records import read_results, write_results
from harness.scenarios import load_scenarios


class Assets(HTMLParser):
    def __init__(self):
        super().__init__()
        self.images, self.links, self.scripts, self.ids = [], [], [], set()

    def handle_starttag(self, tag, attrs):
        attrs = dict(attrs)
        if "id" in attrs:
            self.ids.add(attrs["id"])
        if tag == "img":
            self.images.append(attrs["src"])
        elif tag == "a":
            self.links.append(attrs.get("href", ""))
        elif tag in ("script", "link"):
            self.scripts.append(tag)


@pytest.fixture(scope="module")
def quick_report(tmp_path_factory):
    out = tmp_path_factory.mktemp("report")
    # the quick set plus one sweep, so every kind of figure is drawn
    scenarios = load_scenarios(tags="quick") + load_scenarios(tags="sweep")[:1]
    outcome = runner.run(scenarios, cache=None, workers=1, log=None)
    path = write_results(out / "results.json", outcome.records, outcome.provenance,
                         outcome.scenarios)
    (out / "paper-table3.md").write_text(
        "# Table 3\n\nText with `code`.\n\n![figure](paper-table3.png)\n\n"
        "| cell | printed |\n|---|---:|\n| Δu1 | -0.209 |\n")
    (out / "paper-table3.png").write_bytes(b"\x89PNG\r\n\x1a\n")
    results = read_results(path)
    written = report.write_report(results, out)
    return out, results, written


def test_report_writes_the_files(quick_report):
    out, results, written = quick_report
    assert written["html"] == out / "index.html" and written["html"].stat().st_size > 10_000
    assert written["summary"] == out / "summary.md"
    for path in written["figures"]:
        assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    names = {p.name for p in written["figures"]}
    assert {"heatmap.png", "split.png", "impulse-legend.png"} <= names
    assert any(n.startswith("impulse-") for n in names - {"impulse-legend.png"})
    assert any(n.startswith("sweep-") for n in names)


def test_every_image_the_html_references_exists(quick_report):
    out, results, _ = quick_report
    parser = Assets()
    parser.feed((out / "index.html").read_text(encoding="utf-8"))
    assert len(parser.images) >= 5
    for src in parser.images:
        assert not re.match(r"^[a-z]+://", src), f"external asset {src}"
        assert (out / src).is_file(), f"missing {src}"
    assert parser.scripts == []  # self-contained: no scripts, no stylesheets to fetch
    for href in parser.links:
        if href.startswith("#"):
            assert href[1:] in parser.ids, f"broken anchor {href}"


def test_first_screen_and_contents(quick_report):
    out, results, _ = quick_report
    page = (out / "index.html").read_text(encoding="utf-8")
    # title, what this is, then the headline heat map before any detail
    assert page.index("<h1>") < page.index('class="lead"') < page.index("heatmap.png") \
        < page.index("id='split'") < page.index("id='scenarios'")
    for name in results.scenario_names():
        assert f'id="{views.slug(name)}"' in page
    assert "Table 3" in page and "<td>-0.209</td>" in page  # the paper's table embedded
    assert "Versions and settings" in page and "pybullet" in page


def test_summary_has_the_headline_tables(quick_report):
    out, results, _ = quick_report
    summary = (out / "summary.md").read_text(encoding="utf-8")
    assert "## Departure from Poisson" in summary and "## Departure from Stronge" in summary
    assert "| rod-45-slip-reversal |" in summary and "pymunk.accurate" in summary
    assert "## Gates" in summary


def test_a_rerun_with_the_same_results_redraws_nothing(quick_report):
    out, results, written = quick_report
    before = {p.name: p.stat().st_mtime_ns for p in written["figures"]}
    again = report.write_report(results, out)
    assert {p.name: p.stat().st_mtime_ns for p in again["figures"]} == before


def test_formatting():
    assert views.fmt_departure(0.2073) == "20.7%"
    assert views.fmt_departure(0.0) == "0"
    assert views.fmt_departure(3e-14) == "3e-12%"
    assert views.fmt_departure(float("nan")) == "n/a"
    page = html.markdown_to_html("## Head\n\n| a | b |\n|---|---:|\n| 1 | `x` |\n")
    assert "<h3>Head</h3>" in page and "<code>x</code>" in page and "<td>1</td>" not in page
