"""How the report's figures are drawn: laid out once, and the records read once, before the
workers that draw from them are forked (harness/report/__init__.py, figures.py)."""

from __future__ import annotations

import multiprocessing
import re

import numpy as np
import pytest

from harness import plotting, report
from harness.report.reading import LazyResults, read_for_report
from harness.run.records import Record, write_results

needs_fork = pytest.mark.skipif("fork" not in multiprocessing.get_all_start_methods(),
                                reason="the figures are drawn in forked workers only")


def _agg():
    import matplotlib

    matplotlib.use("Agg")


def _pixels(path):
    from PIL import Image

    with Image.open(path) as image:
        return np.asarray(image.convert("RGBA"))


def _laid_out_figure():
    """A figure whose constrained layout moves its axes: long tick labels, titles, a colour
    bar and texts, as the heat map has; and markers drawn as an image in the SVG, as the
    split figure's."""
    figure = plotting.new_figure(6.0, 3.0)
    axes = figure.subplots(1, 2, sharey=True)
    for ax in axes:
        image = ax.imshow(np.arange(12.0).reshape(3, 4), aspect="auto")
        ax.set_yticks(range(3), ["a long row name", "row", "another row"])
        ax.xaxis.tick_top()
        ax.set_title("a title above the ticks", pad=16)
        ax.text(1, 1, "0.5% / 2%", ha="center", va="center")
        ax.scatter([0.5, 1.5, 2.5], [0.5, 1.0, 1.5], color="white", rasterized=True)
    figure.colorbar(image, ax=list(axes), label="departure [%]")
    return figure


@pytest.mark.parametrize("dpi", [90, 110])
def test_laid_out_once_the_png_and_svg_are_those_savefig_draws(tmp_path, dpi):
    _agg()
    expected = tmp_path / "savefig.png"
    _laid_out_figure().savefig(expected, dpi=dpi)  # laid out inside savefig
    token = plotting.SVG_TWIN.set(True)
    try:
        saved = plotting.save_png(_laid_out_figure(), tmp_path / "once.png", dpi=dpi)
    finally:
        plotting.SVG_TWIN.reset(token)
    assert np.array_equal(_pixels(saved), _pixels(expected))
    # the SVG twin: laid out as the PNG, drawn as before (savefig, then the engine set aside)
    figure = _laid_out_figure()
    figure.savefig(tmp_path / "before.png", dpi=dpi)
    figure.set_layout_engine("none")
    figure.savefig(tmp_path / "before.svg", metadata={"Date": None})
    ids = r'(id="|#)([A-Za-z0-9_]*?)[0-9a-f]{10}(?=["\)])'  # random unless svg.hashsalt set

    def text(path):
        return re.sub(ids, r"\1\2", path.read_text(encoding="utf-8"))

    assert text(saved.with_suffix(".svg")) == text(tmp_path / "before.svg")


def test_the_same_figure_gives_the_same_svg_bytes(tmp_path):
    """A regenerated report leaves an unchanged figure's SVG as it was (matplotlib gives
    clip paths and glyphs random ids, and dates the file, unless told not to)."""
    _agg()
    token = plotting.SVG_TWIN.set(True)
    try:
        first = plotting.save_png(_laid_out_figure(), tmp_path / "first.png")
        second = plotting.save_png(_laid_out_figure(), tmp_path / "second.png")
    finally:
        plotting.SVG_TWIN.reset(token)
    svg = first.with_suffix(".svg").read_bytes()
    assert b"clip-path" in svg  # the figure has ids that matplotlib would make random
    assert b"<dc:date>" not in svg
    assert svg == second.with_suffix(".svg").read_bytes()
    assert first.read_bytes() == second.read_bytes()


@pytest.fixture
def lazy_results(tmp_path) -> LazyResults:
    record = Record(scenario="a", point={"index": 0, "label": "p"}, source="pymunk",
                    preset="defaults", u_after=[1.0, 2.0, 3.0], departure={"poisson": 0.1})
    results = read_for_report(write_results(tmp_path / "r.json", [record], {}, {}))
    assert isinstance(results, LazyResults) and not results.loaded
    return results


