"""The report at scale: figures drawn in a process pool, aggregated above a threshold."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from harness import report
from harness.report.views import engine_scenarios, slug
from harness.run import runner
from harness.run.records import Results, read_results, write_results
from harness.scenarios import load_scenarios


def _text_figure(path, tag, engines: list[str]):
    """A small figure drawn from its inputs alone (no record): the engines' names."""
    from harness.plotting import new_figure, save_png

    figure = new_figure(2.0, 1.0)
    figure.text(0.1, 0.5, ", ".join(engines))
    return save_png(figure, path, tag=tag)


def _legend_task(engines: list[str], svg: bool = True) -> report.FigureTask:
    return report.FigureTask(
        "legend", f"legend-{'-'.join(engines)}.png", engines,
        lambda path, tag: _text_figure(path, tag, engines), ("legend",), svg)


def test_the_pool_draws_the_same_files_as_one_process(tmp_path):
    import matplotlib

    matplotlib.use("Agg")
    tasks = [_legend_task(["pymunk"]), _legend_task(["pybullet"]), _legend_task(["mujoco"]),
             report.FigureTask("legend", "nothing.png", [], lambda path, tag: None,
                               ("nothing",))]
    serial, pooled = tmp_path / "serial", tmp_path / "pooled"
    serial.mkdir()
    pooled.mkdir()
    drawn_serial = report.draw_figures(tasks, serial, workers=1)
    drawn_pooled = report.draw_figures(tasks, pooled, workers=2)
    assert [p and p.name for p in drawn_serial] == [p and p.name for p in drawn_pooled]
    assert drawn_pooled[-1] is None  # a task with nothing to draw writes no file
    for path in drawn_serial[:-1]:
        assert path.read_bytes() == (pooled / path.name).read_bytes()
        assert (pooled / path.name).with_suffix(".svg").is_file()
    # the digest in each PNG keeps the pool from redrawing what is current
    before = {p.name: p.stat().st_mtime_ns for p in pooled.glob("*.png")}
    report.draw_figures(tasks, pooled, workers=2)
    assert {p.name: p.stat().st_mtime_ns for p in pooled.glob("*.png")} == before


def test_without_svg_twin_no_svg_is_written_and_asking_for_one_redraws(tmp_path):
    import matplotlib

    matplotlib.use("Agg")
    task = _legend_task(["pymunk"], svg=False)
    (path,) = report.draw_figures([task], tmp_path, workers=1)
    assert path.is_file() and not path.with_suffix(".svg").exists()
    with_svg = _legend_task(["pymunk"], svg=True)
    report.draw_figures([with_svg], tmp_path, workers=1)
    assert path.with_suffix(".svg").is_file()


@pytest.fixture(scope="module")
def small_results(tmp_path_factory):
    """The quick scenarios and one sweep, run once (no cache)."""
    out = tmp_path_factory.mktemp("results")
    scenarios = load_scenarios(tags="quick") + load_scenarios(tags="sweep")[:1]
    outcome = runner.run(scenarios, cache=None, workers=1, log=None)
    path = write_results(out / "results.json", outcome.records, outcome.provenance,
                         outcome.scenarios)
    return read_results(path)


@pytest.fixture(scope="module")
def few_results(small_results):
    """Two scenarios of ``small_results``, one sweep and one not: a report of few scenarios
    draws every figure of each, so the tests of such a report draw these two only."""
    names = small_results.scenario_names()
    sweep = next(n for n in names if small_results.scenarios.get(n, {}).get("sweep"))
    single = next(n for n in names if n != sweep)
    return Results([r for r in small_results.records if r.scenario in (single, sweep)],
                   small_results.provenance,
                   {n: small_results.scenarios[n] for n in (single, sweep)})


@pytest.fixture(scope="module")
def aggregated(small_results, tmp_path_factory):
    """A report of "many" scenarios (the threshold lowered below the quick set's size),
    written once for the tests that read it."""
    out = tmp_path_factory.mktemp("aggregated")
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(report, "MANY_SCENARIOS", 2)
        written = report.write_report(small_results, out, workers=2,
                                      figures_for=[small_results.scenario_names()[0]])
    return small_results, out, written


def test_no_shared_key_is_drawn_each_impulse_diagram_has_its_own(small_results):
    def kinds(**options):
        arguments = {"many": True, "scenario_figures": "none", "figures_for": (),
                     "svg": "headline", **options}
        return [task.kind for task in report.figure_tasks(small_results, **arguments)]

    names = small_results.scenario_names()
    sweeps = [n for n in names if small_results.scenarios.get(n, {}).get("sweep")]
    single = [n for n in names if n not in sweeps]
    assert sweeps and single
    assert "impulse" not in kinds()  # many: no diagram
    assert kinds(figures_for=single[:1]).count("impulse") == 1
    for options in ({}, {"figures_for": sweeps}, {"figures_for": single[:1]},
                    {"many": False, "scenario_figures": "all"}):
        assert "legend" not in kinds(**options)  # the key is in each diagram's PNG


