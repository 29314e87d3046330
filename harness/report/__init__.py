"""``impact-harness report``: ``reports/index.html`` and ``reports/summary.md`` from results.

::

    impact-harness report                                  # reports/results.json -> reports/
    impact-harness report --results /tmp/r.json --out /tmp/report
    impact-harness report --figures-for 'rod-*' --workers 2   # many scenarios: some figures

The bench and stress pages (``bench.html``, ``stress.html``) are written when their inputs
exist, and linked from the contents only when measured by the code that made the results;
otherwise the contents name them with when they were measured and ``make bench`` or ``make
stress`` (``make validate`` measures neither: minutes each). Past two seconds the command
prints the step it is at on stderr (:mod:`harness.report.progress`).

Without ``--out`` the report goes to ``reports/``, where it replaces an existing report only
when made from ``reports/results.json`` (the results that report was made from, as ``make
validate`` does): a report of another results file there is refused (exit status 2, before
any work) unless ``--force`` -- as ``run`` refuses to replace another selection's results.

The HTML page is self-contained (inline CSS, no scripts, no external assets); its figures are
PNG files in ``<out>/figures/`` beside it, and the Table 3 reproduction
(``<out>/paper-table3.md`` and ``.png``, written by ``impact-harness paper``) is embedded
when present. Matplotlib (Agg) draws the figures; nothing here touches an engine or re-solves
a scenario except the impulse paths of Routh's graph, which ``planar_impact.impulse_process``
walks from the contact-space numbers stored in the results.

At scale (more than :data:`MANY_SCENARIOS` scenarios) the page aggregates: the headline heat
map has a row per family (median / max over its scenarios), each scenario's departures are a
coloured HTML table folded under its family, the scenario sections are folded per family,
and the per-scenario figures are drawn only on demand (``--figures-for PATTERN``,
``--scenario-figures all``): at 1,000 scenarios they were ~1,000 of the ~1,003 figures and
nearly all of a 260 s cold report (each impulse diagram carries its own key: the page has no
shared one). Only the headline figures (heat map, law vs solve, Table 3) get SVG twins then
(``--svg headline``; ``--svg all`` for every one): an SVG costs about as much again as its
PNG and is wanted for a paper's few figures, not for a thousand diagrams (the split figure's
thousands of markers are an image in its SVG, its axes and text vector). Every image loads
eagerly (a lazy one not yet scrolled to is left out of a printed page). Figures are drawn in
a pool of forked processes (``--workers``) while this process builds the page; each figure's
PNG carries the digest of its inputs, so a warm report draws nothing. A scenario's records
enter those digests by what they were made from (its file, the code, the installed versions,
the settings) and what they decided (statuses, verdicts, collision types), never by their
floats, whose last bits depend on the CPU: a fresh clone on another machine draws none of
the committed figures again (:func:`harness.report.reading.scenario_digest`). Likewise each
scenario's HTML section and headline cells are kept in ``<out>/.report-fragments.json``
under the digest of its records (:mod:`harness.report.fragments`): a warm report formats
only what changed, and reads the records themselves only when something is to be formatted
(:mod:`harness.report.reading`: what it needs of them otherwise -- their digests, order,
engines -- comes from the lines of the results file).

What the page shows, in order: what this is; the headline heat maps (departure of every
engine and preset from Poisson and from Stronge, per scenario); the split of each engine's
departure into the law it solves and how well it solves it; the gates; per scenario the
post-impact velocities of every law and engine side by side, the energy change and the
impulse diagram (Fig. 1 of the paper), or for sweeps the post-impact quantities against the
swept parameter with the Poisson type boundaries marked; Table 3; the survey in
``<out>/survey/`` when there is one (what was surveyed and what was not, its table per engine
× preset × family, its figures: :mod:`harness.report.survey`); against experiments;
versions and settings. Each section is folded in a ``<details>`` under its name and headline
(:func:`harness.report.markup.folded`): the overview unfolded, each scenario and the long
sections folded, every fold opened for printing.
"""


