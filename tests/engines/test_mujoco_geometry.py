"""MuJoCo's model per topology: a scene's geometry written into a compiled model is the
compile of that scene, array for array and run for run.

The adapter compiles one model per (ground, shape kinds) and, for disks, rods and boxes,
writes each scene's sizes, bounding volumes, masses and inertias into it, then lets
``mj_setConst`` and the compiler's statistics derive the rest (docs/engines.md, 'MuJoCo').
If one derived number differed at rounding, runs would differ from runs on a fresh compile;
these tests compare every array of the model and whole runs, bit for bit.
"""

from __future__ import annotations

import math
from fractions import Fraction

import numpy as np
import pytest

mujoco = pytest.importorskip("mujoco", reason="mujoco not installed (pip install mujoco==4.0.0)")

from harness.engines.contract import body_extent  # noqa: E402
from harness.engines.mujoco import MujocoEngine  # noqa: E402
from harness.engines.mujoco.model import _Geometry, _model_xml, _topology  # noqa: E402
from harness.scenarios.library import load_scenarios  # noqa: E402
from harness.scene import Body, Box, Disk, Polygon, Rod, Scene  # noqa: E402
from harness.scene.reference import reference_scenes  # noqa: E402
from harness.survey.population import resolve_populations  # noqa: E402
from harness.survey.sampling import sample_population  # noqa: E402

SAMPLES = 12  # per population
STATISTICS = ("center", "extent", "meaninertia", "meanmass", "meansize")


@pytest.fixture(scope="module")
def population_scenes():
    return [sample.scene for population in resolve_populations([])
            for sample in sample_population(population, SAMPLES, seed=11).samples]


def library_scenes():
    """Every scene of the scenario library MuJoCo runs, and the hand-built reference scenes."""
    scenes = [scene for scene, _, _ in reference_scenes().values()]
    for scenario in load_scenarios():
        if scenario.analytic_only or (scenario.engines and "mujoco" not in scenario.engines):
            continue
        scenes += [scene for _, scene in scenario.points()]
    return scenes


def odd_scenes():
    """Shapes at the ends of the ranges: thin, tiny, long, heavy, light, explicit inertia."""
    rng = np.random.default_rng(5)

    def body(shape, mass=1.0, inertia=None):
        return Body("b", shape, mass, (0.0, 0.0), 0.0, (0.0, -1.0), 0.0, inertia=inertia)

    shapes = [Disk(1e-4), Disk(3.7), Rod(1e-3, 1e-4), Rod(5.0, 0.3), Rod(0.2, 0.2),
              Box(1e-3, 2.0), Box(3.0, 1e-4), Box(0.3, 0.3)]
    scenes = []
    for shape in shapes:
        for mass in (1e-3, float(rng.uniform(0.1, 10.0)), 1e3):
            scenes.append(Scene((body(shape, mass),), 0.5, 0.3, ground=True, name="odd"))
        scenes.append(Scene((body(shape, 2.0, inertia=1e-6),), 0.5, 0.3, ground=True))
        partner = body(Disk(float(rng.uniform(0.01, 1.0))), float(rng.uniform(0.1, 5.0)))
        scenes.append(Scene((partner, body(shape, 3.0)), 0.5, 0.3, name="odd-pair"))
    return scenes


def model_differences(model, reference) -> list[str]:
    """Names of the arrays and statistics in which ``model`` and ``reference`` differ."""
    names = [name for name in dir(reference) if not name.startswith("_")
             and isinstance(getattr(reference, name), np.ndarray)]
    differ = [name for name in names
              if getattr(model, name).tobytes() != getattr(reference, name).tobytes()]
    for name in STATISTICS:
        if (np.asarray(getattr(model.stat, name)).tobytes()
                != np.asarray(getattr(reference.stat, name)).tobytes()):
            differ.append(f"stat.{name}")
    return differ


def held_model(engine, worlds, scene):
    """The model of ``scene``'s topology world after it was made to hold ``scene``."""
    topology = _topology(scene)
    if topology not in worlds:  # later scenes of the topology are written into this one
        worlds[topology] = engine._build(scene, engine.settings("defaults"))
    world = worlds[topology]
    engine._hold(world, _Geometry(scene))  # writes even when the world holds the scene
    return world.model


@pytest.mark.parametrize("source", ["populations", "library", "odd"])
def test_held_geometry_is_the_compile_array_for_array(population_scenes, source):
    scenes = {"populations": population_scenes, "library": library_scenes(),
              "odd": odd_scenes()}[source]
    engine, worlds = MujocoEngine(), {}
    editable = 0
    for scene in scenes:
        model = held_model(engine, worlds, scene)
        compiled = mujoco.MjModel.from_xml_string(_model_xml(scene))
        assert model_differences(model, compiled) == [], scene.name
        editable += _Geometry(scene).bodies is not None
    assert editable >= len(scenes) // 2  # mostly the edited path, not the compiled one


