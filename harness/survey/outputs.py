"""What a survey writes: Parquet tables, the Markdown summary and the figures.

* ``samples.parquet`` -- one row per sample: family, index, drawn parameters, contact terms,
  Routh coordinates and every law's collision type, status and energy change;
* ``runs.parquet`` -- one row per sample × engine × preset (harness/survey/statistics.py);
* ``statistics.parquet`` -- one row per engine × preset × family × Poisson type;
* ``summary.md`` -- the statistics as Markdown tables, the rejected draws and the timings;
* ``figures/`` -- departure from Poisson against ``α / r_m`` and ``μ`` coloured by Poisson
  collision type, per engine and preset; the departure CDF per engine, a line per family and
  preset. PNG and SVG.

Each table is one ``pandas.read_parquet(path)`` or ``polars.read_parquet(path)`` call.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from harness.engines import preset_label

TYPE_NAMES = {1: "1 stick (compr.)", 2: "2 stick (restit.)", 3: "3 reverse (compr.)",
              4: "4 reverse (restit.)", 5: "5 forward slide"}


def write_parquet(columns: dict, path: Path) -> Path:
    """Write ``{name: array}`` as one Parquet table."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    table = pa.table({name: _arrow_values(values) for name, values in columns.items()})
    pq.write_table(table, path)
    return path


def _arrow_values(values):
    values = np.asarray(values)
    if values.dtype.kind in "OU":
        return [str(v) for v in values]
    return values


def _number(value: float) -> str:
    if value is None or not math.isfinite(value):
        return "–"
    if value == 0.0:
        return "0"
    return f"{value:.2g}" if abs(value) < 0.01 else f"{value:.3f}"


def _percent(value: float) -> str:
    return "–" if not math.isfinite(value) else f"{100 * value:.1f}%"


def markdown_table(stats: dict, types: str = "all") -> str:
    """The statistics as a Markdown table: ``types="all"`` the rows over every type,
    ``"each"`` the rows per Poisson type."""
    header = ("| engine | preset | family | type | n | flagged | gains E | from Poisson: "
              "median | p90 | p99 | max | from Stronge: median | p90 | max | law part: median "
              "| solve part: median | p90 |")
    lines = [header, "|" + "---|" * (header.count("|") - 1)]
    for row in range(len(stats.get("engine", ()))):
        kind = int(stats["poisson_type"][row])
        if (types == "all") != (kind == 0):
            continue
        value = {key: stats[key][row] for key in stats}
        lines.append(
            f"| {value['engine']} | {preset_label(value['engine'], value['preset'])} | "
            f"{value['family']} | "
            f"{'all' if kind == 0 else kind} | {value['n']} | "
            f"{_percent(value['flagged_fraction'])} | {_percent(value['energy_gain_fraction'])} | "
            f"{_number(value['departure_poisson_median'])} | "
            f"{_number(value['departure_poisson_p90'])} | "
            f"{_number(value['departure_poisson_p99'])} | "
            f"{_number(value['departure_poisson_max'])} | "
            f"{_number(value['departure_stronge_median'])} | "
            f"{_number(value['departure_stronge_p90'])} | "
            f"{_number(value['departure_stronge_max'])} | "
            f"{_number(value['law_part_median'])} | {_number(value['solve_part_median'])} | "
            f"{_number(value['solve_part_p90'])} |")
    return "\n".join(lines)


def reason_table(stats: dict) -> str:
    """Per engine × preset × family, the fraction of runs failing each verdict reason that
    any run fails."""
    reasons = [key for key in stats if key.startswith("flagged_") and key != "flagged_fraction"
               and np.any(np.asarray(stats[key]) > 0)]
    names = [key.removeprefix("flagged_") for key in reasons]
    lines = ["| engine | preset | family | n | flagged | " + " | ".join(names) + " |",
             "|---|---|---|---|---|" + "---|" * len(names)]
    for row in range(len(stats.get("engine", ()))):
        if int(stats["poisson_type"][row]) != 0:
            continue
        lines.append(f"| {stats['engine'][row]} | {stats['preset'][row]} | "
                     f"{stats['family'][row]} | {stats['n'][row]} | "
                     f"{_percent(stats['flagged_fraction'][row])} | "
                     + " | ".join(_percent(stats[key][row]) for key in reasons) + " |")
    return "\n".join(lines)


