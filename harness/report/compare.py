"""``impact-harness compare A.json B.json``: what changed between two results files.

::

    impact-harness compare old/results.json new/results.json --fail-above 1% --csv diff.csv

Records are matched by scenario, sweep point and source (a law, or ``engine.preset``). For
each pair it reports

* the change of every departure, ``d_B − d_A`` (in percentage points: departures are
  fractions of the motion before the impact, shown in percent), and
* the change of the post-impact speeds, ``‖u_B − u_A‖_M / s``: in the kinetic-energy norm
  of the departures, relative to the same frame-free scale ``s`` of the speeds before the
  impact (:func:`harness.run.metrics.departure`; docs/verdicts.md) -- so a speed change and
  a departure change are on one scale, and metres and radians per second are not mixed.
  The results do not hold the mass matrix ``M``: it is read from the scenario's file (the
  path the results record, else the file of that name in ``scenarios/``) and checked
  against the run's own energy change (½uᵀMu after minus before, recorded); a scenario
  whose file is not found, or no longer has the masses its runs used, gets no speed change
  (``n/a``, and a line saying so),

and a change of status (``ok`` against ``multi-contact`` …). A pair *exceeds* the threshold
when the largest of its departure changes or its speed change is above ``--fail-above``,
or when its status changed. A record of A gone from B fails the comparison (a result the
checked run lost: a gate must not pass on what it no longer sees); a record only in B (new)
is listed and counted, never failing (a run that does more is not a regression). A law the
registry does not hold (:data:`harness.laws.LAW_NAMES`), as a record's law or in its
departures, is refused as bad input: its changes would not be weighed.

Exit status, for gating an engine upgrade or a settings change in CI:
0 no pair exceeds the threshold and no record is gone; 1 at least one does or is; 2 bad
input (a file missing or not a results file, a file holding one run twice, a law the
harness does not know, a bad threshold, or no record in common).
A pair whose result is not finite in one file only (a departure or speeds that became NaN),
or whose speeds differ in length, exceeds whatever the threshold, as a changed status does.
``--fail-above`` takes its unit: ``1%`` or ``1pp`` (a bare ``5`` was read as a fraction,
500 pp, while the default printed ``1%``: it is refused).
"""

from __future__ import annotations

import argparse
import csv
import io
import json
import math
import os
import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from harness import bounds
from harness.engines import source_label
from harness.laws import LAW_NAMES
from harness.report.export import csv_cell
from harness.report.markup import html_table, page_head
from harness.report.views import escape_html
from harness.run import metrics
from harness.run.records import ANALYTIC, Record, Results, read_results
from harness.scenarios.errors import ScenarioError
from harness.scenarios.reader import load_scenario
from harness.scenarios.schema import SCENARIO_DIR, recorded_location
from harness.store.files import output_file_problem, write_text_atomically

DEFAULT_THRESHOLD = "1%"
LAWS = LAW_NAMES  # the law registry's order (harness/laws.py)


