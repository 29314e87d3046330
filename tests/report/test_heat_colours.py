"""The HTML heat table's colours are the heat map's, computed without matplotlib."""

from __future__ import annotations

import numpy as np

from harness.report.figures import heat_cmap
from harness.report.overview import heat_colours
from harness.report.views import HEAT_MAX, HEAT_MIN


def _matplotlib_colours(values: np.ndarray) -> np.ndarray:
    from matplotlib.colors import LogNorm

    norm = LogNorm(vmin=HEAT_MIN, vmax=HEAT_MAX)
    clipped = np.clip(np.nan_to_num(values, nan=HEAT_MIN), HEAT_MIN, HEAT_MAX)
    return np.rint(255 * np.asarray(heat_cmap()(norm(clipped)))[..., :3]).astype(int)


def test_heat_colours_are_matplotlibs_for_every_level_and_beyond_the_ends():
    # every one of the 256 levels (and each level's edges), below, above, zero and NaN
    edges = HEAT_MIN * (HEAT_MAX / HEAT_MIN) ** (np.arange(257) / 256)
    values = np.concatenate([
        edges, np.nextafter(edges, 0), np.nextafter(edges, 1),
        np.geomspace(1e-9, 1e3, 20001), [0.0, np.nan, np.inf, -1.0, HEAT_MIN, HEAT_MAX]])
    colours = heat_colours(values.reshape(-1, 2))
    assert colours.shape == (values.size // 2, 2, 3)
    np.testing.assert_array_equal(colours, _matplotlib_colours(values.reshape(-1, 2)))
    assert len({tuple(c) for c in colours.reshape(-1, 3)}) > 200  # the whole scale is used
