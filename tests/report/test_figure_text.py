"""Every text of every figure the report draws is whole and apart from the others: none cut
by the figure's edge, no two overlapping (harness/plotting.py, ``text_problems``), at the
resolution each figure is saved at."""

from __future__ import annotations

from pathlib import Path

import pytest

from harness import plotting, report
from harness.report import table3
from harness.run import runner
from harness.run.records import read_results, write_results
from harness.scenarios import load_scenarios

LIBRARY = Path(__file__).resolve().parents[2] / "scenarios"
#: Beside the quick set: a flagged single point, a sweep with flagged runs and a tilt (whose
#: departure is from the event-driven reference: the longest axis label).
EXTRA = ("ellipse-drop", "sweep-ellipse-angle", "sweep-tilted-box")


def _agg():
    import matplotlib

    matplotlib.use("Agg")


def test_a_title_wider_than_its_figure_is_cut():
    _agg()
    figure = plotting.new_figure(3.0, 2.0)
    figure.subplots().set_title("a title far wider than a figure three inches wide can hold")
    problems = plotting.text_problems(figure, 100)
    assert problems and all(p.startswith("cut by the figure's edge") for p in problems)


def test_two_texts_on_one_another_overlap_and_apart_do_not():
    _agg()
    figure = plotting.new_figure(4.0, 3.0)
    ax = figure.subplots()
    ax.text(0.5, 0.5, "first text", ha="center")
    ax.text(0.52, 0.51, "second text", ha="center")
    assert plotting.text_problems(figure, 100) == ["overlap: 'first text' and 'second text'"]
    figure = plotting.new_figure(4.0, 3.0)
    ax = figure.subplots()
    ax.text(0.5, 0.8, "first text", ha="center")
    ax.text(0.5, 0.2, "second text", ha="center")
    assert plotting.text_problems(figure, 100) == []


def test_only_the_texts_drawn_are_measured():
    """A tick label outside the axes' range is made but never drawn: not a problem."""
    _agg()
    figure = plotting.new_figure(4.0, 3.0)
    ax = figure.subplots()
    ax.set_xticks([0.0, 0.5, 1.0, 1.01, 1.02], ["0", "0.5", "1", "beyond", "the range"])
    ax.set_xlim(0, 1)
    assert plotting.text_problems(figure, 100) == []
    ax.set_xlim(0, 1.02)  # now drawn, on one another
    assert any("'beyond' and 'the range'" in p for p in plotting.text_problems(figure, 100))


@pytest.fixture(scope="module")
def drawn_texts(tmp_path_factory):
    """``{figure file: problems}`` of every figure of a report of the quick set and
    :data:`EXTRA`, each checked as it is saved (nothing written)."""
    _agg()
    scenarios = load_scenarios(tags="quick") + [s for s in load_scenarios(LIBRARY)
                                                if s.name in EXTRA]
    assert {s.name for s in scenarios} >= set(EXTRA)
    outcome = runner.run(scenarios, cache=None, workers=1, log=None)
    out = tmp_path_factory.mktemp("report")
    results = read_results(write_results(out / "results.json", outcome.records,
                                         outcome.provenance, outcome.scenarios))
    found: dict[str, list[str]] = {}

    def check(figure, path, fmt, dpi=100, metadata=None):
        if fmt == "png":
            found[Path(path).name] = plotting.text_problems(figure, dpi)

    patch = pytest.MonkeyPatch()
    patch.setattr(plotting, "save_figure", check)
    patch.setattr(table3, "save_figure", check)
    token = plotting.SVG_TWIN.set(False)
    try:
        for task in report.figure_tasks(results, False, "all", (), "none"):
            task.draw(out / task.file, None)
        # the heat map of many scenarios: a row per family, "median / max (k!)" cells
        from harness.report.figures import heatmap_figure

        groups = report.scenario_groups(results, results.scenario_names())
        heatmap_figure(results, out / "heatmap-families.png", groups=groups)
    finally:
        plotting.SVG_TWIN.reset(token)
        patch.undo()
    return found


def test_every_figure_of_the_report_has_its_texts_whole_and_apart(drawn_texts):
    kinds = {name.split("-")[0].removesuffix(".png") for name in drawn_texts}
    assert kinds >= {"heatmap", "split", "impulse", "history", "sweep", "paper"}
    assert {name: problems for name, problems in drawn_texts.items() if problems} == {}


@pytest.mark.parametrize("engines", [("pymunk", "mujoco"), ("box2d",)])
def test_a_heat_map_of_few_engines_has_its_texts_whole_and_apart(tmp_path, engines):
    """Narrow panels: their titles (MuJoCo's renamed preset the longest) once overlapped."""
    _agg()
    scenarios = [s for s in load_scenarios(tags="quick")][:2]
    outcome = runner.run(scenarios, engines=engines, cache=None, workers=1, log=None)
    results = read_results(write_results(tmp_path / "results.json", outcome.records,
                                         outcome.provenance, outcome.scenarios))
    found = []
    patch = pytest.MonkeyPatch()
    patch.setattr(plotting, "save_figure",
                  lambda figure, path, fmt, dpi=100, metadata=None:
                  found.append(plotting.text_problems(figure, dpi)) if fmt == "png" else None)
    token = plotting.SVG_TWIN.set(False)
    try:
        from harness.report.figures import heatmap_figure

        heatmap_figure(results, tmp_path / "heatmap.png")
    finally:
        plotting.SVG_TWIN.reset(token)
        patch.undo()
    assert found == [[]]


def test_the_survey_figures_have_their_texts_whole_and_apart(tmp_path):
    """The report's survey section draws the survey's maps and CDFs (a CDF's two-column
    keys once ran into each other and past the figure's edge)."""
    from harness.survey import outputs
    from harness.survey.cli import run_survey
    from harness.survey.population import resolve_populations

    _agg()
    survey = run_survey(resolve_populations([]), 12, 0, ("pymunk",), ("defaults", "accurate"),
                        echo=lambda _: None)
    found: dict[str, list[str]] = {}

    def check(figure, path, fmt, dpi=100, metadata=None):
        if fmt == "png":
            found[Path(path).name] = plotting.text_problems(figure, dpi)

    patch = pytest.MonkeyPatch()
    patch.setattr(plotting, "save_figure", check)
    token = plotting.SVG_TWIN.set(False)
    try:
        outputs.figures(survey["runs"], tmp_path)
    finally:
        plotting.SVG_TWIN.reset(token)
        patch.undo()
    assert set(found) == {"map-pymunk.png", "cdf-pymunk.png"}
    assert {name: problems for name, problems in found.items() if problems} == {}