def test_the_edits_change_what_a_compile_derives():
    # The comparison above can fail: a second geometry differs from the first in the very
    # arrays the adapter writes or derives, and in the statistics the solver reads.
    first = Scene((Body("b", Rod(0.5, 0.01), 1.0, (0.0, 0.0)),), 0.5, 0.3, ground=True)
    second = Scene((Body("b", Rod(0.8, 0.02), 2.0, (0.0, 0.0)),), 0.5, 0.3, ground=True)
    one = mujoco.MjModel.from_xml_string(_model_xml(first))
    two = mujoco.MjModel.from_xml_string(_model_xml(second))
    differ = set(model_differences(one, two))
    assert {"geom_size", "geom_rbound", "geom_aabb", "bvh_aabb", "body_mass", "body_inertia",
            "body_invweight0", "dof_invweight0", "dof_M0", "dof_length",
            "stat.meaninertia", "stat.meansize", "stat.extent"} <= differ
    # mj_setConst alone leaves the statistics as they were: the adapter computes them.
    mujoco.mj_setConst(one, mujoco.MjData(one))
    assert one.stat.meaninertia != two.stat.meaninertia or one.stat.meansize != two.stat.meansize


@pytest.mark.parametrize("preset", ["defaults", "accurate"])
def test_runs_on_one_model_per_topology_equal_runs_on_fresh_compiles(population_scenes,
                                                                      preset):
    # run_many and run go through the same held models; a fresh adapter compiles the scene
    # itself. Every field of every run (velocities, records, impulses) must agree.
    scenes = population_scenes[::2]
    engine = MujocoEngine()
    settings = engine.settings(preset)
    batched = engine.run_many(scenes, settings)
    again = [engine.run(scene, settings) for scene in reversed(scenes)][::-1]
    mismatched = []
    for scene, run, rerun in zip(scenes, batched, again):
        fresh = MujocoEngine()
        if not (run == rerun == fresh.run(scene, fresh.settings(preset))):
            mismatched.append(scene.name)
        fresh.close()
    assert not mismatched
    assert len(engine._worlds) == len({_topology(scene) for scene in scenes})


def test_polygon_worlds_keep_compiled_models_and_share_data():
    def triangle(size, mass):
        points = tuple((size * math.cos(a), size * math.sin(a))
                       for a in (0.3, 0.3 + 2 * math.pi / 3, 0.3 + 4 * math.pi / 3))
        body = Body("p", Polygon(points), mass, (0.0, size * 0.5 + 1e-3), 0.0, (0.2, -1.0), 1.0)
        return Scene((body,), 0.6, 0.4, ground=True, name=f"triangle-{size}")

    scenes = [triangle(0.1, 1.0), triangle(0.2, 2.0), triangle(0.1, 1.0), triangle(0.15, 3.0)]
    engine = MujocoEngine()
    settings = engine.settings("accurate")
    runs = [engine.run(scene, settings) for scene in scenes]
    assert runs[0] == runs[2] != runs[1]
    world = next(iter(engine._worlds.values()))
    assert len(world.compiled) == 3 and len(world.datas) == 1  # one MjData for the three
    fresh = [MujocoEngine().run(scene, settings) for scene in scenes]
    assert runs == fresh


def halfway_decimals(count: int) -> list[float]:
    """Doubles exactly halfway between two float32 whose shortest decimal lies on the other
    side than rounding to even: rounding the double (a spec) and rounding the decimal (the
    XML reader) give different float32."""
    rng = np.random.default_rng(9)
    found = []
    while len(found) < count:
        low = np.float32(rng.uniform(0.02, 0.4))
        halfway = (float(low) + float(np.nextafter(low, np.float32(1.0)))) / 2.0
        decimal, exact = Fraction(repr(halfway)), Fraction(halfway)
        to_even_above = float(np.float32(halfway)) > halfway
        if decimal != exact and (decimal > exact) != to_even_above:
            found.append(halfway)
    return found


def test_polygon_vertices_halfway_between_float32_compile_as_from_xml():
    # A spec would round these doubles to the other float32 than the XML reader does; the
    # adapter feeds the spec the reader's float32 (_xml_float32).
    values = halfway_decimals(6)
    engine, worlds = MujocoEngine(), {}
    scenes = []
    for index in range(0, 6, 2):
        x, y = values[index], values[index + 1]
        points = ((x, -y), (0.05, 0.3), (-x, 0.1), (-0.2, -y))
        body = Body("p", Polygon(points), 1.5, (0.0, 0.5), 0.0, (0.0, -1.0), 0.0)
        scenes.append(Scene((body,), 0.5, 0.3, ground=True, name="halfway"))
    for scene in [*scenes, scenes[0]]:
        model = held_model(engine, worlds, scene)
        compiled = mujoco.MjModel.from_xml_string(_model_xml(scene))
        assert model_differences(model, compiled) == []
    # Without the reader's rounding the spec's mesh would differ (the test can fail).
    spec = mujoco.MjSpec.from_string(_model_xml(scenes[1]))
    depth = 2.0 * body_extent(scenes[1].bodies[0].shape)
    spec.mesh("g0_mesh").uservert = [value for x, y in scenes[1].bodies[0].shape.points
                                     for side in (-1.0, 1.0)
                                     for value in (x, side * depth / 2.0, y)]
    naive = spec.compile()
    assert model_differences(naive, mujoco.MjModel.from_xml_string(_model_xml(scenes[1])))
