"""What a survey writes: Parquet tables, the Markdown summary and the figures.

* ``samples.parquet`` -- one row per sample: family, index, drawn parameters, contact terms,
  Routh coordinates and every law's collision type, status and energy change;
* ``runs.parquet`` -- one row per sample × engine × preset (harness/survey/statistics.py);
* ``statistics.parquet`` -- one row per engine × preset × family × Poisson type;
* ``summary.md`` -- the statistics as Markdown tables, the rejected draws and the timings;
* ``settings.json`` -- what was surveyed: samples, seed, engines, presets, the engines not
  installed and the pairs left out (with why), the runs whose engine raised
  (``engine_errors``: their count and the first :data:`SHOWN_ERRORS`), and under ``inputs``
  the digest ``impact-harness suite`` keys its quick survey by (harness/suite.py);
* ``figures/`` -- departure from Poisson against ``α / r_m`` and ``μ`` coloured by Poisson
  collision type, per engine and preset (:func:`map_figure`); the departure CDF per engine,
  a line per family and preset (:func:`cdf_figure`). PNG and SVG. ``impact-harness suite``
  writes none here: its report draws them from ``runs.parquet``, keyed by their inputs like
  its other figures (harness/report/survey.py).

Each table is one ``pandas.read_parquet(path)`` or ``polars.read_parquet(path)`` call.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np

from harness.engines import PRESET_ROLES, preset_label
from harness.plotting import new_figure, percent_tick, save_png
from harness.run.metrics import (
    SCIENTIFIC_BELOW_PERCENT,
    fmt_departure,
    fmt_departures,
)
from harness.store.files import make_inner_directory, write_bytes_atomically

TYPE_NAMES = {1: "1 stick (compr.)", 2: "2 stick (restit.)", 3: "3 reverse (compr.)",
              4: "4 reverse (restit.)", 5: "5 forward slide"}


#: Units of the survey tables' columns, stored in each column's Parquet metadata ("unit").
#: Departures are fractions of the speed scale (docs/verdicts.md); the reports show them in
#: percent.
UNITS = {
    "departure_poisson": "fraction", "departure_stronge": "fraction", "law_part": "fraction",
    "solve_part": "fraction", "energy_change_relative": "fraction", "mu": "1", "e": "1",
    "friction": "1", "restitution": "1", "alpha": "1", "r_m": "1", "alpha_over_rm": "1",
    "speed": "m/s", "direction_deg": "deg", "placement_deg": "deg", "mass_ratio": "1",
    "vn": "m/s", "vt": "m/s", "mnn": "1/kg", "mnt": "1/kg", "mtt": "1/kg", "steps": "1",
    "flagged_fraction": "fraction", "energy_gain_fraction": "fraction",
}
#: Units of a drawn body parameter, by the part after the body's name (``box.width``).
BODY_UNITS = {"mass": "kg", "angle_deg": "deg", "angular_velocity": "rad/s", "width": "m",
              "height": "m", "length": "m", "radius": "m", "sides": "1"}
#: The key of the table-wide metadata (JSON): what was surveyed, with which versions.
METADATA_KEY = "impact_harness"


def column_unit(name: str) -> str | None:
    """The unit of a survey column, or None where it has none (names, codes, flags)."""
    if name in UNITS:
        return UNITS[name]
    if name.startswith(("departure_", "flagged_")) or name.endswith(".from_poisson"):
        return "fraction"  # quantiles, intervals and reason shares of the departures
    if name.endswith(".energy_change"):
        return "J"
    _, _, field = name.rpartition(".")
    return BODY_UNITS.get(field) if "." in name else None


def write_parquet(columns: dict, path: Path, metadata: dict | None = None,
                  row_group_size: int | None = None) -> Path:
    """Write ``{name: array}`` as one Parquet table; each column carries its unit
    (:func:`column_unit`) and the table ``metadata`` as JSON under :data:`METADATA_KEY`.
    A column of comma-joined names (a run's failing ``reasons``) is written as a list column.
    ``row_group_size``: rows per row group (default pyarrow's: one group here)."""

    import pyarrow as pa
    import pyarrow.parquet as pq

    fields, arrays = [], []
    for name, values in columns.items():
        if name == "reasons":
            array = pa.array([[part for part in str(text).split(",") if part]
                              for text in np.asarray(values).tolist()], pa.list_(pa.string()))
        else:
            array = pa.array(_arrow_values(values))
        unit = column_unit(name)
        fields.append(pa.field(name, array.type,
                               metadata=None if unit is None else {"unit": unit}))
        arrays.append(array)
    schema = pa.schema(fields, metadata=None if metadata is None else {
        METADATA_KEY: json.dumps(metadata, sort_keys=True, default=str)})

    buffer = pa.BufferOutputStream()
    pq.write_table(pa.Table.from_arrays(arrays, schema=schema), buffer,
                   row_group_size=row_group_size)
    write_bytes_atomically(path, buffer.getvalue().to_pybytes())  # over a regular file only
    return path


def _arrow_values(values):
    values = np.asarray(values)
    if values.dtype.kind in "OU":
        return [str(v) for v in values]
    return values


def _percent(value: float) -> str:
    return "–" if not math.isfinite(value) else f"{100 * value:.1f}%"


def _with_interval(value: dict, prefix: str) -> str:
    """A quantile in percent with its bootstrap interval: ``2.6% [1.1%, 4.0%]``."""
    low, high = value.get(f"{prefix}_low"), value.get(f"{prefix}_high")
    if low is None or high is None or not (math.isfinite(low) and math.isfinite(high)):
        return fmt_departure(value[prefix])
    text, low_text, high_text = fmt_departures([value[prefix], low, high])  # each as alone
    return f"{text} [{low_text}, {high_text}]"


def markdown_table(stats: dict, types: str = "all") -> str:
    """The statistics as a Markdown table, departures in percent: ``types="all"`` the rows
    over every type, ``"each"`` the rows per Poisson type."""
    header = ("| engine | preset | family | type | n | flagged | gains E | from Poisson, checked "
              "runs: median [95% CI] | p90 [95% CI] | max | from Poisson, all runs: median "
              "[95% CI] | p90 [95% CI] | from Stronge, checked: median | p90 | law part: median "
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
            f"{'all types' if kind == 0 else kind} | {value['n']} | "
            f"{_percent(value['flagged_fraction'])} | {_percent(value['energy_gain_fraction'])} | "
            f"{_with_interval(value, 'departure_poisson_median')} | "
            f"{_with_interval(value, 'departure_poisson_p90')} | "
            f"{fmt_departure(value['departure_poisson_max'])} | "
            f"{_with_interval(value, 'departure_poisson_all_median')} | "
            f"{_with_interval(value, 'departure_poisson_all_p90')} | "
            f"{fmt_departure(value['departure_stronge_median'])} | "
            f"{fmt_departure(value['departure_stronge_p90'])} | "
            f"{fmt_departure(value['law_part_median'])} | "
            f"{fmt_departure(value['solve_part_median'])} | "
            f"{fmt_departure(value['solve_part_p90'])} |")
    return "\n".join(lines)


def _ordinal(rank: int) -> str:
    """``2`` -> ``"2nd"``, ``11`` -> ``"11th"``, ``21`` -> ``"21st"``."""
    suffix = "th" if rank % 100 in (11, 12, 13) else {1: "st", 2: "nd", 3: "rd"}.get(
        rank % 10, "th")
    return f"{rank}{suffix}"


def p90_runs(count: int) -> str:
    """Which of ``count`` runs a p90 is (numpy's linear quantile, as
    harness/survey/statistics.py computes it): ``"the only run"``, ``"the 2nd largest"``,
    ``"between the 3rd and 2nd largest"`` or ``"between the 2nd largest and the largest"``."""
    if count == 1:
        return "the only run"
    virtual = (count - 1) * 0.9  # the p90's index among the runs sorted, from 0
    below = math.floor(virtual + 1e-9)  # 0.9 × 10 is 9 for the rank, not 8.999…
    lower = count - below  # that run's rank from the top, 1 the largest
    if virtual - below < 1e-9:
        return f"the {_ordinal(lower)} largest"
    if lower == 2:
        return "between the 2nd largest and the largest"
    return f"between the {_ordinal(lower)} and {_ordinal(lower - 1)} largest"


def p90_note(stats: dict, types: str = "all") -> str:
    """What a p90 is of the fewest and the most runs a p90 of the table's rows (``types`` as
    :func:`markdown_table`'s) is taken over, checked runs or all of them: a sentence."""
    rows = [row for row in range(len(stats.get("engine", ())))
            if (types == "all") == (int(stats["poisson_type"][row]) == 0)]
    counts = sorted({int(stats[key][row]) for row in rows for key in ("n", "n_ok")
                     if key in stats} - {0})
    if not counts:
        return ""
    fewest, most = counts[0], counts[-1]
    if fewest == most:
        return f"Every p90 here is of {most} runs: {p90_runs(most)}."
    return (f"A p90 here is of {fewest} to {most} runs (a group's checked runs or all of "
            f"them): of {fewest}, {p90_runs(fewest)}; of {most}, {p90_runs(most)}.")


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
        engine = stats["engine"][row]
        lines.append(f"| {engine} | {preset_label(engine, stats['preset'][row])} | "
                     f"{stats['family'][row]} | {stats['n'][row]} | "
                     f"{_percent(stats['flagged_fraction'][row])} | "
                     + " | ".join(_percent(stats[key][row]) for key in reasons) + " |")
    return "\n".join(lines)


def _preset_names(settings: dict) -> list[str]:
    """The surveyed preset roles, each with the names the surveyed engines give it where they
    rename it: ``accurate (mujoco: matched-bounce)``."""
    names = []
    for role in settings["presets"]:
        renamed = [f"{engine}: {preset_label(engine, role)}" for engine in settings["engines"]
                   if preset_label(engine, role) != role]
        names.append(f"{role} ({', '.join(renamed)})" if renamed else role)
    return names


def summary_markdown(stats: dict, rejections: dict, timings: dict, settings: dict,
                     skipped_runs: dict | None = None, engine_errors=()) -> str:
    """The whole ``summary.md``; ``skipped_runs``: ``{"engine preset": ({family: runs},
    why)}`` of the runs an engine could not build, ``engine_errors``: ``[pair, family,
    sample, why]`` of the runs whose engine raised (both left out of the statistics)."""
    lines = [
        "# Survey: departures over families of impacts",
        "",
        (f"Samples per family: {settings['samples']}, seed {settings['seed']}; engines "
         f"{', '.join(settings['engines']) or 'none'}; presets "
         f"{', '.join(_preset_names(settings))}."
         + "".join(f" Not run: {label} ({why})." for label, why in
                   settings.get("left_out", {}).items())
         + "".join(f" Not installed: {engine} ({why})." for engine, why in
                   settings.get("skipped", {}).items())
         + "".join(f" Settings changed from every {engine} preset by --set: "
                   + ", ".join(f"{key}={json.dumps(value)}" for key, value in values.items())
                   + "." for engine, values in settings.get("overrides", {}).items())
         + (f" **Engine errors: {len(engine_errors)} runs raised** (listed under *Engine "
            "errors*, in no statistic)." if engine_errors else "")),
        ("Departure = ‖u − u_law‖_M / ‖u_before‖_M (kinetic-energy norm; two free bodies in "
         "their centre of mass's frame), in percent: decimals down to "
         f"{SCIENTIFIC_BELOW_PERCENT:g}%, scientific notation below it, each number alike "
         "wherever it stands. *Checked runs*: the runs judged one impact "
         "by the verdict checks (docs/verdicts.md); *all runs*: every run, flagged ones "
         "included, so a large flagged share cannot hide the worst runs; *flagged* = runs "
         "failing a check, counted by reason below. [95% CI]: a percentile-bootstrap "
         "interval (1,000 resamples of the group's runs). " + p90_note(stats, "all")
         + " *gains E* = checked runs ending "
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
         "compression, 4 reverse sliding from restitution, 5 forward sliding. "
         + p90_note(stats, "each")),
        "",
        markdown_table(stats, "each"),
        "",
        *skipped_lines(skipped_runs or {}),
        *error_lines(engine_errors),
        "## Rejected draws (redrawn, by reason)",
        "",
        "| family | accepted | " + " | ".join(next(iter(rejections.values()), {}).keys()) + " |",
        "|---|---|" + "---|" * len(next(iter(rejections.values()), {})),
    ]
    impacts = settings["samples"] * len(rejections)  # every family, samples each
    for family, reasons in rejections.items():
        lines.append(f"| {family} | {settings['samples']} | "
                     + " | ".join(str(count) for count in reasons.values()) + " |")
    lines += ["", "## Timings", "", timings_caption(timings, impacts), "",
              timings_table(timings, impacts)]
    return "\n".join(lines) + "\n"


def skipped_lines(skipped_runs: dict) -> list[str]:
    """The summary's section on runs an engine could not build (none: no lines)."""
    if not skipped_runs:
        return []
    lines = ["## Skipped runs (the engine cannot build the scene)", "",
             "Left out of every statistic above, as `impact-harness run` records such a "
             "run `skipped`.", "", "| engine preset | family | runs | why (first) |",
             "|---|---|---|---|"]
    for pair, (counts, why) in skipped_runs.items():
        for family, count in counts.items():
            lines.append(f"| {pair} | {family} | {count} | {why} |")
    return lines + [""]


#: Errored runs the summary lists one by one (the rest are counted, and in ``runs.parquet``).
SHOWN_ERRORS = 50


def error_lines(engine_errors) -> list[str]:
    """The summary's section on runs whose engine raised (none: no lines): the count per
    engine × preset × family, then each run with its reason (the first
    :data:`SHOWN_ERRORS`)."""
    if not len(engine_errors):
        return []
    counts: dict[tuple[str, str], int] = {}
    for pair, family, _sample, _why in engine_errors:
        counts[(pair, family)] = counts.get((pair, family), 0) + 1
    lines = ["## Engine errors (the engine raised)", "",
             "The engine's run of these scenes raised an exception: recorded with status "
             "`error` and the exception's type and first line (column `error` of "
             "`runs.parquet`), left out of every statistic above (counted in `n_error`), as "
             "`impact-harness run` records an engine error; the survey exits 4. The other "
             "runs are a lone run's, bit for bit.", "",
             "| engine preset | family | runs |", "|---|---|---|"]
    lines += [f"| {pair} | {family} | {count} |" for (pair, family), count in counts.items()]
    lines += ["", "| engine preset | family | sample | error |", "|---|---|---|---|"]
    lines += [f"| {pair} | {family} | {sample} | {_table_cell(why)} |"
              for pair, family, sample, why in engine_errors[:SHOWN_ERRORS]]
    if len(engine_errors) > SHOWN_ERRORS:
        lines += ["", f"{len(engine_errors) - SHOWN_ERRORS} more: the rows of `runs.parquet` "
                      "with status `error`."]
    return lines + [""]


def _table_cell(text: str) -> str:
    """``text`` in a Markdown table cell: its bars escaped."""
    return str(text).replace("|", "\\|")


def timings_caption(timings: dict, impacts: int) -> str:
    """What the timings table divides by what (``timings``: ``{stage: (seconds, engine
    runs)}``, harness/survey/cli.py's ``run_survey``)."""
    # the stages over every pair cover the most engine runs: impacts × pairs
    pairs = max((runs // impacts for _, runs in timings.values() if impacts), default=0)
    return (f"*Per impact*: the stage's seconds ÷ the {impacts:,} impacts (samples × families), "
            "on every row. *Per engine run*: the stage's seconds ÷ the engine runs it covers, "
            f"one per impact and engine/preset pair: {impacts:,} on a pair's own rows"
            + (f", {impacts * pairs:,} ({impacts:,} × {pairs} pairs) on the rows over every "
               "pair" if pairs > 1 else "")
            + "; blank where the stage runs no engine. The sampling, laws, verdict terms, "
            "engine and verdicts rows are seconds on one core summed over the parts; *parts* "
            "is the wall time of them all.")


def timings_table(timings: dict, impacts: int) -> str:
    """The timings as a Markdown table: seconds, per impact and per engine run, in µs
    (:func:`timings_caption` says what each divides by)."""
    lines = ["| stage | seconds | per impact (µs) | per engine run (µs) |", "|---|---|---|---|"]
    for stage, (seconds, runs) in timings.items():
        per_impact = "" if not impacts else f"{seconds / impacts * 1e6:.1f}"
        per_run = "" if not runs else f"{seconds / runs * 1e6:.1f}"
        lines.append(f"| {stage} | {seconds:.3f} | {per_impact} | {per_run} |")
    return "\n".join(lines)


def _log_axis(axis, which: str, ticks: int = 6) -> None:
    """Log scale with plain labels, ``0.01`` to ``1000`` as decimals and ``1e-05`` beyond
    (mathtext tick labels cost most of a figure), about ``ticks`` of them."""
    from matplotlib import ticker

    getattr(axis, f"set_{which}scale")("log")
    target = axis.xaxis if which == "x" else axis.yaxis
    target.set_major_locator(ticker.LogLocator(numticks=ticks))
    target.set_major_formatter(ticker.FuncFormatter(_decade_label))
    target.set_minor_locator(ticker.NullLocator())


def _decade_label(value: float, _=None) -> str:
    """A log axis's tick: ``0.01``, ``0.1``, ``1``, ``10``, ``100``, ``1000``, else ``1e-05``."""
    if 0.01 <= value <= 1000:
        return f"{value:g}"
    return f"{value:.0e}"


#: Departures below are drawn at this floor (log axes; exact agreement is 0).
DEPARTURE_FLOOR = 1e-8
#: Resolution of the survey's PNGs.
FIGURE_DPI = 110
#: Colour and marker of each Poisson collision type on the maps (Okabe-Ito colours, told
#: apart with the common colour-vision deficiencies too; a marker each for grey print):
#: sticking blue, reverse sliding orange, forward sliding green, restitution the lighter.
TYPE_STYLE = {1: ("#0072B2", "o"), 2: ("#56B4E9", "s"), 3: ("#D55E00", "^"),
              4: ("#E69F00", "v"), 5: ("#009E73", "D")}


def figure_engines(runs: dict) -> list[str]:
    """The engines with runs in ``runs``, one map and one CDF figure each."""
    return sorted(set(np.asarray(runs["engine"]).tolist()))


def _presets(runs: dict, engine: str) -> list[str]:
    """``engine``'s presets in ``runs``, out of the box first (:data:`PRESET_ROLES`'s order)."""
    present = set(np.asarray(runs["preset"])[np.asarray(runs["engine"]) == engine].tolist())
    return sorted(present, key=lambda preset: (PRESET_ROLES.index(preset)
                                               if preset in PRESET_ROLES else 99, preset))


def _floor_axis(target) -> None:
    """Percent tick labels, the floor's written ``≤ floor``: every departure at or below it
    (exact agreement among them) is drawn there."""
    from matplotlib.ticker import FuncFormatter


    def label(value, _):
        text = percent_tick(value)
        return f"≤{text}" if value <= DEPARTURE_FLOOR * 1.001 else text

    target.set_major_formatter(FuncFormatter(label))


def map_figure(runs: dict, engine: str, path: Path, tag: str | None = None) -> Path:
    """Departure from Poisson against ``α / r_m`` and against ``μ``, a point per ok run of
    ``engine``, coloured by the Poisson collision type; a row per preset. Saved as ``path``
    (PNG, with its SVG twin unless :data:`harness.plotting.SVG_TWIN` says not;
    ``tag``: the digest of the inputs, kept in the PNG)."""
    presets = _presets(runs, engine)
    ok = runs["status"] == "ok"
    figure = new_figure(10, 3.2 * len(presets) + 0.5)
    # one scale for every panel: the presets compared at a glance
    axes = figure.subplots(len(presets), 2, squeeze=False, sharex="col", sharey=True)
    for (left, right), preset in zip(axes, presets):
        chosen = ok & (runs["engine"] == engine) & (runs["preset"] == preset)
        departure = np.maximum(runs["departure_poisson"][chosen], DEPARTURE_FLOOR)
        kinds = runs["poisson_type"][chosen]
        # α = 0 (no initial slip) sits at the left edge of the log axis.
        ratio = np.maximum(runs["alpha_over_rm"][chosen], 1e-3)
        for kind, label in TYPE_NAMES.items():
            mine = kinds == kind
            if mine.any():
                colour, marker = TYPE_STYLE[kind]
                style = {"s": 14, "color": colour, "marker": marker, "alpha": 0.8,
                         "rasterized": True, "linewidths": 0}
                left.scatter(ratio[mine], departure[mine], label=label, **style)
                right.scatter(runs["mu"][chosen][mine], departure[mine], **style)
        left.axvline(1.0, color="0.5", lw=0.8)
        _log_axis(left, "x")
        for axis in (left, right):
            _log_axis(axis, "y", ticks=12)  # every decade: where 10% ends and 1% begins
            axis.grid(True, which="major", color="0.92", lw=0.6)
        _floor_axis(left.yaxis)
        left.set_ylabel("departure from Poisson")
        left.set_title(f"{preset_label(engine, preset)}: against α / r_m", fontsize=11)
        right.set_title(f"{preset_label(engine, preset)}: against μ", fontsize=11)
    axes[-1][0].set_xlabel("α / r_m (initial slip over Routh's sticking ratio; grey line: 1)")
    axes[-1][1].set_xlabel("μ")
    handles, labels = axes[0][0].get_legend_handles_labels()
    if handles:  # once for the figure, outside the panels (it hid points inside one)
        figure.legend(handles, labels, loc="outside lower center", ncols=len(handles),
                      fontsize=9, markerscale=1.6, title="Poisson collision type",
                      title_fontsize=9, frameon=False)
    figure.suptitle(f"{engine}: where on Routh's map it departs from Poisson", fontsize=11)
    return save_png(figure, path, dpi=FIGURE_DPI, tag=tag)


def cdf_figure(runs: dict, engine: str, path: Path, tag: str | None = None) -> Path:
    """The distribution of the departure from Poisson of ``engine``'s ok runs: a panel per
    preset, a line per family. Saved as :func:`map_figure` saves."""
    from matplotlib import colormaps


    presets = _presets(runs, engine)
    ok = runs["status"] == "ok"
    families = sorted(set(np.asarray(runs["family"]).tolist()))
    colours = colormaps["tab10"]
    # one key column per panel: two overflowed the panel once n reached four digits
    figure = new_figure(4.6 * len(presets) + 0.4, 3.8 + 0.22 * len(families))
    axes = figure.subplots(1, len(presets), sharex=True, sharey=True, squeeze=False)[0]
    for axis, preset in zip(axes, presets):
        for index, family in enumerate(families):
            chosen = (ok & (runs["engine"] == engine) & (runs["preset"] == preset)
                      & (runs["family"] == family))
            values = np.sort(np.maximum(runs["departure_poisson"][chosen], DEPARTURE_FLOOR))
            # n: the ok runs the line is drawn from, of all the family's runs (the rest
            # flagged or skipped, never drawn)
            total = int(np.count_nonzero((runs["engine"] == engine) & (runs["preset"] == preset)
                                         & (runs["family"] == family)))
            if values.size:
                axis.step(values, np.arange(1, values.size + 1) / values.size,
                          where="post", color=colours(index % 10),
                          label=f"{family} (n = {values.size} of {total})")
        _log_axis(axis, "x")
        _floor_axis(axis.xaxis)
        axis.set_ylim(0, 1.03)
        axis.grid(True, which="major", color="0.92", lw=0.6)
        axis.set_xlabel("departure from Poisson")
        axis.set_title(f"{engine} {preset_label(engine, preset)}", fontsize=11)
    axes[0].set_ylabel("fraction of the n ok runs ≤ x")
    for axis in axes:  # a key per panel, below it: each preset's n differ
        if axis.get_legend_handles_labels()[0]:  # one column: two ran into the next panel's
            axis.legend(loc="upper center", bbox_to_anchor=(0.5, -0.2), fontsize=9,
                        frameon=False, title="family (n = ok runs of all)", title_fontsize=9)
    return save_png(figure, path, dpi=FIGURE_DPI, tag=tag)


#: The survey's figures' directory in its --out (made there, never through a link).
FIGURES_DIRECTORY = "figures"


def figures(runs: dict, directory: Path) -> list[Path]:
    """Per engine, a departure map (a row per preset, :func:`map_figure`) and the CDFs (a
    panel per preset, a line per family, :func:`cdf_figure`); returns the files written
    (PNG and SVG)."""
    import matplotlib

    matplotlib.use("Agg")
    make_inner_directory(directory.parent, directory.name)
    written: list[Path] = []
    for engine in figure_engines(runs):
        for draw, stem in ((map_figure, "map"), (cdf_figure, "cdf")):
            png = draw(runs, engine, directory / f"{stem}-{engine}.png")
            written += [png, png.with_suffix(".svg")]
    return written