@dataclass
class Change:
    """One matched pair of records and how it changed from A to B."""

    scenario: str
    point: str
    source: str  # a law, or ``engine.preset``
    status_a: str
    status_b: str
    departure_a: dict
    departure_b: dict
    u_a: list | None
    u_b: list | None
    speed_change: float  # ‖u_B − u_A‖_M / s, nan without speeds or the scenario's M
    malformed: tuple[str, ...] = ()  # what compare() found wrong with B's record

    @property
    def departure_change(self) -> dict[str, float]:
        """``law -> d_B − d_A`` for the laws both records have."""
        changes = {}
        for law in LAWS:
            a, b = self.departure_a.get(law), self.departure_b.get(law)
            if a is not None and b is not None and math.isfinite(a) and math.isfinite(b):
                changes[law] = b - a
        return changes

    @property
    def problems(self) -> list[str]:
        """What makes the pair a change whatever its size: a departure or speeds not finite
        in one file only (the results file writes a value that is not finite as null), a
        departure or a speed that is not a number, speeds of different lengths."""
        found = list(self.malformed)
        for law in LAWS:
            if law in self.departure_a and law not in self.departure_b:
                found.append(f"departure from {law} gone")  # a result lost: never passes
                continue
            if law not in self.departure_a or law not in self.departure_b:
                continue  # a law A's run did not solve (one added since): no pair
            a, b = self.departure_a[law], self.departure_b[law]
            if not all(v is None or _is_number(v) for v in (a, b)):
                found.append(f"departure from {law} not a number")
            elif _finite(a) != _finite(b):
                found.append(f"departure from {law} {_spelled(a)} → {_spelled(b)}")
        if (self.u_a is None) != (self.u_b is None):  # a result in one file only
            found.append("speeds " + ("gone" if self.u_b is None else "new"))
        elif self.u_a is not None and self.u_b is not None:
            if not all(v is None or _is_number(v) for v in (*self.u_a, *self.u_b)):
                found.append("speeds not numbers")
            elif len(self.u_a) != len(self.u_b):
                found.append(f"{len(self.u_a)} speeds → {len(self.u_b)}")
            elif all(map(_finite, self.u_a)) != all(map(_finite, self.u_b)):
                found.append("speeds " + ("became" if all(map(_finite, self.u_a))
                                          else "were") + " not finite")
        return found

    @property
    def largest(self) -> float:
        """The largest absolute change (departures and speeds), for sorting and gating."""
        values = [abs(v) for v in self.departure_change.values()]
        if not math.isnan(self.speed_change):  # inf: speeds too large to weigh, a change
            values.append(self.speed_change)
        return max(values, default=0.0)

    @property
    def largest_is_speeds(self) -> bool:
        """Whether :attr:`largest` is the speeds' change (else a departure's)."""
        return (not math.isnan(self.speed_change) and self.speed_change > 0
                and self.speed_change == self.largest)

    @property
    def status_changed(self) -> bool:
        return self.status_a != self.status_b

    def exceeds(self, threshold: float) -> bool:
        return self.status_changed or bool(self.problems) or self.largest > threshold


def _is_number(value) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def _finite(value) -> bool:
    return _is_number(value) and math.isfinite(value)


def _spelled(value) -> str:
    """A departure as the row shows it: null (not finite) or its value."""
    return "null" if value is None else f"{value:g}"


def parse_threshold(text: str) -> float:
    """``--fail-above``'s text as a fraction: ``"1%"`` and ``"1pp"`` are 0.01 (a departure's
    change in percentage points, the speeds' in percent of the motion before: one scale);
    ``"0"`` alone may go without a unit. A bare number is refused as ambiguous (``5`` read
    as a fraction was 500 pp, 100 times looser than the ``1%`` the default prints), as is
    a negative or not finite one: ``ValueError`` with a sentence saying what is allowed."""
    spelled = text.strip()
    number, unit = spelled, None
    for suffix in ("%", "pp"):
        if spelled.lower().endswith(suffix):
            number, unit = spelled[:-len(suffix)].strip(), suffix
            break
    allowed = ("allowed: a change in percentage points with its unit, e.g. 1% or 1pp (of a "
               "departure, and percent of the motion for the speeds); 0 alone needs none")
    try:
        value = float(number) if len(number) <= 40 else math.nan
    except ValueError:
        raise ValueError(f"--fail-above {text!r} is not a number; {allowed}") from None
    if unit is None and value != 0:
        raise ValueError(f"--fail-above {text!r} has no unit: is it {value:g}% or a fraction "
                         f"({100 * value:g}%)? A bare number is ambiguous; {allowed}")
    if not math.isfinite(value) or value < 0:
        raise ValueError(f"--fail-above {text!r} is not a non-negative finite number; "
                         f"{allowed}")
    return value / 100.0


def record_key(record: Record) -> tuple[str, str, str]:
    return record.scenario, str(record.point.get("label", record.point.get("index"))), record.label


def duplicate_problem(results: Results, path) -> str | None:
    """Why ``results`` cannot be compared record by record: two records of one run (the
    same scenario, point and source), which a results file of one run never holds (the
    comparison kept the last silently); None when every key is unique."""
    seen: set = set()
    for record in results.records:
        key = record_key(record)
        if key in seen:
            scenario, point, source = key
            return (f"{path}: two records of one run: scenario {scenario!r}"
                    + (f", point {point!r}" if point else "") + f", source {source!r} "
                    "(a results file holds each run once: duplicates are refused)")
        seen.add(key)
    return None


