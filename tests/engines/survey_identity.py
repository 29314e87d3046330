"""An engine's runs of stored survey scenes, those of its adapter at an older commit to a
stated bound: the helper of ``tests/engines/test_*_survey_identity.py`` (loaded by path
through the ``survey_identity`` fixture of tests/conftest.py: the tests are not a package).

A stored file ``tests/data/ENGINE-survey-runs-COMMIT.json`` holds the scenes themselves
(``survey_scenes(all populations, 50, seed 0)`` when recorded, every float as ``float.hex``),
the run fields it holds, and per preset each run's values of those fields
(:func:`run_values`) recorded with the adapter at COMMIT (``run_many``). The files first held
SHA-256 fingerprints of each run's fields, every float exact; the values were written in
later from the adapter of the day, each run checked to have its stored fingerprint.

The engines are compiled C with their own float code over libm, and the harness builds what
it hands them with numpy (BLAS products): on another CPU a run can move in its last bits,
which a thousand steps carry on. So every status, count, flag, note and the contact record's
layout must be equal, and every float within :data:`RELATIVE` of its magnitude, or of the
run's largest speed for a value near zero (:func:`differences`).

Since the scenes are stored, not sampled anew, a later change to the
populations or the survey's sampling leaves the pin on the old adapter. A change to the
adapter's arithmetic, settings or records must regenerate the file on purpose, from a clean
tree at COMMIT::

    python tests/engines/survey_identity.py ENGINE COMMIT [SAMPLES]

(:func:`write_stored`), then point the test's ``STORED`` at the new file and delete the old.
"""

from __future__ import annotations

import functools
import hashlib
import importlib.util
import json
import math
from pathlib import Path
from typing import NamedTuple

from harness.scene.model import Scene

DATA = Path(__file__).parent.parent / "data"
SAMPLES = 50  # per population
PRESETS = ("defaults", "accurate")
SINGLE_EVERY = 5  # every 5th scene also run alone (``run``), to the same values
#: The run fields a newly written file holds: all a run reports but its wall time.
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
    """A stored file read back: its scenes, and per preset their runs' values."""

    commit: str
    fields: tuple[str, ...]
    scenes: list[Scene]
    runs: dict[str, list[dict]]


def stored_path(engine: str, commit: str) -> Path:
    """Where the runs of ``engine``'s adapter at ``commit`` are stored."""
    return DATA / f"{engine}-survey-runs-{commit}.json"


#: A float's bound, relative to its magnitude or (near zero) to the run's largest speed.
#: Kind (docs/verdicts.md, 'Same answers on every CPU'): a decision with a tolerance band,
#: "is this the stored run?", not a derived bound: no forward error bound exists for a
#: thousand steps of an engine's contact solver. The band lies between the drift of the last
#: bits (relative 1e-13 measured under other OpenBLAS kernels, tests/run/test_bit_identity.py;
#: the scenes' geometry now takes no BLAS product at all) and a change of the adapter, which
#: moves velocities by far more (``test_the_bound_takes_the_last_bits_and_catches_a_change``).
RELATIVE = 1e-9


def fingerprint(run, fields) -> str:
    """SHA-256 (hex) of ``repr`` of the run's ``fields`` (status as its value, derived values
    sorted): every float exact (``repr`` round-trips). What the stored files first held."""
    values = tuple(run.status.value if name == "status" else
                   sorted(run.derived.items()) if name == "derived" else getattr(run, name)
                   for name in fields)
    return hashlib.sha256(repr(values).encode()).hexdigest()


def _without_floats(value):
    if isinstance(value, float):
        return None
    if isinstance(value, (list, tuple)):
        return [_without_floats(item) for item in value]
    return value


def _floats(value):
    if isinstance(value, float):
        yield value
    elif isinstance(value, (list, tuple)):
        for item in value:
            yield from _floats(item)


def run_values(run, fields) -> dict:
    """The run's ``fields`` as JSON (status as its value, derived values sorted); its
    contact record as its layout without the floats (a SHA-256: steps, points, which
    contacts) and the sum and largest of its floats' magnitudes."""
    values = {}
    for name in fields:
        value = getattr(run, name)
        if name == "status":
            value = value.value
        elif name == "derived":
            value = sorted(value.items())
        elif name == "contact_record":
            magnitudes = [abs(x) for x in _floats(value)]
            layout = json.dumps(_without_floats(value))
            value = {"layout": hashlib.sha256(layout.encode()).hexdigest(),
                     "sum": math.fsum(magnitudes), "largest": max(magnitudes, default=0.0)}
        values[name] = json.loads(json.dumps(value))  # tuples as lists, as read back
    return values