from __future__ import annotations

import argparse
import fnmatch
import gc
import multiprocessing
import os
import sys
import time
from collections.abc import Callable, Sequence
from pathlib import Path

from harness import bounds
from harness.plotting import SVG_TWIN
from harness.processes import start_forked
from harness.report.experiments import data_option_problem
from harness.report.figure_cache import (
    FIGURE_KINDS,
    FigureTask,
    inputs_digest,
    is_current,
    scenario_digests,
    table3_payload,
)
from harness.report.figures import heatmap_figure, impulse_figure, split_figure, sweep_figure
from harness.report.fragments import CACHE_FILE, DIGESTS_FILE, open_cache, prepare
from harness.report.history import history_figure, history_inputs
from harness.report.html import html_page
from harness.report.pages import PAGE_DIRECTORIES, write_pages
from harness.report.progress import Progress, Silent
from harness.report.reading import read_for_report
from harness.report.summary import write_summary
from harness.report.survey import survey_figure_tasks
from harness.report.table3 import table3_figure
from harness.report.views import FIGURES, has_library_scenarios, slug, split_rows
from harness.run.records import DEFAULT_RESULTS, Results
from harness.store.cache_directory import output_seal
from harness.store.files import (
    inner_directory_problem,
    keep_manifest,
    make_inner_directory,
    output_directory_problem,
    replaceable_problem,
    write_text_atomically,
)

#: Above this many scenarios the report aggregates (``--scenario-figures auto``, ``--svg
#: auto``): the headline heat map has one row per family of scenarios (:func:`scenario_group`)
#: instead of one per scenario, each scenario's departures are an HTML table folded under its
#: family, no per-scenario figures are drawn unless asked for (``--figures-for``), only the
#: headline figures get SVG twins, and the scenarios' sections are folded per family. At 60
#: scenarios the one-row-per-scenario heat map is ~1,700 px tall and the per-scenario figures
#: take ~1 min to draw on two cores; the shipped library (28 scenarios) stays below.
MANY_SCENARIOS = 60
#: Where ``report`` writes without ``--out`` (the library's report, beside ``run``'s results).
DEFAULT_OUT = DEFAULT_RESULTS.parent
#: Tags that select scenarios for a run rather than say what they are: never a family.
SELECTION_TAGS = ("quick", "sweep", "slow")
#: Figure kinds drawn once per report (not per scenario): their SVG twins are kept with
#: ``--svg headline`` (:data:`~harness.report.figure_cache.FIGURE_KINDS`).
HEADLINE_KINDS = tuple(name for name, kind in FIGURE_KINDS.items() if kind.headline)


def scenario_group(info: dict) -> str:
    """The family a scenario is filed under when the report aggregates: its first tag that is
    not one of :data:`SELECTION_TAGS` (``"untagged"`` when none is left)."""
    tags = [str(t) for t in info.get("tags") or [] if t not in SELECTION_TAGS]
    return tags[0] if tags else "untagged"


def scenario_groups(results: Results, names: Sequence[str]) -> dict[str, list[str]]:
    """``{tag: scenario names}`` in order of first appearance (:func:`scenario_group`)."""
    groups: dict[str, list[str]] = {}
    for name in names:
        groups.setdefault(scenario_group(results.scenarios.get(name, {})), []).append(name)
    return groups


