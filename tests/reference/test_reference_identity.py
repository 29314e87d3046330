"""The several-contact references are bit for bit those of the code before session 7's
speed-ups (event sequences, coherent solutions, Newton–Coulomb and sequential readings).

The stored file holds several-contact points (every scene float as ``float.hex``) and a
fingerprint of each point's reference (:func:`harness.run.references.scene_reference`): a
SHA-256 of the reference as JSON, every float exact (``repr`` round-trips). The points are
the library's several-contact points (flat faces, the tilted box and rod), perturbed copies
of them (:func:`harness.bench.many_scenarios.perturbed_copies`) and the library's points
with other frictions and restitutions (:data:`EXTREMES`). They were recorded with the code
at commit 17570bc. A change to a reference's arithmetic must regenerate the file on
purpose: ``python tests/reference/test_reference_identity.py COMMIT`` (:func:`write_stored`).
"""

from __future__ import annotations

import dataclasses
import hashlib
import importlib.util
import json
import tempfile
from pathlib import Path

import pytest

from harness.run import references
from harness.run.references import PointLaws, scene_reference
from harness.scene.model import Scene

# Scenes to JSON and back, every float exact: shared with the survey identity tests.
_spec = importlib.util.spec_from_file_location(
    "exact_scenes", Path(__file__).parent.parent / "exact_scenes.py")
exact_scenes = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(exact_scenes)
hexed, unhexed = exact_scenes.hexed, exact_scenes.unhexed

STORED = Path(__file__).parent.parent / "data" / "several-contact-references-17570bc.json"
#: The perturbed copies: perturbed_copies(COPIES, COPY_SEED), their several-contact points.
COPIES, COPY_SEED = 185, 1
#: (friction, restitution) of the library's points again: ends of the ranges, and a plastic
#: impact with friction, whose event sequences chatter (~40 impacts; with μ = 1 they run to
#: the 1,000-impact cap, a second per point: too slow here).
EXTREMES = ((0.0, 0.0), (0.0, 1.0), (0.3, 0.0), (1.0, 1.0))


def fingerprint(reference: dict) -> str:
    """SHA-256 (hex) of a reference as JSON, every float exact (``repr`` round-trips), the
    answers of laws added after the file was recorded left out (:data:`LATER_LAWS`)."""
    return hashlib.sha256(json.dumps(recorded_part(reference), sort_keys=True).encode()
                          ).hexdigest()


#: References added after 17570bc, pinned by their own tests
#: (tests/theory/test_multicontact.py, tests/run/test_references.py): left out of the
#: fingerprint, so that the file pins the older references' bits unchanged.
LATER_LAWS = (references.TWO_PHASE_POISSON,)


def recorded_part(reference: dict) -> dict:
    """``reference`` without the entries of :data:`LATER_LAWS` (also ``at-pose/…``)."""
    def later(name: str) -> bool:
        return any(name == law or name.startswith((law + "#", law + "/")) or
                   name.startswith(("at-pose/" + law,)) for law in LATER_LAWS)

    return {key: ({name: value for name, value in value.items() if not later(name)}
                  if key in ("speeds", "energy_change", "solutions", "departure_from_primary")
                  else value)
            for key, value in reference.items()}


def point_record(name: str, kind: str, scene: Scene, laws: PointLaws) -> dict:
    """A several-contact point as JSON, every float exact."""
    record = exact_scenes.scene_record(scene)
    record["scene_name"] = record.pop("name")
    return {"name": name, "kind": kind, **record,
            "laws": {"friction": hexed(laws.friction), "restitution": hexed(laws.restitution),
                     "laws": list(laws.laws)}}


def _point(record: dict) -> tuple[str, Scene, PointLaws]:
    scene = exact_scenes.read_scene({**record, "name": record["scene_name"]})
    laws = record["laws"]
    return record["kind"], scene, PointLaws(unhexed(laws["friction"]),
                                            unhexed(laws["restitution"]), tuple(laws["laws"]))


def several_contact_points(scenarios) -> list[tuple[str, str, Scene, PointLaws]]:
    """``(name, kind, scene, laws)`` of every several-contact point of ``scenarios``."""
    points = []
    for scenario in scenarios:
        kind = references.kind_of(scenario)
        if kind == references.SINGLE:
            continue
        for point in scenario.point_list():
            points.append((f"{scenario.name}#{point.index}", kind, scenario.scene(point),
                           PointLaws.of(scenario.at(point))))
    return points


def recorded_points() -> list[tuple[str, str, Scene, PointLaws]]:
    """The points :func:`write_stored` records (module docstring)."""
    from harness.bench.many_scenarios import write_copies
    from harness.scenarios import load_scenarios

    library = several_contact_points(load_scenarios())
    with tempfile.TemporaryDirectory() as directory:
        write_copies(Path(directory), COPIES, COPY_SEED)
        copies = several_contact_points(load_scenarios(directory))
    extremes = []
    for name, kind, scene, laws in library:
        for friction, restitution in EXTREMES:
            extremes.append((f"{name}/mu={friction}/e={restitution}", kind,
                             dataclasses.replace(scene, friction=friction,
                                                 restitution=restitution),
                             dataclasses.replace(laws, friction=friction,
                                                 restitution=restitution)))
    return library + copies + extremes


def write_stored(commit: str, path: Path = STORED) -> None:
    """Record the stored file anew from the references as they are now, at ``commit``."""
    points = recorded_points()
    path.write_text(json.dumps({
        "commit": commit,
        "points": [point_record(name, kind, scene, laws) for name, kind, scene, laws in points],
        "fingerprints": [fingerprint(scene_reference(kind, scene, laws))
                         for _, kind, scene, laws in points]}, indent=0))


@pytest.fixture(scope="module")
def stored():
    data = json.loads(STORED.read_text())
    return data["points"], data["fingerprints"]


def test_the_stored_points_read_back_exactly(stored):
    records, _ = stored
    for record in records:
        kind, scene, laws = _point(record)
        assert point_record(record["name"], kind, scene, laws) == record


def test_the_stored_points_cover_both_situations_and_both_shapes(stored):
    records, _ = stored
    kinds = {(record["kind"], record["bodies"][0]["kind"]) for record in records}
    assert kinds == {(situation, shape) for situation in (references.SIMULTANEOUS,
                                                          references.EVENT_DRIVEN)
                     for shape in ("box", "rod")}
    assert len(records) > 150


def test_references_are_bit_identical_to_stored(stored):
    records, fingerprints = stored
    changed = [record["name"] for record, then in zip(records, fingerprints)
               if fingerprint(scene_reference(*_point(record))) != then]
    assert not changed, f"{len(changed)} of {len(records)} references changed bits: {changed[:5]}"


if __name__ == "__main__":
    import sys

    write_stored(sys.argv[1])
