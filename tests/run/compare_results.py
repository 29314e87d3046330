"""Two results files of the same scenarios, compared with what differs from run to run masked:
the records must be the same line for line (every float bit for bit, as ``repr`` writes it).

Run on purpose, as a script, to check that a change to how records are built leaves them
unchanged (two cold runs of the same files, one before and one after the change)::

    python tests/run/compare_results.py BEFORE.json AFTER.json

Masked: each record's ``wall_time_s`` and ``diagnostics.engine_wall_time_s``, and in the
provenance the times, the command, the commit, the code version, the cache's place and
counts (what a run of the same scenarios by other code in another place changes). Exit
status 0 when the rest is equal, 1 (with the first differences) when not.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

#: Provenance keys that differ between two runs of the same scenarios by different code.
VOLATILE_PROVENANCE = ("created_utc", "command", "git", "code_version", "cache",
                       "wall_time_s", "machine")


def masked_record(record: dict) -> dict:
    """``record`` without its run times."""
    record = dict(record, wall_time_s=None)
    if isinstance(record.get("diagnostics"), dict) and "engine_wall_time_s" in record[
            "diagnostics"]:
        record["diagnostics"] = dict(record["diagnostics"], engine_wall_time_s=None)
    return record


def differences(before: dict, after: dict, limit: int = 10) -> list[str]:
    """The first ``limit`` differences of two results documents, masked."""
    found = []
    for key in sorted(set(before) | set(after)):
        if key in ("records", "provenance"):
            continue
        if before.get(key) != after.get(key):
            found.append(f"top-level {key!r} differs")
    old, new = before.get("provenance", {}), after.get("provenance", {})
    for key in sorted(set(old) | set(new)):
        if key not in VOLATILE_PROVENANCE and old.get(key) != new.get(key):
            found.append(f"provenance {key!r}: {old.get(key)!r} != {new.get(key)!r}")
    records_before, records_after = before.get("records", []), after.get("records", [])
    if len(records_before) != len(records_after):
        found.append(f"{len(records_before)} records != {len(records_after)}")
    for index, (one, other) in enumerate(zip(records_before, records_after)):
        one_line = json.dumps(masked_record(one), sort_keys=True)
        other_line = json.dumps(masked_record(other), sort_keys=True)
        if one_line != other_line:
            found.append(f"record {index} ({one.get('scenario')}, {one.get('source')}) "
                         f"differs:\n  {one_line[:300]}\n  {other_line[:300]}")
        if len(found) >= limit:
            break
    return found[:limit]


def main(argv: list[str]) -> int:
    if len(argv) != 2:
        print(__doc__, file=sys.stderr)
        return 2
    before, after = (json.loads(Path(path).read_text()) for path in argv)
    found = differences(before, after)
    for line in found:
        print(line)
    count = len(before.get("records", []))
    print(f"{count} records: " + ("the same (masked)" if not found else "DIFFERENT"))
    return 1 if found else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
