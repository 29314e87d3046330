"""The ellipse in every engine: MuJoCo's ellipsoid, elsewhere the placed 8-gon stand-in;
both touch the ground first at the ellipse's lowest point."""

from __future__ import annotations

import math

import numpy as np
import pytest

from harness.engines import ENGINE_NAMES
from harness.engines.contract import UnsupportedScene
from harness.scene import Body, Disk, Ellipse, Scene, ellipse, geometry
from harness.scene.reference import reference_scenes

A, B = 0.035, 0.025


@pytest.fixture(params=ENGINE_NAMES)
def engine(load_or_skip, request):
    return load_or_skip(request.param)


def test_an_ellipse_against_another_body_is_refused(engine):
    body = Body("e", Ellipse(A, B), 0.0364, (0.0, 0.0))
    disk = Body("d", Disk(0.01), 0.01, (0.0, 0.036), velocity=(0.0, -1.0))
    with pytest.raises(UnsupportedScene, match="an ellipse touches only the ground"):
        engine.run(Scene((body, disk), 0.5, 0.3, ground=False), preset="accurate")


def test_the_first_impulse_acts_at_the_lowest_point(engine):
    """Under ``accurate`` the reference ellipse (30°, spinning, μ 0.3) is one single
    impact along the ground's normal, and the run's angular impulse about the centre is
    p × P for the ellipse's lowest point p, to 1e-4 m × |P| (the body turns a few mrad
    during contact, which moves a stand-in's vertex and the ellipsoid's point by less);
    pybullet's contact lies 1 mm lower, its polygons' collision margin, which adds 1 mm ×
    the tangential impulse."""
    scene, point, _ = reference_scenes()["ellipse"]
    body = scene.bodies[0]
    run = engine.run(scene, preset="accurate")
    assert run.status == "ok" and run.separated
    assert run.contact_normal == pytest.approx((0.0, 1.0), abs=1e-6)
    v_x, v_y, omega = run.u_after[:3]
    impulse = body.mass * np.array([v_x - body.velocity[0], v_y - body.velocity[1]])
    angular = body.moment_of_inertia * (omega - body.angular_velocity)
    p_x, p_y = ellipse.lowest_offset(body.angle, A, B)
    assert p_x == pytest.approx(point[0] - body.position[0], abs=1e-15)
    bound = 1e-4 * np.hypot(*impulse)
    if engine.name == "pybullet":  # its hull margin: the contact 1 mm below the polygon
        bound += 1e-3 * abs(impulse[0])
    assert abs(angular - (p_x * impulse[1] - p_y * impulse[0])) < bound


def test_mujoco_builds_an_ellipsoid_whose_third_axis_is_the_larger(load_or_skip):
    """MuJoCo's geom is an ellipsoid (semi_x, max, semi_y) with the scene's inertia; its one
    contact with the plane is the ellipse's lowest point (the third axis is out of the
    plane of motion and moves neither)."""
    load_or_skip("mujoco")
    import mujoco

    from harness.engines.mujoco import model as mujoco_engine

    body = Body("e", Ellipse(A, B), 0.0364, (0.0, 0.0), math.radians(40.0))
    body = geometry.place_stand_in(geometry.place_on_ground(body))
    scene = Scene((body,), 0.5, 0.3, ground=True)
    model = mujoco.MjModel.from_xml_string(mujoco_engine._model_xml(scene))
    geom = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, "g0")
    assert model.geom_type[geom] == mujoco.mjtGeom.mjGEOM_ELLIPSOID
    np.testing.assert_allclose(model.geom_size[geom], [A, A, B], rtol=1e-7)
    np.testing.assert_allclose(model.body_inertia[1], [body.moment_of_inertia] * 3, rtol=1e-7)
    data = mujoco.MjData(model)
    data.qpos[:] = [body.position[0], body.position[1] - 1e-6, -body.angle]
    mujoco.mj_forward(model, data)
    assert data.ncon == 1
    p_x, _ = ellipse.lowest_offset(body.angle, A, B)
    assert data.contact[0].pos[0] == pytest.approx(p_x, abs=1e-8)
    assert data.contact[0].pos[1] == pytest.approx(0.0, abs=1e-12)  # in the plane y = 0
