"""The report's Survey section: the survey in ``<out>/survey/`` (``impact-harness suite``'s
quick one, or an ``impact-harness survey --out <out>/survey``) as a table and figures.

What a survey wrote (harness/survey/outputs.py) is read here: ``settings.json`` (what was
surveyed), ``statistics.parquet`` (the table) and ``runs.parquet`` (the figures). The figures
are two per engine -- the departure from Poisson on Routh's map coloured by collision type,
and its distribution per family -- drawn by the report's pool like its other figures
(:func:`survey_figure_tasks`), each PNG tagged with the digest of ``runs.parquet`` and of the
code drawing it, so that a warm report draws none. The section's HTML is kept in the
report's fragment cache (:mod:`harness.report.fragments`) under the digest of the files it
reads: a warm report reads no Parquet (nor imports pyarrow).

No ``survey/summary.md``: no section and no figure.
"""

from __future__ import annotations

import functools
import hashlib
import json
import math
from pathlib import Path

import numpy as np

from harness.engines import PRESET_ROLES, engine_names, preset_label, source_label
from harness.report.figure_cache import FIGURE_KINDS
from harness.report.markup import folded, html_table, report_figure
from harness.report.views import escape_html, fmt_departure
from harness.run.metrics import fmt_departures
from harness.survey import outputs
from harness.survey.outputs import figure_engines as engines_of

#: The survey's directory under the report's.
SURVEY_DIR = "survey"
#: The files of the survey the section links to, with what each holds.
SURVEY_FILES = (("summary.md", "the summary: these tables, the tables per collision type, the "
                 "rejected draws and the timings"),
                ("samples.parquet", "a row per sample: drawn parameters, contact terms, every "
                 "law's result"),
                ("runs.parquet", "a row per sample × engine × preset"),
                ("statistics.parquet", "a row per engine × preset × family × collision type"))
#: Below this many samples per family the section says that the survey is a quick look.
FULL_SAMPLES = 2000


def survey_dir(out_dir: Path) -> Path | None:
    """``<out_dir>/survey`` when it holds a survey (its ``summary.md``), else None."""
    directory = Path(out_dir) / SURVEY_DIR
    return directory if (directory / "summary.md").is_file() else None


def _file_digest(path: Path) -> str:
    try:
        return hashlib.sha256(path.read_bytes()).hexdigest()
    except OSError:
        return "missing"


@functools.cache
def figure_code_digest() -> str:
    """The sha256 of the module drawing the survey's figures (harness/survey/outputs.py,
    read, not imported); this package's modules are in every figure's digest already
    (:func:`harness.report.figure_cache.inputs_digest`)."""
    from importlib.util import find_spec

    spec = find_spec("harness.survey")
    folders = list(spec.submodule_search_locations or []) if spec else []
    return _file_digest(Path(folders[0]) / "outputs.py") if folders else "missing"