def unknown_law_problem(results: Results, path) -> str | None:
    """Why ``results`` cannot be compared law by law: a record of a law, or a departure
    from a law, the registry (:data:`harness.laws.LAW_NAMES`) does not hold -- a departure
    the gate would not weigh, so a change in it would pass unseen; None when every law is
    known."""
    for record in results.records:
        laws = list(record.departure)
        if record.source == ANALYTIC:
            laws.insert(0, record.law)
        for law in laws:
            if law not in LAW_NAMES:
                return (f"{path}: scenario {record.scenario!r}, source {record.label!r}: "
                        f"law {str(law)[:80]!r} is not one the harness knows; allowed: "
                        f"{', '.join(LAW_NAMES)} (a file of another version of the harness: "
                        "run it again)")
    return None


class MassMatrices:
    """The mass matrix and frame of each (scenario, sweep point) of two results files,
    from the scenarios' files, read once each; None for a scenario whose file is not found
    (or no longer holds that scenario)."""

    def __init__(self, *results: Results) -> None:
        self.results = results
        self.scenarios: dict = {}
        self.points: dict = {}
        self.missing: set[str] = set()
        self.mismatched: set[str] = set()  # found, but not with the masses the runs used

    def candidates(self, name: str) -> list[Path]:
        """Where the scenario's file may be: the paths the results record (B's first), then
        the file of that name in the library (a results file made on another machine)."""
        paths = [info.get("path") for results in reversed(self.results)
                 if isinstance(info := results.scenarios.get(name), dict)]
        found = [recorded_location(path) for path in paths if path]
        found += [SCENARIO_DIR / path.name for path in found]
        return found + [SCENARIO_DIR / f"{name}.toml"]

    def scenario(self, name: str):
        if name not in self.scenarios:
            self.scenarios[name] = None
            for path in dict.fromkeys(self.candidates(name)):
                try:
                    loaded = load_scenario(path) if path.is_file() else None
                except ScenarioError:
                    loaded = None
                if loaded is not None and loaded.name == name:
                    self.scenarios[name] = loaded
                    break
            else:
                self.missing.add(name)
        return self.scenarios[name]

    def __call__(self, record: Record) -> tuple | None:
        """``(M, free_bodies)`` at ``record``'s point, as the run weighed its departures; None
        where the file is not found or its masses are not the run's."""
        weights = self._point_weights(record)
        if weights is None or not self._masses_agree(record, weights[0]):
            return None
        return weights

    def _masses_agree(self, record: Record, mass_matrix: np.ndarray) -> bool:
        """Whether today's file weighs ``record``'s speeds as its run did: the record's own
        energy change, ½(uᵀMu after − before), recomputed with ``mass_matrix`` (a file
        edited since the run, another mass or inertia, fails it)."""
        if record.u_before is None or record.u_after is None or record.energy_change is None:
            return True  # nothing to check against
        before = np.asarray(record.u_before, dtype=float)
        after = np.asarray(record.u_after, dtype=float)
        if before.shape != (len(mass_matrix),) or after.shape != before.shape:
            self.mismatched.add(record.scenario)
            return False
        with np.errstate(over="ignore", invalid="ignore"):  # 1e308 speeds: inf, a mismatch
            energy_before = 0.5 * before @ mass_matrix @ before
            recomputed = 0.5 * after @ mass_matrix @ after - energy_before
        if not abs(recomputed - record.energy_change) <= 1e-9 * max(energy_before, 1e-300):
            self.mismatched.add(record.scenario)
            return False
        return True

    def _point_weights(self, record: Record) -> tuple | None:
        index = int(record.point.get("index") or 0)
        key = (record.scenario, index)
        if key not in self.points:
            scenario = self.scenario(record.scenario)
            try:
                if scenario is None:
                    raise LookupError(record.scenario)
                fixed = scenario.at(index)
                self.points[key] = (np.asarray(scenario.analytic_problem(index).mass_matrix,
                                               dtype=float),
                                    fixed.system == "bodies" and not fixed.ground)
            except (LookupError, ValueError, TypeError, ScenarioError):
                self.missing.add(record.scenario)
                self.points[key] = None
        return self.points[key]