def summary_markdown(stats: dict, rejections: dict, timings: dict, settings: dict) -> str:
    """The whole ``summary.md``."""
    lines = [
        "# Survey: departures over families of impacts",
        "",
        (f"Samples per family: {settings['samples']}, seed {settings['seed']}; engines "
         f"{', '.join(settings['engines']) or 'none'}; presets "
         f"{', '.join(settings['presets'])}."
         + "".join(f" Not run: {label} ({why})." for label, why in
                   settings.get("left_out", {}).items())),
        ("Departure = ‖u − u_law‖_M / ‖u_before‖_M (kinetic-energy norm; two free bodies in "
         "their centre of mass's frame). Quantiles over runs judged one impact by the verdict "
         "checks (docs/verdicts.md); *flagged* = runs failing a check, kept out of the "
         "quantiles and counted by reason below; *gains E* = ok runs ending "
         "with more kinetic energy than they began with (by more than 1e-9 of it). "
         "*law part* = newton-lcp from Poisson, *solve part* = engine from newton-lcp."),
        "",
        "## Every collision type",
        "",
        markdown_table(stats, "all"),
        "",
        "## Flagged runs by reason (every collision type)",
        "",
        "A run failing several checks counts under each.",
        "",
        reason_table(stats),
        "",
        "## Per Poisson collision type",
        "",
        ("Types: 1 sticking in compression, 2 sticking in restitution, 3 reverse sliding from "
         "compression, 4 reverse sliding from restitution, 5 forward sliding."),
        "",
        markdown_table(stats, "each"),
        "",
        "## Rejected draws (redrawn, by reason)",
        "",
        "| family | accepted | " + " | ".join(next(iter(rejections.values()), {}).keys()) + " |",
        "|---|---|" + "---|" * len(next(iter(rejections.values()), {})),
    ]
    for family, reasons in rejections.items():
        lines.append(f"| {family} | {settings['samples']} | "
                     + " | ".join(str(count) for count in reasons.values()) + " |")
    lines += ["", "## Timings", "", "| stage | seconds | per impact (µs) |", "|---|---|---|"]
    for stage, (seconds, impacts) in timings.items():
        per = "" if not impacts else f"{seconds / impacts * 1e6:.1f}"
        lines.append(f"| {stage} | {seconds:.3f} | {per} |")
    return "\n".join(lines) + "\n"


def _save(figure, stem: Path) -> list[Path]:
    paths = [stem.with_suffix(".png"), stem.with_suffix(".svg")]
    for path in paths:
        figure.savefig(path, dpi=110 if path.suffix == ".png" else None)
    return paths


def _log_axis(axis, which: str) -> None:
    """Log scale with plain ``1e-05`` labels: mathtext tick labels cost most of a figure."""
    from matplotlib import ticker

    getattr(axis, f"set_{which}scale")("log")
    target = axis.xaxis if which == "x" else axis.yaxis
    target.set_major_locator(ticker.LogLocator(numticks=6))
    target.set_major_formatter(ticker.LogFormatter(labelOnlyBase=True))
    target.set_minor_locator(ticker.NullLocator())


def figures(runs: dict, directory: Path) -> list[Path]:
    """Per engine, a departure map (a row per preset) and the CDFs (a panel per preset, a
    line per family); returns the files written."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    directory.mkdir(parents=True, exist_ok=True)
    written: list[Path] = []
    colours = plt.get_cmap("tab10")
    floor = 1e-8  # departures below are drawn at the floor (log axis; exact agreement is 0)
    ok = runs["status"] == "ok"
    families = sorted(set(runs["family"]))
    for engine in sorted(set(runs["engine"])):
        presets = sorted(set(runs["preset"][runs["engine"] == engine]))
        # constrained layout: fixed fractions clipped the x labels of a one-preset figure
        figure, axes = plt.subplots(len(presets), 2, figsize=(10, 3.6 * len(presets)),
                                    squeeze=False, layout="constrained")
        for (left, right), preset in zip(axes, presets):
            chosen = ok & (runs["engine"] == engine) & (runs["preset"] == preset)
            departure = np.maximum(runs["departure_poisson"][chosen], floor)
            kinds = runs["poisson_type"][chosen]
            # α = 0 (no initial slip) sits at the left edge of the log axis.
            ratio = np.maximum(runs["alpha_over_rm"][chosen], 1e-3)
            for kind, label in TYPE_NAMES.items():
                mine = kinds == kind
                if mine.any():
                    left.scatter(ratio[mine], departure[mine], s=5, color=colours(kind - 1),
                                 label=label, alpha=0.7, rasterized=True)
                    right.scatter(runs["mu"][chosen][mine], departure[mine], s=5,
                                  color=colours(kind - 1), alpha=0.7, rasterized=True)
            left.axvline(1.0, color="0.5", lw=0.8)
            _log_axis(left, "x")
            for axis in (left, right):
                _log_axis(axis, "y")
            left.set_ylabel(f"{preset_label(engine, preset)}: departure from Poisson")
            right.set_xlabel("μ")
            left.set_xlabel("α / r_m (Table 1 cases 1–3: types change at 1 and 1 + e)")
        axes[0][0].legend(fontsize=7, markerscale=2)
        figure.suptitle(f"{engine}: where on Routh's map it departs from Poisson")
        written += _save(figure, directory / f"map-{engine}")
        plt.close(figure)

        figure, axes = plt.subplots(1, len(presets), figsize=(5 * len(presets), 3.8),
                                    sharey=True, squeeze=False, layout="constrained")
        for axis, preset in zip(axes[0], presets):
            for index, family in enumerate(families):
                chosen = (ok & (runs["engine"] == engine) & (runs["preset"] == preset)
                          & (runs["family"] == family))
                values = np.sort(np.maximum(runs["departure_poisson"][chosen], floor))
                if values.size:
                    axis.step(values, np.arange(1, values.size + 1) / values.size,
                              where="post", color=colours(index), label=family)
            _log_axis(axis, "x")
            axis.set_xlabel("departure from Poisson")
            axis.set_title(f"{engine} {preset_label(engine, preset)}")
        axes[0][0].set_ylabel("fraction of ok runs ≤ x")
        axes[0][0].legend(fontsize=7)
        written += _save(figure, directory / f"cdf-{engine}")
        plt.close(figure)
    return written
