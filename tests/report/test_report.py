"""Report generation: the files, every image the HTML references, no external assets."""

from __future__ import annotations

import json
import re
import shutil
from html.parser import HTMLParser
from pathlib import Path

import pytest

from harness import report
from harness.report import html, markup, overview, scenario_sections, table3, views
from harness.run import references, runner
from harness.run.records import ANALYTIC, Record, Results, read_results, write_results
from harness.scenarios import load_scenarios

LIBRARY = Path(__file__).resolve().parents[2] / "scenarios"
OVERRIDE = "\n[engine_settings.pymunk]\niterations = 1\n"


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
        elif tag in ("script", "link"):  # a script's source, or where a link would load from
            self.scripts.append((tag, attrs.get("src") or attrs.get("href")))


@pytest.fixture(scope="module")
def quick_report(tmp_path_factory):
    out = tmp_path_factory.mktemp("report")
    # the quick set plus one sweep, so every kind of figure is drawn, and one scenario that
    # overrides an engine setting (pymunk with a single iteration)
    extra = tmp_path_factory.mktemp("scenarios")
    text = (LIBRARY / "disk-oblique.toml").read_text(encoding="utf-8")
    text = text.replace('name = "disk-oblique"', 'name = "disk-oblique-one-iteration"')
    (extra / "disk-oblique-one-iteration.toml").write_text(text + OVERRIDE, encoding="utf-8")
    scenarios = (load_scenarios(tags="quick") + load_scenarios(tags="sweep")[:1]
                 + load_scenarios(extra))
    outcome = runner.run(scenarios, cache=None, workers=1, log=None)
    path = write_results(out / "results.json", outcome.records, outcome.provenance,
                         outcome.scenarios)
    # inputs of the bench and stress pages, as `impact-harness bench` / `stress` write them
    sources = tmp_path_factory.mktemp("inputs")
    (sources / "bench").mkdir()
    # made by the results' code: linked (older pages are named, not linked)
    made = {"python": "3.11", "code_version": outcome.provenance["code_version"]}
    (sources / "bench" / "bench.json").write_text(json.dumps(
        {"provenance": made, "solver": {"laws": {
            "poisson": {"batch_s": 0.05, "problems_per_s": 2.0e7},
            "stronge": {"batch_s": 0.06, "problems_per_s": 1.7e7}}}}))
    (sources / "bench" / "solver-throughput.png").write_bytes(b"\x89PNG\r\n\x1a\n")
    (sources / "stress").mkdir()
    (sources / "stress" / "stress.md").write_text(
        "# Stress report\n\n## Solver\n\n| check | count |\n|---|---|\n| silent non finite | 0 |\n")
    (sources / "stress" / "engine-grid.png").write_bytes(b"\x89PNG\r\n\x1a\n")
    (sources / "stress" / "stress.json").write_text(json.dumps({"provenance": made}))
    results = read_results(path)
    written = report.write_report(results, out, sources=[sources])
    return out, results, written


def test_report_writes_the_files(quick_report):
    out, _results, written = quick_report
    assert written["html"] == out / "index.html" and written["html"].stat().st_size > 10_000
    assert written["summary"] == out / "summary.md"
    for path in written["figures"]:
        assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    names = {p.name for p in written["figures"]}
    assert {"heatmap.png", "split.png"} <= names
    assert any(n.startswith("impulse-") for n in names)
    assert "impulse-legend.png" not in names  # each impulse diagram carries its own key
    assert any(n.startswith("sweep-") for n in names)


def test_every_figure_is_also_svg(quick_report):
    out, _results, written = quick_report
    for path in written["figures"]:
        svg = path.with_suffix(".svg")
        assert svg.is_file() and svg.read_text(encoding="utf-8").lstrip().startswith("<?xml")
    assert (out / "figures" / "paper-table3.png").is_file()


def local_targets(page: Path) -> tuple[list[str], Assets]:
    parser = Assets()
    parser.feed(page.read_text(encoding="utf-8"))
    return [*parser.images, *(h for h in parser.links if not h.startswith("#"))], parser


