"""The results file's documented format: docs/results.schema.json validates every results
file the harness writes, and rejects files that break it; the tidy export."""

from __future__ import annotations

import copy
import json
from pathlib import Path

import jsonschema
import pyarrow.parquet as pq
import pytest

from harness.cli import main
from harness.run import runner
from harness.run.records import write_results
from harness.scenarios import load_scenarios

ROOT = Path(__file__).resolve().parents[2]
SCHEMA = json.loads((ROOT / "docs" / "results.schema.json").read_text(encoding="utf-8"))


@pytest.fixture(scope="module")
def results_path(tmp_path_factory):
    """A results file written by a run of two library scenarios (one flagged engine run at
    least: a flat face), every engine."""
    out = tmp_path_factory.mktemp("results")
    scenarios = [s for s in load_scenarios() if s.name in ("disk-oblique", "flat-box")]
    outcome = runner.run(scenarios, cache=None, workers=1, log=None)
    return write_results(out / "results.json", outcome.records, outcome.provenance,
                         outcome.scenarios)


def test_the_schema_is_a_valid_json_schema():
    jsonschema.Draft202012Validator.check_schema(SCHEMA)


def test_a_fresh_results_file_validates(results_path):
    document = json.loads(results_path.read_text(encoding="utf-8"))
    jsonschema.validate(document, SCHEMA)
    assert any(record["reasons"] for record in document["records"])  # reasons were checked


def test_the_committed_report_results_validate():
    path = ROOT / "reports" / "results.json"
    jsonschema.validate(json.loads(path.read_text(encoding="utf-8")), SCHEMA)


@pytest.mark.parametrize("breakage", [
    lambda d: d.update(format_version=2),
    lambda d: d["records"][0].pop("status"),
    lambda d: d["records"][0].update(departure={"poisson": "3%"}),
    lambda d: d["records"][0].update(extra_field=1),
    lambda d: d["records"][-1]["reasons"].append({"name": "x"}),
])
def test_the_schema_rejects_a_broken_file(results_path, breakage):
    document = json.loads(results_path.read_text(encoding="utf-8"))
    broken = copy.deepcopy(document)
    breakage(broken)
    with pytest.raises(jsonschema.ValidationError):
        jsonschema.validate(broken, SCHEMA)


def test_export_writes_one_row_per_run_and_law(results_path, tmp_path):
    document = json.loads(results_path.read_text(encoding="utf-8"))
    expected = sum(len(record["departure"]) for record in document["records"])
    out = tmp_path / "long.parquet"
    assert main(["export", str(results_path), "--out", str(out)]) == 0
    table = pq.read_table(out)
    assert table.num_rows == expected
    rows = table.to_pylist()
    engine_rows = [row for row in rows if row["engine"]]
    assert engine_rows and all(row["source"].startswith(row["engine"] + ".")
                               for row in engine_rows)
    flagged = [row for row in engine_rows if row["status"] != "ok"]
    assert flagged and all(isinstance(row["reasons"], list) and row["reasons"]
                           for row in flagged)
    one = next(row for row in engine_rows if row["departure"] is not None)
    assert one["departure_pct"] == pytest.approx(100 * one["departure"])
    assert table.schema.field("departure").metadata == {b"unit": b"fraction"}
    csv_out = tmp_path / "long.csv"
    assert main(["export", str(results_path), "--out", str(csv_out)]) == 0
    assert len(csv_out.read_text(encoding="utf-8").splitlines()) == expected + 1
    assert main(["export", str(results_path), "--out", str(tmp_path)]) == 2
    assert main(["export", str(results_path), "--out", str(tmp_path / "x.txt")]) == 2
