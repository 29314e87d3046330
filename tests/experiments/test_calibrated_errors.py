"""Every engine and law at its fitted or calibrated settings, with intervals
(harness/experiments/calibrated_errors.py), on a synthetic copy in the published layout
(the toy engine of tests/engines: exact Poisson impulses) and, where a user's copy is given
(IMPACT_HARNESS_FAZELI_DIR), on the real files."""

import json
import os
from pathlib import Path

import numpy as np
import pytest

from harness.experiments import (
    calibrate,
    calibrated_errors,
    drops_engines,
    fazeli,
    frames,
    registry,
)

from .conftest import TRUE_E, TRUE_MU, write_synthetic

REAL_DIR = os.environ.get(registry.FAZELI_2017.env_var)
needs_real = pytest.mark.skipif(
    not REAL_DIR or not Path(REAL_DIR, "data_ellipse.mat").is_file(),
    reason=f"the Fazeli et al. 2017 files are not redistributable: set "
           f"{registry.FAZELI_2017.env_var} to a copy to run this test")
TRUTH = {"mu": TRUE_MU, "e": TRUE_E}


@pytest.fixture(scope="module")
def toy():
    from tests.engines.toy_engine import ToyEngine

    return ToyEngine()


@pytest.fixture(scope="module")
def drops(tmp_path_factory):
    directory = tmp_path_factory.mktemp("calibrated_errors")
    write_synthetic(directory, drops=60, flagged=3, noise=0.05)
    data = fazeli.load(directory, check_hashes=False)  # synthetic: not the published hashes
    target = frames.in_frame(data.impacts, frames.DEFAULT_FRAME)
    thetas, _ = drops_engines.jacobian_angles(target, data.pre_impact_angles)
    return target, thetas


def preset_runs(engine, target, thetas, fit=TRUTH):
    return [(engine, preset, drops_engines.run_drops(engine, preset, target, thetas, fit["mu"],
                                                     fit["e"], keep_errors=True))
            for preset in engine.presets]


def inside(found: dict, key: str = "median") -> bool:
    low, high = found["interval"]
    return low <= found[key] <= high


@pytest.fixture(scope="module")
def computed(toy, drops):
    target, thetas = drops
    result = calibrated_errors.compute(target, thetas, {"poisson": TRUTH, "newton": TRUTH},
                                       preset_runs(toy, target, thetas), replicates=200,
                                       calibration_drops=12)
    return result, len(target)


def test_the_drops_split_by_drop_and_the_calibration_draws_from_the_training_half():
    training, held = calibrated_errors.split(61, seed=3)
    assert not set(training) & set(held) and len(training) + len(held) == 61
    sample = calibrated_errors.calibration_sample(61, seed=3, count=12)
    assert sample.size == 12 and set(sample) <= set(training)
    assert np.array_equal(sample, calibrated_errors.calibration_sample(61, seed=3, count=12))


def test_every_engine_and_law_has_a_median_inside_its_interval(computed):
    result, drops = computed
    split = result["split"]
    assert split["training"] + split["held_out"] == drops
    for row in result["engines"]:
        preset, calibrated = row["at_preset"], row["calibrated"]
        assert preset["scored"] == drops and inside(preset)
        assert inside(preset["vs_reference"], "difference")
        assert row["cannot"] is None and calibrated["settings"].keys() == {"mu", "e"}
        assert calibrated["scored"] == split["held_out"] and inside(calibrated)
        assert inside(calibrated["vs_reference"], "difference")
        assert calibrated["cdf"]["drops"] == split["held_out"]
        # the toy is Poisson's law: at Poisson's settings it scores as Poisson does
        assert abs(preset["vs_reference"]["difference"]) < 0.01
    for row in result["laws"]:
        assert inside(row["at_fit"]) and inside(row["held_out"]) and row["unsolved"] == 0
        assert row["at_fit"]["scored"] == drops
    poisson = next(row for row in result["laws"] if row["law"] == "poisson")
    assert poisson["held_out_vs_reference"]["difference"] == 0.0
    text = "\n".join(calibrated_errors.markdown(result))
    assert f"{split['training']} training, {split['held_out']} held out" in text