def test_every_page_is_self_contained(quick_report):
    """No external asset, one inline script (printing opens the folded sections), every image
    and link resolves inside the report."""
    out, _results, _ = quick_report
    pages = [out / "index.html", out / "bench.html", out / "stress.html"]
    for page in pages:
        targets, parser = local_targets(page)
        assert parser.scripts == [("script", None)], page.name
        for target in targets:
            assert not re.match(r"^[a-z]+://", target), f"external asset {target}"
            assert (out / target.split("#")[0]).is_file(), f"{page.name}: missing {target}"
        for href in parser.links:
            if href.startswith("#"):
                assert href[1:] in parser.ids, f"{page.name}: broken anchor {href}"
    targets, parser = local_targets(out / "index.html")
    assert len(parser.images) >= 5
    assert "bench.html" in targets and "stress.html" in targets


def test_the_report_directory_can_move(quick_report, tmp_path):
    """`report --out DIR` is self-contained: a copy elsewhere has no broken link."""
    out, _results, _ = quick_report
    moved = tmp_path / "moved"
    shutil.copytree(out, moved)
    for page in moved.glob("*.html"):
        for target in local_targets(page)[0]:
            assert (moved / target.split("#")[0]).is_file(), f"{page.name}: {target}"


def test_first_screen_and_contents(quick_report):
    out, results, _ = quick_report
    page = (out / "index.html").read_text(encoding="utf-8")
    # title, what this is, the contents, then the headline heat map before any detail
    assert page.index("<h1>") < page.index('class="lead"') < page.index("class='contents'") \
        < page.index("heatmap.png") < page.index("id='why'") < page.index("id='split'") \
        < page.index("id='scenarios'")
    for name in results.scenario_names():
        assert f"id='{views.slug(name)}'" in page
        assert f"href='#{views.slug(name)}'" in page
    assert "Versions and settings" in page and "pybullet" in page


def test_table3_is_html_from_the_structured_rows(quick_report):
    out, _, _ = quick_report
    page = (out / "index.html").read_text(encoding="utf-8")
    section = page[page.index("id='table3'"):page.index("id='versions'")]
    assert "|---" not in section and "**" not in section  # no Markdown left
    printed = table3.load_table3()
    assert printed and all(f"<td>{row['du1']}</td>" in section for row in printed)
    rows = table3.reproduce_table3()
    for sec in table3.table3_sections(rows):
        assert views.escape_html(sec.title) in section
    assert section.count("class=\"flag\"") == sum(
        not c.reproduced for r in rows for c in r["cells"])


def test_wide_tables_scroll_inside_the_page(quick_report):
    out, _, _ = quick_report
    page = (out / "index.html").read_text(encoding="utf-8")
    assert ".scroll{overflow-x:auto" in page
    assert page.count("<table") == page.count('<div class="scroll"><table')


def test_why_notes_and_overrides_are_shown(quick_report):
    out, results, _ = quick_report
    page = (out / "index.html").read_text(encoding="utf-8")
    why = page[page.index("id='why'"):page.index("id='split'")]
    for engine in {label.split(".")[0] for label in results.engine_labels()}:
        assert f"<dt>{engine}</dt>" in why
    # every note an engine made appears in its scenario's section, beside the run's numbers
    for record in results.records:
        for note in views.run_notes(record):
            section = page[page.index(f"id='{views.slug(record.scenario)}'"):]
            next_one = section.find("<details class='fold scenario'>")
            section = section[:next_one] if next_one >= 0 else section
            assert views.escape_html(note) in section, (record.scenario, note)
    # the overridden scenario: its labels and its section say so, the others do not
    overridden = page[page.index("id='disk-oblique-one-iteration'"):]
    assert "pymunk.defaults</b><br><span class='override'>[iterations=1]" in overridden
    assert "Engine settings overridden by this scenario" in overridden
    plain = page[page.index("id='disk-oblique'"):page.index("id='disk-oblique-one-iteration'")]
    assert "[iterations=1]" not in plain
    summary = (out / "summary.md").read_text(encoding="utf-8")
    line = next(row for row in summary.splitlines()
                if row.startswith("| disk-oblique-one-iteration |"))
    assert line.count("*") >= 1


def test_summary_has_the_headline_tables(quick_report):
    out, _results, _ = quick_report
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
    assert views.fmt_departure(0.0) == "0%"
    assert views.fmt_departure(3e-14) == "3e-12%"
    assert views.fmt_departure(float("nan")) == "n/a"
    page = markup.markdown_to_html("## Head\n\n| a | b |\n|---|---:|\n| 1 | `x` |\n")
    assert "<h3>Head</h3>" in page and "<code>x</code>" in page and "<td>1</td>" not in page