def speed_change(a: Record, b: Record, weights: tuple | None) -> float:
    """``‖u_B − u_A‖_M / s``, ``s`` the frame-free kinetic-energy norm of the speeds before
    (:func:`harness.run.metrics.frame_free_scale`): the departures' measure, so that a
    common velocity of free bodies changes nothing. ``weights``: ``(M, free_bodies)``; nan
    without them or when a record has no speeds."""
    if weights is None or not a.u_after or not b.u_after or len(a.u_after) != len(b.u_after):
        return math.nan
    if any(v is None for v in (*a.u_after, *b.u_after)):
        return math.nan
    mass_matrix, free_bodies = weights
    before = b.u_before or a.u_before
    if before is None or len(before) != len(a.u_after) or len(before) != len(mass_matrix):
        return math.nan
    scale = metrics.frame_free_scale(mass_matrix, np.asarray(before, dtype=float),
                                     free_bodies=free_bodies)
    difference = np.asarray(b.u_after, dtype=float) - np.asarray(a.u_after, dtype=float)
    return metrics.ke_norm(mass_matrix, difference) / scale if scale > 0 else math.nan


def compare(a: Results, b: Results,
            weights: MassMatrices | None = None) -> tuple[list[Change], list[tuple], list[tuple]]:
    """The changes of the records in both, and the keys only in A and only in B.

    ``weights``: the mass matrices of the speed changes (default: from the scenarios' files,
    :class:`MassMatrices`).
    """
    weights = MassMatrices(a, b) if weights is None else weights
    records_a = {record_key(r): r for r in a.records}
    records_b = {record_key(r): r for r in b.records}
    changes = []
    for key, ra in records_a.items():
        rb = records_b.get(key)
        if rb is None:
            continue
        has_speeds = ra.u_after is not None and rb.u_after is not None
        weights_b = weights(rb) if has_speeds else None
        change = speed_change(ra, rb, weights_b)
        # B's speeds that do not give B's own recorded energy change, where A's give A's
        # (so the scenario's file is the runs'): B's record is malformed, not "n/a"
        malformed = (("speeds not those of its own energy change",)
                     if has_speeds and weights_b is None and weights(ra) is not None else ())
        changes.append(Change(*key, ra.status, rb.status, dict(ra.departure),
                              dict(rb.departure), ra.u_after, rb.u_after, change, malformed))
    only_a = [key for key in records_a if key not in records_b]
    only_b = [key for key in records_b if key not in records_a]
    return changes, only_a, only_b


def fmt_points(change: float) -> str:
    """A change of a fraction in percentage points, signed: ``+1.23 pp``."""
    return "0 pp" if change == 0 else f"{100.0 * change:+.3g} pp"


#: A change of a departure smaller than this (a fraction: 1e-9 %) is "unchanged": rounding
#: of a rerun on another CPU stays far below it, any setting's effect far above.
UNCHANGED = 1e-11


@dataclass
class SourceSummary:
    """What changed for one source (``engine.preset`` or a law), against one law."""

    source: str
    matched: int
    improved: int  # runs ok in both whose departure from the law is smaller in B (closer)
    worse: int  # … larger in B
    status_changed: int
    flagged: int  # matched runs not ``ok`` in B
    new: int  # only in B
    gone: int  # only in A
    median_change: float  # d_B − d_A over the runs ok in both (nan: none)
    worst_change: float  # the change of largest size among them, signed (nan: none)
    exceeding: int


