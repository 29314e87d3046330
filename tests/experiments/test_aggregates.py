"""The drops' aggregates for the report (issue 25, item 7): fits and distributions only, no
per-drop number, on a synthetic copy in the published layout."""

from __future__ import annotations

import json

import numpy as np
import pytest

from harness.experiments import aggregates, calibrate, fazeli

from .conftest import write_synthetic

#: A coarse grid keeps the fits to a second; the truth (μ 0.3, e 0.7) is on it.
COARSE = np.round(np.linspace(0.0, 1.0, 11), 12)


@pytest.fixture(scope="module")
def computed(tmp_path_factory):
    from harness.engines import EngineNotInstalled, load_engine

    directory = tmp_path_factory.mktemp("fazeli_aggregates")
    truth = write_synthetic(directory, drops=60, flagged=5)
    data = fazeli.load(directory, check_hashes=False)  # synthetic: not the published hashes
    try:
        engines = [load_engine("pymunk")]
    except EngineNotInstalled:
        engines = []
    result = aggregates.compute(data, engines=engines, replicates=10, workers=1,
                                calibration_drops=4, laws=("poisson", "stronge"), mus=COARSE,
                                es=COARSE)
    return result, truth, engines


def test_the_fits_recover_the_truth_under_the_impulse_objective(computed):
    result, truth, _ = computed
    fit = result["laws"]["impulse"][truth["law"]]
    assert abs(fit["mu"] - truth["mu"]) <= 0.02 and abs(fit["e"] - truth["e"]) <= 0.06
    low, high = fit["e_interval"]
    assert low <= fit["e"] <= high and fit["replicates"] == 10
    assert set(result["laws"]) == set(aggregates.OBJECTIVES)


def test_poisson_against_stronge_has_an_interval_and_a_verdict(computed):
    result, truth, _ = computed
    for objective in aggregates.OBJECTIVES:
        found = result["poisson_vs_stronge"][objective]
        low, high = found["interval"]
        assert low <= high and found["replicates"] == aggregates.COMPARE_REPLICATES
        assert ("contains 0" in found["verdict"]) == (low <= 0 <= high)
    assert result["routh"]["drops"] == truth["drops"]


def test_nothing_per_drop_is_kept(computed):
    """No list as long as the drops (a per-drop column) anywhere in the result, and every
    histogram bin shown holds at least MIN_BIN_COUNT drops."""
    result, truth, _ = computed
    text = json.dumps(result)  # plain JSON throughout

    def walk(value):
        if isinstance(value, dict):
            for item in value.values():
                yield from walk(item)
        elif isinstance(value, list):
            yield value
            for item in value:
                yield from walk(item)

    assert all(len(array) != truth["drops"] for array in walk(json.loads(text)))
    for panel in result["shown"]["density"]:
        counts = np.asarray(panel["counts"])
        assert np.all((counts == 0) | (counts >= aggregates.MIN_BIN_COUNT))
        assert counts.sum() + panel["hidden_in_sparse_bins"] <= truth["drops"]


def test_sparse_bins_are_emptied_and_counted():
    rng = np.random.default_rng(0)
    measured = np.concatenate([rng.normal(0.0, 0.01, 200), [5.0, -5.0]])  # two stragglers
    panel = aggregates.density(measured + rng.normal(0, 0.001, measured.size), measured,
                               bins=10)
    counts = np.asarray(panel["counts"])
    assert np.all((counts == 0) | (counts >= aggregates.MIN_BIN_COUNT))
    assert panel["outside_range"] >= 2  # the central 99 % leaves the stragglers out
    assert all(q25 <= q50 <= q75 for q25, q50, q75 in zip(
        panel["binned"]["q25"], panel["binned"]["q50"], panel["binned"]["q75"]))


def test_engines_are_run_judged_and_calibrated_on_a_seeded_sample(computed):
    result, truth, engines = computed
    if not engines:
        pytest.skip("pymunk not installed")
    assert {run["preset"] for run in result["engines"]} == set(engines[0].presets)
    for run in result["engines"]:
        assert sum(run["verdicts"].values()) == truth["drops"]
        assert run["cdf"]["drops"] == run["verdicts"].get("ok", 0)
    sample = result["calibration"]["sample"]
    assert sample == {"drops": 4, "of": truth["drops"], "seed": 0, "from": "training half"}
    assert all(row["best"] is not None for row in result["calibration"]["results"])
    calibration = result["calibration"]
    assert calibration["replicates"] == calibrate.REPLICATES
    for row in calibration["results"]:  # the intervals and the held-out error, as aggregates
        low, high = row["objective_interval"]
        assert low <= row["objective"] <= high
        for knob, value in row["best"].items():
            assert row["settings_interval"][knob][0] <= value <= row["settings_interval"][knob][1]
        split = row["held_out"]
        assert split["fitting_drops"] + split["held_out_drops"] == sample["drops"]
        assert split["held_out"] is None or split["held_out"] >= 0
