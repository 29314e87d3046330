"""MuJoCo's fast reads: what the adapter reads through views made once, and the model fields
it leaves alone between runs, equal what the bindings read and what a fresh model holds.

The adapter reads each step's contacts through one numpy view of the data's arena
(``_contact_rows``), not through ``data.contact``, its constraint forces through views of the
same arena made once per run and row count (``_force_view``), not through
``data.efc_force``, and rewrites a pair's ``solref``,
``condim`` and friction only when they change. These tests read the same values the slow
way, step by step and run by run, bit for bit.
"""

from __future__ import annotations

import math
import random
import struct

import numpy as np
import pytest

mujoco = pytest.importorskip("mujoco", reason="mujoco not installed (pip install mujoco==4.0.0)")

from harness.engines.mujoco import MujocoEngine  # noqa: E402
from harness.engines.mujoco.model import _model_xml, _xml_float32, _xml_float32s  # noqa: E402
from harness.engines.mujoco.world import _layout  # noqa: E402
from harness.scene import Body, Box, Disk, Polygon, Scene  # noqa: E402
from harness.scene.geometry import place_on_ground  # noqa: E402
from harness.survey.population import resolve_populations  # noqa: E402
from harness.survey.sampling import sample_population  # noqa: E402


def bits(values) -> list[bytes]:
    return [struct.pack("<d", value) for value in np.ravel(values).tolist()]


class _CheckedReads(MujocoEngine):
    """The adapter, each contact step compared with ``data.contact`` read the slow way."""

    def __init__(self) -> None:
        self.steps = self.multi = self.forces = 0
        self.force_shapes: set[tuple[int, int]] = set()
        self.addresses: set[int] = set()

    def _step(self, world):
        raw = super()._step(world)
        if raw is None:
            return raw
        d = world.data
        contact = d.contact
        count = d.ncon
        slow = np.column_stack([contact.dist, contact.pos, contact.frame[:, :3]])
        assert bits(world.contact_rows[:count]) == bits(slow)
        points = tuple((x, z, -distance) for (x, _, z), distance
                       in zip(contact.pos.tolist(), contact.dist.tolist()))
        assert bits(raw[0]) == bits(points)
        frame = contact.frame.tolist()[0]
        length = math.hypot(frame[0], frame[2])
        normal = (world.normal_sign * frame[0] / length, world.normal_sign * frame[2] / length)
        assert bits(raw[1]) == bits(normal)
        if count == 1:  # the distance the adapter read before: every row carries it
            assert bits([-d.efc_pos.item(0)]) == bits([raw[0][0][2]])
        if raw[3] is not None:
            assert bits([raw[3]]) == bits([sum(map(abs, d.efc_force.tolist())) * world.dt])
            self.forces += 1
            self.force_shapes.add((count, d.nefc))
        self.steps += 1
        self.multi += count > 1
        self.addresses.add(world.contact_address)
        return raw


@pytest.mark.parametrize("preset", ["defaults", "accurate"])
def test_contact_view_reads_what_the_bindings_read(preset):
    scenes = [sample.scene for population in resolve_populations([])
              for sample in sample_population(population, 10, seed=3).samples]
    engine = _CheckedReads()
    engine.run_many(scenes, engine.settings(preset))
    # Not vacuous: many contact steps, several contacts at once, several datas (the
    # topologies' and a polygon world's layouts).
    assert engine.steps > 10 * len(scenes)
    assert engine.multi > 0
    assert len(engine.addresses) > len({(s.ground, len(s.bodies)) for s in scenes})
    assert engine.forces > 5 * len(scenes) and len(engine.force_shapes) >= 2


@pytest.mark.parametrize("overrides", [{"cone": "elliptic"}, {"noslip_iterations": 10},
                                       {"solver": "CG", "integrator": "implicitfast"}])
def test_force_views_read_what_the_bindings_read_under_other_options(overrides):
    # Other cones, solvers and integrators make other row counts and constraint arrays.
    scenes = [sample.scene for population in resolve_populations([])
              for sample in sample_population(population, 4, seed=5).samples]
    engine = _CheckedReads()
    engine.run_many(scenes, engine.settings("defaults", overrides=overrides))
    assert engine.forces > 2 * len(scenes)


def test_polygon_world_switching_datas_reads_each_datas_contacts():
    # Polygons of 3 and 6 vertices compile to models of different layouts, each with its
    # own MjData: alternating them must read each data's own contacts.
    def polygon(count, size):
        points = tuple((size * math.cos(2 * math.pi * k / count + 0.1),
                        size * math.sin(2 * math.pi * k / count + 0.1)) for k in range(count))
        body = Body("p", Polygon(points), 1.0, (0.0, 0.0), 0.3, (0.1, -1.0), 0.5)
        return Scene((place_on_ground(body),), 0.5, 0.3, ground=True, name=f"polygon-{count}")

    scenes = [polygon(count, size)
              for size in (0.1, 0.12, 0.15) for count in (3, 6)]
    engine = _CheckedReads()
    settings = engine.settings("defaults")
    runs = engine.run_many(scenes, settings)
    assert len(engine.addresses) >= 2
    fresh = [MujocoEngine().run(scene, settings) for scene in scenes]
    assert runs == fresh


