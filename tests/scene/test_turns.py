"""The 2-D turns of body-frame points outside the contact geometry, written elementwise (issue
35): the scene's point features at many poses (:func:`harness.scene.features.centres_at_poses`,
the verdicts' touched features), the event-driven reference's features
(:mod:`harness.reference.event_driven`) and the scenario checks' feature gaps
(:mod:`harness.scenarios.checks`), all through :func:`harness.scene.geometry.turn` or the same
sums.

Kind (docs/verdicts.md, 'Same answers on every CPU'): bit for bit. Against a reference written
here in Python floats, ``(x cos θ − y sin θ + p_x, x sin θ + y cos θ + p_y)``, one IEEE rounding
per operation (``blas_free``: no BLAS product is taken, so no kernel can move them); and rerun
against rerun on this machine under OpenBLAS's oldest kernel with numpy's SIMD loops off (run by
tests/other_kernels.py under every other core type as well). A product with the rotation matrix
(``p @ R``) goes through BLAS: on the development machine the stacked product ``centres @ R``
of 2,000 poses gave the elementwise bits under Prescott and differed from them in 5,602 of
24,000 coordinates (by up to 2.2e-16) under Haswell and SkylakeX, which is why none is left.
"""

from __future__ import annotations

import hashlib
import math

import numpy as np
import pytest

from harness.reference import event_driven
from harness.scenarios import checks
from harness.scene import Body, Box, Disk, Polygon, Rod, Scene, geometry
from harness.scene.features import centres_at_poses, feature_points


def reference_turn(x: float, y: float, angle: float, px: float | None = None,
                   py: float | None = None):
    """The turned (and, given a position, moved) point in Python floats, one rounding per
    operation (no position is not a zero one: ``-0.0 + 0.0`` is ``0.0``)."""
    c, s = math.cos(angle), math.sin(angle)
    turned = (x * c - y * s), (x * s + y * c)
    return turned if px is None else (turned[0] + px, turned[1] + py)


def random_shape(rng):
    kind = int(rng.integers(4))
    if kind == 0:
        return Disk(float(rng.uniform(0.01, 0.2)))
    if kind == 1:
        return Rod(float(rng.uniform(0.05, 0.5)), float(rng.uniform(0.005, 0.05)))
    if kind == 2:
        return Box(float(rng.uniform(0.05, 0.4)), float(rng.uniform(0.05, 0.4)))
    sides = int(rng.integers(3, 9))
    return Polygon(tuple((0.1 * math.cos(2 * math.pi * k / sides + 0.3),
                          0.1 * math.sin(2 * math.pi * k / sides + 0.3))
                         for k in range(sides)))


def random_poses(rng, count):
    poses = np.column_stack([rng.uniform(-2, 2, count), rng.uniform(-2, 2, count),
                             rng.uniform(-4 * math.pi, 4 * math.pi, count)])
    poses[::7, 2] = rng.choice([0.0, math.pi / 2, math.pi, -math.pi / 4], len(poses[::7]))
    return poses


@pytest.mark.kernel_sensitive
@pytest.mark.blas_free
def test_centres_at_poses_is_the_elementwise_turn():
    rng = np.random.default_rng(351)
    for count in (1, 5, 300):
        centres = rng.normal(scale=0.3, size=(int(rng.integers(1, 9)), 2))
        poses = random_poses(rng, count)
        expected = np.array([[reference_turn(x, y, angle, px, py) for x, y in centres.tolist()]
                             for px, py, angle in poses.tolist()])
        assert centres_at_poses(centres, poses).tobytes() == expected.tobytes()
        # each pose its own centres (the verdicts' groups of runs)
        own = rng.normal(scale=0.3, size=(count, len(centres), 2))
        expected = np.array([[reference_turn(x, y, angle, px, py) for x, y in points]
                             for points, (px, py, angle) in zip(own.tolist(), poses.tolist())])
        assert centres_at_poses(own, poses).tobytes() == expected.tobytes()


