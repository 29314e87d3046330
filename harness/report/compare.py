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
or when its status changed. Records only in A or only in B are listed but do not fail the
comparison (a quick run compared with a full one is not a regression).

Exit status, for gating an engine upgrade or a settings change in CI:
0 no pair exceeds the threshold; 1 at least one does; 2 bad input (a file missing or not a
results file, a bad threshold, or no record in common).
"""

from __future__ import annotations

import argparse
import csv
import io
import json
import math
import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from harness.engines import source_label
from harness.laws import LAW_NAMES
from harness.report.markup import html_table, page_head
from harness.report.views import escape_html
from harness.run import metrics
from harness.run.records import Record, Results, read_results
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
    def largest(self) -> float:
        """The largest absolute change (departures and speeds), for sorting and gating."""
        values = [abs(v) for v in self.departure_change.values()]
        if math.isfinite(self.speed_change):
            values.append(self.speed_change)
        return max(values, default=0.0)

    @property
    def status_changed(self) -> bool:
        return self.status_a != self.status_b

    def exceeds(self, threshold: float) -> bool:
        return self.status_changed or self.largest > threshold


def parse_threshold(text: str) -> float:
    """``"1%"`` -> 0.01, ``"0.01"`` -> 0.01; raises ValueError for a negative or bad value."""
    text = text.strip()
    value = float(text[:-1]) / 100.0 if text.endswith("%") else float(text)
    if not math.isfinite(value) or value < 0:
        raise ValueError(f"threshold must be a non-negative number or percentage, not {text!r}")
    return value


def record_key(record: Record) -> tuple[str, str, str]:
    return record.scenario, str(record.point.get("label", record.point.get("index"))), record.label


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
        energy_before = 0.5 * before @ mass_matrix @ before
        recomputed = 0.5 * after @ mass_matrix @ after - energy_before
        if abs(recomputed - record.energy_change) > 1e-9 * max(energy_before, 1e-300):
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
        change = speed_change(ra, rb, weights(rb) if has_speeds else None)
        changes.append(Change(*key, ra.status, rb.status, dict(ra.departure),
                              dict(rb.departure), ra.u_after, rb.u_after, change))
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
        return "" if value is None or not math.isfinite(value) else 100.0 * value

    handle = io.StringIO(newline="")  # the rows in memory, then written atomically
    writer = csv.writer(handle)
    writer.writerow(header)
    for c in changes:
        row = [c.scenario, c.point, c.source, c.status_a, c.status_b]
        deltas = c.departure_change
        for law in LAWS:
            row += [percent(c.departure_a.get(law)), percent(c.departure_b.get(law)),
                    percent(deltas.get(law))]
        count = len(c.u_a or c.u_b or [])
        names = speed_names(b, c, count) if b is not None else [
            f"u{i + 1}" for i in range(count)]
        for i in range(size):
            row += ([names[i], (c.u_a or [""] * count)[i], (c.u_b or [""] * count)[i]]
                    if i < count else ["", "", ""])
        row += [percent(c.speed_change), percent(c.largest)]
        writer.writerow(row)
    write_text_atomically(path, handle.getvalue())
    return path


def row_cells(c: Change, law: str, threshold: float) -> list[str]:
    """A matched pair against one law: before, after, change, speed change, status."""
    before, after = c.departure_a.get(law), c.departure_b.get(law)
    change = c.departure_change.get(law)
    status = f"{c.status_a} → {c.status_b}" if c.status_changed else c.status_b
    return ["EXCEEDS" if c.exceeds(threshold) else "ok",
            c.scenario + (f" [{c.point}]" if c.point else ""), c.source,
            "—" if before is None else metrics.fmt_departure(before),
            "—" if after is None else metrics.fmt_departure(after),
            fmt_points(change) if change is not None else "—",
            "n/a" if math.isnan(c.speed_change) else f"{100 * c.speed_change:.3g}%", status]


ROW_HEADER = ["", "scenario", "source", "before", "after", "change", "speeds", "status"]


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
        "status; 1 when one did; 2 on bad input (missing or invalid file, bad threshold, no "
        "record in common). Records only in one file are listed but do not fail.")
    parser.add_argument("a", type=Path, help="the reference results file (before)")
    parser.add_argument("b", type=Path, help="the results file to check (after)")
    parser.add_argument("--fail-above", default=DEFAULT_THRESHOLD, metavar="X",
                        help="largest allowed change, as a percentage (1%%) or a fraction "
                             f"(0.01); default {DEFAULT_THRESHOLD.replace('%', '%%')}")
    parser.add_argument("--law", default="poisson", choices=LAWS,
                        help="the law whose departures the rows and the summary show, before "
                             "and after (default poisson); the gate weighs every law")
    parser.add_argument("--csv", type=Path, default=None, metavar="OUT",
                        help="also write every matched pair (both values and the change, in "
                             "percent) here")
    parser.add_argument("--html", type=Path, default=None, metavar="OUT",
                        help="also write the same tables as an HTML page here")
    parser.add_argument("--show", type=int, default=20, metavar="N",
                        help="print the N largest changes (default 20; 0 prints none)")


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
    weights = MassMatrices(*loaded)
    changes, only_a, only_b = compare(*loaded, weights)
    if not changes:
        return _bad_input(f"{args.a} and {args.b} have no record in common")
    law = getattr(args, "law", "poisson")
    changes.sort(key=lambda c: (not c.status_changed, -c.largest))
    exceeding = [c for c in changes if c.exceeds(threshold)]
    changed = [c for c in changes if c.status_changed or c.largest > 0]
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
        print(f"\nthe {min(args.show, len(rows))} largest changes of {len(rows)}:")
        print(text_table(ROW_HEADER, rows[:args.show]))
    for label, keys in (("only in A", only_a), ("only in B", only_b)):
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
          f"changed by more than {threshold_text(threshold)} or changed status"
          + (f"; wrote {', '.join(written)}" if written else ""))
    return 1 if exceeding else 0


__all__ = ["Change", "MassMatrices", "SourceSummary", "add_arguments", "compare", "main",
           "parse_threshold", "setting_differences", "summarise", "write_csv", "write_html"]