def test_families_skip_selection_tags():
    assert report.scenario_group({"tags": ["quick", "rod", "spin"]}) == "rod"
    assert report.scenario_group({"tags": ["sweep"]}) == "untagged"
    assert report.scenario_group({}) == "untagged"


def test_many_scenarios_give_one_heat_map_row_per_family_and_a_table_per_family(aggregated):
    results, out, written = aggregated
    assert "heatmap.png" in {p.name for p in written["figures"]}
    page = (out / "index.html").read_text(encoding="utf-8")
    groups = report.scenario_groups(results, results.scenario_names())
    assert len(groups) > 1  # the quick set spans several families
    engine_rows = set(engine_scenarios(results))
    for tag, members in groups.items():
        start = page.index(f"<details><summary>{tag} ({len(members)} scenarios)</summary>")
        table = page[start:page.index("</details>", start)]
        # every scenario of the family links to its section, coloured cells where it ran
        for name in members:
            assert f"<a href='#{slug(name)}'>" in table
        if engine_rows & set(members):
            assert "class='heat' style='background-color:#" in table


def test_many_scenarios_draw_scenario_figures_only_on_demand_and_svg_for_headline(aggregated):
    results, out, written = aggregated
    first = slug(results.scenario_names()[0])
    per_scenario = {p.name for p in written["figures"]
                    if p.name.startswith(("impulse-", "sweep-", "history-"))}
    assert per_scenario and all(first in name for name in per_scenario)
    for path in written["figures"]:
        headline = path.name.startswith(("heatmap", "split", "paper-table3"))
        assert path.with_suffix(".svg").exists() == headline, path.name


def test_many_scenarios_page_is_folded_per_tag_and_its_images_print(aggregated):
    results, out, _ = aggregated
    page = (out / "index.html").read_text(encoding="utf-8")
    images = re.findall(r"<img [^>]*>", page)
    # loaded eagerly: a lazy image not scrolled to is left out of a printed page, and the
    # many-scenario page holds only the headline figures (per-scenario ones stop at 60)
    assert images and not any('loading="lazy"' in tag for tag in images)
    groups = report.scenario_groups(results, results.scenario_names())
    for tag, members in groups.items():
        # the section of every scenario lies inside its tag's <details>
        start = page.index(f"<details class='group'><summary><b>{tag}</b>")
        end = page.index("</details>", page.index(f"id='{slug(members[-1])}'"))
        for name in members:
            assert start < page.index(f"id='{slug(name)}'") < end
    # no SVG link to a file that was not written
    for href in re.findall(r"href=['\"](figures/[^'\"]+\.svg)['\"]", page):
        assert (out / href).is_file(), href


def test_few_scenarios_keep_one_heat_map_every_figure_and_every_svg(few_results, tmp_path):
    written = report.write_report(few_results, tmp_path, workers=2)
    names = {p.name for p in written["figures"]}
    assert "heatmap.png" in names and not any(n.startswith("heatmap-") for n in names)
    assert any(n.startswith("sweep-") for n in names)
    assert all(p.with_suffix(".svg").is_file() for p in written["figures"])
    page = Path(written["html"]).read_text(encoding="utf-8")
    assert "<details class='group'>" not in page


def test_a_figure_with_nothing_to_show_leaves_the_page_built_while_drawing(few_results,
                                                                          tmp_path, monkeypatch):
    """The page is built while the pool draws, assuming every figure has something to
    show; one that has not (here the split) is missing from it as from a page built after
    the figures (one process). The thing tested is the page, not the figures: no
    scenario's figure is asked for, and the other headline figures are stand-in files."""

    def stand_in(path, tag):
        path.write_bytes(b"a figure")
        return path

    monkeypatch.setattr(report, "split_figure", lambda rows, path, tag: None)
    monkeypatch.setattr(report, "heatmap_figure",
                        lambda results, path, tag, groups: stand_in(path, tag))
    monkeypatch.setattr(report, "table3_figure", stand_in)
    pages = {}
    for workers in (1, 2):
        out = tmp_path / f"workers-{workers}"
        written = report.write_report(few_results, out, workers=workers,
                                      scenario_figures="none")
        assert out / "figures" / "split.png" not in written["figures"]
        assert out / "figures" / "heatmap.png" in written["figures"]
        pages[workers] = re.sub(r"Report generated [^<]*", "",
                                (out / "index.html").read_text(encoding="utf-8"))
    assert "split.png" not in pages[2] and "heatmap.png" in pages[2]
    assert pages[1] == pages[2]
