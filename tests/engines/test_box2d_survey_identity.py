"""Box2D's runs of survey scenes are bit for bit the runs of the adapter before session 6's
speed-ups (in-place reads, shared shapes, batches by speed class, inline geometry).

The stored file holds survey scenes (every float as ``float.hex``) and, per preset, a
fingerprint of each run of them -- a SHA-256 of the velocities, status, steps, impulses,
contact record, derived values and notes -- recorded with the adapter at commit 41a1da8
(``run_many``, batches of scenes in a row). A change to the adapter's arithmetic, its
settings or its records must regenerate the file on purpose:
``python tests/engines/test_box2d_survey_identity.py COMMIT`` (:func:`write_stored`).
"""

from __future__ import annotations

import hashlib
import json
from pathlib import Path

import pytest

pytest.importorskip("Box2D", reason="Box2D not installed (pip install box2d==2.3.10)")

from harness.engines import load_engine
from harness.scene.model import Body, Box, Disk, Polygon, Rod, Scene

STORED = Path(__file__).parent.parent / "data" / "box2d-survey-runs-41a1da8.json"
SAMPLES = 50  # per population: the stored scenes are survey_scenes(all populations, 50, 0)
_SHAPES = {"disk": Disk, "rod": Rod, "box": Box, "polygon": Polygon}


def fingerprint(run) -> str:
    """SHA-256 (hex) of what a run reports, every float exact (``repr`` round-trips)."""
    fields = (run.velocities, run.status.value, run.steps, run.contact_steps,
              run.first_contact_step, run.max_contact_points, run.max_penetration,
              run.normal_impulse, run.tangential_impulse, run.contact_normal,
              run.contact_record, sorted(run.derived.items()), run.notes)
    return hashlib.sha256(repr(fields).encode()).hexdigest()


def _hex(value):
    if isinstance(value, (tuple, list)):
        return [_hex(item) for item in value]
    return float(value).hex()


def _unhex(value):
    if isinstance(value, list):
        return tuple(_unhex(item) for item in value)
    return float.fromhex(value)


def scene_record(scene: Scene) -> dict:
    """A scene as JSON, every float exact."""
    bodies = []
    for body in scene.bodies:
        shape = body.shape
        fields = ({"points": _hex(shape.points)} if shape.kind == "polygon" else
                  {name: _hex(getattr(shape, name)) for name in vars(shape)})
        bodies.append({"name": body.name, "kind": shape.kind, "shape": fields,
                       "mass": _hex(body.mass), "position": _hex(body.position),
                       "angle": _hex(body.angle), "velocity": _hex(body.velocity),
                       "angular_velocity": _hex(body.angular_velocity),
                       "inertia": None if body.inertia is None else _hex(body.inertia)})
    return {"name": scene.name, "ground": scene.ground, "bodies": bodies,
            "restitution": _hex(scene.restitution), "friction": _hex(scene.friction)}


def _scene(record: dict) -> Scene:
    bodies = []
    for body in record["bodies"]:
        shape = _SHAPES[body["kind"]](**{name: _unhex(value)
                                         for name, value in body["shape"].items()})
        bodies.append(Body(body["name"], shape, _unhex(body["mass"]), _unhex(body["position"]),
                           _unhex(body["angle"]), _unhex(body["velocity"]),
                           _unhex(body["angular_velocity"]),
                           None if body["inertia"] is None else _unhex(body["inertia"])))
    return Scene(tuple(bodies), _unhex(record["restitution"]), _unhex(record["friction"]),
                 record["ground"], record["name"])


def write_stored(commit: str, path: Path = STORED) -> None:
    """Record the stored file anew from the adapter as it is now, at ``commit``."""
    from harness.survey.cli import survey_scenes
    from harness.survey.population import resolve_populations

    scenes = survey_scenes(resolve_populations([]), SAMPLES, 0)
    engine = load_engine("box2d")
    runs = {preset: [fingerprint(run) for run in engine.run_many(scenes,
                                                                 engine.settings(preset))]
            for preset in ("defaults", "accurate")}
    path.write_text(json.dumps({"commit": commit,
                                "scenes": [scene_record(scene) for scene in scenes],
                                "runs": runs}, indent=0))


@pytest.fixture(scope="module")
def stored():
    data = json.loads(STORED.read_text())
    return [_scene(record) for record in data["scenes"]], data["runs"]


def test_the_stored_scenes_read_back_exactly(stored):
    scenes, _ = stored
    for scene, record in zip(scenes, json.loads(STORED.read_text())["scenes"]):
        assert scene_record(scene) == record


@pytest.mark.parametrize("preset", ["defaults", "accurate"])
def test_survey_runs_are_bit_identical_to_stored(stored, preset):
    scenes, runs = stored
    assert len(scenes) == len(runs[preset]) > 300
    engine = load_engine("box2d")
    settings = engine.settings(preset)
    batched = [fingerprint(run) for run in engine.run_many(scenes, settings)]
    changed = [scene.name for scene, now, then in zip(scenes, batched, runs[preset])
               if now != then]
    assert not changed, f"{len(changed)} runs changed bits, first: {changed[:5]}"
    single = [fingerprint(engine.run(scene, settings)) for scene in scenes[::5]]
    assert single == runs[preset][::5]


if __name__ == "__main__":
    import sys

    write_stored(sys.argv[1])