def _task(name: str, draws, reads_records: bool = True) -> report.FigureTask:
    return report.FigureTask("legend", f"{name}.png", name, draws, (name,), svg=False,
                             reads_records=reads_records)


def _text_figure(path, tag, text: str):
    """A small figure drawn from its inputs alone (no record)."""
    from harness.plotting import new_figure, save_png

    figure = new_figure(2.0, 1.0)
    figure.text(0.1, 0.5, text)
    return save_png(figure, path, tag=tag)


def _legend_if(condition):
    """A figure drawn (a small text) only when ``condition()`` holds where it is drawn."""
    return lambda path, tag: _text_figure(path, tag, "pymunk") if condition() else None


@needs_fork
def test_the_workers_drawing_from_the_records_inherit_them_read_once(lazy_results, tmp_path):
    _agg()
    reads = []

    def read_records():
        reads.append(lazy_results.loaded)
        report.read_records(lazy_results)

    tasks = [_task("from-records", _legend_if(lambda: lazy_results.loaded)),
             _task("also-from-records", _legend_if(lambda: lazy_results.loaded)),
             _task("no-records", _legend_if(lambda: True), reads_records=False)]
    expected, finish = report.start_drawing(tasks, tmp_path, workers=2,
                                            read_records=read_records)
    assert reads == [False] and lazy_results.loaded  # read here, before the workers
    drawn = finish()
    assert drawn == expected  # every worker found the records read (else it drew nothing)
    assert all(path.is_file() for path in drawn)


@needs_fork
def test_without_a_stale_figure_from_the_records_they_are_not_read(lazy_results, tmp_path):
    _agg()
    tasks = [_task("from-records", _legend_if(lambda: True)),
             _task("no-records", _legend_if(lambda: True), reads_records=False),
             _task("no-records-either", _legend_if(lambda: True), reads_records=False)]
    report.draw_figures(tasks[:1], tmp_path, workers=1)  # current: not drawn again
    _, finish = report.start_drawing(tasks, tmp_path, workers=2,
                                     read_records=lambda: report.read_records(lazy_results))
    assert not lazy_results.loaded
    assert all(path.is_file() for path in finish())


@needs_fork
def test_a_failed_reading_ends_the_pool_already_drawing_and_is_raised(tmp_path):
    _agg()
    tasks = [_task("from-records", _legend_if(lambda: True)),
             _task("no-records", _legend_if(lambda: True), reads_records=False)]

    def read_records():
        raise ValueError("the results file changed while being read")

    with pytest.raises(ValueError, match="changed while being read"):
        report.start_drawing(tasks, tmp_path, workers=2, read_records=read_records)
    assert not report._PENDING  # the pool that drew the key has ended: its figure is whole
    assert (tmp_path / "no-records.png").is_file()


def test_records_read_for_a_frozen_caller_are_frozen_with_what_it_read(lazy_results):
    import gc

    gc.unfreeze()  # a command run in-process by an earlier test may have frozen objects
    assert gc.get_freeze_count() == 0
    report.read_records(lazy_results)
    assert lazy_results.loaded and gc.get_freeze_count() == 0
    lazy_results._results = None  # read again, for a frozen caller
    try:
        gc.freeze()  # as main does after reading the lines
        frozen = gc.get_freeze_count()
        report.read_records(lazy_results)
        assert lazy_results.loaded and gc.get_freeze_count() > frozen
        assert gc.isenabled()
    finally:
        gc.unfreeze()


@pytest.mark.parametrize(("value", "label"), [
    (0.5, "50%"), (0.01, "1%"), (0.001, "0.1%"), (0.0001, "0.01%"), (0.0005, "0.05%"),
    (1e-5, "1e-3%"), (1e-10, "1e-8%")])
def test_percent_ticks_read_as_in_the_text(value, label):
    from harness.plotting import percent_tick

    assert percent_tick(value) == label
