"""Laws and models compared in one frame (harness/experiments/frames.py), engines beside the
law on the drops they scored (calibrated_errors.paired_difference): issue 34, item 4."""

from __future__ import annotations

import numpy as np
import pytest

from harness.experiments import calibrated_errors, fazeli, frames, predict


@pytest.fixture(scope="module")
def data(synthetic_copy):
    directory, truth = synthetic_copy
    return fazeli.load(directory, check_hashes=False), truth


def test_the_frames_differ_by_the_published_offset_only(data):
    loaded, _ = data
    published = frames.in_frame(loaded.impacts, "published")
    raw = frames.in_frame(loaded.impacts, "raw")
    assert published is loaded.impacts
    np.testing.assert_allclose(published.speeds_after - raw.speeds_after,
                               np.tile([0.0, fazeli.POST_VY_OFFSET, 0.0], (len(raw), 1)))
    with pytest.raises(ValueError, match="frame: unknown 'cooked'; allowed: published, raw"):
        frames.in_frame(loaded.impacts, "cooked")


def test_an_impulse_laws_answer_lies_in_the_impulse_span_and_noise_does_not(data):
    loaded, truth = data
    impacts = loaded.impacts
    exact = predict.predict(impacts, truth["law"], truth["mu"], truth["e"]).speeds_after
    assert np.max(frames.outside_impulse_span(impacts, exact)) < 1e-12
    assert np.median(frames.outside_impulse_span(impacts)) > 1e-3  # the synthetic noise


def test_each_frame_scores_models_and_the_law_against_the_same_speeds(data):
    """The synthetic law's answer (with noise) is written as the published speeds and its
    six 'models' are those speeds: in the published frame the models score 0, in the raw
    frame they do not; the law fitted to each frame finds the truth only in the published
    one, and its paired difference from the best model is positive there."""
    loaded, truth = data
    found = frames.compare(loaded, replicates=50)
    published, raw = found["frames"]["published"], found["frames"]["raw"]
    assert found["default"] == "published" and found["models_outside_impulse_span_max"] < 0.2
    assert all(model["median"] == 0.0 for model in published["models"].values())
    assert all(model["median"] > 0.01 for model in raw["models"].values())
    fit = published["fits"]["impulse"]
    assert abs(fit["mu"] - truth["mu"]) < 0.03 and abs(fit["e"] - truth["e"]) < 0.03
    assert abs(raw["fits"]["impulse"]["e"] - truth["e"]) > 0.03  # the offset moves e
    vs = fit["vs_best_model"]
    assert vs["difference"] > 0 and vs["interval"][0] > 0 and vs["drops"] == truth["drops"]
    text = "\n".join(frames.markdown(found))
    assert "| published (default) |" in text and "| raw |" in text


def test_an_engine_is_set_beside_the_law_on_the_drops_it_scored():
    """A made-up engine equal to the law on the drops it keeps and losing the law's worst
    drops: its median is lower than the law's over every drop, but the paired difference is
    0 and the lost drops are counted with the law's (high) median error on them."""
    rng = np.random.default_rng(3)
    law = rng.uniform(0.0, 1.0, 400)
    engine = law.copy()
    engine[law > 0.9] = np.nan  # lost: the hard drops
    vs = calibrated_errors.paired_difference(engine, law, replicates=200)
    assert np.nanmedian(engine) < np.median(law)
    assert vs["difference"] == 0.0 and vs["interval"] == [0.0, 0.0]
    assert vs["median"]["median"] == vs["reference"]["median"] == np.nanmedian(engine)
    lost = int(np.count_nonzero(law > 0.9))
    assert vs["lost"] == {"drops": lost, "reference_median": float(np.median(law[law > 0.9]))}
    cells = calibrated_errors.paired_cells(vs)
    assert cells[2] == "+0.000 [+0.000, +0.000]" and cells[3].startswith(f"{lost} (law 0.9")
    assert calibrated_errors.paired_cells(None)[3] == "every drop"
