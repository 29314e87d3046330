"""A figure is redrawn when, and only when, its inputs change: the digests of the records --
of what they decided and what they were made from, never of their floats' last bits, which
depend on the CPU (a fresh clone on another machine reuses the committed figures)."""

from __future__ import annotations

import copy
import json
import math
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from harness import report
from harness.report.figure_cache import scenario_digests
from harness.report.views import slug
from harness.run import runner
from harness.run.records import Record, Results, read_results, write_results
from harness.scenarios import load_scenarios

ROOT = Path(__file__).resolve().parents[2]


def _record(scenario: str, departure: float, **changes) -> Record:
    return Record(scenario=scenario, point={"index": 0, "label": "p"}, source="pymunk",
                  preset="defaults", u_after=[1.0, 2.0, 3.0], departure={"poisson": departure},
                  diagnostics={"engine_wall_time_s": 0.5, "history": {"normal_impulse": [1.0]}},
                  **changes)


def test_digests_of_results_read_and_in_memory_agree_and_ignore_times(tmp_path):
    records = [_record("a", 0.1), _record("b", 0.2), _record("a", 0.3)]
    path = write_results(tmp_path / "r.json", records, {}, {})
    digests = scenario_digests(read_results(path))
    assert set(digests) == {"a", "b"}
    assert scenario_digests(Results(records)) == digests
    timed = [_record("a", 0.1, wall_time_s=9.0, cached=True), _record("b", 0.2),
             _record("a", 0.3, wall_time_s=0.001)]
    timed[1].diagnostics["engine_wall_time_s"] = 7.0
    assert scenario_digests(Results(timed)) == digests


def _next_float(value):
    """``value`` one unit in the last place up, inside lists and dicts too."""
    if isinstance(value, float):
        return float(np.nextafter(value, math.inf))
    if isinstance(value, list):
        return [_next_float(item) for item in value]
    if isinstance(value, dict):
        return {key: _next_float(item) for key, item in value.items()}
    return value


@pytest.mark.parametrize("change", [
    lambda r: r.departure.update(poisson=float(np.nextafter(r.departure["poisson"], 1.0))),
    lambda r: r.u_after.__setitem__(1, float(np.nextafter(2.0, 3.0))),
    lambda r: r.u_after.__setitem__(1, 2.0000000001),  # a float moved further: still a float
    lambda r: setattr(r, "diagnostics", _next_float(r.diagnostics)),
    lambda r: setattr(r, "wall_time_s", 9.0), lambda r: setattr(r, "cached", True),
])
def test_a_float_of_a_result_in_its_last_bits_or_a_time_changes_no_digest(change):
    records = [_record("a", 0.1), _record("b", 0.2)]
    before = scenario_digests(Results(records))
    change(records[0])
    assert scenario_digests(Results(records)) == before


@pytest.mark.parametrize("change", [
    lambda r: setattr(r, "status", "flagged"),
    lambda r: setattr(r, "verdict", "flagged"),
    lambda r: setattr(r, "collision_type", 3),
    lambda r: r.point.update(index=1),
    lambda r: setattr(r, "preset", "accurate"),
])
def test_a_change_of_what_a_record_decided_changes_its_scenarios_digest_only(change):
    records = [_record("a", 0.1), _record("b", 0.2)]
    before = scenario_digests(Results(records))
    change(records[0])
    after = scenario_digests(Results(records))
    assert after["a"] != before["a"] and after["b"] == before["b"]


def test_a_change_of_what_made_the_records_changes_the_digests():
    records = [_record("a", 0.1), _record("b", 0.2)]
    provenance = {"code_version": "c0de", "versions": {"numpy": "2.4.6"},
                  "engine_settings": {"pymunk": {"defaults": {"time_step": 0.01}}},
                  "settings_overrides": {}, "machine": {"cpu_model": "AMD EPYC"}}
    scenarios = {"a": {"definition": "d1", "path": "/here/a.toml"},
                 "b": {"definition": "d2", "path": "/here/b.toml"}}
    before = scenario_digests(Results(records, provenance, scenarios))

    def digests(provenance_change=None, scenarios_change=None):
        changed_provenance, changed_scenarios = copy.deepcopy((provenance, scenarios))
        (provenance_change or (lambda p: None))(changed_provenance)
        (scenarios_change or (lambda s: None))(changed_scenarios)
        return scenario_digests(Results(records, changed_provenance, changed_scenarios))

    # the code, an installed version, a setting given: every scenario's digest
    for change in (lambda p: p.update(code_version="c0de2"),
                   lambda p: p["versions"].update(numpy="2.5.0"),
                   lambda p: p.update(settings_overrides={"pymunk.iterations": 20})):
        after = digests(provenance_change=change)
        assert after["a"] != before["a"] and after["b"] != before["b"]
    # a scenario's definition: its digest only
    after = digests(scenarios_change=lambda s: s["a"].update(definition="d1-edited"))
    assert after["a"] != before["a"] and after["b"] == before["b"]
    # where the files are, the machine, and a worked-out setting's last bit: none
    assert digests(scenarios_change=lambda s: s["a"].update(path="/elsewhere/a.toml"),
                   provenance_change=lambda p: p.update(
                       machine={"cpu_model": "Intel Xeon"},
                       engine_settings=_next_float(p["engine_settings"]))) == before