def model_arrays(model) -> dict[str, bytes]:
    return {name: getattr(model, name).tobytes() for name in dir(model)
            if not name.startswith("_") and isinstance(getattr(model, name), np.ndarray)}


def test_fields_left_alone_between_runs_equal_a_fresh_models():
    # e, μ (0 and not: condim 1 and 3), e = 1 (ζ = 0) and the settings change run by run;
    # after every run the held model equals, array for array, a fresh adapter's model
    # after the same run.
    rng = random.Random(7)
    engine = MujocoEngine()
    presets = [engine.settings("accurate"), engine.settings("defaults"),
               engine.settings("accurate", {"cone": "elliptic"})]
    shapes = [Disk(0.1), Box(0.2, 0.1)]
    changed = set()
    last = None
    for _ in range(40):
        shape = rng.choice(shapes)
        e = rng.choice([0.0, 0.3, 0.5, 1.0])
        mu = rng.choice([0.0, 0.2, 0.5])
        settings = presets[0] if rng.random() < 0.7 else rng.choice(presets)
        body = Body("b", shape, 1.0, (0.0, 0.1 if shape.kind == "disk" else 0.05), 0.0,
                    (0.3, -1.0), 0.0)
        scene = Scene((body,), e, mu, ground=True, name="sequence")
        run = engine.run(scene, settings)
        fresh = MujocoEngine()
        assert run == fresh.run(scene, settings)
        held = engine._worlds[engine._world_key(scene, settings)].model
        new = fresh._worlds[fresh._world_key(scene, settings)].model
        assert model_arrays(held) == model_arrays(new)
        fresh.close()
        if last is not None:
            changed.add((last[0] != e, last[1] != mu, last[2] is settings))
        last = (e, mu, settings)
    # The sequence changed e alone, μ alone and both under the same settings.
    assert {(True, False, True), (False, True, True), (True, True, True)} <= changed


def test_float32_rounding_in_one_pass_equals_one_by_one():
    rng = random.Random(2)
    values = [rng.uniform(-1.0, 1.0) for _ in range(2000)]
    values += [rng.uniform(-1.0, 1.0) * 10.0 ** rng.randint(-8, 3) for _ in range(2000)]
    halfway = []
    for value in values[:500]:  # exactly between a float32 and the next: the decimal decides
        low = np.float32(value)
        high = np.nextafter(low, np.float32(np.inf))
        halfway.append((float(low) + float(high)) / 2.0)
    values += halfway + [0.0, -0.0, 1.0, 0.1, float(np.float32(0.1))]
    one_by_one = [_xml_float32(value) for value in values]
    assert bits(_xml_float32s(values)) == bits(one_by_one)
    # Not vacuous: halfway values take both sides, unlike a plain float32 rounding.
    plain = np.array(halfway).astype(np.float32).astype(float).tolist()
    assert bits(_xml_float32s(halfway)) != bits(plain)


def test_layout_holds_every_size_the_attributes_hold():
    # _layout reads the bindings' array of sizes in one go: it must be every integer n*
    # attribute, so that two models share an MjData exactly when all their sizes agree.
    def polygon_model(count):
        points = tuple((0.1 * math.cos(2 * math.pi * k / count),
                        0.1 * math.sin(2 * math.pi * k / count)) for k in range(count))
        body = Body("p", Polygon(points), 1.0, (0.0, 0.1), 0.0, (0.0, -1.0), 0.0)
        return mujoco.MjModel.from_xml_string(
            _model_xml(Scene((body,), 0.5, 0.3, ground=True)))

    models = [polygon_model(count) for count in (3, 3, 6)]
    for model in models:
        names = sorted(name for name in dir(model) if name.startswith("n")
                       and isinstance(getattr(model, name), int))
        assert sorted(model._size_fields) == names
        assert model._sizes.tolist() == [getattr(model, name) for name in model._size_fields]
    assert _layout(models[0]) == _layout(models[1]) != _layout(models[2])


def test_a_mujoco_warning_leaves_no_log_file_in_the_working_directory(tmp_path, monkeypatch):
    """MuJoCo's default warning handler appended to MUJOCO_LOG.TXT in the working directory
    (issue 37, item 11): the adapter keeps the text in memory instead."""
    from harness.engines.mujoco import adapter

    mujoco = pytest.importorskip("mujoco")
    monkeypatch.chdir(tmp_path)
    model = mujoco.MjModel.from_xml_string(
        '<mujoco><worldbody><body><freejoint/><geom size="0.1"/></body></worldbody></mujoco>')
    data = mujoco.MjData(model)
    data.qvel[:] = np.nan
    mujoco.mj_step(model, data)
    assert list(tmp_path.iterdir()) == []
    assert "unstable" in adapter.WARNINGS[-1]
