"""The geometric error of each engine's ellipse (MuJoCo's ellipsoid, elsewhere the placed
8-gon), measured from the runs' own impulses (drops_engines.moment_arm_errors), against
stated bounds (docs/engines.md, 'The ellipse')."""

from __future__ import annotations

import pytest

from harness.engines import ENGINE_NAMES
from harness.experiments import drops_engines

#: Moment arm (w_n's third entry) of every single impact under ``accurate``: within 0.1 mm,
#: 1% of this ellipse's largest arm (a − b = 10 mm, at a turn of 40°).
ARM_BOUND = 1e-4
#: Contact height below the centre (w_t's third entry): 0.3 mm, and pybullet's polygon
#: collision margin (1 mm) on top, which puts its contact below the polygon.
HEIGHT_BOUND = 3e-4
MARGIN = {"pybullet": 1e-3}
#: The placed polygon in a rigid engine: its vertex is the lowest point, to rounding
#: (float32 in Box2D).
EXACT = 1e-6


@pytest.fixture(params=ENGINE_NAMES)
def engine(load_or_skip, request):
    return load_or_skip(request.param)


def test_every_engine_touches_where_the_ellipse_does(engine):
    measured = drops_engines.moment_arm_errors(engine, "accurate")
    arm, height = measured["arm"], measured["height"]
    angles = len(drops_engines.ARM_ANGLES)
    assert arm["verdicts"] == {"ok": angles} and height["verdicts"] == {"ok": angles}
    assert arm["max_ok"] <= ARM_BOUND
    assert height["max_ok"] <= HEIGHT_BOUND + MARGIN.get(engine.name, 0.0)
    if engine.name in ("pymunk", "box2d"):
        assert arm["max_ok"] <= EXACT and height["max_ok"] <= EXACT
    # the measurement can fail: a stand-in not placed on the lowest point is caught (MuJoCo
    # and Drake collide the true ellipsoid: no stand-in to misplace)
    assert engine.name in ("mujoco", "drake") or _unplaced_error(engine) > 10 * ARM_BOUND


def _unplaced_error(engine) -> float:
    """The moment-arm error of the 8-gon left at its default placement (a vertex at the
    lowest point of the unturned ellipse) on an ellipse turned 20°: what placing it avoids
    (its lowest vertex is elsewhere, and the body starts a hair above the ground)."""
    import math

    from harness.experiments import fazeli
    from harness.scene import Body, Ellipse, Scene, ellipse, geometry

    a, b = fazeli.SEMI_AXES
    body = geometry.place_on_ground(Body("e", Ellipse(a, b), fazeli.MASS, (0.0, 0.0),
                                         math.radians(20.0), (0.0, -2.5), 0.0))
    run = engine.run(Scene((body,), 0.5, 0.0, ground=True), preset="accurate")
    _, v_y, omega = run.u_after[:3]
    effective = body.moment_of_inertia * omega / (body.mass * (v_y - body.velocity[1]))
    return abs(effective - ellipse.lowest_offset(body.angle, a, b)[0])
