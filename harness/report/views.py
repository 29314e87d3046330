"""Pure views of a results file: formatting, the rows and grids the figures and pages show.

Nothing here draws or writes; figures, html and summary all read the same views.
"""

from __future__ import annotations

import html
import math
import re
from typing import Iterable, Sequence

import numpy as np

from harness.run.metrics import departure_split
from harness.run.records import ANALYTIC, Record, Results

FIGURES = "figures"
LAW_ORDER = ("poisson", "stronge", "stronge-paper", "newton", "newton-lcp")
HEADLINE_LAWS = ("poisson", "stronge")
LAW_STYLE = {  # colour, line style, label
    "poisson": ("black", "-", "Poisson"),
    "stronge": ("tab:red", "-", "Stronge (exact)"),
    "stronge-paper": ("tab:purple", "--", "Stronge (paper's mapping)"),
    "newton": ("tab:gray", "-.", "Newton (process)"),
    "newton-lcp": ("tab:brown", ":", "newton-lcp (engines' law)"),
}
ENGINE_STYLE = {"pymunk": ("tab:blue", "o"), "pybullet": ("tab:orange", "s"),
                "mujoco": ("tab:green", "^"), "box2d": ("tab:olive", "D")}
TYPE_NAMES = {1: "stick in compression", 2: "stick in restitution",
              3: "reverse slide from compression", 4: "reverse slide from restitution",
              5: "forward slide"}
# Split figure: law parts below X_FLOOR (the law equals Poisson there) are drawn at X_FLOOR.
X_FLOOR = 1.5e-4
# Heat-map colour range (relative departure): below 1e-4 counts as "agrees".
HEAT_MIN, HEAT_MAX = 1e-4, 1.0


# --------------------------------------------------------------------------------------------
# Formatting
# --------------------------------------------------------------------------------------------
def fmt_departure(value) -> str:
    """A departure as a percentage: ``20.7%``, ``0.18%``, ``2e-12%``, ``0``; ``n/a``."""
    if value is None or (isinstance(value, float) and not math.isfinite(value)):
        return "n/a"
    percent = 100.0 * value
    if percent == 0:
        return "0"
    if percent < 0.01:
        return f"{percent:.0e}%"
    return f"{percent:.3g}%"


def fmt_number(value, digits: int = 4) -> str:
    if value is None:
        return "–"
    if isinstance(value, float) and not math.isfinite(value):
        return "nan"
    if abs(value) < 5e-13:
        return "0"
    return f"{value:.{digits}g}"


def slug(name: str) -> str:
    return re.sub(r"[^A-Za-z0-9_.-]+", "-", name)




def escape_html(text) -> str:
    """``text`` escaped for HTML text and attribute values."""
    return html.escape(str(text), quote=True)


# --------------------------------------------------------------------------------------------
# Data views
# --------------------------------------------------------------------------------------------
def engine_scenarios(results: Results) -> list[str]:
    """Scenarios with engine records, in run order."""
    return [name for name in results.scenario_names()
            if any(r.source != ANALYTIC for r in results.for_scenario(name))]


def worst_departure(records: Iterable[Record], law: str) -> tuple[float, bool, bool]:
    """Largest departure from ``law`` over a scenario's points; (value, any flagged, all skipped).

    Only ``ok`` runs (single impacts, harness/run/verdicts.py) enter the value: a flagged
    run is not a departure of the engine from the law; it is shown by the flag and counted.
    """
    records = list(records)
    values = [r.departure.get(law) for r in records if r.ok]
    values = [v for v in values if v is not None and math.isfinite(v)]
    flagged = any(not r.ok and not r.skipped for r in records)
    skipped = bool(records) and all(r.skipped for r in records)
    return (max(values) if values else math.nan), flagged, skipped


def departure_grid(results: Results, law: str, labels: Sequence[str]):
    """``(scenarios, values[s, l], flagged[s, l], skipped[s, l])``, max over sweep points."""
    names = engine_scenarios(results)
    values = np.full((len(names), len(labels)), np.nan)
    flagged = np.zeros_like(values, dtype=bool)
    skipped = np.zeros_like(values, dtype=bool)
    for i, name in enumerate(names):
        records = results.for_scenario(name)
        for j, label in enumerate(labels):
            subset = [r for r in records if r.source != ANALYTIC and r.label == label]
            if subset:
                values[i, j], flagged[i, j], skipped[i, j] = worst_departure(subset, law)
            else:
                skipped[i, j] = True
    return names, values, flagged, skipped


def split_rows(results: Results) -> list[dict]:
    """The departure split of every engine record (metrics.departure_split)."""

    lcp = {(r.scenario, r.point["index"]): r for r in results.records
           if r.source == ANALYTIC and r.law == "newton-lcp" and r.ok}
    rows = []
    for record in results.records:
        if record.source == ANALYTIC or record.skipped or record.u_after is None:
            continue
        law_record = lcp.get((record.scenario, record.point["index"]))
        if law_record is None:
            continue
        split = departure_split(record.departure, law_record.departure)
        rows.append({"scenario": record.scenario, "point": record.point["label"],
                     "label": record.label, "engine": record.source, "preset": record.preset,
                     "status": record.status, **split})
    return rows


def row_name(results: Results, name: str) -> str:
    """A scenario's row label: a sweep shows how many points its maximum is over."""
    info = results.scenarios.get(name, {})
    sweep = info.get("sweep")
    return f"{name} (max of {len(sweep['values'])})" if sweep else name