def summarise(changes: list[Change], only_a: list[tuple], only_b: list[tuple], law: str,
              threshold: float) -> list[SourceSummary]:
    """One :class:`SourceSummary` per source, engines first, in the order first seen."""
    sources = list(dict.fromkeys([c.source for c in changes]
                                 + [key[2] for key in (*only_a, *only_b)]))
    rows = []
    for source in sources:
        mine = [c for c in changes if c.source == source]
        # a flagged run's departure is not a departure from the law's situation: the
        # median and worst are over runs ok in both files, the flagged are counted apart
        deltas = np.array([c.departure_change[law] for c in mine
                           if law in c.departure_change and c.status_a == c.status_b == "ok"])
        worst = float(deltas[np.argmax(np.abs(deltas))]) if deltas.size else math.nan
        rows.append(SourceSummary(
            source=source, matched=len(mine),
            improved=int(np.sum(deltas < -UNCHANGED)), worse=int(np.sum(deltas > UNCHANGED)),
            status_changed=sum(c.status_changed for c in mine),
            flagged=sum(c.status_b != "ok" for c in mine),
            new=sum(key[2] == source for key in only_b),
            gone=sum(key[2] == source for key in only_a),
            median_change=float(np.median(deltas)) if deltas.size else math.nan,
            worst_change=worst, exceeding=sum(c.exceeds(threshold) for c in mine)))
    rows.sort(key=lambda row: row.source in LAWS)  # engines first: a law changes only
    return rows                                      # with the solver


def setting_differences(a: Results, b: Results) -> list[tuple[str, str, str]]:
    """``(what, in A, in B)`` for every version, commit and engine setting that differs
    between the two runs' provenance (settings as each preset resolved them)."""
    def mapping(value) -> dict:  # a hand-edited file may hold anything in its provenance
        return value if isinstance(value, dict) else {}

    pa, pb = mapping(a.provenance), mapping(b.provenance)
    rows = []
    commit_a, commit_b = (str(mapping(p.get("git")).get("commit") or "") for p in (pa, pb))
    if commit_a != commit_b:
        rows.append(("commit", commit_a[:12] or "?", commit_b[:12] or "?"))
    versions_a, versions_b = mapping(pa.get("versions")), mapping(pb.get("versions"))
    for name in sorted(set(versions_a) | set(versions_b)):
        if versions_a.get(name) != versions_b.get(name):
            rows.append((f"version of {name}", str(versions_a.get(name, "—")),
                         str(versions_b.get(name, "—"))))
    settings_a, settings_b = (mapping(pa.get("engine_settings")),
                              mapping(pb.get("engine_settings")))
    for engine in sorted(set(settings_a) | set(settings_b)):
        presets_a, presets_b = mapping(settings_a.get(engine)), mapping(settings_b.get(engine))
        for preset in sorted(set(presets_a) | set(presets_b)):
            keys_a, keys_b = mapping(presets_a.get(preset)), mapping(presets_b.get(preset))
            for key in sorted(set(keys_a) | set(keys_b)):
                if keys_a.get(key) != keys_b.get(key):
                    # the preset under the name users see (mujoco.matched-bounce)
                    rows.append((f"{source_label(engine, preset)}.{key}",
                                 json_text(keys_a.get(key, "—")),
                                 json_text(keys_b.get(key, "—"))))
    return rows


def json_text(value) -> str:
    """A setting's value as the scenario files write it (``null``, ``[0.02, 1.0]``)."""
    return value if isinstance(value, str) else json.dumps(value)


def speed_names(results: Results, change: Change, size: int) -> list[str]:
    """The speeds' names of a change's scenario (``box.v_x [m/s]``), ``u1 …`` without."""
    info = results.scenarios.get(change.scenario) if isinstance(results.scenarios, dict) \
        else None
    labels = info.get("speed_labels") if isinstance(info, dict) else None
    if isinstance(labels, list) and len(labels) == size:
        return [str(label) for label in labels]
    return [f"u{i + 1}" for i in range(size)]