def write_report(results: Results, out_dir: Path | str,
                 sources: Sequence[Path] = (DEFAULT_RESULTS.parent,), workers: int | None = None,
                 scenario_figures: str = "auto", figures_for: Sequence[str] = (),
                 svg: str = "auto", experiments_data: str | os.PathLike | None = None,
                 progress: Progress | Silent | None = None) -> dict:
    """Write index.html, summary.md, the figures (PNG and SVG) and, when the benchmark's
    ``bench.json`` or the stress test's ``stress.md`` exist (in ``bench/`` and ``stress/``
    under ``out_dir`` or one of ``sources``, by default where ``bench`` and ``stress`` write
    them), their pages; returns the paths written.

    Parameters
    ----------
    workers
        Processes drawing the figures (default: the machine's cores); 1 draws them here.
    scenario_figures
        ``"all"``, ``"none"`` or ``"auto"`` (all up to :data:`MANY_SCENARIOS` scenarios,
        none above): whether each scenario gets its impulse diagram, sweep and history.
    figures_for
        Shell patterns (``fnmatch``) of scenario names whose figures are drawn anyway.
    svg
        ``"all"``, ``"headline"`` (SVG twins of :data:`HEADLINE_KINDS` only) or ``"auto"``
        (all up to :data:`MANY_SCENARIOS` scenarios, headline above).
    experiments_data
        The directory of a copy of the Fazeli et al. 2017 drops (else
        ``IMPACT_HARNESS_FAZELI_DIR``'s): the "Against experiments" section shows their
        aggregates (harness/report/experiments.py).
    progress
        Where the report says the step it is at (:class:`harness.report.progress.Progress`:
        stderr once it has taken two seconds); by default nowhere.
    """
    progress = Silent() if progress is None else progress
    progress.step("reading the results' digests")
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)  # the directory asked for (a link is fine)
    figure_dir = make_inner_directory(out_dir, FIGURES)  # the report's own: never a link
    names = results.scenario_names()
    many = len(names) > MANY_SCENARIOS
    if scenario_figures == "auto":
        scenario_figures = "none" if many else "all"
    if svg == "auto":
        svg = "headline" if many else "all"
    cache = open_cache(results, out_dir)
    known = open_cache(results, out_dir, DIGESTS_FILE)  # digests of lines hashed before
    digests = scenario_digests(results, known.get)
    tasks = figure_tasks(results, many, scenario_figures, figures_for, svg, digests)
    # the survey's, when out_dir holds one (harness/report/survey.py): headline figures
    tasks += survey_figure_tasks(out_dir, svg)
    # The figures are drawn by forked workers while this process builds the page, which
    # needs only their names: it assumes that every figure to be drawn has something to
    # show, and is built again in the rare case one had not.
    progress.step("reading the records")
    expected, finish_drawing = start_drawing(tasks, figure_dir, workers,
                                             read_records=lambda: read_records(results),
                                             on_stale=progress.drawing)
    try:
        progress.step("building the page while the figures are drawn")
        prepared = prepare(results, out_dir, digests, cache)
        groups = scenario_groups(results, names) if many else {}
        pages, stale_pages = write_pages(out_dir, sources, results.provenance)
        page = html_page(results, out_dir, figure_map(tasks, expected, many, groups,
                                                      scenario_figures), pages, prepared,
                         experiments_data, stale_pages)
        progress.step("drawing the figures")
    finally:  # the pool ends either way
        drawn = finish_drawing()
    progress.step("writing the page and summary.md")
    if drawn != expected:
        page = html_page(results, out_dir, figure_map(tasks, drawn, many, groups,
                                                      scenario_figures), pages, prepared,
                         experiments_data, stale_pages)
    wanted = {task.file for task, path in zip(tasks, drawn) if path is not None}
    wanted |= {str(Path(task.file).with_suffix(".svg")) for task, path in zip(tasks, drawn)
               if path is not None and task.svg}
    _remove_stale_figures(figure_dir, wanted)
    html_path = out_dir / "index.html"
    write_text_atomically(html_path, page)
    summary = write_summary(results, out_dir, prepared)
    prepared.cache.save()
    known.save()
    return {"html": html_path, "summary": summary,
            "figures": sorted(figure_dir / f for f in wanted if f.endswith(".png"))}


