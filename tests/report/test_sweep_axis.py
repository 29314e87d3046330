"""A sweep over decades (the tilts 0.01° … 3°) is drawn on a logarithmic axis."""

from __future__ import annotations

import pytest

from harness.report import figures
from harness.run.records import ANALYTIC, Record

TILTS = [0.01, 0.03, 0.1, 0.3, 1.0, 3.0]  # scenarios/sweep-tilted-*.toml


@pytest.mark.parametrize("values, log", [
    (TILTS, True),
    ([0.25, 0.5, 0.75, 1.0, 1.25, 1.5, 2.0], False),  # sweep-rod-45-alpha: one decade
    ([0.0, 0.1, 1.0, 10.0], False),  # a zero has no place on a log axis
    ([-75.0, -15.0, 20.0, 75.0], False),
    ([], False),
])
def test_log_axis_only_for_positive_values_over_decades(values, log):
    assert figures.log_sweep_axis(values) is log


def _records(values):
    return [Record(scenario="tilt", point={"index": i, "label": f"angle={v}", "value": v,
                                           "parameter": "body.box.angle_deg"},
                   source=ANALYTIC, law="poisson", vn_separation=0.5, vt_separation=0.1,
                   energy_change=-0.1, collision_type=1)
            for i, v in enumerate(values)]


@pytest.mark.parametrize("values, scale", [(TILTS, "log"), ([0.5, 1.0, 2.0], "linear")])
def test_sweep_figure_draws_the_swept_axis_so(tmp_path, monkeypatch, values, scale):
    import matplotlib

    matplotlib.use("Agg")
    drawn = []
    monkeypatch.setattr(figures, "save_png", lambda figure, path, **_: drawn.append(figure))
    info = {"sweep": {"parameter": "body.box.angle_deg", "values": values}}
    figures.sweep_figure("tilt", info, _records(values), tmp_path / "s.png")
    axes = drawn[0].axes
    assert axes and all(ax.get_xscale() == scale for ax in axes)
