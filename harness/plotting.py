"""Figures shared by the report and the survey: a new figure, saving it as PNG (tagged with
the digest of its inputs) with its SVG twin, and log axes of fractions in percent.

Below both ``harness.report`` and ``harness.survey`` (which draw with it) and above
``harness.run`` (whose atomic writer saves the files): the survey draws its figures without
importing the report, and the report reads the survey's tables without the survey importing
it back.
"""

from __future__ import annotations

import contextvars
from pathlib import Path

from harness.store.files import save_figure

#: The PNG text chunk holding the digest of a figure's inputs (the report's redraw test).
TAG_KEY = "impact-harness-inputs"


def new_figure(width: float, height: float):
    from matplotlib.figure import Figure

    return Figure(figsize=(width, height), layout="constrained")


#: Whether :func:`save_png` writes the SVG twin: set per figure by the report (``--svg``),
#: since an SVG costs as much again as its PNG to write.
SVG_TWIN: contextvars.ContextVar[bool] = contextvars.ContextVar("svg_twin", default=True)


def save_png(figure, path: Path, dpi: int = 100, tag: str | None = None) -> Path:
    """Save a PNG and, beside it unless :data:`SVG_TWIN` says not, the same figure as SVG
    (for a paper); ``tag`` (the digest of the figure's inputs) goes into the PNG's
    metadata."""
    lay_out(figure, dpi)
    save_figure(figure, path, "png", dpi=dpi, metadata={TAG_KEY: tag} if tag else None)
    if SVG_TWIN.get():
        save_svg_twin(figure, path)
    return path


def lay_out(figure, dpi: float) -> None:
    """Lay ``figure`` out once, as ``savefig`` at ``dpi`` would, and set its layout engine
    aside, so that the PNG and its SVG twin are drawn with this layout.

    ``savefig`` of a figure with a layout engine draws it twice: once, with the drawing
    itself switched off, to lay it out (every text measured and every tick made again after
    the layout moved the axes), then for real. The layout engine run here, at the PNG's
    resolution (the text extents it measures depend on it), finds the same positions
    without that first drawing, a fifth of a headline figure's time; the pixels are the
    same (tests/report/test_drawing.py).
    """
    engine = figure.get_layout_engine()
    if engine is None or not figure.axes:  # Figure.draw lays out only a figure with axes
        return
    resolution = figure.dpi
    figure.dpi = dpi  # as savefig sets it while it saves
    try:
        engine.execute(figure)
    finally:
        figure.dpi = resolution  # the figure as it was (as savefig leaves it)
    figure.set_layout_engine("none")


def save_svg_twin(figure, path: Path) -> Path:
    """The SVG beside the PNG ``path`` just saved from ``figure``, laid out as the PNG was.

    The constrained layout found for the PNG is kept (:func:`lay_out` set its engine
    aside): laying the figure out again for the SVG was a third of the dearest figure's
    time (the heat map's ~100 texts measured again, at 1,000 scenarios), and moves nothing
    by more than the difference in text extents between the two resolutions (< 0.5 pt).
    """
    figure.set_layout_engine("none")
    return save_svg(figure, path.with_suffix(".svg"))


#: The salt of the ids matplotlib gives an SVG's clip paths and glyphs (``svg.hashsalt``):
#: fixed, since by default each file gets random ones.
SVG_HASH_SALT = "planar-impact-harness"


def save_svg(figure, svg: Path) -> Path:
    """Save ``figure`` as the SVG ``svg``, the same bytes for the same figure: no date and
    ids from :data:`SVG_HASH_SALT` (else a regenerated report changes every SVG)."""
    from matplotlib import rc_context

    with rc_context({"svg.hashsalt": SVG_HASH_SALT}):
        save_figure(figure, svg, "svg", metadata={"Date": None})
    return svg


def percent_axis(axis) -> None:
    """Tick labels of a log axis of fractions, written in percent (0.01 -> 1%), the minor
    ticks' too: on an axis spanning less than a few decades matplotlib labels some of them,
    and in its own style ``2×10⁻¹`` beside a major tick's ``10%``."""
    from matplotlib.ticker import FuncFormatter, LogFormatter

    class PercentLogFormatter(LogFormatter):
        """matplotlib's choice of which minor ticks to label, each in percent."""

        def _num_to_string(self, x, vmin, vmax):
            return percent_tick(x)

    axis.set_major_formatter(FuncFormatter(lambda value, _: percent_tick(value)))
    axis.set_minor_formatter(PercentLogFormatter(labelOnlyBase=False))


def percent_tick(value: float) -> str:
    """A log axis's tick as a percentage: ``10%``, ``0.1%``, ``0.01%``, then ``1e-3%``."""
    percent = 100.0 * value
    if percent >= 1:
        return f"{percent:.0f}%"
    if percent >= 0.01:  # as written in the text and tables, not 1e-1%
        return f"{percent:.2g}%"
    return f"{percent:.0e}%".replace("e-0", "e-")




def text_problems(figure, dpi: float = 100, slack: float = 1.0) -> list[str]:
    """What is wrong with the texts of ``figure`` drawn at ``dpi`` (laid out as
    :func:`save_png` lays it out): each text cut by the figure's edge, and each pair of texts
    that overlap, by more than ``slack`` pixels. Empty when every text is whole and apart.

    Only the texts the drawing actually draws are measured (a renderer that notes each
    text as it is drawn: tick labels outside the axes' range are never drawn).
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    lay_out(figure, dpi)
    resolution = figure.dpi
    figure.dpi = dpi
    try:
        canvas = FigureCanvasAgg(figure)
        renderer = canvas.get_renderer()
        drawn: dict[int, object] = {}
        draw_text = renderer.draw_text

        def noting(gc, x, y, s, prop, angle, ismath=False, mtext=None):
            if mtext is not None and s.strip():
                drawn[id(mtext)] = mtext
            return draw_text(gc, x, y, s, prop, angle, ismath=ismath, mtext=mtext)

        renderer.draw_text = noting
        figure.draw(renderer)
        boxes = [(text.get_text().replace("\n", " | "), text.get_window_extent(renderer))
                 for text in drawn.values()]
        width, height = figure.bbox.width, figure.bbox.height
    finally:
        figure.dpi = resolution
    problems = []
    for text, box in boxes:
        if (box.x0 < -slack or box.y0 < -slack or box.x1 > width + slack
                or box.y1 > height + slack):
            problems.append(f"cut by the figure's edge: {text!r}")
    for index, (first, a) in enumerate(boxes):
        for second, b in boxes[index + 1:]:
            across = min(a.x1, b.x1) - max(a.x0, b.x0)
            up = min(a.y1, b.y1) - max(a.y0, b.y0)
            if across > slack and up > slack:
                problems.append(f"overlap: {first!r} and {second!r}")
    return problems