def read_records(results: Results) -> None:
    """Read the records of ``results`` now if they were not (:class:`~harness.report.
    reading.LazyResults`), and keep them out of the collector's sight when the caller keeps
    its results so (:func:`main`: ``gc.freeze``).

    Called before the workers that draw from the records are forked: they inherit them,
    where each read them again otherwise (a second of CPU each at 1,000 scenarios, and as
    much again in collections walking them); the page reads them anyway.
    """
    if getattr(results, "loaded", True):
        return
    if not gc.get_freeze_count():
        results.full()
        return
    # What main read is frozen: these join it, frozen before the collector is on again (else
    # its next collection walks every container just made, and a forked worker's
    # collections copy the pages they touch).
    enabled = gc.isenabled()
    gc.disable()
    try:
        results.full()
    finally:
        gc.freeze()
        if enabled:
            gc.enable()


def figure_map(tasks: Sequence[FigureTask], drawn: Sequence[Path | None], many: bool,
               groups: dict[str, list[str]], scenario_figures: str) -> dict:
    """What the page knows of the figures (:func:`harness.report.html.html_page`): each
    drawn task's file in its slot, the files with an SVG twin and how the scenarios are
    shown."""
    figures: dict = {"impulse": {}, "sweep": {}, "svg": set(), "many": many,
                     "groups": groups, "scenario_figures": scenario_figures}
    for task, path in zip(tasks, drawn):
        if path is None:
            continue
        if len(task.slot) == 2:
            figures.setdefault(task.slot[0], {})[task.slot[1]] = task.file
        else:
            figures[task.slot[0]] = task.file
        if task.svg:
            figures["svg"].add(task.file)
    return figures


def figure_tasks(results: Results, many: bool, scenario_figures: str,
                 figures_for: Sequence[str], svg: str,
                 digests: dict[str, str] | None = None) -> list[FigureTask]:
    """Every figure of the report, with the inputs its digest covers (a scenario's records
    by their digest, ``digests``: :func:`scenario_digests` when known).

    The closures read the values bound in this call (default arguments), never a loop's
    later values.
    """
    names = results.scenario_names()
    kinds = FIGURE_KINDS
    digests = scenario_digests(results) if digests is None else digests
    records_digest = {name: digests.get(name, "") for name in names}
    tasks = []
    groups = scenario_groups(results, names) if many else None
    # above MANY_SCENARIOS one row per family (the scenarios' rows are HTML tables instead)
    tasks.append(kinds["heatmap"].task(
        [groups, records_digest], lambda path, tag: heatmap_figure(results, path, tag, groups),
        kinds["heatmap"].svg(svg)))
    # the split rows are the records' (views.split_rows): drawn from them only when stale
    tasks.append(kinds["split"].task(
        records_digest, lambda path, tag: split_figure(split_rows(results), path, tag),
        kinds["split"].svg(svg)))
    for name in names:
        if scenario_figures != "all" and not any(fnmatch.fnmatchcase(name, pattern)
                                                 for pattern in figures_for):
            continue
        records = results.for_scenario(name)
        info = results.scenarios.get(name, {})
        if info.get("sweep"):
            tasks.append(kinds["sweep"].task(
                # what the figure reads of the scenario: its sweep (not its file's path,
                # which differs between checkouts and would redraw every clone's figures)
                [name, info["sweep"], records_digest[name]],
                lambda path, tag, name=name, info=info, records=records:
                sweep_figure(name, info, records, path, tag), kinds["sweep"].svg(svg),
                key=name, file_key=slug(name)))
        else:
            tasks.append(kinds["impulse"].task(
                [name, records_digest[name]],
                lambda path, tag, name=name, records=records:
                impulse_figure(name, records, path, tag), kinds["impulse"].svg(svg),
                key=name, file_key=slug(name)))
            # the contact in time (harness.report.history)
            tasks.append(kinds["history"].task(
                history_inputs(name, records_digest[name]),
                lambda path, tag, name=name, records=records:
                history_figure(name, records, path, tag), kinds["history"].svg(svg),
                key=name, file_key=slug(name)))
    if has_library_scenarios(results):  # the paper's table only beside the library
        tasks.append(kinds["table3"].task(table3_payload(),
                                          lambda path, tag: table3_figure(path, tag),
                                          kinds["table3"].svg(svg), reads_records=False))
    return tasks


