"""The resampling the law fits and the calibration share (harness/experiments/fitting.py):
folds split by drop, K-fold over any grid of cells, percentile intervals."""

import numpy as np

from harness.experiments import fitting, metric


def test_folds_split_by_drop_and_cover_every_drop_once():
    splits = fitting.fold_splits(11, 2, seed=4)
    held = np.concatenate([fold for _, fold in splits])
    assert sorted(held.tolist()) == list(range(11))
    for train, fold in splits:
        assert not set(train.tolist()) & set(fold.tolist())
        assert len(train) + len(fold) == 11
    assert [len(fold) for _, fold in splits] == [6, 5]


def test_cross_validation_on_a_grid_of_three_axes_picks_the_best_cell_per_fold():
    rng = np.random.default_rng(0)
    errors = rng.uniform(0.5, 1.0, (2, 3, 2, 30))
    errors[1, 2, 0] = rng.uniform(0.0, 0.1, 30)  # the best cell on any subset of drops
    found = fitting.cross_validate(errors, lambda e: metric.aggregate("median-error", e),
                                   folds=3, seed=1)
    assert found.cells == ((1, 2, 0),) * 3 and found.held_out_drops == (10, 10, 10)
    for (train, fold), inside, outside in zip(fitting.fold_splits(30, 3, 1), found.in_sample,
                                              found.held_out):
        assert inside == np.median(errors[1, 2, 0, train])
        assert outside == np.median(errors[1, 2, 0, fold])


def test_a_fold_with_no_scored_cell_is_reported_as_such():
    errors = np.ones((3, 4))

    def nothing_scores_on_two_drops(rows):  # a stand-in rule: at least three drops
        return np.full(rows.shape[:-1], np.nan) if rows.shape[-1] < 3 else rows.mean(-1)

    found = fitting.cross_validate(errors, nothing_scores_on_two_drops, folds=2, seed=0)
    assert found.cells == (None, None) and np.isnan(found.held_out).all()


def test_percentile_intervals_stay_on_values_taken_when_asked():
    values = [0] * 50 + [2] * 50
    assert fitting.percentile_interval(values, 0.5).low == 0.0
    inside = fitting.percentile_interval(values, 0.95, method="inverted_cdf")
    assert (inside.low, inside.high) == (0.0, 2.0)
    linear = fitting.percentile_interval([0, 1, 2, 3, 4], 0.5)
    assert (linear.low, linear.high) == (1.0, 3.0)


def test_resampled_rows_are_seeded_draws_with_replacement():
    first = list(fitting.resampled_rows(20, 5, seed=3))
    again = list(fitting.resampled_rows(20, 5, seed=3))
    assert all(np.array_equal(a, b) for a, b in zip(first, again)) and len(first) == 5
    assert all(rows.size == 20 and rows.min() >= 0 and rows.max() < 20 for rows in first)
    assert any(np.unique(rows).size < 20 for rows in first)  # with replacement
