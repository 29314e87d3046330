"""An engine's runs of stored survey scenes, bit for bit the runs of its adapter at an older
commit: the helper of ``tests/engines/test_*_survey_identity.py`` (loaded by path through the
``survey_identity`` fixture of tests/conftest.py: the tests are not a package).

A stored file ``tests/data/ENGINE-survey-runs-COMMIT.json`` holds the scenes themselves
(``survey_scenes(all populations, 50, seed 0)`` when recorded, every float as ``float.hex``),
the run fields its fingerprints cover, and per preset a fingerprint of each run -- a SHA-256
of those fields' ``repr``, every float exact -- recorded with the adapter at COMMIT
(``run_many``). Since the scenes are stored, not sampled anew, a later change to the
populations or the survey's sampling leaves the pin on the old adapter. A change to the
adapter's arithmetic, settings or records must regenerate the file on purpose, from a clean
tree at COMMIT::

    python tests/engines/survey_identity.py ENGINE COMMIT

(:func:`write_stored`), then point the test's ``STORED`` at the new file and delete the old.
"""

from __future__ import annotations

import functools
import hashlib
import importlib.util
import json
from pathlib import Path
from typing import NamedTuple

from harness.scene.model import Scene

DATA = Path(__file__).parent.parent / "data"
SAMPLES = 50  # per population
PRESETS = ("defaults", "accurate")
SINGLE_EVERY = 5  # every 5th scene also run alone (``run``), to the same fingerprint
#: The run fields a newly written file fingerprints: all a run reports but its wall time.
RUN_FIELDS = ("velocities", "status", "status_reason", "steps", "contact_steps",
              "first_contact_step", "max_contact_points", "max_penetration", "separated",
              "step_cap_hit", "contact_normal", "normal_impulse", "tangential_impulse",
              "impulse_source", "out_of_plane_drift", "energy_before", "energy_after",
              "contact_record", "derived", "notes")
# Scenes to JSON and back, every float exact: shared with the reference identity test.
_spec = importlib.util.spec_from_file_location(
    "exact_scenes", Path(__file__).parent.parent / "exact_scenes.py")
exact_scenes = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(exact_scenes)
scene_record, read_scene = exact_scenes.scene_record, exact_scenes.read_scene


class Stored(NamedTuple):
    """A stored file read back: its scenes, and per preset the fingerprints of their runs."""

    commit: str
    fields: tuple[str, ...]
    scenes: list[Scene]
    runs: dict[str, list[str]]


def stored_path(engine: str, commit: str) -> Path:
    """Where the runs of ``engine``'s adapter at ``commit`` are stored."""
    return DATA / f"{engine}-survey-runs-{commit}.json"


def fingerprint(run, fields) -> str:
    """SHA-256 (hex) of ``repr`` of the run's ``fields`` (status as its value, derived values
    sorted): every float exact (``repr`` round-trips)."""
    values = tuple(run.status.value if name == "status" else
                   sorted(run.derived.items()) if name == "derived" else getattr(run, name)
                   for name in fields)
    return hashlib.sha256(repr(values).encode()).hexdigest()


@functools.cache
def read_stored(path: Path) -> Stored:
    """The stored file at ``path``, its scenes read back; checked sound: each scene writes the
    record it was read from, and no two runs share a fingerprint (one of something constant
    would match whatever the adapter did)."""
    data = json.loads(path.read_text())
    stored = Stored(data["commit"], tuple(data["fields"]),
                    [read_scene(record) for record in data["scenes"]], data["runs"])
    assert [scene_record(scene) for scene in stored.scenes] == data["scenes"], path
    every = [run for preset in PRESETS for run in stored.runs[preset]]
    assert len(set(every)) == len(every) == len(PRESETS) * len(stored.scenes), path
    return stored


def write_stored(engine_name: str, commit: str) -> Path:
    """Record the runs of survey scenes by ``engine_name``'s adapter as it is now, at
    ``commit``, in :func:`stored_path`; return that path."""
    from harness.engines import load_engine
    from harness.survey.cli import survey_scenes
    from harness.survey.population import resolve_populations

    scenes = survey_scenes(resolve_populations([]), SAMPLES, 0)
    engine = load_engine(engine_name)
    try:
        runs = {preset: [fingerprint(run, RUN_FIELDS)
                         for run in engine.run_many(scenes, engine.settings(preset))]
                for preset in PRESETS}
    finally:
        engine.close()
    path = stored_path(engine_name, commit)
    path.write_text(json.dumps({"commit": commit, "fields": list(RUN_FIELDS),
                                "scenes": [scene_record(scene) for scene in scenes],
                                "runs": runs}, indent=0))
    return path


def assert_runs_unchanged(engine, path: Path, preset: str) -> None:
    """``engine``'s runs of the scenes stored at ``path`` under ``preset`` -- all of them by
    ``run_many``, every :data:`SINGLE_EVERY`-th alone by ``run`` -- have the stored
    fingerprints."""
    stored = read_stored(path)
    expected = stored.runs[preset]
    assert len(stored.scenes) == len(expected) > 300
    settings = engine.settings(preset)
    batched = [fingerprint(run, stored.fields)
               for run in engine.run_many(stored.scenes, settings)]
    single = {index: fingerprint(engine.run(stored.scenes[index], settings), stored.fields)
              for index in range(0, len(stored.scenes), SINGLE_EVERY)}
    for how, now in (("run_many", dict(enumerate(batched))), ("run", single)):
        changed = [f"#{index} {stored.scenes[index].name}" for index, digest in now.items()
                   if digest != expected[index]]
        assert not changed, (f"{len(changed)} of {len(now)} {engine.name} {preset} runs "
                             f"({how}) differ from those of the adapter at {stored.commit}, "
                             f"first: {changed[:5]}; if the change is meant, regenerate the "
                             f"stored file: python tests/engines/survey_identity.py "
                             f"{engine.name} COMMIT (see its docstring)")


if __name__ == "__main__":
    import sys

    print(write_stored(sys.argv[1], sys.argv[2]))
