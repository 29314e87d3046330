"""The report's table of every engine and law on the Fazeli drops at its fitted or
calibrated settings, with intervals (issue 25; the aggregates of
``harness.experiments.calibrated_errors``, kept under ``"calibrated_errors"``)."""

from __future__ import annotations

from html import escape as escape_html

from harness.engines import preset_label
from harness.experiments.calibrated_errors import (
    PAIRED_COLUMNS,
    interval_text,
    paired_cells,
    settings_text,
)
from harness.report.markup import html_table

#: A bracket puts the rest of a header on a second line (markup.header_cell): the headers
#: stay narrow.
ENGINE_HEADER = ("engine", "preset", "calibrated settings", "median [at preset]",
                 "Poisson [same drops]", "difference", "lost [Poisson there]",
                 "median [calibrated, held out]", "Poisson [same drops]", "difference",
                 "lost [Poisson there]", "flagged [preset / held out]")
#: Text columns wrap (a "cannot" reason, the flagged runs' reasons): the table stays
#: within the page at 1400 px.
ENGINE_COLUMNS = ("l", "l", "note", "", "", "", "", "", "", "", "", "note")
LAW_HEADER = ("law", "fit [all drops]", "median error [at fit]", "fit [training half]",
              "median error [held out]", "vs Poisson [held out]", "unsolved")


def _flagged(part: dict | None) -> str:
    if part is None:
        return "—"
    return ", ".join(f"{reason}: {count:,}" for reason, count in part["flagged"].items()) \
        or "none"


def _narrow(cells: list[str]) -> list[str]:
    """Paired cells with each interval below its value: the wide table fits the page."""
    return [cell.replace(" [", "<br>[", 1).replace(" (law", "<br>(law", 1) for cell in cells]


def engine_rows(result: dict) -> tuple[list[list[str]], list[str]]:
    """The engines' rows (HTML cells) and their row classes (a "cannot" row is shaded)."""
    rows, classes = [], []
    for row in result["engines"]:
        preset, calibrated = row["at_preset"], row["calibrated"]
        settings = (f"<i>cannot be calibrated</i>: {escape_html(row['cannot'])}"
                    if calibrated is None else escape_html(settings_text(calibrated["settings"])))
        held = (paired_cells(calibrated["vs_reference"]) if calibrated is not None
                else ["—"] * len(PAIRED_COLUMNS))
        rows.append([escape_html(row["engine"]),
                     escape_html(preset_label(row["engine"], row["preset"])), settings,
                     *_narrow(paired_cells(preset["vs_reference"])), *_narrow(held),
                     escape_html(_flagged(preset)) + "<br>/ " + escape_html(_flagged(calibrated))])
        classes.append("flag" if calibrated is None else "")
    return rows, classes


def law_rows(result: dict) -> list[list[str]]:
    return [[escape_html(row["law"]), f"μ {row['fit']['mu']:.3f}, e {row['fit']['e']:.3f}",
             interval_text(row["at_fit"]),
             f"μ {row['training_fit']['mu']:.3f}, e {row['training_fit']['e']:.3f}",
             interval_text(row["held_out"]),
             interval_text(row["held_out_vs_reference"], "difference"),
             f"{row['unsolved']:,}"] for row in result["laws"]]


def calibrated_html(aggregates: dict) -> str:
    """The two tables and what they mean; empty when the aggregates predate them."""
    result = aggregates.get("calibrated_errors")
    if not result:
        return ""
    level = f"{result['confidence']:.0%}"
    split, calibration = result["split"], result["calibration"]
    shown = aggregates["shown"]
    rows, classes = engine_rows(result)
    knobs = "; ".join(f"{engine}'s {setting} " + ", ".join(
        f"({', '.join(f'{v:g}' for v in value)})" if isinstance(value, list) else f"{value:g}"
        for value in values)
        for engine, settings in calibration["knobs"].items()
        for setting, values in settings.items())
    own_values = ", and each preset's own value" if knobs else ""
    es = result["law_grid"]["es"]
    parts = [
        "<h4>Every engine and law at its fitted or calibrated settings</h4>",
        f"<p>The drops split by drop into halves with seed {result['seed']}: "
        f"{split['training']:,} training, {split['held_out']:,} held out. "
        "<i>At preset</i>: every drop, at the (μ, e) the engines run at above "
        f"({escape_html(shown['law'])}'s <i>{escape_html(shown['objective'])}</i> fit), the "
        "preset's own settings untouched. <i>Calibrated</i>: the engine's (μ, e) and own "
        f"settings picked on {calibration['drops']} training drops (quick grid μ "
        f"{', '.join(f'{m:g}' for m in calibration['mus'])} × e "
        f"{', '.join(f'{e:g}' for e in calibration['es'])}; {escape_html(knobs)}"
        f"{own_values}), then "
        "scored on every held-out drop. An engine's median of the paper's normalized error "
        "is over its runs judged single impacts (flagged runs are counted, never scored) "
        "and stands beside Poisson's median on the very same drops (at the same (μ, e) for "
        "the preset; Poisson fitted to the training half for the held-out half), with "
        "their difference; all three with the "
        f"{level} percentile interval of {result['replicates']:,} bootstrap resamples of "
        "those drops taken in pairs, so the drops' own spread, which both share, cancels "
        "in the difference. The drops an engine loses are counted with Poisson's median "
        "error on them: an engine that loses the hard drops has a lower median over the "
        "rest, not a better answer, so compare the difference, never two medians of "
        "different drops. A row shaded cannot be calibrated (the reason given) and keeps "
        "its preset's numbers.</p>",
        html_table(ENGINE_HEADER, rows, left=2, row_classes=classes,
                   column_classes=ENGINE_COLUMNS),
        html_table(LAW_HEADER, law_rows(result), left=1),
        f"<p class='muted'>Every law at its <i>{escape_html(shown['objective'])}</i> fit "
        "to every drop (the headline objective; the median there is in-sample), and fitted "
        f"by <i>{escape_html(result['objective'])}</i> to the training half "
        f"on μ {', '.join(f'{m:g}' for m in result['law_grid']['mus'])} × e {es[0]:g} to "
        f"{es[-1]:g} in steps of {es[1] - es[0]:.2g}, refined ten times "
        "finer, scored on the held-out half beside the engines.</p>"]
    return "\n".join(parts)
