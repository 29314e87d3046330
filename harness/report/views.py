"""Pure views of a results file: formatting, the rows and grids the figures and pages show.

Nothing here draws or writes; figures, html and summary all read the same views.
"""

from __future__ import annotations

import functools
import html
import math
import re
from collections.abc import Iterable, Sequence

import numpy as np

from harness.engines import PRESET_ROLES, engine_names, engine_trait, source_label
from harness.laws import HEADLINE_LAWS, LAW_NAMES  # noqa: F401 - HEADLINE_LAWS re-exported
from harness.laws import REGISTRY as LAW_REGISTRY
from harness.report.reading import source_presets
from harness.run.metrics import departure_split, fmt_departure
from harness.run.records import ANALYTIC, Record, Results
from harness.run.references import SINGLE
from harness.scenarios.schema import SCENARIO_DIR, recorded_location

FIGURES = "figures"
# The laws' order, headline laws and style: the law registry's (harness/laws.py).
LAW_ORDER = LAW_NAMES
LAW_STYLE = {entry.name: (entry.colour, entry.line, entry.label)  # colour, line style, label
             for entry in LAW_REGISTRY}


def engine_style(engine: str) -> tuple[str, str]:
    """(colour, marker) of ``engine`` in every figure: its adapter's ``plot_style``."""
    return tuple(engine_trait(engine, "plot_style"))


def engine_why(engine: str) -> str:
    """Why ``engine`` lands where it does (its adapter's ``description``)."""
    return engine_trait(engine, "description") or "No description of this engine."


def preset_why(engine: str, role: str) -> str:
    """What ``engine``'s preset ``role`` changes (its adapter's ``preset_why``)."""
    return engine_trait(engine, "preset_why").get(role, "")


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


# Axis names of the sweep parameters (harness/scenarios/schema.py, BODY_SWEEP_FIELDS).
PARAMETER_NAMES = {"friction": "friction μ", "restitution": "restitution e"}
BODY_FIELD_NAMES = {
    "mass": "mass [kg]", "inertia": "inertia [kg m²]", "angle_deg": "angle [°]",
    "angular_velocity": "angular velocity ω [rad/s]", "velocity.x": "velocity x [m/s]",
    "velocity.y": "velocity y [m/s]", "radius": "radius [m]", "length": "length [m]",
    "width": "width [m]", "height": "height [m]",
}
SLED_PARAMETER_NAMES = {"gamma": "steering angle γ [rad]", "delta": "steering angle δ [rad]",
                        "m": "sled mass m [kg]", "l": "length l [m]", "s": "offset s [m]",
                        "c": "offset c [m]", "q3": "angle q3 [rad]", "q6": "angle q6 [rad]"}


def parameter_name(parameter: str) -> str:
    """A sweep parameter as an axis label with its unit: ``body.disk.velocity.x`` ->
    ``disk velocity x [m/s]``, ``friction`` -> ``friction μ``."""
    if parameter in PARAMETER_NAMES:
        return PARAMETER_NAMES[parameter]
    head, _, rest = parameter.partition(".")
    if head == "body":
        body, _, field_name = rest.partition(".")
        if field_name in BODY_FIELD_NAMES:
            return f"{body} {BODY_FIELD_NAMES[field_name]}"
    if head == "parameters" and rest in SLED_PARAMETER_NAMES:
        return SLED_PARAMETER_NAMES[rest]
    return parameter


def escape_html(text) -> str:
    """``text`` escaped for HTML text and attribute values."""
    return html.escape(str(text), quote=True)


# --------------------------------------------------------------------------------------------
# Data views
# --------------------------------------------------------------------------------------------
def engine_scenarios(results: Results) -> list[str]:
    """Scenarios with engine records the single-contact laws can describe, in run order (a
    scenario whose every point is a declared flat face has its own section)."""
    return [name for name in results.scenario_names()
            if any(r.source != ANALYTIC and single_contact(r) for r in results.for_scenario(name))]


def single_contact(record: Record) -> bool:
    """Whether the single-contact laws can describe ``record``'s run: its point's reference
    is the single-contact laws (harness/run/references.py), not a declared flat face
    (``simultaneous``) nor a tilt (``event-driven``: its runs are judged against the whole
    sequence of impacts, and a run of its first impact only is flagged
    ``truncated-sequence``); results without references count. The other points have their
    own section, with the references that apply (harness/report/contacts.py)."""
    reference = (record.diagnostics or {}).get("reference") or {}
    return reference.get("kind", SINGLE) == SINGLE


