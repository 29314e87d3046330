"""pybullet's runs of survey scenes are bit for bit the runs of the adapter before session 8's
speed-ups of ``run_many`` (fewer calls and less Python per impact).

The stored file holds, per survey scene (``survey_scenes(all populations, 50, seed 0)``), a
SHA-256 of the scene itself and, per preset, one of its run -- velocities, status, steps,
impulses, energies, drift, the contact record, derived values and notes -- recorded with
the adapter at commit c267d83 (``run_many``, the survey's batches). A change to the survey's
sampling changes the scenes' digests (the test says so); a change to the adapter's
arithmetic, settings or records changes the runs'. Either must regenerate the file on
purpose: ``python tests/engines/test_pybullet_survey_identity.py COMMIT``
(:func:`write_stored`).
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
from pathlib import Path

import pytest

pytest.importorskip("pybullet", reason="pybullet not installed (pip install pybullet==3.2.7)")

from harness.engines import load_engine  # noqa: E402
from harness.survey.cli import survey_scenes  # noqa: E402
from harness.survey.population import resolve_populations  # noqa: E402

STORED = Path(__file__).parent.parent / "data" / "pybullet-survey-runs-c267d83.json"
SAMPLES = 50  # per population
PRESETS = ("defaults", "accurate")


def digest(value) -> str:
    """SHA-256 (hex) of ``repr(value)``: every float exact (``repr`` round-trips)."""
    return hashlib.sha256(repr(value).encode()).hexdigest()


def scene_digest(scene) -> str:
    """Digest of everything a run reads from a scene (a shape as its fields' values, not
    what it caches once used)."""
    bodies = tuple((body.name, body.shape.kind,
                    [(f.name, getattr(body.shape, f.name)) for f in dataclasses.fields(body.shape)],
                    body.mass,
                    body.position, body.angle, body.velocity, body.angular_velocity,
                    body.inertia) for body in scene.bodies)
    return digest((scene.name, scene.ground, scene.restitution, scene.friction, bodies))


def run_digest(run) -> str:
    """Digest of what a run reports (all but its wall time)."""
    return digest((run.velocities, run.status.value, run.status_reason, run.steps,
                   run.contact_steps, run.first_contact_step, run.max_contact_points,
                   run.max_penetration, run.separated, run.step_cap_hit, run.contact_normal,
                   run.normal_impulse, run.tangential_impulse, run.impulse_source,
                   run.out_of_plane_drift, run.energy_before, run.energy_after,
                   run.contact_record, sorted(run.derived.items()), run.notes))


def _scenes():
    return survey_scenes(resolve_populations([]), SAMPLES, 0)


def write_stored(commit: str, path: Path = STORED) -> None:
    """Record the stored file anew from the adapter as it is now, at ``commit``."""
    scenes = _scenes()
    engine = load_engine("pybullet")
    runs = {preset: [run_digest(run) for run in engine.run_many(scenes,
                                                                engine.settings(preset))]
            for preset in PRESETS}
    path.write_text(json.dumps({"commit": commit,
                                "scenes": [scene_digest(scene) for scene in scenes],
                                "runs": runs}, indent=0))


@pytest.fixture(scope="module")
def stored():
    data = json.loads(STORED.read_text())
    scenes = _scenes()
    now = [scene_digest(scene) for scene in scenes]
    assert now == data["scenes"], ("the survey's scenes changed: regenerate the stored file "
                                   "(see the module docstring)")
    return scenes, data["runs"]


@pytest.fixture(scope="module")
def engine():
    engine = load_engine("pybullet")
    yield engine
    engine.close()


@pytest.mark.parametrize("preset", PRESETS)
def test_survey_runs_are_bit_identical_to_stored(stored, engine, preset):
    scenes, runs = stored
    assert len(scenes) == len(runs[preset]) > 300
    settings = engine.settings(preset)
    batched = [run_digest(run) for run in engine.run_many(scenes, settings)]
    changed = [scene.name for scene, now, then in zip(scenes, batched, runs[preset])
               if now != then]
    assert not changed, f"{len(changed)} runs changed bits, first: {changed[:5]}"
    single = [run_digest(engine.run(scene, settings)) for scene in scenes[::7]]
    assert single == runs[preset][::7]


def test_the_stored_runs_differ_between_scenes_and_presets(stored):
    # A digest of something constant would match whatever the adapter did.
    _, runs = stored
    assert len(set(runs["defaults"])) == len(runs["defaults"])
    assert not set(runs["defaults"]) & set(runs["accurate"])


if __name__ == "__main__":
    import sys

    write_stored(sys.argv[1])
