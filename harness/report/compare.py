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
import math
import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from harness.run import metrics
from harness.run.records import Record, Results, read_results
from harness.scenarios.errors import ScenarioError

DEFAULT_THRESHOLD = "1%"
LAWS = ("poisson", "stronge", "stronge-paper", "newton", "newton-lcp")


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
        from harness.scenarios.schema import SCENARIO_DIR

        paths = [info.get("path") for results in reversed(self.results)
                 if isinstance(info := results.scenarios.get(name), dict)]
        found = [Path(path) for path in paths if path]
        found += [SCENARIO_DIR / path.name for path in found]
        return found + [SCENARIO_DIR / f"{name}.toml"]

    def scenario(self, name: str):
        if name not in self.scenarios:
            from harness.scenarios.reader import load_scenario

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
    return f"{100.0 * change:+.3g} pp"


def write_csv(changes: list[Change], path: Path) -> Path:
    """One row per matched pair: statuses, every departure in A and B and its change, the
    speeds in A and B and the speed change."""
    size = max((len(c.u_a or c.u_b or []) for c in changes), default=0)
    header = ["scenario", "point", "source", "status_a", "status_b"]
    for law in LAWS:
        header += [f"departure_{law}_a", f"departure_{law}_b", f"departure_{law}_change"]
    header += [f"u{i + 1}_a" for i in range(size)] + [f"u{i + 1}_b" for i in range(size)]
    header += ["speed_change", "largest_change"]
    with path.open("w", newline="", encoding="utf-8") as handle:
        writer = csv.writer(handle)
        writer.writerow(header)
        for c in changes:
            row = [c.scenario, c.point, c.source, c.status_a, c.status_b]
            deltas = c.departure_change
            for law in LAWS:
                row += [c.departure_a.get(law, ""), c.departure_b.get(law, ""),
                        deltas.get(law, "")]
            for speeds in (c.u_a, c.u_b):
                speeds = list(speeds or [])
                row += speeds + [""] * (size - len(speeds))
            row += ["" if math.isnan(c.speed_change) else c.speed_change, c.largest]
            writer.writerow(row)
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
    parser.add_argument("--csv", type=Path, default=None, metavar="OUT",
                        help="also write every matched pair (both values and the change) here")
    parser.add_argument("--show", type=int, default=20, metavar="N",
                        help="print the N largest changes (default 20; 0 prints none)")


def csv_problem(path: Path) -> str | None:
    """Why ``--csv PATH`` cannot be written (checked before any file is read), or None."""
    try:
        if path.exists() and not path.is_file():
            return "is not a regular file (a directory or a device)"
        if not path.parent.is_dir():
            return f"no directory {path.parent}"
    except OSError as error:  # a name too long, a loop of links
        return error.strerror or str(error)
    return None


def _bad_input(message: str) -> int:
    print(f"impact-harness compare: {message}", file=sys.stderr)
    return 2


def main(args) -> int:
    try:
        threshold = parse_threshold(args.fail_above)
    except ValueError as error:
        return _bad_input(str(error))
    if args.csv is not None and (problem := csv_problem(Path(args.csv))):
        return _bad_input(f"--csv {args.csv}: {problem}")
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
    changes.sort(key=lambda c: (not c.status_changed, -c.largest))
    exceeding = [c for c in changes if c.exceeds(threshold)]
    if args.csv is not None:
        try:
            write_csv(changes, args.csv)
        except OSError as error:
            return _bad_input(f"--csv {args.csv}: cannot write: {error.strerror or error}")
    changed = [c for c in changes if c.status_changed or c.largest > 0]
    for c in changed[:args.show]:
        deltas = c.departure_change
        worst_law = max(deltas, key=lambda law: abs(deltas[law])) if deltas else None
        status = f"{c.status_a} -> {c.status_b}" if c.status_changed else c.status_b
        speeds = "n/a" if math.isnan(c.speed_change) else f"{100 * c.speed_change:.3g}%"
        law_text = (f"departure from {worst_law} {fmt_points(deltas[worst_law])}"
                    if worst_law else "no departures")
        mark = "EXCEEDS" if c.exceeds(threshold) else "ok"
        point = f" [{c.point}]" if c.point else ""
        print(f"{mark:7s} {c.scenario}{point} {c.source}: {law_text}; speeds {speeds}; {status}")
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
    print(f"compared {len(changes)} records ({len(changed)} changed at all): {len(exceeding)} "
          "changed by more than "
          f"{100 * threshold:g}% or changed status"
          + (f"; wrote {args.csv}" if args.csv is not None else ""))
    return 1 if exceeding else 0


__all__ = ["Change", "MassMatrices", "add_arguments", "compare", "main", "parse_threshold",
           "write_csv"]