def test_sweep_axes_name_the_quantity_and_its_unit():
    assert views.parameter_name("friction") == "friction μ"
    assert views.parameter_name("body.disk.velocity.x") == "disk velocity x [m/s]"
    assert views.parameter_name("body.rod.angle_deg") == "rod angle [°]"
    assert views.parameter_name("parameters.delta") == "steering angle δ [rad]"


def sweep_run(index: int, departure: float, status: str = "ok", overrides=None) -> Record:
    return Record(scenario="sweep", point={"index": index, "label": f"p={index}",
                                           "value": float(index)},
                  source="pybullet", preset="defaults", status=status,
                  departure={"poisson": departure},
                  diagnostics={"notes": [], "settings_overrides": overrides or {}})


def test_flagged_runs_are_counted_never_in_the_value():
    # the largest single-impact departure (3%) is the value; the flagged run is counted
    runs = [sweep_run(0, 0.03), sweep_run(1, 0.01, "multi-contact"), sweep_run(2, 0.02)]
    assert views.departure_cell(runs, "poisson") == "3% (1 of 3!)"  # of the sweep's runs
    assert views.worst_departure(runs, "poisson") == (0.03, True, False)
    # a flagged run with a larger departure does not become the value
    runs[1] = sweep_run(1, 0.05, "multi-contact")
    assert views.departure_cell(runs, "poisson") == "3% (1 of 3!)"
    # every run flagged: no value at all
    assert views.departure_cell([sweep_run(0, 0.05, "multi-contact")], "poisson") \
        == "flagged (1!)"
    # overrides are marked, skipped cells say so
    assert views.departure_cell([sweep_run(0, 0.03, overrides={"iterations": 1})],
                                "poisson") == "3% *"
    assert views.departure_cell([sweep_run(0, 0.03, "skipped: no engine")], "poisson") \
        == "skipped"


def test_run_labels_carry_the_overrides():
    run = sweep_run(0, 0.03, overrides={"iterations": 1, "time_step": 0.001})
    assert views.run_label(run) == "pybullet.defaults [iterations=1, time_step=0.001]"
    assert views.run_label(sweep_run(0, 0.03)) == "pybullet.defaults"
    law = Record(scenario="s", point={"index": 0, "label": ""}, source=ANALYTIC, law="poisson")
    assert views.run_label(law) == "poisson" and views.overrides_of(law) == {}


