"""``impact-harness report``: ``reports/index.html`` and ``reports/summary.md`` from results.

::

    impact-harness report                                  # reports/results.json -> reports/
    impact-harness report --results /tmp/r.json --out /tmp/report

The HTML page is self-contained (inline CSS, no scripts, no external assets); its figures are
PNG files in ``<out>/figures/`` beside it, and the Table 3 reproduction
(``<out>/paper-table3.md`` and ``.png``, written by ``impact-harness paper``) is embedded
when present. Matplotlib (Agg) draws the figures; nothing here touches an engine or re-solves
a scenario except the impulse paths of Routh's graph, which ``planar_impact.impulse_process``
walks from the contact-space numbers stored in the results.

What the page shows, in order: what this is; the headline heat maps (departure of every
engine and preset from Poisson and from Stronge, per scenario); the split of each engine's
departure into the law it solves and how well it solves it; the gates; per scenario the
post-impact velocities of every law and engine side by side, the energy change and the
impulse diagram (Fig. 1 of the paper), or for sweeps the post-impact quantities against the
swept parameter with the Poisson type boundaries marked; Table 3; versions and settings.
"""


from __future__ import annotations

import argparse
import json
import sys
import time
from collections.abc import Sequence
from pathlib import Path

from harness.report.figures import (
    heatmap_figure,
    impulse_figure,
    impulse_legend_figure,
    render_once,
    split_figure,
    stable_record,
    sweep_figure,
    table3_figure,
    table3_inputs,
)
from harness.report.history import history_figure, history_inputs
from harness.report.html import write_html
from harness.report.pages import write_pages
from harness.report.summary import write_summary
from harness.report.views import FIGURES, slug, split_rows
from harness.run.records import DEFAULT_RESULTS, Results, read_results


def write_report(results: Results, out_dir: Path | str,
                 sources: Sequence[Path] = (DEFAULT_RESULTS.parent,)) -> dict:
    """Write index.html, summary.md, the figures (PNG and SVG) and, when the benchmark's
    ``bench.json`` or the stress test's ``stress.md`` exist (in ``bench/`` and ``stress/``
    under ``out_dir`` or one of ``sources``, by default where ``bench`` and ``stress`` write
    them), their pages;
    returns the paths written."""
    import matplotlib

    matplotlib.use("Agg")
    out_dir = Path(out_dir)
    figure_dir = out_dir / FIGURES
    figure_dir.mkdir(parents=True, exist_ok=True)
    figures: dict = {"impulse": {}, "sweep": {}}
    engines = list(dict.fromkeys(label.split(".")[0] for label in results.engine_labels()))
    if render_once("legend", figure_dir / "impulse-legend.png", engines,
                   lambda path, tag: impulse_legend_figure(path, tag, engines)):
        figures["legend"] = "impulse-legend.png"
    stable = {name: [stable_record(r) for r in results.for_scenario(name)]
              for name in results.scenario_names()}
    if render_once("heatmap", figure_dir / "heatmap.png", stable,
               lambda path, tag: heatmap_figure(results, path, tag)):
        figures["heatmap"] = "heatmap.png"
    rows = split_rows(results)
    if render_once("split", figure_dir / "split.png", rows,
               lambda path, tag: split_figure(rows, path, tag)):
        figures["split"] = "split.png"
    for name in results.scenario_names():
        records = results.for_scenario(name)
        info = results.scenarios.get(name, {})
        # render_once calls its draw before returning: the closures use this pass's values
        if info.get("sweep"):
            file = f"sweep-{slug(name)}.png"
            if render_once("sweep", figure_dir / file, [name, info, stable[name]],
                       lambda path, tag: sweep_figure(name, info, records, path, tag)):  # noqa: B023
                figures["sweep"][name] = file
        else:
            file = f"impulse-{slug(name)}.png"
            if render_once("impulse", figure_dir / file, [name, stable[name]],
                       lambda path, tag: impulse_figure(name, records, path, tag)):  # noqa: B023
                figures["impulse"][name] = file
            file = f"history-{slug(name)}.png"  # the contact in time (harness.report.history)
            if render_once("history", figure_dir / file, history_inputs(name, records),
                           lambda path, tag, name=name, records=records:
                           history_figure(name, records, path, tag)):
                figures.setdefault("history", {})[name] = file
    if render_once("table3", figure_dir / "paper-table3.png", table3_inputs(),
                   lambda path, tag: table3_figure(path, tag)):
        figures["table3"] = "paper-table3.png"
    pages = write_pages(out_dir, sources)
    wanted = {figures.get("heatmap"), figures.get("table3"), figures.get("split"),
              figures.get("legend"),
              *figures["impulse"].values(), *figures.get("history", {}).values(),
              *figures["sweep"].values()}
    wanted.discard(None)
    # every figure is drawn as PNG and SVG: both are this report's
    wanted |= {str(Path(name).with_suffix(".svg")) for name in wanted}
    _remove_stale_figures(figure_dir, wanted)
    html_path = write_html(results, out_dir, figures, rows, pages)
    summary = write_summary(results, out_dir)
    return {"html": html_path, "summary": summary,
            "figures": sorted(figure_dir / f for f in wanted if f.endswith(".png"))}


#: The figures a report wrote into its directory; only these may be removed by a later report.
WRITTEN = ".written-by-report.json"


def _remove_stale_figures(figure_dir: Path, wanted: set) -> None:
    """Remove the figures an earlier report wrote here that this one no longer draws.

    Only names listed in :data:`WRITTEN` (by an earlier report) are ever removed: a file the
    report did not write -- someone's figure, a tracked file -- stays.
    """
    manifest = figure_dir / WRITTEN
    try:
        written_before = set(json.loads(manifest.read_text(encoding="utf-8")))
    except (OSError, ValueError, TypeError):
        written_before = set()
    for name in sorted(written_before - wanted):
        stale = figure_dir / name
        if Path(name).name == name and stale.suffix in (".png", ".svg"):  # only figures/
            stale.unlink(missing_ok=True)
    manifest.write_text(json.dumps(sorted(wanted), indent=0) + "\n", encoding="utf-8")


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--results", type=Path, default=DEFAULT_RESULTS,
                        help=f"results file from `impact-harness run` (default: {DEFAULT_RESULTS})")
    parser.add_argument("--out", type=Path, default=Path("reports"),
                        help="output directory (default: reports)")


def main(args) -> int:
    try:
        results = read_results(args.results)
    except (FileNotFoundError, ValueError) as error:  # the message names the file
        print(f"impact-harness report: {error}", file=sys.stderr)
        return 2
    start = time.perf_counter()
    written = write_report(results, args.out, sources=[args.results.parent, Path("reports")])
    print(f"wrote {written['html']} and {written['summary']} with {len(written['figures'])} "
          f"figures in {time.perf_counter() - start:.1f} s")
    return 0


__all__ = ["add_arguments", "main", "write_report"]