def _cost(kind: str) -> float:
    """A kind's rough drawing cost (:class:`~harness.report.figure_cache.FigureKind`); 1 s
    for a kind not registered (a caller's own task)."""
    return FIGURE_KINDS[kind].cost if kind in FIGURE_KINDS else 1.0


#: The figure tasks being drawn, read by the pool's forked workers (which inherit it: the
#: closures and the results they read are never pickled).
_PENDING: list[tuple[FigureTask, Path, str]] = []


def _draw_pending(index: int) -> str | None:
    task, path, tag = _PENDING[index]
    token = SVG_TWIN.set(task.svg)
    try:
        drawn = task.draw(path, tag)
    finally:
        SVG_TWIN.reset(token)
    return None if drawn is None else str(drawn)


def _warm_matplotlib() -> None:
    """Import what the figures draw with and load the font, once here rather than in every
    forked worker, which inherit them (loading them is a large part of a worker's CPU
    otherwise)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.backends.backend_agg
    import matplotlib.backends.backend_svg  # noqa: F401
    from matplotlib.figure import Figure

    figure = Figure(figsize=(1, 1))
    figure.text(0.5, 0.5, "0")
    figure.canvas.draw()  # the first text drawn in a process loads the font


def draw_figures(tasks: Sequence[FigureTask], figure_dir: Path,
                 workers: int | None = None) -> list[Path | None]:
    """Draw the tasks whose files do not hold their current inputs' digest (the rest are
    kept), in a pool of ``workers`` forked processes (default: the machine's cores) when more
    than one figure is to be drawn; returns each task's file, or None where there was nothing
    to draw.

    Every task is deterministic and writes only its own files, so the pool changes when a
    figure is drawn, never what it holds.
    """
    return start_drawing(tasks, figure_dir, workers)[1]()


def start_drawing(tasks: Sequence[FigureTask], figure_dir: Path, workers: int | None = None,
                  read_records: Callable[[], None] | None = None,
                  on_stale: Callable[[list[Path]], None] | None = None
                  ) -> tuple[list[Path], Callable[[], list[Path | None]]]:
    """:func:`draw_figures` started: the pool's workers draw while this process goes on.

    Returns each task's file as it will be if every figure drawn has something to show,
    and the function that waits for the drawing and returns what :func:`draw_figures` does
    (with one worker, it draws then). The workers are forked here: what they read (the
    tasks, the results) is as it is now.

    ``read_records`` (:func:`read_records`), when given, reads the records here before the
    workers drawing from them are forked, so that they inherit them instead of each reading
    them; the figures that read none (:attr:`FigureTask.reads_records`) are forked first,
    in a pool of their own, and drawn meanwhile. ``on_stale`` is told the files to be
    drawn (the rest are current), before any is.
    """
    global _PENDING
    expected: list[Path] = []
    result: list[Path | None] = []
    stale = []
    for index, task in enumerate(tasks):
        path = figure_dir / task.file
        expected.append(path)
        tag = inputs_digest(task.kind, task.payload)
        if is_current(path, tag, task.svg):
            result.append(path)
        else:
            result.append(None)
            stale.append((index, (task, path, tag)))
    if on_stale is not None:
        on_stale([path for _, (_, path, _) in stale])
    if not stale:  # matplotlib only when something is drawn (its import is a warm report's tenth)
        return expected, lambda: result
    workers = min(workers or os.cpu_count() or 1, len(stale))
    if workers > 1:
        _warm_matplotlib()
    else:
        import matplotlib

        matplotlib.use("Agg")
    # Those that read no record first: forked before the records are read (below).
    stale.sort(key=lambda item: (item[1][0].reads_records,
                                 -_cost(item[1][0].kind)))
    _PENDING = [item for _, item in stale]

    reading = [i for i, (task, _, _) in enumerate(_PENDING) if task.reads_records]
    stages = []  # (pending indexes, the function waiting for their drawing)
    if read_records is not None and reading and workers > 1 and "fork" in (
            multiprocessing.get_all_start_methods()):
        first = range(reading[0])  # read no record
        if len(first):
            stages.append((first, start_forked(_draw_pending, first,
                                               min(len(first), max(1, workers // 2)),
                                               in_background=True)))
        try:
            read_records()
        except BaseException:
            _wait_quietly(stages)  # the first pool ends either way
            _PENDING = []
            raise
        stages.append((reading, start_forked(_draw_pending, reading,
                                             min(len(reading), workers), in_background=True)))
    else:
        stages.append((range(len(_PENDING)),
                       start_forked(_draw_pending, range(len(_PENDING)), workers)))

    def finish() -> list[Path | None]:
        global _PENDING
        drawn: list[str | None] = [None] * len(_PENDING)
        try:
            for number, (indexes, drawing) in enumerate(stages):
                try:
                    files = drawing()
                except BaseException:
                    _wait_quietly(stages[number + 1:])  # every pool ends either way
                    raise
                for index, file in zip(indexes, files):
                    drawn[index] = file
        finally:
            _PENDING = []
        for (index, _), file in zip(stale, drawn):
            result[index] = None if file is None else Path(file)
        return result

    return expected, finish


def _wait_quietly(stages) -> None:
    """Wait for the pools of ``stages`` (``(indexes, wait)`` of :func:`start_drawing`) to end,
    their errors set aside for the one being raised."""
    for _, drawing in stages:
        try:
            drawing()
        except Exception:  # noqa: BLE001, S112 - the error being raised is the one reported
            continue


#: The directories the report makes in its --out (never written through a link planted there).
INNER_DIRECTORIES = (FIGURES, *PAGE_DIRECTORIES)
#: The figures a report wrote into its directory; only these may be removed by a later report.
WRITTEN = ".written-by-report.json"


def _remove_stale_figures(figure_dir: Path, wanted: set) -> None:
    """Remove the figures an earlier report wrote here that this one no longer draws.

    Only files :data:`WRITTEN` lists with the SHA-256 of what the report wrote, still
    holding exactly that, are ever removed, and only when the manifest is sealed under the
    key of the result cache (:func:`harness.store.files.keep_manifest`): a file the report
    did not write -- someone's figure, a tracked file, a name planted in the manifest --
    stays.
    """
    keep_manifest(figure_dir, WRITTEN, wanted, (".png", ".svg"), output_seal())


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--results", type=Path, default=DEFAULT_RESULTS,
                        help=f"results file from `impact-harness run` (default: {DEFAULT_RESULTS})")
    parser.add_argument("--out", type=Path, default=None,
                        help=f"output directory (default: {DEFAULT_OUT}; there only a report "
                        f"of {DEFAULT_RESULTS} replaces an existing one: see --force)")
    parser.add_argument("--force", action="store_true",
                        help=f"without --out, replace the report in {DEFAULT_OUT}/ (its "
                        f"index.html, summary.md and figures) even when made from another "
                        f"results file than {DEFAULT_OUT}/results.json")
    parser.add_argument("--workers", type=bounds.option("workers"), default=None,
                        help="processes drawing the figures (default: all cores; 1: none)")
    parser.add_argument("--scenario-figures", choices=("auto", "all", "none"), default="auto",
                        help="per-scenario figures: all, none, or auto (all up to "
                             f"{MANY_SCENARIOS} scenarios, none above)")
    parser.add_argument("--figures-for", action="append", default=[], metavar="PATTERN",
                        help="draw the figures of the scenarios matching this shell pattern "
                             "anyway (repeatable)")
    parser.add_argument("--svg", choices=("auto", "all", "headline"), default="auto",
                        help="SVG twins of every figure, of the headline figures only, or "
                             f"auto (all up to {MANY_SCENARIOS} scenarios, headline above)")
    add_experiments_data_argument(parser)


def add_experiments_data_argument(parser: argparse.ArgumentParser) -> None:
    """``--experiments-data PATH``, of ``report`` and ``suite``."""
    parser.add_argument("--experiments-data", metavar="PATH", default=None,
                        help="directory of a copy of the Fazeli et al. 2017 drops (default: "
                             "$IMPACT_HARNESS_FAZELI_DIR): the report's 'Against experiments' "
                             "section shows their aggregates (the first time: minutes)")


def experiments_data_problem(path) -> str | None:
    """Why ``--experiments-data`` cannot be used (checked before any work), or None."""
    if path is None:
        return None
    return data_option_problem(path)


def replaces_another_report(results: Path, out: Path) -> bool:
    """Whether writing a report of ``results`` into ``out`` would replace a report made
    from other results: ``out`` holds a report (``index.html``) and ``results`` is not
    the results file in ``out`` (``reports/results.json`` for ``reports/``, which ``run``
    writes and ``make validate`` reports)."""
    if not (out / "index.html").exists():
        return False
    return Path(results).resolve() != (out / DEFAULT_RESULTS.name).resolve()


def main(args) -> int:
    out = args.out
    if out is None:  # the default directory: refuse to replace another results' report
        out = DEFAULT_OUT
        if (not getattr(args, "force", False)
                and replaces_another_report(args.results, out)):
            print(f"impact-harness report: {out}/ holds a report, of "
                  f"{out / DEFAULT_RESULTS.name} when made by the suite, and this one is of "
                  f"{args.results}; write this report "
                  f"elsewhere with --out DIR, or replace it with --force", file=sys.stderr)
            return 2
    problem = output_directory_problem(out) or next(
        filter(None, (inner_directory_problem(out, name) for name in INNER_DIRECTORIES)), None)
    if not problem:  # the page's own files: a link or a device there is refused now
        problem = next(filter(None, (
            f"{name}: {why}" for name in ("index.html", "summary.md", CACHE_FILE, DIGESTS_FILE)
            if (why := replaceable_problem(Path(out) / name)))), None)
    if problem:  # before any work
        print(f"impact-harness report: --out {out}: {problem}", file=sys.stderr)
        return 2
    experiments_data = getattr(args, "experiments_data", None)
    problem = experiments_data_problem(experiments_data)
    if problem:
        print(f"impact-harness report: --experiments-data {experiments_data}: {problem}",
              file=sys.stderr)
        return 2
    try:
        results = read_for_report(args.results)  # the records only when asked for
    except (FileNotFoundError, ValueError) as error:  # the message names the file
        print(f"impact-harness report: {error}", file=sys.stderr)
        return 2
    # The results live as long as this process: out of the collector's sight, which would
    # otherwise walk their millions of containers each time the page's strings set it off.
    gc.freeze()
    start = time.perf_counter()
    # the bench and stress pages beside the results only: a report of a user's results in
    # another directory does not take the library's pages from reports/
    with Progress() as progress:  # on stderr once the report has taken two seconds
        written = write_report(results, out, sources=[args.results.parent],
                               workers=getattr(args, "workers", None),
                               scenario_figures=getattr(args, "scenario_figures", "auto"),
                               figures_for=getattr(args, "figures_for", ()),
                               svg=getattr(args, "svg", "auto"),
                               experiments_data=experiments_data, progress=progress)
    print(f"wrote {written['html']} and {written['summary']} with {len(written['figures'])} "
          f"figures in {time.perf_counter() - start:.1f} s")
    return 0


__all__ = ["add_arguments", "main", "write_report"]