@pytest.mark.kernel_sensitive
@pytest.mark.blas_free
def test_turn_and_the_event_driven_features_are_the_elementwise_turn():
    rng = np.random.default_rng(352)
    for _ in range(300):
        body = Body("b", random_shape(rng), 1.0, tuple(rng.uniform(-1, 1, 2).tolist()),
                    float(rng.uniform(-7, 7)))
        points, radius = geometry.local_core(body.shape)
        expected = np.array([reference_turn(x, y, body.angle) for x, y in points.tolist()])
        assert geometry.turn(points, body.angle).tobytes() == expected.tobytes()
        assert geometry.turn(points[0], body.angle).tobytes() == expected[:1].tobytes()
        px, py = body.position
        moved = np.array([reference_turn(x, y, body.angle, px, py) for x, y in points.tolist()])
        world, _ = event_driven._feature_state(body, body.position, body.angle)  # noqa: SLF001
        assert world.tobytes() == moved.tobytes()


@pytest.mark.kernel_sensitive
@pytest.mark.blas_free
def test_the_checks_feature_gaps_are_the_elementwise_turn():
    rng = np.random.default_rng(353)
    for _ in range(200):
        bodies = [Body(name, random_shape(rng), 1.0, tuple(rng.uniform(-0.5, 0.5, 2).tolist()),
                       float(rng.uniform(-7, 7))) for name in ("a", "b")]
        for scene in (Scene(tuple(bodies[:1]), 0.5, 0.3, ground=True),
                      Scene(tuple(bodies), 0.5, 0.3)):
            poses = [(b.position[0], b.position[1], b.angle) for b in scene.bodies]
            for index, body in enumerate(scene.bodies):
                centres, radius, _ = feature_points(body.shape)
                for centre in np.asarray(centres).reshape(-1, 2):
                    x, y = reference_turn(*centre.tolist(), body.angle, *body.position)
                    if scene.ground:
                        expected = y - radius
                    else:
                        feature = Body("feature", Disk(radius), 1.0, (x, y))
                        expected = geometry.body_contact(scene.bodies[1 - index], feature).gap
                    got = checks._feature_gap(scene, index, centre, radius, poses)  # noqa: SLF001
                    assert got.hex() == expected.hex()


def turns_digest() -> str:
    """SHA-256 of every bit of the turns above on fixed random inputs (run here and, by the
    test below, under another kernel)."""
    rng = np.random.default_rng(354)
    digest = hashlib.sha256()
    for count in (1, 40, 400):
        centres = rng.normal(scale=0.3, size=(int(rng.integers(1, 9)), 2))
        poses = random_poses(rng, count)
        digest.update(centres_at_poses(centres, poses).tobytes())
        digest.update(centres_at_poses(rng.normal(size=(count, 3, 2)), poses).tobytes())
    for _ in range(200):
        body = Body("b", random_shape(rng), 1.0, tuple(rng.uniform(-0.5, 0.5, 2).tolist()),
                    float(rng.uniform(-7, 7)))
        world, _ = event_driven._feature_state(body, body.position, body.angle)  # noqa: SLF001
        digest.update(world.tobytes())
        scene = Scene((body,), 0.5, 0.3, ground=True)
        centres, radius, _ = feature_points(body.shape)
        pose = [(body.position[0], body.position[1], body.angle)]
        for centre in np.asarray(centres).reshape(-1, 2):
            gap = checks._feature_gap(scene, 0, centre, radius, pose)  # noqa: SLF001
            digest.update(gap.hex().encode())
    return digest.hexdigest()


@pytest.mark.kernel_sensitive
def test_turns_are_the_same_bits_under_another_kernel():
    # Bit for bit, rerun against rerun on this machine: the turns take no BLAS product, so
    # OpenBLAS's oldest kernel (Prescott, x86-64) with numpy's SIMD loops off must give the
    # same bits as this run's kernels (whichever tests/other_kernels.py chose).
    import subprocess
    import sys
    from pathlib import Path

    from tests.other_kernels import kernel_environment

    environment, _ = kernel_environment("Prescott")
    root = Path(__file__).resolve().parents[2]
    script = "from tests.scene.test_turns import turns_digest; print(turns_digest())"
    there = subprocess.run([sys.executable, "-c", script], cwd=root, env=environment,
                           capture_output=True, text=True, timeout=600, check=True)
    assert there.stdout.strip() == turns_digest()
