"""Box2D's bodies as the adapter builds them: its shortcuts around pybox2d's constructors
make the shapes pybox2d's own constructors make (harness/engines/building.py,
``_add_impact``)."""

from __future__ import annotations

import pytest

pytest.importorskip("Box2D", reason="Box2D not installed (pip install box2d==2.3.10)")

from Box2D import b2

from harness.engines.box2d import building
from harness.survey.population import resolve_populations
from harness.survey.sampling import sample_population

SAMPLES = 10  # per population


@pytest.fixture(scope="module")
def outlined_shapes():
    """Every box and polygon of the populations' samples."""
    shapes = [body.shape for population in resolve_populations([])
              for sample in sample_population(population, SAMPLES, seed=3).samples
              for body in sample.scene.bodies if body.shape.kind in ("box", "polygon")]
    assert {shape.kind for shape in shapes} == {"box", "polygon"}
    return shapes


def test_outlines_are_the_shapes_vertices(outlined_shapes):
    for shape in outlined_shapes:
        assert building._outline(shape) == [tuple(row) for row in shape.vertices().tolist()]


def _shape_fields(shape) -> tuple:
    return (shape.vertexCount, shape.vertices, shape.normals, tuple(shape.centroid),
            shape.radius)


def test_the_shared_polygon_is_pybox2ds_polygon(outlined_shapes):
    # Filled one after another, as for the fixtures of a batch: nothing of the last
    # polygon stays in the next.
    for scale in (1.0, 4.0):
        for shape in outlined_shapes:
            vertices = [(x * scale, y * scale) for x, y in building._outline(shape)]
            fresh = b2.polygonShape(vertices=vertices)
            fresh.radius = 0.25
            shared = building._polygon_shape(vertices, 0.25)
            assert _shape_fields(shared) == _shape_fields(fresh)


def test_the_shared_circle_is_pybox2ds_circle():
    for radius, x in ((0.5, 0.0), (0.25, -1.5), (0.125, 0.0)):
        fresh = b2.circleShape()
        fresh.radius = radius
        if x:
            fresh.pos = (x, 0.0)
        shared = building._circle_shape(radius, x)
        assert (shared.radius, tuple(shared.pos)) == (fresh.radius, tuple(fresh.pos))


def test_a_polygon_box2d_refuses_or_welds_is_unsupported():
    tiny = [(0.0, 0.0), (1e-9, 0.0), (0.0, 1e-9)]
    with pytest.raises(AssertionError):
        b2.polygonShape(vertices=tiny)  # pybox2d's own constructor refuses it too
    with pytest.raises(building.UnsupportedScene, match="refused"):
        building._polygon_shape(tiny, 0.01)
    with pytest.raises(building.UnsupportedScene, match="refused"):
        building._polygon_shape([(float(k), float(k * k)) for k in range(20)], 0.01)
    near = [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (1.0, 1.001), (0.0, 1.0)]
    assert b2.polygonShape(vertices=near).vertexCount == 4
    with pytest.raises(building.UnsupportedScene, match="welds"):
        building._polygon_shape(near, 0.01)
    # The shared shape is whole again after a refusal.
    square = [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)]
    fresh = b2.polygonShape(vertices=square)
    fresh.radius = 0.0
    assert _shape_fields(building._polygon_shape(square, 0.0)) == _shape_fields(fresh)