def worst_departure(records: Iterable[Record], law: str) -> tuple[float, bool, bool]:
    """Largest departure from ``law`` over a scenario's single-impact runs.

    Returns ``(value, flagged, skipped)``. Only ``ok`` runs (single impacts,
    harness/run/verdicts/) enter the value: a flagged run is not a departure of the engine
    from the law; ``flagged`` says that at least one run was flagged (shown by the flag and
    counted by :func:`flagged_count`), ``skipped`` that every run was skipped.
    """
    records = list(records)
    worst = worst_record(records, law)
    flagged = any(not r.ok and not r.skipped for r in records)
    skipped = bool(records) and all(r.skipped for r in records)
    if worst is None:
        return math.nan, flagged, skipped
    return worst.departure[law], flagged, skipped


def worst_record(records: Iterable[Record], law: str) -> Record | None:
    """The single-impact (``ok``) run with the largest finite departure from ``law``, never
    at a flat face or a tilt (it departs from its own reference, not from the single-contact
    laws: :func:`single_contact`)."""
    runs = [r for r in records if r.ok and r.departure.get(law) is not None
            and math.isfinite(r.departure[law]) and single_contact(r)]
    return max(runs, key=lambda r: r.departure[law]) if runs else None


def flagged_count(records: Iterable[Record]) -> int:
    """How many runs were flagged (not single impacts); none of them is in a value."""
    return sum(1 for r in records if not r.ok and not r.skipped)


def departure_cell(records: Sequence[Record], law: str) -> str:
    """A headline cell: the largest departure over the single-impact runs, ``(k!)`` when k
    runs were flagged (kept out of the value), ``*`` if the scenario overrode the engine's
    settings."""
    records = list(records)
    if not records or all(r.skipped for r in records):
        return "skipped"
    value, _, _ = worst_departure(records, law)
    text = fmt_departure(value) if math.isfinite(value) else "flagged"
    flagged = flagged_count(records)
    if flagged:
        text += f" ({flagged}!)"
    if any(overrides_of(r) for r in records):
        text += " *"
    return text


def departure_grid(results: Results, law: str, labels: Sequence[str],
                   names: Sequence[str] | None = None,
                   grouped: dict[str, dict[str, list[Record]]] | None = None):
    """``(scenarios, values[s, l], flagged[s, l], skipped[s, l])``, max over sweep points;
    ``flagged`` marks a cell whose maximum is a run the engine flagged. ``names`` restricts
    the rows (default: every scenario with engine records); ``grouped``: their runs by
    label (:func:`label_records`) when known."""
    names = engine_scenarios(results) if names is None else list(names)
    values = np.full((len(names), len(labels)), np.nan)
    flagged = np.zeros_like(values, dtype=bool)
    skipped = np.zeros_like(values, dtype=bool)
    for i, name in enumerate(names):
        by_label = (label_records(results.for_scenario(name)) if grouped is None
                    else grouped[name])
        for j, label in enumerate(labels):
            subset = by_label.get(label)
            if subset:
                values[i, j], flagged[i, j], skipped[i, j] = worst_departure(subset, law)
            else:
                skipped[i, j] = True
    return names, values, flagged, skipped


def engine_roles(results: Results) -> list[tuple[str, str]]:
    """``Results.engine_roles``: the ``(engine, preset role)`` pairs present, presets in
    order, engines in registry order, read from :mod:`harness.engines` (the scenario
    package that ``Results`` reads them from takes a third of a warm report's imports)."""
    present = source_presets(results)  # from the file's lines when the report read them
    return [(e, p) for p in PRESET_ROLES for e in engine_names() if (e, p) in present]


def engine_labels(results: Results) -> list[str]:
    """``Results.engine_labels`` (:func:`engine_roles`' pairs as labels)."""
    return [_engine_label(engine, role) for engine, role in engine_roles(results)]


@functools.cache
def _engine_label(source: str, preset: str | None) -> str:
    return source_label(source, preset)


def record_label(record: Record) -> str:
    """``record.label``, the engine labels computed once per (engine, preset): a report of
    1,000 scenarios asks half a million times."""
    return record.law if record.source == ANALYTIC else _engine_label(record.source,
                                                                       record.preset)


def label_records(records: Iterable[Record]) -> dict[str, list[Record]]:
    """A scenario's engine runs grouped by ``engine.preset`` label (a record's label is
    computed on each access: grouping once keeps a 1,000-scenario report linear)."""
    grouped: dict[str, list[Record]] = {}
    for record in records:
        if record.source != ANALYTIC:
            grouped.setdefault(record_label(record), []).append(record)
    return grouped


