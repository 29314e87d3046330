"""Scenes as JSON with every float exact (``float.hex``), and back: the stored scenes of the
identity tests (tests/engines/survey_identity.py, tests/reference/test_reference_identity.py).

Both load it by path: the tests are not a package, and both also run as scripts that
record their stored files.
"""

from __future__ import annotations

import dataclasses

from harness.scene.model import Body, Box, Disk, Polygon, Rod, Scene

SHAPES = {"disk": Disk, "rod": Rod, "box": Box, "polygon": Polygon}


def hexed(value):
    """A float, or nested tuples/lists of them, as ``float.hex`` strings (lists)."""
    if isinstance(value, (tuple, list)):
        return [hexed(item) for item in value]
    return float(value).hex()


def unhexed(value):
    """The floats of :func:`hexed` (tuples)."""
    if isinstance(value, list):
        return tuple(unhexed(item) for item in value)
    return float.fromhex(value)


def scene_record(scene: Scene) -> dict:
    """A scene as JSON, every float exact (a shape as its fields, not what it caches)."""
    bodies = []
    for body in scene.bodies:
        shape = {field.name: hexed(getattr(body.shape, field.name))
                 for field in dataclasses.fields(body.shape)}
        bodies.append({"name": body.name, "kind": body.shape.kind, "shape": shape,
                       "mass": hexed(body.mass), "position": hexed(body.position),
                       "angle": hexed(body.angle), "velocity": hexed(body.velocity),
                       "angular_velocity": hexed(body.angular_velocity),
                       "inertia": None if body.inertia is None else hexed(body.inertia)})
    return {"name": scene.name, "ground": scene.ground, "bodies": bodies,
            "restitution": hexed(scene.restitution), "friction": hexed(scene.friction)}


def read_scene(record: dict) -> Scene:
    """The scene of :func:`scene_record`."""
    bodies = []
    for body in record["bodies"]:
        shape = SHAPES[body["kind"]](**{name: unhexed(value)
                                        for name, value in body["shape"].items()})
        bodies.append(Body(body["name"], shape, unhexed(body["mass"]), unhexed(body["position"]),
                           unhexed(body["angle"]), unhexed(body["velocity"]),
                           unhexed(body["angular_velocity"]),
                           None if body["inertia"] is None else unhexed(body["inertia"])))
    return Scene(tuple(bodies), unhexed(record["restitution"]), unhexed(record["friction"]),
                 record["ground"], record["name"])