def load_screenshot_script():
    """tests/report/screenshot.py, loaded by path (the tests are not a package)."""
    import importlib.util

    path = Path(__file__).with_name("screenshot.py")
    spec = importlib.util.spec_from_file_location("report_screenshot", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.mark.skipif(not Path("/usr/bin/chromium").exists(),
                    reason="no /usr/bin/chromium: install it (apt-get install -y chromium) to "
                           "screenshot the report")
def test_screenshots_at_1400_px_show_no_horizontal_overflow(quick_report, tmp_path):
    out, _, _ = quick_report
    script = load_screenshot_script()
    layouts = script.check_report(out, tmp_path / "shots", width=1400, height=1200)
    assert set(layouts) == {"index.html", "bench.html", "stress.html"}
    for name, layout in layouts.items():
        assert layout["clientWidth"] >= 1300, name  # the window really was 1400 px wide
        assert layout["scrollWidth"] <= layout["clientWidth"] + 1, (name, layout)
        assert layout["culprits"] == [], (name, layout["culprits"])
        shot = Path(layout["screenshot"])
        assert shot.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and shot.stat().st_size > 20_000


def test_the_overflow_check_catches_a_wide_page(tmp_path):
    """The check itself can fail: a table of unbreakable text, wider than the window, outside
    any scrolling wrapper (what an unwrapped wide table does)."""
    if not Path("/usr/bin/chromium").exists():
        pytest.skip("no /usr/bin/chromium: install it (apt-get install -y chromium)")
    script = load_screenshot_script()
    (tmp_path / "index.html").write_text(
        "<!DOCTYPE html><html><body><table><tr><td style='white-space:nowrap'>"
        + "wide " * 600 + "</td></tr></table></body></html>", encoding="utf-8")
    layout = script.check_report(tmp_path, tmp_path / "shots", height=400)["index.html"]
    assert layout["overflow"] and layout["scrollWidth"] > 2000 and layout["culprits"]


def test_flat_face_and_tilt_points_never_enter_a_single_contact_law_cell():
    # a declared flat face (reference "simultaneous") and a tilt (reference "event-driven",
    # its runs judged against the whole sequence) depart from their own references: their
    # departure from the single-contact laws is not a value, and the scenario is not a row
    flat = sweep_run(0, 0.5)
    flat.diagnostics["reference"] = {"kind": references.SIMULTANEOUS,
                                     "primary": "newton-coulomb"}
    tilt = sweep_run(1, 0.02)
    tilt.diagnostics["reference"] = {"kind": references.EVENT_DRIVEN,
                                     "primary": "event-driven/newton-lcp"}
    single = sweep_run(2, 0.01)
    single.diagnostics["reference"] = {"kind": references.SINGLE, "primary": "newton-lcp"}
    assert views.worst_departure([flat, tilt, single], "poisson") == (0.01, False, False)
    assert views.worst_record([flat, tilt], "poisson") is None
    assert views.single_contact(sweep_run(3, 0.1))  # results without references: one contact
    assert views.engine_scenarios(Results([flat, tilt])) == []
    assert views.engine_scenarios(Results([flat, tilt, single])) == ["sweep"]


#: What a Python repr looks like in a page: a dict or list literal of strings, or a bare
#: None/True/False between separators (a sentence says "not a failure", never "False").
PYTHON_REPR = re.compile(r"\{'|\['|: None[,}]|: (True|False)[,}]|np\.float64|array\(")


def test_a_flagged_runs_reasons_read_as_sentences_never_as_python():
    reason = {"name": "penetration", "value": 0.0057, "tolerance": 0.005,
              "detail": "deepest overlap 0.0057 m > 0.005 m", "attribution": None,
              "fails": True}
    remark = {"name": "energy-gain", "value": 0.11, "tolerance": None,
              "detail": "newton-lcp gains 0.1148 J on this problem", "attribution": "law",
              "fails": False}
    run = sweep_run(0, 0.03, "ok")
    run.diagnostics.update(verdict="flagged", reasons=[reason, remark])
    footnotes: dict[str, int] = {}
    cell = scenario_sections.status_cell(run, footnotes)
    notes = scenario_sections.footnotes_html(footnotes)
    assert "<sup>1</sup>" in cell and "<sup>2</sup>" in cell
    assert "penetration: deepest overlap 0.0057 m &gt; 0.005 m" in notes
    assert ("energy-gain: newton-lcp gains 0.1148 J on this problem (attributed to the law);"
            " reported, not a failure") in notes
    assert not PYTHON_REPR.search(cell + notes)
    # what the pattern catches: the page as it was before reasons were sentences
    assert PYTHON_REPR.search(scenario_sections.footnotes_html({str(reason): 1}))


def test_no_python_repr_on_any_page(quick_report):
    import html as html_module
    out = quick_report[0]
    for page in [out / "index.html", out / "summary.md", *out.glob("*.html")]:
        text = html_module.unescape(page.read_text(encoding="utf-8"))
        text = re.sub(r"<img[^>]*>|<svg.*?</svg>", "", text, flags=re.S)
        match = PYTHON_REPR.search(text)
        assert match is None, f"{page.name}: {text[max(0, match.start() - 80):match.end() + 80]}"


def test_overrides_are_labelled_by_where_they_were_set():
    # pymunk ran with --set iterations=2 and its scenario set time_step: each is named as such
    run = sweep_run(0, 0.03, overrides={"iterations": 2, "time_step": 0.001})
    run.source = "pymunk"
    command = {"pymunk": {"iterations": 2}}
    assert views.split_overrides(run, command) == ({"iterations": 2}, {"time_step": 0.001})
    text = scenario_sections.overrides_paragraph([run], command)
    assert "on the command line (<code>--set</code>): pymunk: <code>iterations=2</code>" in text
    assert "by this scenario (<code>[engine_settings]</code>): pymunk: <code>time_step=0.001" \
        in text
    # only --set: nothing is said of the scenario
    only = sweep_run(0, 0.03, overrides={"iterations": 2})
    only.source = "pymunk"
    text = scenario_sections.overrides_paragraph([only], command)
    assert "--set" in text and "by this scenario" not in text
    # the engine notes say the runs are not the preset the text describes
    results = Results(records=[only], provenance={"settings_overrides": command})
    why = overview.why_html(results)
    assert "every run with <code>--set iterations=2</code>" in why
    assert "runs with their scenario's overrides" not in why


def test_a_page_of_other_code_is_named_not_linked(tmp_path):
    """The contents link a bench or stress page only when measured by the results' code;
    an older one is named with the command that measures it again."""
    from harness.report.pages import BENCH_PAGE, STRESS_PAGE, write_pages

    sources = tmp_path / "inputs"
    (sources / "bench").mkdir(parents=True)
    (sources / "bench" / "bench.json").write_text(json.dumps(
        {"provenance": {"code_version": "old", "created_utc": "2026-11-22T18:23:00Z"}}))
    (sources / "stress").mkdir()
    (sources / "stress" / "stress.md").write_text("# Stress\n\nno numbers\n")
    (sources / "stress" / "stress.json").write_text(json.dumps(
        {"provenance": {"code_version": "new"}}))
    out = tmp_path / "out"
    out.mkdir()
    linked, stale = write_pages(out, [sources], {"code_version": "new"})
    assert linked == {STRESS_PAGE: "Stress test: the solver and the engines at extremes"}
    assert list(stale) == ["Benchmarks: speed and accuracy"]
    assert "2026-11-22T18:23:00Z" in stale["Benchmarks: speed and accuracy"]
    assert "<code>make bench</code>" in stale["Benchmarks: speed and accuracy"]
    assert (out / BENCH_PAGE).is_file()  # written, saying at its top that it is older
    assert "Older than the report" in (out / BENCH_PAGE).read_text(encoding="utf-8")
    contents = html.contents_html([], linked, ["headline", "versions"], stale=stale)
    assert f"href='{STRESS_PAGE}'" in contents and f"href='{BENCH_PAGE}'" not in contents
    assert "Benchmarks: speed and accuracy <span class='muted'>(not linked: measured" in contents


def test_a_page_measured_by_another_version_of_its_command_is_named_not_linked(tmp_path):
    """The same cached code (the solver, the engines) but another harness/stress/ (its
    outcomes, its cases) or harness/bench/: named, not linked; today's: linked. What
    `stress` records is what the report computes (`bench`'s: tests/bench/test_solver.py)."""
    from harness.report.pages import (
        BENCH_PAGE,
        STRESS_PAGE,
        command_code_version,
        write_pages,
    )
    from harness.stress import COMMAND_CODE_VERSION

    assert COMMAND_CODE_VERSION == command_code_version("stress")
    sources = tmp_path / "inputs"
    (sources / "bench").mkdir(parents=True)
    (sources / "stress").mkdir()
    (sources / "stress" / "stress.md").write_text("# Stress\n\nno numbers\n")
    for stress_code, linked_pages in (("other", {BENCH_PAGE}),
                                      (COMMAND_CODE_VERSION, {BENCH_PAGE, STRESS_PAGE})):
        (sources / "stress" / "stress.json").write_text(json.dumps({"provenance": {
            "code_version": "new", "command_code_version": stress_code}}))
        (sources / "bench" / "bench.json").write_text(json.dumps({"provenance": {
            "code_version": "new", "command_code_version": command_code_version("bench")}}))
        out = tmp_path / f"out-{stress_code[:5]}"
        out.mkdir()
        linked, stale = write_pages(out, [sources], {"code_version": "new"})
        assert set(linked) == linked_pages
        if STRESS_PAGE not in linked:
            assert "another version of harness/stress/" in stale[
                "Stress test: the solver and the engines at extremes"]
            assert "another version of <code>harness/stress/</code>" in (
                out / STRESS_PAGE).read_text(encoding="utf-8")


def test_the_contents_follow_the_page():
    parts = ["<div id='headline'>", "<div id='gates'>", "<div id='contacts'>",
             "<div id='scenarios'>", "<div id='table3'>", "<div id='survey'>",
             "<div id='versions'>"]
    sections = html.page_sections(parts)
    assert sections == ["headline", "gates", "contacts", "scenarios", "table3", "survey",
                        "versions"]
    contents = html.contents_html(["a"], {}, sections)
    order = [contents.index(f"href='#{anchor}'") for anchor in sections]
    assert order == sorted(order)


def test_a_page_says_where_its_numbers_come_from_and_when_they_are_older():
    from harness.report.pages import provenance_html

    made = {"created_utc": "2026-11-01T10:00:00Z", "git": {"commit": "a" * 40, "dirty": False},
            "machine": {"cpu_model": "AMD EPYC"}, "code_version": "c1"}
    same = provenance_html(made, {"git": {"commit": "b" * 40}, "code_version": "c1"},
                           "make bench")
    assert "Measured 2026-11-01T10:00:00Z at commit <code>aaaaaaaaaa</code> on AMD EPYC" in same
    assert "Older" not in same  # another commit, the same code: the numbers still hold
    older = provenance_html(made, {"git": {"commit": "b" * 40}, "code_version": "c2"},
                            "make bench")
    assert "<b>Older than the report</b>: measured with other code" in older
    assert "<code>make bench</code>" in older
    unknown = provenance_html({"time": "2026"}, {"code_version": "c2"}, "make stress")
    assert "commit not recorded" in unknown and "not recorded, so it may predate" in unknown


def test_only_a_report_of_library_scenarios_reproduces_table3(tmp_path):
    from harness.scenarios.schema import SCENARIO_DIR

    mine = Results(records=[], scenarios={"mine": {"path": str(tmp_path / "mine.toml")}})
    assert not views.has_library_scenarios(mine)
    library = Results(records=[], scenarios={
        "mine": {"path": str(tmp_path / "mine.toml")},
        "disk-oblique": {"path": str(SCENARIO_DIR / "disk-oblique.toml")}})
    assert views.has_library_scenarios(library)
    assert "#table3" not in html.contents_html(["mine"], {}, ["headline", "versions"])
    assert "#table3" in html.contents_html(["mine"], {}, ["headline", "table3", "versions"])


def test_bench_and_stress_figures_have_captions_that_say_what_to_read():
    from harness.report.pages import caption

    assert "Pareto front" in caption("pareto-mujoco.png") and "mujoco" in caption(
        "pareto-mujoco.png")
    assert "batch size" in caption("solver-throughput.png")
    assert caption("unknown-figure.png") == "unknown-figure.png"


class Folds(HTMLParser):
    """The page's ``<details>`` as it nests: per fold its summary's headings (``(level,
    text)``), whether its summary has a headline, whether it opens unfolded, and the ids in
    its content (outside its summary); also the headings and ids outside any fold's content,
    and ids put on a ``<details>`` or ``<summary>`` itself."""

    def __init__(self):
        super().__init__()
        self.folds, self.stack, self.loose_headings, self.loose_ids = [], [], [], set()
        self.ids_on_folds, self.contents_links, self._heading, self._in_nav = [], [], None, False

    def handle_starttag(self, tag, attrs):
        attrs = dict(attrs)
        top = self.stack[-1] if self.stack else None
        if tag == "details":
            self.stack.append({"open": "open" in attrs, "headings": [], "headline": False,
                               "ids": set(), "in_summary": False, "class": attrs.get("class")})
        elif tag == "summary" and top is not None:
            top["in_summary"] = True
        elif tag == "nav":
            self._in_nav = True
        elif tag == "a" and self._in_nav and attrs.get("href", "").startswith("#"):
            self.contents_links.append(attrs["href"][1:])
        elif tag in ("h2", "h3"):
            self._heading = [int(tag[1]), ""]
        elif tag == "span" and top is not None and top["in_summary"] \
                and attrs.get("class") == "headline":
            top["headline"] = True
        if "id" in attrs:
            if tag in ("details", "summary"):
                self.ids_on_folds.append(attrs["id"])
            elif top is not None and not top["in_summary"]:
                top["ids"].add(attrs["id"])
            else:
                self.loose_ids.add(attrs["id"])

    def handle_data(self, data):
        if self._heading is not None:
            self._heading[1] += data

    def handle_endtag(self, tag):
        if tag in ("h2", "h3") and self._heading is not None:
            top = self.stack[-1] if self.stack else None
            if top is not None and top["in_summary"]:
                top["headings"].append(tuple(self._heading))
            else:
                self.loose_headings.append(tuple(self._heading))
            self._heading = None
        elif tag == "summary" and self.stack:
            self.stack[-1]["in_summary"] = False
        elif tag == "nav":
            self._in_nav = False
        elif tag == "details" and self.stack:
            self.folds.append(self.stack.pop())


def test_every_section_is_folded_with_its_anchor_inside(quick_report):
    """Each section (h2) and each scenario (h3) is a ``<details>`` whose summary says its
    name and a headline; its anchor is inside the folded content (a link to it opens the
    fold), never on the ``<details>`` or ``<summary>``; the contents link only there. The
    overview opens unfolded, each scenario folded."""
    out, results, _ = quick_report
    parser = Folds()
    parser.feed((out / "index.html").read_text(encoding="utf-8"))
    assert parser.stack == [] and parser.ids_on_folds == []
    assert [h for h in parser.loose_headings if h[0] == 2] == []  # no section left unfolded
    sections = {fold["headings"][0][1]: fold for fold in parser.folds
                if fold["headings"] and fold["headings"][0][0] == 2}
    assert len(sections) >= 8, list(sections)
    for title, fold in sections.items():
        assert fold["headline"] and fold["ids"], title
    anchored = {anchor: fold for fold in parser.folds for anchor in fold["ids"]}
    for anchor in ("headline", "why", "split", "gates", "scenarios"):
        assert anchored[anchor]["open"], anchor  # the overview, unfolded
    for anchor in ("table3", "experiments", "versions"):
        assert not anchored[anchor]["open"], anchor  # long sections, folded
    for name in results.scenario_names():
        fold = anchored[views.slug(name)]
        assert fold["headings"] == [(3, name)] and fold["headline"] and not fold["open"]
        assert fold["class"] == "fold scenario"
    assert parser.contents_links and all(link in anchored for link in parser.contents_links)


def print_rules(page: str) -> str:
    """The page's ``@media print`` block (its braces balanced)."""
    start = page.index("@media print{") + len("@media print{")
    depth, at = 1, start
    while depth:
        depth += {"{": 1, "}": -1}.get(page[at], 0)
        at += 1
    return page[start:at - 1]


def test_printing_shows_every_fold_and_no_chrome(quick_report):
    """Printed, the page unfolds every section (a script opens the closed ``<details>``
    before printing and closes them after; the print style sheet reveals their content too),
    hides the contents, keeps figures and tables whole on a page, fits images to its width,
    and loads every image eagerly (a lazy one not yet scrolled to is missing from print)."""
    out, _, _ = quick_report
    for name in ("index.html", "bench.html", "stress.html"):
        page = (out / name).read_text(encoding="utf-8")
        rules = print_rules(page)
        assert re.search(r"nav\.contents[^{]*\{display:none", rules), name
        assert re.search(r"figure,table[^{]*\{break-inside:avoid", rules), name
        assert "details::details-content{content-visibility:visible" in rules
        assert re.search(r"img[^{]*\{[^}]*max-width:100%", rules), name
        script = re.findall(r"<script>(.*?)</script>", page, re.DOTALL)
        assert len(script) == 1, name
        opens = script[0][script[0].index("'beforeprint'"):script[0].index("'afterprint'")]
        assert "details:not([open])" in opens and "d.open = true" in opens
        assert "d.open = false" in script[0][script[0].index("'afterprint'"):]
        assert 'loading="lazy"' not in page and "loading='lazy'" not in page


@pytest.mark.skipif(not Path("/usr/bin/chromium").exists(),
                    reason="no /usr/bin/chromium: install it (apt-get install -y chromium)")
def test_in_chromium_a_link_opens_its_fold_and_printing_opens_all(quick_report):
    """In the browser: a link to a folded scenario opens its fold; ``beforeprint`` opens
    every fold and ``afterprint`` closes again those it opened."""
    out, results, _ = quick_report
    script = load_screenshot_script()
    name = views.slug(results.scenario_names()[-1])
    probe = out / ".fold-probe.html"
    check = ("<script>window.addEventListener('load', function () { setTimeout(function () {"
             "var closed = function () { return document.querySelectorAll("
             "'details:not([open])').length; };"
             f"var target = document.getElementById('{name}'), ancestors = 0, opened = 0;"
             "for (var e = target; e; e = e.parentElement) { if (e.tagName === 'DETAILS') {"
             "ancestors += 1; if (e.open) { opened += 1; } } }"
             "var before = closed(); window.dispatchEvent(new Event('beforeprint'));"
             "var printing = closed(); window.dispatchEvent(new Event('afterprint'));"
             "var out = document.createElement('pre'); out.id = 'fold-result';"
             "out.textContent = JSON.stringify({ancestors: ancestors, opened: opened,"
             "before: before, printing: printing, after: closed()});"
             "document.body.appendChild(out); }, 100); });</script>")
    page = (out / "index.html").read_text(encoding="utf-8")
    probe.write_text(page.replace("</body>", check + "</body>"), encoding="utf-8")
    try:
        done = script.chromium(["--window-size=1400,1000", "--virtual-time-budget=5000",
                                "--dump-dom", probe.resolve().as_uri() + f"#{name}"])
    finally:
        probe.unlink(missing_ok=True)
    found = re.search(r'<pre id="fold-result">(.*?)</pre>', done.stdout, re.DOTALL)
    assert found, done.stderr[-500:]
    state = json.loads(found.group(1).replace("&quot;", '"'))
    assert state["ancestors"] >= 1 and state["opened"] == state["ancestors"], state
    assert state["before"] > 0 and state["printing"] == 0, state
    assert state["after"] == state["before"], state


def test_a_set_run_is_named_in_every_output_that_shows_its_numbers(quick_report, tmp_path):
    """summary.md, the page and the heat map of a run with ``--set`` say so: shared alone,
    its tables would pass for the presets' numbers."""
    from harness.report.figures import heatmap_figure
    from harness.report.summary import write_summary

    _out, results, _ = quick_report
    provenance = {**results.provenance, "settings_overrides": {"pymunk": {"iterations": 3}}}
    set_run = Results(records=results.records, provenance=provenance,
                      scenarios=results.scenarios)
    summary = write_summary(set_run, tmp_path).read_text(encoding="utf-8")
    assert "**Not the presets as shipped**: this run set `pymunk: iterations=3`" in summary
    header = next(line for line in summary.splitlines() if line.startswith("| scenario |"))
    assert "pymunk.defaults (--set)" in header and "pybullet.defaults |" in header
    assert "paper-table3.md" not in summary  # not written in this directory
    plain = write_summary(results, tmp_path).read_text(encoding="utf-8")
    assert "Not the presets" not in plain and "(--set)" not in plain
    page = html.html_page(set_run, tmp_path, {"svg": set()})
    assert "Not the presets as shipped: this run set <code>pymunk: iterations=3</code>" in page
    import matplotlib

    matplotlib.use("Agg")
    drawn = []
    patch = pytest.MonkeyPatch()
    patch.setattr("harness.report.figures.save_png",
                  lambda figure, path, **_: drawn.append(figure))
    try:
        heatmap_figure(set_run, tmp_path / "heatmap.png")
    finally:
        patch.undo()
    texts = [t.get_text() for t in drawn[0].findobj(
        lambda artist: hasattr(artist, "get_text"))]
    assert "Not the presets as shipped: --set pymunk: iterations=3 on the command line" in texts
    assert "pymunk (--set)" in texts


def test_a_sweeps_gate_rows_name_their_points():
    gate = {"scenario": "sweep-x", "gate": "pymunk.accurate", "record": "pymunk.accurate",
            "law": "newton-lcp", "departure": 1e-16, "max_departure": 1e-6, "status": "pass"}
    gates = [{**gate, "point": "alpha=0.5"}, {**gate, "point": "alpha=1"}]
    table = overview.gates_html({"gates": gates})
    assert ">point<" in table
    assert "alpha=0.5" in table and "alpha=1" in table
    single = overview.gates_html({"gates": [{**gate, "point": ""}]})
    assert ">point<" not in single


def test_every_engine_setting_has_a_unit_and_none_reads_as_the_engines_default():
    from harness.engines import engine_class, engine_names

    keys = {key for name in engine_names() for preset in engine_class(name).presets.values()
            for key in preset}
    assert keys and keys <= set(views.SETTING_UNITS), keys - set(views.SETTING_UNITS)
    table = html.settings_table({"engine_settings": {"pybullet": {
        "defaults": {"time_step": 1 / 240, "num_sub_steps": None, "use_split_impulse": True},
        "accurate": {"time_step": 1 / 240, "num_sub_steps": None, "use_split_impulse": False}}}})
    import html as html_text

    table = html_text.unescape(table)
    assert "null" not in table and "pybullet's default" in table
    assert ">s<" in table and ">sub-steps per step<" in table and ">on<" in table