def write_csv(changes: list[Change], path: Path, b: Results | None = None) -> Path:
    """One row per matched pair: statuses; every departure in A and B and its change, in
    percent and percentage points (the unit of the terminal and the report); the speeds in
    A and B, each named by its scenario (``speed_1_name`` = ``box.v_x [m/s]``); the speed
    change in percent."""
    size = max((len(c.u_a or c.u_b or []) for c in changes), default=0)
    header = ["scenario", "point", "source", "status_a", "status_b"]
    for law in LAWS:
        header += [f"departure_{law}_a_pct", f"departure_{law}_b_pct",
                   f"departure_{law}_change_pp"]
    for i in range(size):
        header += [f"speed_{i + 1}_name", f"speed_{i + 1}_a", f"speed_{i + 1}_b"]
    header += ["speed_change_pct", "largest_change_pct"]

    def percent(value):
        return "" if not _is_number(value) or not math.isfinite(value) else 100.0 * value

    def _cell(values, index):  # speeds of different lengths leave the shorter's cells empty
        return csv_cell(values[index]) if index < len(values) else ""

    handle = io.StringIO(newline="")  # the rows in memory, then written atomically
    writer = csv.writer(handle)
    writer.writerow(header)
    for c in changes:
        row = [csv_cell(text) for text in (c.scenario, c.point, c.source, c.status_a,
                                           c.status_b)]
        deltas = c.departure_change
        for law in LAWS:
            row += [percent(c.departure_a.get(law)), percent(c.departure_b.get(law)),
                    percent(deltas.get(law))]
        count = len(c.u_a or c.u_b or [])
        names = speed_names(b, c, count) if b is not None else [
            f"u{i + 1}" for i in range(count)]
        for i in range(size):
            row += ([csv_cell(names[i]), _cell((c.u_a or [""] * count), i),
                     _cell((c.u_b or [""] * count), i)] if i < count else ["", "", ""])
        row += [percent(c.speed_change), percent(c.largest)]
        writer.writerow(row)
    write_text_atomically(path, handle.getvalue())
    return path


def row_cells(c: Change, law: str, threshold: float) -> list[str]:
    """A matched pair against one law: before, after, change, speed change, status."""
    before, after = c.departure_a.get(law), c.departure_b.get(law)
    change = c.departure_change.get(law)
    status = f"{c.status_a} → {c.status_b}" if c.status_changed else c.status_b
    status = "; ".join([status, *c.problems])
    largest = (f"{100 * c.largest:.3g}" + ("% (speeds)" if c.largest_is_speeds else " pp")
               if c.largest > 0 else "0")
    return ["EXCEEDS" if c.exceeds(threshold) else "ok",
            c.scenario + (f" [{c.point}]" if c.point else ""), c.source,
            "—" if not _is_number(before) else metrics.fmt_departure(before),
            "—" if not _is_number(after) else metrics.fmt_departure(after),
            fmt_points(change) if change is not None else "—",
            "n/a" if math.isnan(c.speed_change) else f"{100 * c.speed_change:.3g}%",
            largest, status]


#: The rows' columns: ``largest`` is what the rows are sorted by and --fail-above bounds
#: (the largest change of any law's departure, or of the speeds).
ROW_HEADER = ["", "scenario", "source", "before", "after", "change", "speeds", "largest",
              "status"]


def summary_header(law: str) -> list[str]:
    """The per-source summary's columns. A smaller departure is *closer to the law*, which is
    not always better: an engine cut to fewer iterations may move closer to Poisson while it
    leaves the law its gate asks for."""
    return ["source", "matched", "median change (ok)", "worst change (ok)", f"closer to {law}",
            f"further from {law}", "status changed", "flagged in B", "new", "gone", "exceeding"]


def threshold_text(threshold: float) -> str:
    """What --fail-above bounds: a departure's change in percentage points, the speeds'
    change in percent of the motion before the impact."""
    return (f"{100 * threshold:g} pp (a departure) or {100 * threshold:g}% of the motion "
            "(the speeds)")


def summary_cells(row: SourceSummary) -> list[str]:
    def points(value):
        return "—" if math.isnan(value) else fmt_points(value)
    return [row.source, str(row.matched), points(row.median_change), points(row.worst_change),
            str(row.improved), str(row.worse), str(row.status_changed), str(row.flagged),
            str(row.new), str(row.gone), str(row.exceeding)]


def text_table(header: list[str], rows: list[list[str]]) -> str:
    """Columns padded to their widest cell, for the terminal."""
    widths = [max(len(str(cell)) for cell in column) for column in zip(header, *rows)]
    return "\n".join("  ".join(str(cell).ljust(width) for cell, width in zip(line, widths))
                     .rstrip() for line in [header, *rows])