# --------------------------------------------------------------------------------------------
# Settings overrides, notes, verdicts
# --------------------------------------------------------------------------------------------
def overrides_of(record: Record) -> dict:
    """The settings a run changed from its preset, as the runner stored them in the record's
    diagnostics (``settings_overrides``): a scenario's ``[engine_settings.<engine>]`` and the
    command line's ``--set`` together (:func:`split_overrides` tells them apart); {} for a
    law or a run without any."""
    return dict((record.diagnostics or {}).get("settings_overrides") or {})


def fmt_overrides(overrides: dict) -> str:
    """``iterations=1, time_step=0.001``; "" for none."""
    return ", ".join(f"{key}={short_value(value)}" for key, value in overrides.items())


def short_value(value) -> str:
    if isinstance(value, float):
        return f"{value:.6g}"
    if isinstance(value, str):
        return value
    import json

    return json.dumps(value)


def run_label(record: Record) -> str:
    """A record's label with its overrides: ``pymunk.defaults [iterations=1]``."""
    overrides = overrides_of(record)
    return record.label + (f" [{fmt_overrides(overrides)}]" if overrides else "")


def scenario_overrides(records: Iterable[Record]) -> dict[str, dict]:
    """``engine -> overrides`` of a scenario's runs (its ``[engine_settings]`` and ``--set``)."""
    found: dict[str, dict] = {}
    for record in records:
        if record.source != ANALYTIC and overrides_of(record):
            found.setdefault(record.source, overrides_of(record))
    return found


def has_library_scenarios(results: Results) -> bool:
    """True when some scenario of ``results`` is a file of the library (``scenarios/``): the
    report then also reproduces the paper's Table 3, which the library's scenarios are about.
    A report of a user's own scenarios shows only what applies to them."""
    library = SCENARIO_DIR.resolve()
    for info in results.scenarios.values():
        path = (info or {}).get("path")
        if path and recorded_location(path).resolve().parent == library:
            return True
    return False


def split_overrides(record: Record, command: dict) -> tuple[dict, dict]:
    """A run's overrides by where they were set: ``(from --set, from the scenario file)``.
    ``command`` is the run's ``--set`` overrides (``provenance["settings_overrides"]``,
    ``engine -> {key: value}``); a key set both ways took the command line's value."""
    overrides = overrides_of(record)
    given = (command or {}).get(record.source, {})
    from_command = {key: value for key, value in overrides.items() if key in given}
    return from_command, {key: value for key, value in overrides.items()
                          if key not in from_command}


def run_notes(record: Record) -> list[str]:
    """The engine's notes on a run (e.g. MuJoCo's "restitution e not used")."""
    return [str(note) for note in (record.diagnostics or {}).get("notes") or []]


def run_verdict(record: Record) -> tuple[str | None, list[str]]:
    """``(verdict, reasons)`` when the results carry them (the run's verdict is computed by
    harness/run, never here); ``(None, [])`` for older results."""
    data = record.diagnostics or {}
    verdict = getattr(record, "verdict", None) or data.get("verdict")
    reasons = getattr(record, "reasons", None) or data.get("reasons") or []
    return verdict, [reason_sentence(reason) for reason in reasons]


def reason_sentence(reason) -> str:
    """One verdict reason as a reader's sentence: its name, then its detail (which already
    says the measured value, the bound and the units), then what it means for the run. A
    reason is a mapping (results files) or an object with the same fields (a ``Reason``);
    a plain string (older results) is shown as it is."""
    if isinstance(reason, str):
        return reason
    field = reason.get if isinstance(reason, dict) else (lambda key: getattr(reason, key, None))
    name, detail = field("name") or "reason", field("detail")
    value, tolerance = field("value"), field("tolerance")
    if not detail and value is not None:
        detail = (f"measured {value:.4g}" if tolerance is None
                  else f"measured {value:.4g} against the bound {tolerance:.4g}")
    text = f"{name}: {detail}" if detail else str(name)
    attribution = field("attribution")
    if attribution:
        text += f" (attributed to {'the law' if attribution == 'law' else attribution})"
    if field("fails") is False:
        text += "; reported, not a failure"
    return text


def split_rows(results: Results) -> list[dict]:
    """The departure split of every engine record at a single-contact point
    (metrics.departure_split; a flat face's or a tilt's record holds no departure from the
    single-contact laws, :func:`single_contact`)."""

    lcp = {(r.scenario, r.point["index"]): r for r in results.records
           if r.source == ANALYTIC and r.law == "newton-lcp" and r.ok}
    rows = []
    for record in results.records:
        if (record.source == ANALYTIC or record.skipped or record.u_after is None
                or not single_contact(record)):
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