def read_settings(directory: Path) -> dict:
    """The survey's ``settings.json`` ({} when it wrote none: an older survey)."""
    try:
        settings = json.loads((directory / "settings.json").read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return {}
    return settings if isinstance(settings, dict) else {}


def read_columns(path: Path) -> dict:
    """A Parquet table as ``{column: numpy array}``."""
    import pyarrow.parquet as pq

    columns = {}
    for name, values in pq.read_table(path).to_pydict().items():
        if values and isinstance(values[0], list):  # a list column (a run's reasons)
            array = np.empty(len(values), dtype=object)
            array[:] = values
            columns[name] = array
        else:
            columns[name] = np.asarray(values)
    return columns


def surveyed_engines(directory: Path) -> list[str]:
    """The engines the survey ran (a map and a CDF figure each), from its settings; without
    settings, from ``runs.parquet``."""
    settings = read_settings(directory)
    if "engines" in settings:
        return sorted(settings["engines"]) if (directory / "runs.parquet").is_file() else []
    if not (directory / "runs.parquet").is_file():
        return []

    return engines_of(read_columns(directory / "runs.parquet"))


def survey_figure_tasks(out_dir: Path, svg: str) -> list:
    """The survey's figures as tasks of the report's pool (:class:`harness.report.
    FigureTask`): per engine ``survey-map-<engine>.png`` and ``survey-cdf-<engine>.png``,
    keyed by the digest of ``runs.parquet`` and of the code drawing them; none without a
    survey. ``svg``: the report's ``--svg`` choice."""
    directory = survey_dir(out_dir)
    if directory is None:
        return []
    runs_path = directory / "runs.parquet"
    runs_digest = _file_digest(runs_path)
    tasks = []
    for engine in surveyed_engines(directory):
        for kind in ("map", "cdf"):
            figure = FIGURE_KINDS[f"survey_{kind}"]
            tasks.append(figure.task(
                [runs_digest, figure_code_digest(), engine],
                lambda path, tag, kind=kind, engine=engine:
                _draw(kind, runs_path, engine, path, tag),
                figure.svg(svg), key=engine, reads_records=False))
    return tasks


def _draw(kind: str, runs_path: Path, engine: str, path: Path, tag: str) -> Path:
    draw = outputs.map_figure if kind == "map" else outputs.cdf_figure
    return draw(read_columns(runs_path), engine, path, tag)


def cached_survey_section(out_dir: Path, figures: dict, prepared) -> str:
    """:func:`survey_section`, kept in the report's cache under the digests of the files it
    reads and the figures' files; "" without a survey."""
    directory = survey_dir(out_dir)
    if directory is None:
        return ""
    shown = [[kind, engine, file, file in figures.get("svg", ())]
             for kind in ("survey_map", "survey_cdf")
             for engine, file in sorted(figures.get(kind, {}).items())]
    present = [name for name, _ in SURVEY_FILES if (directory / name).is_file()]
    inputs = json.dumps([_file_digest(directory / "settings.json"),
                         _file_digest(directory / "statistics.parquet"), shown, present])
    key = f"survey\0{hashlib.sha256(inputs.encode()).hexdigest()}"
    return prepared.cache.get(key, lambda: survey_section(directory, figures))


def _percent(value) -> str:
    return "–" if value is None or not math.isfinite(value) else f"{100 * value:.0f}%"


def _names(items) -> str:
    return ", ".join(escape_html(item) for item in items) or "none"


def settings_paragraph(settings: dict, families: list[str]) -> str:
    """What was surveyed, and what was not and why."""
    if not settings:
        return ("<p>The survey wrote no <code>settings.json</code> (an older survey): its "
                "samples, seed, engines and presets are in its summary.</p>")
    samples = settings.get("samples")
    engines = settings.get("engines", [])
    presets = settings.get("presets", [])
    pairs = [source_label(engine, preset) for engine in engines for preset in presets
             if source_label(engine, preset) not in settings.get("left_out", {})]
    text = (f"<p><b>{escape_html(samples)}</b> random impacts from each of the "
            f"<b>{len(families)}</b> populations of <code>populations/</code> "
            f"({_names(families)}), seed {escape_html(settings.get('seed'))}, each run through "
            f"every engine and preset: {_names(pairs)}")
    if isinstance(samples, int) and families:
        text += f" ({samples * len(families)} impacts per engine and preset)"
    text += ".</p>"
    missing = []
    for label, why in settings.get("left_out", {}).items():
        missing.append(f"<b>{escape_html(label)}</b> left out ({escape_html(why)})")
    for engine, why in settings.get("skipped", {}).items():
        missing.append(f"<b>{escape_html(engine)}</b> not installed ({escape_html(why)})")
    unselected = [engine for engine in engine_names() if engine not in engines
                  and engine not in settings.get("skipped", {})]
    if unselected:
        missing.append(f"<b>{_names(unselected)}</b> not selected (<code>--engines</code>)")
    if missing:
        text += "<p class='fail'>Not run: " + "; ".join(missing) + ".</p>"
    return text


def engine_order(engine: str) -> tuple[int, str]:
    """Where ``engine`` goes in the section's tables: the registry's order
    (:func:`harness.engines.engine_names`), then by name for one unknown here."""
    names = engine_names()
    return (names.index(engine) if engine in names else len(names), engine)


def statistics_rows(stats: dict) -> list[int]:
    """The rows of ``statistics.parquet`` over every collision type, ordered as the rest of
    the page orders engines and presets (out of the box first), then by family."""
    def order(row: int) -> tuple:
        engine, preset = str(stats["engine"][row]), str(stats["preset"][row])
        return (*engine_order(engine),
                PRESET_ROLES.index(preset) if preset in PRESET_ROLES else 99, preset,
                str(stats["family"][row]))

    return sorted((row for row, kind in enumerate(stats.get("poisson_type", ()))
                   if int(kind) == 0), key=order)


def _group_cells(stats: dict, rows: list[int]) -> list[list[str]]:
    """The engine and preset cells of ``rows``, each written only where it changes (a
    table of many families reads as blocks)."""
    cells, previous = [], (None, None)
    for row in rows:
        engine = str(stats["engine"][row])
        preset = preset_label(engine, stats["preset"][row])
        cells.append([f"<b>{escape_html(engine)}</b>" if engine != previous[0] else "",
                      escape_html(preset) if (engine, preset) != previous else ""])
        previous = (engine, preset)
    return cells


def _interval_cell(stats: dict, prefix: str, row: int) -> str:
    """A quantile in percent, its 95% bootstrap interval below it in small type."""
    low, high = (stats.get(f"{prefix}_{end}") for end in ("low", "high"))
    if low is None or high is None or not (math.isfinite(low[row]) and math.isfinite(high[row])):
        return fmt_departure(float(stats[prefix][row]))
    # the quantile and its bounds, each as it reads alone (harness/run/metrics.py)
    value, low_text, high_text = fmt_departures(
        [float(stats[prefix][row]), float(low[row]), float(high[row])])
    return f"{value}<br><small>[{low_text}, {high_text}]</small>"


def statistics_table(stats: dict) -> str:
    """Per engine × preset × family over every collision type: runs, flagged and
    energy-gaining fractions, the departure from Poisson over the checked runs and over all
    runs (each median and p90 with its bootstrap interval), and from Stronge."""
    every = "departure_poisson_all_median" in stats  # surveys before the all-runs columns
    header = ["engine", "preset", "family", "n", "flagged", "gains E",
              "from Poisson, checked runs: median", "p90", "max",
              *(["from Poisson, all runs: median", "p90"] if every else []),
              "from Stronge, checked: median", "p90"]
    order = statistics_rows(stats)
    rows = []
    for row, group in zip(order, _group_cells(stats, order)):
        flagged = _percent(stats["flagged_fraction"][row])
        rows.append([*group, escape_html(stats["family"][row]), str(int(stats["n"][row])),
                     f"<b>{flagged}</b>" if stats["flagged_fraction"][row] > 0 else flagged,
                     _percent(stats["energy_gain_fraction"][row]),
                     _interval_cell(stats, "departure_poisson_median", row),
                     _interval_cell(stats, "departure_poisson_p90", row),
                     fmt_departure(float(stats["departure_poisson_max"][row])),
                     *([_interval_cell(stats, "departure_poisson_all_median", row),
                        _interval_cell(stats, "departure_poisson_all_p90", row)]
                       if every else []),
                     *(fmt_departure(float(stats[f"departure_stronge_{name}"][row]))
                       for name in ("median", "p90"))])
    return html_table(header, rows, left=3)


def reason_table(stats: dict) -> str:
    """The flagged runs by verdict reason, a row per engine × preset × family with any
    (over every collision type); "" when none is flagged."""
    reasons = [key for key in stats if key.startswith("flagged_") and key != "flagged_fraction"
               and np.any(np.asarray(stats[key]) > 0)]
    flagged = [row for row in statistics_rows(stats) if stats["flagged_fraction"][row] > 0]
    if not flagged:
        return ""
    header = ["engine", "preset", "family", "n", "flagged",
              *(key.removeprefix("flagged_").replace("_", " ") for key in reasons)]
    # a reason no run of the row fails is left blank: the eye finds the ones that matter
    rows = [[*group, escape_html(stats["family"][row]), str(int(stats["n"][row])),
             _percent(stats["flagged_fraction"][row]),
             *(_percent(stats[key][row]) if stats[key][row] > 0 else "" for key in reasons)]
            for row, group in zip(flagged, _group_cells(stats, flagged))]
    return html_table(header, rows, left=3)


def engine_errors_html(settings: dict) -> str:
    """The runs whose engine raised (``settings.json``'s ``engine_errors``: their count and
    the first ones), each with its reason; "" when none did."""
    errors = settings.get("engine_errors")
    if not isinstance(errors, dict) or not errors.get("runs"):
        return ""
    shown = [error for error in errors.get("shown", [])
             if isinstance(error, list) and len(error) == 4]
    rows = [[escape_html(pair), escape_html(family), escape_html(sample), escape_html(why)]
            for pair, family, sample, why in shown]
    more = int(errors["runs"]) - len(shown)
    return ("<h3>Engine errors</h3><p>" + f"{int(errors['runs'])} runs raised an exception "
            "of the engine: recorded with status <code>error</code> and the exception's type "
            "and first line, in no statistic above (counted in <code>n_error</code> of "
            "statistics.parquet), as <code>impact-harness run</code> records an engine "
            "error.</p>" + html_table(["engine preset", "family", "sample", "error"], rows,
                                      left=4)
            + (f"<p>{more} more: the rows of runs.parquet with status error.</p>"
               if more > 0 else ""))


MAP_CAPTION = (
    "Each point is one run of {engine} that passed the verdict checks, placed on Routh's map "
    "of the impact: its initial slip over the sticking ratio, α / r<sub>m</sub> (left edge: "
    "no initial slip; the grey line at 1, where the Poisson type changes in Table 1's cases "
    "1–3), and its friction μ; its height is the departure from Poisson (log scale, exact "
    "agreement drawn at the bottom), its colour the Poisson collision type. Read it for where "
    "the engine goes wrong: a colour sitting high is a collision type its law or solver "
    "mishandles, a climb along α / r<sub>m</sub> or μ the slip or friction it mishandles.")
CDF_CAPTION = (
    "The fraction of {engine}'s checked runs whose departure from Poisson is at most x, a "
    "line per family and a panel per preset. Read it for how often, not where: a line to the "
    "right is a family the engine gets wrong, a line that ends far right a few bad runs; "
    "with {samples} samples a family's line climbs in steps of {step}.")


def figures_html(figures: dict, engines: list[str], samples) -> str:
    parts = []
    step = (f"{100 / samples:.0f}%" if isinstance(samples, int) and samples > 0
            else "one run")
    for engine in engines:
        if engine in figures.get("survey_map", {}):
            parts.append(report_figure(figures, figures["survey_map"][engine],
                                       f"survey: {engine}'s departure on Routh's map",
                                       caption=MAP_CAPTION.format(engine=escape_html(engine))))
        if engine in figures.get("survey_cdf", {}):
            parts.append(report_figure(
                figures, figures["survey_cdf"][engine],
                f"survey: distribution of {engine}'s departure per family",
                caption=CDF_CAPTION.format(engine=escape_html(engine), samples=samples,
                                           step=step)))
    return "\n".join(parts)


def survey_section(directory: Path, figures: dict) -> str:
    """The Survey section of the page, from the survey in ``directory``, folded under
    :func:`survey_headline`."""
    settings = read_settings(directory)
    stats = (read_columns(directory / "statistics.parquet")
             if (directory / "statistics.parquet").is_file() else {})
    families = settings.get("families") or sorted(set(np.asarray(
        stats.get("family", [])).tolist()))
    samples = settings.get("samples")
    link = f"{SURVEY_DIR}/summary.md"
    parts = ["<p>The scenarios above are picked by hand; the survey draws impacts at random "
             "from families of them (<i>populations</i>: a body, its contact and ranges of "
             "speed, spin, friction and restitution) and measures each engine's departure "
             "over all of them, in percent as above. A run that fails a verdict check is "
             "<i>flagged</i>: counted, never in the quantiles.</p>",
             settings_paragraph(settings, families)]
    if isinstance(samples, int) and samples < FULL_SAMPLES:
        parts.append(
            f"<p><b>A quick look.</b> {samples} samples per family give a rough median; the "
            f"p90 is one of a family's few largest departures and the max is one run. The "
            f"tails — the rare bad impact, the p99 — need the full survey: "
            f"<code>impact-harness survey</code> ({FULL_SAMPLES:,} samples per family by "
            f"default, about a minute on two cores).</p>")
    if not stats:
        parts.append("<p>No engine ran in this survey: no statistics.</p>")
    else:
        parts.append("<h3>Per engine, preset and family, every collision type</h3>"
                     "<p><i>n</i> runs; <i>flagged</i>: the fraction failing a verdict check "
                     "(bold when any); <i>gains E</i>: checked runs ending with more kinetic "
                     "energy than they began with; the departure's median, 90th percentile "
                     "and maximum over the checked runs, and its median and 90th percentile "
                     "over all runs, flagged ones included (where most runs are flagged the "
                     "checked runs are the easy ones). Under each median and p90, in small "
                     "type, its 95% percentile-bootstrap interval (1,000 resamples).</p>"
                     + statistics_table(stats))
        reasons = reason_table(stats)
        if reasons:
            parts.append("<h3>Flagged runs by reason</h3><p>The rows with flagged runs; a run "
                         "failing several checks counts under each (docs/verdicts.md).</p>"
                         + reasons)
        errors = engine_errors_html(settings)
        if errors:
            parts.append(errors)
        engines = sorted(set(np.asarray(stats["engine"]).tolist()), key=engine_order)
        parts.append("<h3>Where and how often they depart</h3>")
        parts.append(figures_html(figures, engines, samples))
    files = "; ".join(
        f"<a href='{SURVEY_DIR}/{name}'>{name}</a> ({escape_html(what)})"
        for name, what in SURVEY_FILES if (directory / name).is_file())
    parts.append(f"<p>The survey's files (<a href='{link}'>summary.md</a> has the tables per "
                 f"collision type): {files}. Each Parquet table is one "
                 "<code>pandas.read_parquet</code> call.</p>")
    return folded("survey", "Survey: departures over random families of impacts",
                  "\n".join(parts), survey_headline(settings, families, stats))


def survey_headline(settings: dict, families: list[str], stats: dict) -> str:
    """What the folded section says: impacts per family and families, and how many of the
    engine runs were flagged (over every collision type)."""
    samples = settings.get("samples")
    text = (f"{escape_html(samples)} impacts × {len(families)} families"
            if samples is not None else f"{len(families)} families")
    rows = [row for row, kind in enumerate(stats.get("poisson_type", ())) if int(kind) == 0]
    if rows:
        runs = sum(int(stats["n"][row]) for row in rows)
        flagged = sum(int(stats["n"][row]) * float(stats["flagged_fraction"][row])
                      for row in rows)
        text += f"; {runs} engine runs, {_percent(flagged / runs if runs else math.nan)} flagged"
    errors = settings.get("engine_errors")
    if isinstance(errors, dict) and errors.get("runs"):
        text += f"; {int(errors['runs'])} engine errors"
    return text


__all__ = ["cached_survey_section", "survey_figure_tasks", "survey_section"]