def differences(now, then, scale: float, path: str = "") -> list[str]:
    """Where run values ``now`` depart from ``then``: a different key, length, kind, status,
    count, flag or note, or a float outside :data:`RELATIVE` of its magnitude or of
    ``scale`` (the run's largest speed)."""
    if isinstance(then, dict) and isinstance(now, dict):
        if now.keys() != then.keys():
            return [f"{path}: keys {sorted(now.keys() ^ then.keys())} added or missing"]
        return [d for key in then for d in differences(now[key], then[key], scale,
                                                         f"{path}/{key}")]
    if isinstance(then, list) and isinstance(now, list):
        if len(now) != len(then):
            return [f"{path}: {len(now)} items, stored {len(then)}"]
        return [d for index, (a, b) in enumerate(zip(now, then))
                for d in differences(a, b, scale, f"{path}[{index}]")]
    if isinstance(then, float) and isinstance(now, float):
        if now == then or (math.isnan(now) and math.isnan(then)) or abs(now - then) <= (
                RELATIVE * max(abs(now), abs(then), scale)):
            return []
        return [f"{path}: {now!r}, stored {then!r}"]
    if type(now) is not type(then) or now != then:
        return [f"{path}: {now!r}, stored {then!r}"]
    return []


def speed_scale(scene: Scene, values: dict) -> float:
    """The largest speed of ``scene`` before the impact or of the run's velocities after."""
    after = [abs(x) for x in _floats(values.get("velocities", []))]
    return max([float(abs(x)) for x in scene.state()] + after + [1e-300])


@functools.cache
def read_stored(path: Path) -> Stored:
    """The stored file at ``path``, its scenes read back; checked sound: each scene writes the
    record it was read from, and no two runs have the same values (one of something constant
    would match whatever the adapter did)."""
    data = json.loads(path.read_text())
    stored = Stored(data["commit"], tuple(data["fields"]),
                    [read_scene(record) for record in data["scenes"]], data["runs"])
    assert [scene_record(scene) for scene in stored.scenes] == data["scenes"], path
    every = [json.dumps(run, sort_keys=True) for preset in PRESETS for run in stored.runs[preset]]
    assert len(set(every)) == len(every) == len(PRESETS) * len(stored.scenes), path
    return stored


def write_stored(engine_name: str, commit: str, samples: int = SAMPLES) -> Path:
    """Record the runs of survey scenes (``samples`` per population) by ``engine_name``'s
    adapter as it is now, at ``commit``, in :func:`stored_path`; return that path."""
    from harness.engines import load_engine
    from harness.survey.cli import survey_scenes
    from harness.survey.population import resolve_populations

    scenes = survey_scenes(resolve_populations([]), samples, 0)
    engine = load_engine(engine_name)
    try:
        runs = {preset: [run_values(run, RUN_FIELDS)
                         for run in engine.run_many(scenes, engine.settings(preset))]
                for preset in PRESETS}
    finally:
        engine.close()
    path = stored_path(engine_name, commit)
    path.write_text(json.dumps({"commit": commit, "fields": list(RUN_FIELDS),
                                "scenes": [scene_record(scene) for scene in scenes],
                                "runs": runs}, indent=0))
    return path


def assert_runs_unchanged(engine, path: Path, preset: str, least: int = 300) -> None:
    """``engine``'s runs of the scenes stored at ``path`` under ``preset`` -- all of them by
    ``run_many``, every :data:`SINGLE_EVERY`-th alone by ``run`` -- have the stored values
    (:func:`differences`); a run alone is its run in the batch, bit for bit (one machine).
    ``least``: the fewest scenes the file must hold."""
    stored = read_stored(path)
    expected = stored.runs[preset]
    assert len(stored.scenes) == len(expected) > least
    settings = engine.settings(preset)
    batched = [run_values(run, stored.fields)
               for run in engine.run_many(stored.scenes, settings)]
    single = {index: run_values(engine.run(stored.scenes[index], settings), stored.fields)
              for index in range(0, len(stored.scenes), SINGLE_EVERY)}
    alone_differs = [index for index, values in single.items() if values != batched[index]]
    assert not alone_differs, f"{engine.name} {preset}: run alone is not run_many's run: " \
                              f"{alone_differs[:5]}"
    for how, now in (("run_many", dict(enumerate(batched))), ("run", single)):
        changed = [f"#{index} {stored.scenes[index].name}: {found[:2]}"
                   for index, values in now.items()
                   for found in [differences(values, expected[index], speed_scale(
                       stored.scenes[index], expected[index]))] if found]
        assert not changed, (f"{len(changed)} of {len(now)} {engine.name} {preset} runs "
                             f"({how}) differ from those of the adapter at {stored.commit}, "
                             f"first: {changed[:5]}; if the change is meant, regenerate the "
                             f"stored file: python tests/engines/survey_identity.py "
                             f"{engine.name} COMMIT (see its docstring)")


if __name__ == "__main__":
    import sys

    print(write_stored(sys.argv[1], sys.argv[2], *map(int, sys.argv[3:4])))
