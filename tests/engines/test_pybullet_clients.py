"""pybullet's clients between uses: run_many's batch client is kept (with its plane) and
emptied by removing bodies, reset only now and then; a world's poses and velocities of one
step come from one read.

``EngineRun`` equality compares every field but the wall time as exact floats.
"""

from __future__ import annotations

import pytest

pybullet = pytest.importorskip("pybullet",
                               reason="pybullet not installed (pip install pybullet==3.2.7)")

from harness.engines.pybullet import adapter  # noqa: E402
from harness.survey.population import resolve_populations  # noqa: E402
from harness.survey.sampling import sample_population  # noqa: E402

SAMPLES = 12  # per population


@pytest.fixture(scope="module")
def population_scenes():
    return [sample.scene for population in resolve_populations([])
            for sample in sample_population(population, SAMPLES, seed=11).samples]


def test_a_kept_batch_client_holds_only_its_plane_between_batches(population_scenes):
    engine = adapter.PybulletEngine()
    try:
        engine.run_many(population_scenes, preset="defaults")
        kept = {key: clients for key, clients in engine._idle.items() if key[0] == "many"}
        assert {key[2] for key in kept} == {True, False}  # a ground and a two-body client
        for (_, _, ground), clients in kept.items():
            (client,) = clients
            assert pybullet.getNumBodies(physicsClientId=client.uid) == (1 if ground else 0)
            assert (client.plane is not None) == ground
    finally:
        engine.close()


@pytest.mark.parametrize("preset", ["defaults", "accurate"])
def test_runs_keep_their_bits_across_batch_client_resets(population_scenes, preset,
                                                         monkeypatch):
    # A batch client is reset once it has built _MANY_RESET_AFTER impacts (and its plane
    # made again); batches before and after a reset equal lone runs in a fresh adapter.
    monkeypatch.setattr(adapter, "MANY_IMPACTS", 5)
    monkeypatch.setattr(adapter, "_MANY_RESET_AFTER", 12)
    resets = []
    reset_client = adapter._reset_client
    monkeypatch.setattr(adapter, "_reset_client",
                        lambda client: resets.append(client.uid) or reset_client(client))
    batching = adapter.PybulletEngine()
    try:
        batched = batching.run_many(population_scenes, preset=preset)
    finally:
        batching.close()
    assert len(resets) >= 4  # ground and two-body clients, each reset more than once
    fresh = adapter.PybulletEngine()
    try:
        single = [fresh.run(scene, preset=preset) for scene in population_scenes]
    finally:
        fresh.close()
    assert [run == lone for run, lone in zip(batched, single)] == [True] * len(single)


def read_velocities(world):
    """Every body's ``(v_x, v_y, ω)`` read from Bullet now."""
    return tuple((x[1], z[1], -angle[1]) for x, z, angle in (
        pybullet.getJointStates(uid, [0, 1, 2], physicsClientId=world.client)
        for uid in world.bodies))


def test_velocities_are_read_again_after_a_step_or_a_reset(population_scenes):
    # The velocities read with a step's poses serve that step only.
    engine = adapter.PybulletEngine()
    try:
        scene = next(scene for scene in population_scenes if not scene.ground)
        plan = engine._plan_for(scene, engine.settings("accurate"))
        world = plan.world
        engine._reset(world, plan.prepared)
        start = engine._read_velocities(world)
        assert start == read_velocities(world)
        engine._step(world)
        engine._read_poses(world)
        hit = engine._read_velocities(world)
        assert hit == read_velocities(world)
        assert hit != start  # the bodies met: the step changed their velocities
        engine._reset(world, plan.prepared)
        assert engine._read_velocities(world) == start
        engine._read_poses(world)
        engine._step(world)
        assert engine._read_velocities(world) == hit  # not the start's, read before the step
    finally:
        engine.close()


def read_joint_by_joint(world):
    """Every body's ``(x, y, θ)`` and ``(v_x, v_y, ω)``, one ``getJointState`` per joint."""
    poses, velocities = [], []
    for uid in world.bodies:
        (x, v_x), (z, v_z), (angle, rate) = (
            pybullet.getJointState(uid, joint, physicsClientId=world.client)[:2]
            for joint in (0, 1, 2))
        poses.append((x, z, -angle))
        velocities.append((v_x, v_z, -rate))
    return tuple(poses), tuple(velocities)


@pytest.mark.parametrize("ground", [True, False])
def test_a_steps_poses_and_rates_are_each_bodys_own_in_a_batch(population_scenes, ground):
    # Three impacts of one kind in one batch client, stepped into contact: each view reads
    # its own bodies (one for a ground scene, two otherwise), in the scene's conventions.
    engine = adapter.PybulletEngine()
    try:
        settings = engine.settings("accurate")
        scenes = [scene for scene in population_scenes if scene.ground == ground][:3]
        plans = [engine._plan_for(scene, settings) for scene in scenes]
        batch, worlds, _ = engine._build_many(plans)
        try:
            for _ in range(3):
                engine._step_many(batch, range(len(worlds)))
            for world, scene in zip(worlds, scenes):
                assert len(world.bodies) == len(scene.bodies)
                poses = engine._read_poses(world)
                assert (poses, engine._read_velocities(world)) == read_joint_by_joint(world)
        finally:
            engine._release_many(batch)
    finally:
        engine.close()