def write_html(path: Path, a_path: Path, b_path: Path, law: str, threshold: float,
               summary: list[SourceSummary], rows: list[list[str]],
               differences: list[tuple[str, str, str]]) -> Path:
    """The comparison as a page: the per-source summary, what differs, every changed row."""
    parts = [page_head(f"compare {a_path.name} → {b_path.name}"),
             f"<h1>What changed from <code>{escape_html(a_path)}</code> to "
             f"<code>{escape_html(b_path)}</code></h1>",
             f"<p>Departures from <b>{escape_html(law)}</b>, in percent of the motion before "
             "the impact; changes in percentage points (pp). A row exceeds when a departure "
             f"from any law or the speeds changed by more than {threshold_text(threshold)}, "
             "or its status changed.</p>",
             "<h2>Per source</h2>",
             html_table(summary_header(law), [[escape_html(x) for x in summary_cells(r)]
                                         for r in summary]),
             "<h2>Versions and settings that differ</h2>",
             html_table(["what", "before", "after"],
                        [[escape_html(x) for x in row] for row in differences])
             if differences else "<p>None: the same versions and settings.</p>",
             "<h2>Changed runs</h2>",
             html_table(ROW_HEADER, [[escape_html(x) for x in row] for row in rows], left=3)
             if rows else "<p>No run changed.</p>",
             "</body></html>"]
    write_text_atomically(path, "\n".join(parts))
    return path

def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.description = __doc__.split("\n\n")[0].strip("`: ").replace("``", "")
    parser.epilog = (
        "Exit status: 0 when no matched record changed by more than --fail-above (departure "
        "change in percentage points, or speed change ‖u_B − u_A‖_M / s in the departures' "
        "kinetic-energy norm, M from the scenario's file) and none changed "
        "status, and no record of A is gone from B; 1 when one did or one is gone; 2 on bad "
        "input (missing or invalid file, bad threshold, no record in common, a record held "
        "twice, a law the harness does not know). Records only in B (new) are listed and "
        "counted but do not fail.")
    parser.add_argument("a", type=Path, help="the reference results file (before)")
    parser.add_argument("b", type=Path, help="the results file to check (after)")
    parser.add_argument("--fail-above", default=DEFAULT_THRESHOLD, metavar="X",
                        help="largest allowed change with its unit: 1%% or 1pp (percentage "
                             "points of a departure, percent of the motion for the speeds); "
                             "a bare number other than 0 is refused as ambiguous; default "
                             f"{DEFAULT_THRESHOLD.replace('%', '%%')}")
    parser.add_argument("--law", default="poisson", choices=LAWS,
                        help="the law whose departures the rows and the summary show, before "
                             "and after (default poisson); the gate weighs every law")
    parser.add_argument("--csv", type=Path, default=None, metavar="OUT",
                        help="also write every matched pair (both values and the change, in "
                             "percent) here")
    parser.add_argument("--html", type=Path, default=None, metavar="OUT",
                        help="also write the same tables as an HTML page here")
    parser.add_argument("--show", type=bounds.option("show"), default=20, metavar="N",
                        help="print the N largest changes (default 20; 0 prints none)")


def _same_file(one, other) -> bool:
    """Whether two paths name one existing file (through links, ``..`` or hard links), or
    are the same path."""
    if one is None or other is None:
        return False
    try:
        return os.path.samefile(one, other)
    except OSError:  # one is missing: the same only if spelled to the same place
        return os.path.abspath(one) == os.path.abspath(other)


def _bad_input(message: str) -> int:
    print(f"impact-harness compare: {message}", file=sys.stderr)
    return 2


