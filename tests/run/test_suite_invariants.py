"""Suite-wide invariants over every scenario × engine × preset of the library.

One run of the whole library (laws and engines, no cache, inline) is shared by the module;
a second run checks determinism. Each case is one (scenario, source, preset), with an id such
as ``rod-45-slip-reversal-pymunk-accurate`` or ``two-sled-row1-analytic``.
"""

from __future__ import annotations

import math

import pytest

from harness.engines import STATUSES, engine_names
from harness.run import runner
from harness.run.records import ANALYTIC
from harness.run.verdicts import REASONS, SINGLE_IMPACT
from harness.scenarios import PRESETS, load_scenarios

SCENARIOS = load_scenarios()
CASES = []
for _scenario in SCENARIOS:
    CASES.append(pytest.param(_scenario.name, ANALYTIC, None, id=f"{_scenario.name}-analytic"))
    if not _scenario.analytic_only:
        for _engine in _scenario.engines or engine_names():
            for _preset in PRESETS:
                CASES.append(pytest.param(_scenario.name, _engine, _preset,
                                          id=f"{_scenario.name}-{_engine}-{_preset}"))

# Energy "gain" allowed to a Poisson/Stronge solution: round-off of ½uᵀMu, relative to the
# kinetic energy before the impact (a few ulps of each term, 1e-12 leaves a wide margin).
ENERGY_ROUND_OFF = 1e-12
VOLATILE = ("wall_time_s", "cached")


def _run():
    return runner.run(SCENARIOS, cache=None, workers=1, log=None).records


@pytest.fixture(scope="module")
def runs():
    return _run(), _run()


def _select(records, scenario, source, preset):
    return [r for r in records if r.scenario == scenario and r.source == source
            and (preset is None or r.preset == preset)]


def _stable(record) -> dict:
    data = record.as_dict()
    for key in VOLATILE:
        data.pop(key)
    if data["diagnostics"]:
        data["diagnostics"].pop("engine_wall_time_s", None)
    return data


@pytest.mark.parametrize("scenario, source, preset", CASES)
def test_finite_numbers_or_a_reported_status(runs, scenario, source, preset):
    records = _select(runs[0], scenario, source, preset)
    assert records, "every case gives at least one record (skipped engines included)"
    for record in records:
        if source == ANALYTIC:
            assert record.status == "ok", f"{record.label}: {record.status}"
        else:
            assert (record.status in STATUSES or record.status in REASONS
                    or record.status.startswith("skipped: ")), record.status
            # a run failing a verdict check is never ok (harness/run/verdicts/)
            if record.u_after is not None:
                assert (record.status == "ok") == (record.verdict == SINGLE_IMPACT)
        if record.status != "ok":
            continue
        numbers = [*record.u_after, record.vn_separation, record.vt_separation,
                   record.energy_change, *record.departure.values()]
        assert all(isinstance(v, float) and math.isfinite(v) for v in numbers), record.label
        reference = (record.diagnostics or {}).get("reference") or {}
        if source == ANALYTIC or reference.get("kind", "single-contact") == "single-contact":
            assert set(record.departure) == set(load_scenario_laws(scenario))
        else:  # a flat face or a tilt: only the references that apply there
            assert reference["primary"] in record.departure
            assert not set(record.departure) & set(load_scenario_laws(scenario))


def load_scenario_laws(name):
    return next(s.laws for s in SCENARIOS if s.name == name)


@pytest.mark.parametrize("scenario, source, preset", CASES)
def test_reruns_are_bit_identical(runs, scenario, source, preset):
    first = [_stable(r) for r in _select(runs[0], scenario, source, preset)]
    second = [_stable(r) for r in _select(runs[1], scenario, source, preset)]
    assert first == second  # exact: floats compared bit for bit


@pytest.mark.parametrize("scenario", SCENARIOS, ids=[s.name for s in SCENARIOS])
def test_poisson_and_stronge_never_gain_energy(runs, scenario):
    for record in _select(runs[0], scenario.name, ANALYTIC, None):
        if record.law not in ("poisson", "stronge"):
            continue
        kinetic = scenario.analytic_problem(record.point["index"]).kinetic_energy()  # J
        assert record.energy_change <= ENERGY_ROUND_OFF * kinetic, (
            f"{record.law} at {record.point['label'] or 'the point'} gains "
            f"{record.energy_change} J of {kinetic} J")


def test_every_engine_case_of_the_library_has_a_record(runs):
    sources = {(r.scenario, r.source, r.preset) for r in runs[0]}
    for scenario in SCENARIOS:
        for engine in ([] if scenario.analytic_only else (scenario.engines or engine_names())):
            for preset in PRESETS:
                assert (scenario.name, engine, preset) in sources
        if scenario.analytic_only:
            assert not any(r.scenario == scenario.name and r.source != ANALYTIC
                           for r in runs[0]), "analytic-only systems never start an engine"


def test_the_counts_the_readme_states_are_those_of_this_run(runs):
    """The validation suite's counts stated in README.md (source ``library`` of
    harness.report.stated: engine runs, single impacts, runs per verdict reason) equal this
    fresh run's; on a failure, ``make validate`` then ``impact-harness findings --write
    --only library`` rewrites them from reports/results.json."""
    from harness.report import stated

    numbers = {f"library.{key}": value
               for key, value in stated.library_numbers_of(runs[0], len(SCENARIOS)).items()}
    marked = [s for path in stated.texts() for s in stated.stated_in(path)
              if s.source == "library"]
    assert marked and stated.differences(marked, numbers) == []