def test_nothing_per_drop_is_kept(computed):
    result, drops = computed
    held = result["split"]["held_out"]

    def lists(value):
        if isinstance(value, dict):
            for item in value.values():
                yield from lists(item)
        elif isinstance(value, list):
            yield value
            for item in value:
                yield from lists(item)

    assert all(len(found) not in (drops, held) for found in lists(json.loads(json.dumps(
        result))))


def test_an_engine_flagged_on_every_drop_is_counted_not_scored(toy, drops, monkeypatch):
    target, thetas = drops
    monkeypatch.setattr(drops_engines, "judged", lambda run, scene: "multi-contact")
    monkeypatch.setattr(calibrate, "judged", lambda run, scene: "multi-contact")
    result = calibrated_errors.compute(target, thetas, {"poisson": TRUTH},
                                       preset_runs(toy, target, thetas), replicates=50)
    for row in result["engines"]:
        preset = row["at_preset"]
        assert preset["scored"] == 0 and preset["median"] is None
        assert preset["interval"] is None and preset["vs_reference"] is None
        assert preset["flagged"] == {"multi-contact": len(target)}
        assert row["calibrated"] is None and "single impacts" in row["cannot"]
    assert "| — | — |" in "\n".join(calibrated_errors.markdown(result))


def test_an_engine_that_cannot_be_calibrated_keeps_its_preset_row(toy, drops, monkeypatch):
    target, thetas = drops
    runs = preset_runs(toy, target, thetas)  # judged as usual: every run a single impact
    monkeypatch.setattr(calibrate, "judged", lambda run, scene: "penetration")
    result = calibrated_errors.compute(target, thetas, {"poisson": TRUTH}, runs,
                                       replicates=50)
    for row in result["engines"]:
        assert row["calibrated"] is None
        assert row["cannot"].startswith("no setting tried gives single impacts on half")
        assert row["at_preset"]["scored"] == len(target) and inside(row["at_preset"])
    text = "\n".join(calibrated_errors.markdown(result))
    assert "cannot be calibrated: no setting tried" in text


def test_the_reference_law_is_required(drops):
    target, thetas = drops
    with pytest.raises(ValueError, match="law_fits: must hold 'poisson'"):
        calibrated_errors.compute(target, thetas, {"newton": TRUTH}, [])


@needs_real
def test_real_files_pymunk_at_its_calibrated_settings_beside_poisson():
    """On the real drops: pymunk calibrated on the training half and scored on the held-out
    half, beside Poisson fitted to the training half, each median inside its interval."""
    from harness.engines import EngineNotInstalled, load_engine

    try:
        pymunk = load_engine("pymunk")
    except EngineNotInstalled as missing:
        pytest.skip(f"pymunk not installed: {missing}")
    data = fazeli.load(Path(REAL_DIR))
    target = frames.in_frame(data.impacts, frames.DEFAULT_FRAME)
    thetas, _ = drops_engines.jacobian_angles(target, data.pre_impact_angles)
    fit = calibrated_errors.training_fit(target, "poisson")
    assert fit.mu == 0.0  # every law's best fit to these drops is frictionless
    runs = [(pymunk, "accurate", drops_engines.run_drops(
        pymunk, "accurate", target, thetas, fit.mu, fit.e, keep_errors=True))]
    result = calibrated_errors.compute(target, thetas, {"poisson": {"mu": fit.mu, "e": fit.e}},
                                       runs, replicates=200)
    (row,) = result["engines"]
    calibrated = row["calibrated"]
    assert calibrated["settings"]["mu"] == 0.0
    assert inside(calibrated) and inside(calibrated["vs_reference"], "difference")
    assert calibrated["scored"] == result["split"]["held_out"]
    # an impulse engine at the law's settings is the law, within the data's resolution
    low, high = calibrated["vs_reference"]["interval"]
    assert low < 0.02 and high > -0.02
