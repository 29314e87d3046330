"""``impact-harness compare A.json B.json``: what changed between two results files.

::

    impact-harness compare old/results.json new/results.json --fail-above 1% --csv diff.csv

Records are matched by scenario, sweep point and source (a law, or ``engine.preset``). For
each pair it reports

* the change of every departure, ``d_B − d_A`` (in percentage points: departures are
  fractions of the motion before the impact, shown in percent), and
* the change of the post-impact speeds, ``‖u_B − u_A‖ / ‖u_before‖`` (Euclidean over the
  generalized speeds, relative to the speeds before the impact; the results do not hold
  the mass matrix, so this is not the kinetic-energy norm of the departures),

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
from dataclasses import dataclass
from pathlib import Path

from harness.run.records import Record, Results, read_results

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
    speed_change: float  # ‖u_B − u_A‖ / ‖u_before‖, nan when either has no speeds

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


def speed_change(a: Record, b: Record) -> float:
    """``‖u_B − u_A‖ / ‖u_before‖`` (Euclidean); nan when a record has no speeds."""
    if not a.u_after or not b.u_after or len(a.u_after) != len(b.u_after):
        return math.nan
    if any(v is None for v in (*a.u_after, *b.u_after)):
        return math.nan
    before = b.u_before or a.u_before or []
    scale = math.sqrt(sum(v * v for v in before)) or 1.0
    return math.sqrt(sum((vb - va) ** 2 for va, vb in zip(a.u_after, b.u_after))) / scale


def compare(a: Results, b: Results) -> tuple[list[Change], list[tuple], list[tuple]]:
    """The changes of the records in both, and the keys only in A and only in B."""
    records_a = {record_key(r): r for r in a.records}
    records_b = {record_key(r): r for r in b.records}
    changes = []
    for key, ra in records_a.items():
        rb = records_b.get(key)
        if rb is None:
            continue
        changes.append(Change(*key, ra.status, rb.status, dict(ra.departure),
                              dict(rb.departure), ra.u_after, rb.u_after, speed_change(ra, rb)))
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
        "change in percentage points, or speed change ‖u_B − u_A‖/‖u_before‖) and none changed "
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


def main(args) -> int:
    try:
        threshold = parse_threshold(args.fail_above)
    except ValueError as error:
        print(f"impact-harness compare: {error}")
        return 2
    loaded = []
    for path in (args.a, args.b):
        try:
            loaded.append(read_results(path))
        except (OSError, ValueError, KeyError, TypeError) as error:
            print(f"impact-harness compare: {error}")
            return 2
    changes, only_a, only_b = compare(*loaded)
    if not changes:
        print(f"impact-harness compare: {args.a} and {args.b} have no record in common")
        return 2
    changes.sort(key=lambda c: (not c.status_changed, -c.largest))
    exceeding = [c for c in changes if c.exceeds(threshold)]
    if args.csv is not None:
        write_csv(changes, args.csv)
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
    print(f"compared {len(changes)} records ({len(changed)} changed at all): {len(exceeding)} "
          "changed by more than "
          f"{100 * threshold:g}% or changed status"
          + (f"; wrote {args.csv}" if args.csv is not None else ""))
    return 1 if exceeding else 0


__all__ = ["Change", "add_arguments", "compare", "main", "parse_threshold", "write_csv"]
