"""An engine registered at run time is an engine like the shipped ones for ``impact-harness
run`` (issue 26): ``--engines`` and ``--set`` accept it, a run with no ``--engines`` runs it,
and its records land in the results. The toy of tests/engines/toy_engine.py (exact Poisson
impulses), registered by the ``toy_engine`` fixture of tests/conftest.py as the only engine
listed, runs a library scenario."""

from __future__ import annotations

import pytest

from harness import cli
from harness.engines import engine_names, parse_overrides
from harness.run import plan, runner
from harness.run.records import read_results
from harness.scenarios import SCENARIO_DIR, load_scenario

# A library scenario whose laws disagree (the slip reverses during restitution): Poisson's
# answer is not the other laws', so matching it says the toy's own impulse was applied.
LIBRARY_FILE = SCENARIO_DIR / "rod-45-reversal-in-restitution.toml"


def test_run_engines_toy_runs_a_library_scenario_through_the_toy(tmp_path, capsys,
                                                                   toy_engine):
    out = tmp_path / "results.json"
    status = cli.main(["run", str(LIBRARY_FILE), "--engines", toy_engine, "--no-cache",
                       "--workers", "1", "--json", str(out)])
    assert status == 0, capsys.readouterr().err
    results = read_results(out)
    engine_records = [r for r in results.records if r.source != "analytic"]
    assert {(r.source, r.preset) for r in engine_records} == {(toy_engine, "defaults"),
                                                              (toy_engine, "accurate")}
    assert results.provenance["selection"]["engines"] == [toy_engine]
    laws = {r.law: r for r in results.records if r.source == "analytic"}
    assert laws["poisson"].u_after != pytest.approx(laws["newton-lcp"].u_after, abs=1e-6)
    for record in engine_records:
        assert record.status == "ok"
        assert record.u_after == pytest.approx(laws["poisson"].u_after, abs=1e-9)
        assert record.departure["poisson"] < 1e-9 < record.departure["newton-lcp"]


def test_a_run_naming_no_engines_runs_every_registered_one(toy_engine):
    scenario = load_scenario(LIBRARY_FILE)
    assert scenario.engines == (toy_engine,)  # the file names none: every registered engine
    records = runner.run([scenario], cache=None, workers=1, log=None).records
    assert {r.source for r in records if r.source != "analytic"} == {toy_engine}
    assert plan.parse_engines(None) == engine_names() == (toy_engine,)


def test_an_unknown_engine_is_refused_naming_the_registered_ones(tmp_path, capsys,
                                                                 toy_engine):
    status = cli.main(["run", str(LIBRARY_FILE), "--engines", "toy,nosuch", "--no-cache",
                       "--json", str(tmp_path / "results.json")])
    err = capsys.readouterr().err
    assert status == 2
    assert "--engines" in err and "nosuch" in err and f"allowed (the registered engines): " \
        f"{toy_engine}" in err
    assert not (tmp_path / "results.json").exists()


def test_set_takes_a_registered_engines_setting(toy_engine):
    assert parse_overrides([f"{toy_engine}.max_steps=50"]) == {toy_engine: {"max_steps": 50}}
    with pytest.raises(ValueError, match="unknown setting; allowed: approach_steps"):
        parse_overrides([f"{toy_engine}.iterations=5"])