@pytest.fixture(scope="module")
def results_file(tmp_path_factory):
    """Two quick scenarios run once (no cache), written as `run` writes them."""
    out = tmp_path_factory.mktemp("results")
    scenarios = load_scenarios(tags="quick")[:2]
    outcome = runner.run(scenarios, cache=None, workers=1, log=None)
    return write_results(out / "results.json", outcome.records, outcome.provenance,
                         outcome.scenarios)


#: The report options of every report written here: SVG twins of the headline figures only
#: (a scenario's SVG twins are tested in test_scale.py and test_table3.py).
OPTIONS = {"workers": 1, "svg": "headline"}


@pytest.fixture(scope="module")
def drawn_report(results_file, tmp_path_factory) -> Path:
    """The report of ``results_file``, drawn once: each test starts from a copy of it (the
    drawing is most of these tests' time, and what each tests comes after it)."""
    out = tmp_path_factory.mktemp("drawn") / "report"
    report.write_report(read_results(results_file), out, **OPTIONS)
    return out


def _copy_of(report_dir: Path, target: Path) -> Path:
    """A copy of a written report, the files' times kept (they tell a redrawn figure)."""
    shutil.copytree(report_dir, target)
    return target


def _rewrite(source: Path, target: Path, change) -> Path:
    """``source`` with ``change(record dict)`` applied to every record, as `run` writes."""
    results = read_results(source)
    data = [record.as_dict() for record in results.records]
    for item in data:
        change(item)
    return write_results(target, [Record.from_dict(item) for item in data],
                         results.provenance, results.scenarios)


def _times(out: Path) -> dict[str, int]:
    return {p.name: p.stat().st_mtime_ns for p in (out / "figures").glob("*.png")}


def test_a_changed_record_redraws_its_figures_and_the_headline_only(results_file, drawn_report,
                                                                   tmp_path):
    """Which PNGs are drawn again; a scenario's figures without their SVG twins (when a
    twin is drawn with its PNG: test_scale.py and test_table3.py)."""
    out = _copy_of(drawn_report, tmp_path / "report")
    drawn = _times(out)
    first, second = read_results(results_file).scenario_names()
    assert {"heatmap.png", f"impulse-{slug(first)}.png",
            f"impulse-{slug(second)}.png"} <= set(drawn)

    def new_times(item):
        item["wall_time_s"] = 123.0
        if item["source"] != "analytic":
            item["cached"] = not item["cached"]
            (item["diagnostics"] or {})["engine_wall_time_s"] = 4.5

    retimed = _rewrite(results_file, tmp_path / "retimed.json", new_times)
    report.write_report(read_results(retimed), out, **OPTIONS)
    assert _times(out) == drawn  # only times changed: nothing redrawn

    nudged = _rewrite(retimed, tmp_path / "nudged.json",
                      lambda item: item.update(_next_float(item)))
    report.write_report(read_results(nudged), out, **OPTIONS)
    assert _times(out) == drawn  # every float a last bit up (another CPU): nothing redrawn

    def decides_otherwise(item):
        if item["scenario"] == first and item["source"] != "analytic":
            item["status"] = "flagged"

    changed = _rewrite(retimed, tmp_path / "changed.json", decides_otherwise)
    report.write_report(read_results(changed), out, **OPTIONS)
    after = _times(out)
    redrawn = {name for name in drawn if after[name] != drawn[name]}
    assert {"heatmap.png", f"impulse-{slug(first)}.png"} <= redrawn
    assert not any(slug(second) in name for name in redrawn)
    assert "paper-table3.png" not in redrawn


@pytest.mark.parametrize("many", [False, True])
def test_a_report_with_nothing_to_draw_never_imports_matplotlib(results_file, drawn_report,
                                                                tmp_path, monkeypatch, many):
    threshold = 1 if many else report.MANY_SCENARIOS  # many: the aggregated page's heat table
    monkeypatch.setattr(report, "MANY_SCENARIOS", threshold)
    out = _copy_of(drawn_report, tmp_path / "report")
    report.write_report(read_results(results_file), out, **OPTIONS)  # draws what is missing
    script = ("import sys\nfrom harness import report\n"
              "from harness.run.records import read_results\n"
              f"report.MANY_SCENARIOS = {threshold}\n"
              f"report.write_report(read_results({str(results_file)!r}), {str(out)!r}, "
              f"**{OPTIONS!r})\n"
              "print(json.dumps(sorted(m for m in sys.modules if m.split('.')[0] in "
              "('matplotlib', 'PIL'))))\n")
    done = subprocess.run([sys.executable, "-c", "import json\n" + script], cwd=ROOT,
                          capture_output=True, text=True, check=True)
    assert json.loads(done.stdout.strip().splitlines()[-1]) == []


def test_a_sweep_figures_digest_is_the_same_in_any_checkout():
    """The results record each scenario file's absolute path; a figure reading only the
    sweep must not be redrawn because the repository sits elsewhere (a fresh clone)."""
    from harness.report.figure_cache import inputs_digest

    results = read_results(ROOT / "reports" / "results.json")

    def sweep_tags():
        return {task.file: inputs_digest(task.kind, task.payload)
                for task in report.figure_tasks(results, False, "all", (), "none")
                if task.kind == "sweep"}

    here = sweep_tags()
    assert here  # the library has sweeps
    for info in results.scenarios.values():
        if isinstance(info, dict) and info.get("path"):
            info["path"] = "/elsewhere/" + Path(info["path"]).name
    assert sweep_tags() == here
