"""``impact-harness export RESULTS --out FILE``: the records as one tidy long table.

::

    impact-harness export reports/results.json --out records.parquet   # or .csv

One row per run × law: a law's record gives a row per law it is compared with (its departure
from each), an engine run a row per law too, so "departure of pymunk.accurate from Poisson
in scenario X" is one row and a pivot or group-by is one call in pandas, polars or a
spreadsheet. Columns: ``scenario``, ``point`` (the sweep point's label, empty for a single
point), ``point_index``, ``point_value``, ``source`` (``"poisson"`` or ``"pymunk.accurate"``),
``engine`` (empty for a law), ``preset``, ``law`` (the law departed from), ``departure`` (a
fraction, as in the results file; ``departure_pct`` in percent, as the reports show it),
``status``, ``verdict``, ``reasons`` (the failing checks' names: a list column in Parquet,
``;``-separated in CSV), ``overrides`` (the engine settings the run overrode, as JSON).
Every column and its unit are also in the Parquet file's metadata.

Exit status: 0 written; 2 bad input (results file missing or not a results file, an output
that is not a new or regular ``.csv``/``.parquet`` file).
"""

from __future__ import annotations

import argparse
import csv
import io
import json
import sys
from pathlib import Path

from harness.run.records import ANALYTIC, Results, read_results
from harness.store.files import output_file_problem, write_bytes_atomically, write_text_atomically

COLUMNS = ("scenario", "point", "point_index", "point_value", "source", "engine", "preset",
           "law", "departure", "departure_pct", "status", "verdict", "reasons", "overrides")
UNITS = {"departure": "fraction", "departure_pct": "percent"}


def long_rows(results: Results) -> list[dict]:
    """One row per record × law it has a departure from, in the file's record order."""
    rows = []
    for record in results.records:
        engine = "" if record.source == ANALYTIC else record.source
        overrides = (record.diagnostics or {}).get("settings_overrides") or {}
        common = {"scenario": record.scenario,
                  "point": str(record.point.get("label") or ""),
                  "point_index": int(record.point.get("index", 0)),
                  "point_value": record.point.get("value"),
                  "source": record.label, "engine": engine,
                  "preset": record.preset or "", "status": record.status,
                  "verdict": record.verdict or "",
                  "reasons": list(record.failing_reasons),
                  "overrides": json.dumps(overrides, sort_keys=True) if overrides else ""}
        for law, departure in record.departure.items():
            value = None if departure is None else float(departure)
            rows.append({**common, "law": law, "departure": value,
                         "departure_pct": None if value is None else 100.0 * value})
    return rows


#: What a spreadsheet reads as the start of a formula in a cell (CWE-1236).
_FORMULA_START = ("=", "+", "-", "@", "\t", "\r")


def csv_cell(value):
    """``value`` as a CSV cell a spreadsheet shows as text: a string starting like a formula
    (``=HYPERLINK(...)`` in a scenario's name read from a results file) gets a leading
    ``'``; numbers and other strings are as they are."""
    if isinstance(value, str) and value.startswith(_FORMULA_START):
        return "'" + value
    return value


def write_long(results: Results, path: Path) -> int:
    """Write :func:`long_rows` to ``path`` (``.csv`` or ``.parquet``); the row count."""
    rows = long_rows(results)
    if path.suffix == ".parquet":
        import pyarrow as pa
        import pyarrow.parquet as pq

        types = {"point_index": pa.int64(), "point_value": pa.float64(),
                 "departure": pa.float64(), "departure_pct": pa.float64(),
                 "reasons": pa.list_(pa.string())}
        provenance = results.provenance or {}
        schema = pa.schema(
            [pa.field(name, types.get(name, pa.string()),
                      metadata={"unit": UNITS[name]} if name in UNITS else None)
             for name in COLUMNS],
            metadata={"impact_harness": json.dumps(
                {"format": "impact-harness-records-long",
                 "created_utc": provenance.get("created_utc"), "git": provenance.get("git"),
                 "versions": provenance.get("versions")}, sort_keys=True)})
        values = {name: [row[name] for row in rows] for name in COLUMNS}
        values["point_value"] = [v if isinstance(v, (int, float)) else None
                                 for v in values["point_value"]]
        buffer = pa.BufferOutputStream()
        pq.write_table(pa.table(values, schema=schema), buffer)
        write_bytes_atomically(path, buffer.getvalue().to_pybytes())  # a regular file only
    else:
        handle = io.StringIO(newline="")
        writer = csv.DictWriter(handle, COLUMNS)
        writer.writeheader()
        for row in rows:
            row = {**row, "reasons": ";".join(row["reasons"]),
                   **{key: "" if row[key] is None else row[key]
                      for key in ("point_value", "departure", "departure_pct")}}
            writer.writerow({key: csv_cell(value) for key, value in row.items()})
        write_text_atomically(path, handle.getvalue())  # a regular file only
    return len(rows)


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.description = __doc__.split("\n\n")[0].strip("`: ").replace("``", "")
    parser.epilog = __doc__.split("\n\n")[-1]
    parser.add_argument("results", type=Path, help="a results file (reports/results.json)")
    parser.add_argument("--out", type=Path, required=True,
                        help="the table to write: FILE.csv or FILE.parquet")


def main(args) -> int:
    out = args.out
    if out.suffix not in (".csv", ".parquet"):
        print(f"impact-harness export: --out {out}: the file must end in .csv or .parquet",
              file=sys.stderr)
        return 2
    problem = output_file_problem(out)
    if problem:
        print(f"impact-harness export: --out {out}: {problem}", file=sys.stderr)
        return 2
    try:
        results = read_results(args.results)
    except (OSError, ValueError, KeyError, TypeError) as error:
        print(f"impact-harness export: {error}", file=sys.stderr)
        return 2
    try:
        count = write_long(results, out)
    except (TypeError, ValueError, AttributeError, KeyError, IndexError) as error:
        # read_results checks a record's fields, not every value's type: a departure that
        # is a list, a diagnostics that is a number fail here, before anything is written
        print(f"impact-harness export: {args.results}: a record is malformed: "
              f"{type(error).__name__}: {str(error)[:200]}", file=sys.stderr)
        return 2
    print(f"wrote {count} rows (run × law) to {out}")
    return 0


__all__ = ["COLUMNS", "add_arguments", "long_rows", "main", "write_long"]