def main(args) -> int:
    try:
        threshold = parse_threshold(args.fail_above)
    except ValueError as error:
        return _bad_input(str(error))
    for option, target in (("--csv", args.csv), ("--html", getattr(args, "html", None))):
        problem = None if target is None else output_file_problem(target)
        if problem:
            return _bad_input(f"{option} {target}: {problem}")
        if target is not None and any(_same_file(target, path) for path in (args.a, args.b)):
            return _bad_input(f"{option} {target}: is a results file being compared; allowed: "
                              "another file (it would be replaced by the table)")
    if args.csv is not None and _same_file(args.csv, getattr(args, "html", None)):
        return _bad_input(f"--csv and --html name one file, {args.csv}; allowed: two files")
    loaded = []
    for path in (args.a, args.b):
        try:
            loaded.append(read_results(path))
        except (OSError, ValueError, KeyError, TypeError) as error:
            return _bad_input(str(error))
    try:
        return _compare_and_show(args, loaded, threshold)
    except (TypeError, ValueError, KeyError, AttributeError, IndexError) as error:
        # read_results checks a record's fields, not every value's type: a record whose
        # speeds are not numbers, or whose name is not text, fails here
        return _bad_input(f"{args.a}, {args.b}: a record is malformed: "
                          f"{type(error).__name__}: {str(error)[:200]}")


def _compare_and_show(args, loaded: list[Results], threshold: float) -> int:
    """:func:`main` once both files are read: the comparison, printed."""
    for path, results in zip((args.a, args.b), loaded):
        problem = duplicate_problem(results, path) or unknown_law_problem(results, path)
        if problem:
            return _bad_input(problem)
    weights = MassMatrices(*loaded)
    changes, only_a, only_b = compare(*loaded, weights)
    if not changes:
        return _bad_input(f"{args.a} and {args.b} have no record in common")
    law = getattr(args, "law", "poisson")
    changes.sort(key=lambda c: (not c.status_changed, not c.problems, -c.largest))
    exceeding = [c for c in changes if c.exceeds(threshold)]
    changed = [c for c in changes if c.status_changed or c.problems or c.largest > 0]
    summary = summarise(changes, only_a, only_b, law, threshold)
    differences = setting_differences(*loaded)
    rows = [row_cells(c, law, threshold) for c in changed]
    try:
        if args.csv is not None:
            write_csv(changes, args.csv, loaded[1])
        if getattr(args, "html", None) is not None:
            write_html(args.html, args.a, args.b, law, threshold, summary, rows, differences)
    except OSError as error:
        return _bad_input(f"cannot write {error.filename or 'an output'}: "
                          f"{error.strerror or error}")
    print(f"departures from {law} in percent; changes in percentage points (pp)\n")
    print(text_table(summary_header(law), [summary_cells(row) for row in summary]))
    if differences:
        print("\nversions and settings that differ (before → after):")
        for what, before, after in differences:
            print(f"  {what}: {before} → {after}")
    if rows[:args.show]:
        print(f"\nthe {min(args.show, len(rows))} largest changes of {len(rows)} (a changed "
              "status or a result not finite first, then by the largest column):")
        print(text_table(ROW_HEADER, rows[:args.show]))
    for label, keys in (("only in A (gone from B: each fails the gate)", only_a),
                        ("only in B (new: listed, never failing)", only_b)):
        if keys:
            print(f"{len(keys)} records {label}, e.g. " + ", ".join(
                " ".join(part for part in key if part) for key in keys[:3]))
    if weights.missing:
        names = sorted(weights.missing)
        print(f"speeds not compared for {len(names)} scenarios whose file was not found "
              f"(their mass matrix weighs the speeds), e.g. {', '.join(names[:3])}")
    if weights.mismatched:
        names = sorted(weights.mismatched)
        print(f"speeds not compared for {len(names)} scenarios whose file no longer has the "
              f"masses their runs used (edited since?), e.g. {', '.join(names[:3])}")
    written = [str(p) for p in (args.csv, getattr(args, "html", None)) if p is not None]
    print(f"compared {len(changes)} records ({len(changed)} changed at all): {len(exceeding)} "
          f"changed by more than {threshold_text(threshold)}, changed status or hold a "
          f"result not finite in one file only; {len(only_a)} gone, {len(only_b)} new"
          + (f"; wrote {', '.join(written)}" if written else ""))
    return 1 if exceeding or only_a else 0


__all__ = ["Change", "MassMatrices", "SourceSummary", "add_arguments", "compare", "main",
           "parse_threshold", "setting_differences", "summarise", "unknown_law_problem",
           "write_csv", "write_html"]
