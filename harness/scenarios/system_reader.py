"""The system of a scenario file, read: its bodies and their shapes (``system = "bodies"``),
a mass matrix with its contact rows (``"matrix"``), or the two sleds' parameters
(``"two-sled"``); problems collected by the :class:`~harness.scenarios.table_reader.TableReader`.
"""

from __future__ import annotations

import math
from types import MappingProxyType

import numpy as np

from harness.scenarios.model import BodySpec, MatrixSystem
from harness.scenarios.schema import (
    BODY_KEYS,
    NAME_ALLOWED,
    NAME_PATTERN,
    SHAPE_FIELDS,
    TWO_SLED_KEYS,
)
from harness.scenarios.table_reader import TableReader
from harness.scene import Box, Disk, Ellipse, Polygon, Rod

#: The keys of every shape: checked against a body's shape only when the shape is known.
ANY_SHAPE_FIELDS = tuple(dict.fromkeys(key for keys in SHAPE_FIELDS.values() for key in keys))


def _read_shape(reader: TableReader, table, prefix):
    kind = reader.string(table, "shape", prefix, choices=tuple(SHAPE_FIELDS))
    if kind is None:
        return None
    if kind == "disk":
        radius = reader.number(table, "radius", prefix, low=0.0, low_open=True, field="length")
        return None if radius is None else Disk(radius)
    if kind == "rod":
        length = reader.number(table, "length", prefix, low=0.0, low_open=True, field="length")
        radius = reader.number(table, "radius", prefix, low=0.0, low_open=True, field="length")
        return None if None in (length, radius) else Rod(length, radius)
    if kind == "box":
        width = reader.number(table, "width", prefix, low=0.0, low_open=True, field="length")
        height = reader.number(table, "height", prefix, low=0.0, low_open=True, field="length")
        return None if None in (width, height) else Box(width, height)
    if kind == "ellipse":
        semi_x = reader.number(table, "semi_x", prefix, low=0.0, low_open=True, field="length")
        semi_y = reader.number(table, "semi_y", prefix, low=0.0, low_open=True, field="length")
        return None if None in (semi_x, semi_y) else Ellipse(semi_x, semi_y)
    return _read_polygon(reader, table, prefix)


def _read_polygon(reader: TableReader, table, prefix):
    dotted = f"{prefix}.vertices"
    if not reader.require(table, "vertices", prefix):
        return None
    raw = table["vertices"]
    allowed = "a list of 3 or more [x, y] pairs, convex, counter-clockwise"
    if (not isinstance(raw, list) or len(raw) < 3
            or not all(isinstance(v, list) and len(v) == 2 for v in raw)):
        return reader.error(dotted, "must be a list of [x, y] pairs", raw, allowed)
    points = []
    for i, vertex in enumerate(raw):
        xy = [reader.check_number(f"{dotted}[{i}]", c, field="coordinate") for c in vertex]
        if None in xy:
            return None
        points.append(xy)
    vertices = np.array(points, dtype=float)
    edges = np.roll(vertices, -1, axis=0) - vertices
    following = np.roll(edges, -1, axis=0)
    turns = edges[:, 0] * following[:, 1] - edges[:, 1] * following[:, 0]
    size = float(np.abs(vertices).max()) or 1.0
    if np.all(turns < 0):
        return reader.error(dotted, "vertices are clockwise", raw,
                            "counter-clockwise order (reverse the list)")
    if not np.all(turns > 1e-12 * size * size):
        return reader.error(dotted, "polygon is not strictly convex (or repeats a vertex)", raw,
                            allowed)
    # Vertices are taken about the centroid: the centre of mass of a uniform polygon.
    centroid = Polygon(tuple(map(tuple, vertices))).centroid()
    return Polygon(tuple((float(x), float(y)) for x, y in vertices - centroid))


def _read_body(reader: TableReader, table, index: int, ground: bool) -> BodySpec | None:
    prefix = f"body[{index}]"
    if not isinstance(table, dict):
        return reader.error(prefix, "must be a table", table, "[[body]] tables")
    name = reader.string(table, "name", prefix, pattern=NAME_PATTERN,
                         allowed=NAME_ALLOWED)
    if name is not None:
        prefix = f"body.{name}"
    kind = table.get("shape")
    if isinstance(kind, str) and kind in SHAPE_FIELDS:
        reader.keys(table, prefix, BODY_KEYS + SHAPE_FIELDS[kind], f"a {kind} body")
    else:  # a bad or missing shape is the one error: another shape's keys may be right
        reader.keys(table, prefix, BODY_KEYS + ANY_SHAPE_FIELDS, "a body")
    shape = _read_shape(reader, table, prefix)
    if isinstance(shape, Ellipse) and not ground:
        shape = reader.error(f"{prefix}.shape", "an ellipse touches only the ground (its "
                             "contact with another body is not supported)", "ellipse",
                             "an ellipse in a scene with [ground], or another shape")
    mass = reader.number(table, "mass", prefix, low=0.0, low_open=True, field="mass")
    inertia = reader.number(table, "inertia", prefix, default=None, low=0.0, low_open=True,
                            field="inertia")
    angle_deg = reader.number(table, "angle_deg", prefix, default=0.0, field="angle_deg")
    velocity = reader.vector(table, "velocity", prefix, 2, default=(0.0, 0.0), field="speed")
    angular_velocity = reader.number(table, "angular_velocity", prefix, default=0.0,
                                     field="angular_velocity")
    if ground:
        position = reader.vector(table, "position", prefix, 2, default=None,
                                 field="coordinate")
    else:
        position = reader.vector(table, "position", prefix, 2, field="coordinate")
    values = (name, shape, mass, angle_deg, velocity, angular_velocity)
    if any(v is None for v in values) or (not ground and position is None):
        return None
    return BodySpec(name=name, shape=shape, mass=mass, inertia=inertia, angle_deg=angle_deg,
                    velocity=velocity, angular_velocity=angular_velocity, position=position)


def read_bodies(reader: TableReader, doc, ground: bool):
    if "body" not in doc:
        count = "one [[body]] table" if ground else "two [[body]] tables"
        return reader.error("body", "missing required key", allowed=count)
    raw = doc["body"]
    expected = 1 if ground else 2
    if not isinstance(raw, list) or len(raw) != expected:
        count = len(raw) if isinstance(raw, list) else 1
        what = "with [ground]: exactly one [[body]]" if ground else \
            "without [ground]: exactly two [[body]] tables"
        return reader.error("body", f"{count} bodies given", f"<{count} tables>", what)
    specs = [_read_body(reader, table, i, ground) for i, table in enumerate(raw)]
    if any(spec is None for spec in specs):
        return None
    if len(specs) == 2 and specs[0].name == specs[1].name:
        return reader.error("body[1].name", "two bodies share a name", specs[1].name,
                            "distinct names")
    return tuple(specs)


def read_matrix(reader: TableReader, doc):
    raw = doc.get("mass_matrix")
    if raw is None:
        reader.error("mass_matrix", "missing required key",
                     allowed="a square list of lists (symmetric positive definite)")
        rows = None
    elif (not isinstance(raw, list) or not raw
          or not all(isinstance(r, list) and len(r) == len(raw) for r in raw)):
        rows = reader.error("mass_matrix", "must be a square list of lists", raw,
                            "[[m11, m12], [m21, m22]], symmetric positive definite")
    else:
        rows = []
        for i, row in enumerate(raw):
            numbers = [reader.check_number(f"mass_matrix[{i}][{j}]", v, field="matrix")
                       for j, v in enumerate(row)]
            rows.append(None if None in numbers else tuple(numbers))
        rows = None if None in rows else tuple(rows)
    size = len(rows) if rows else None
    wn = reader.vector(doc, "wn", "", size, field="direction")
    wt = reader.vector(doc, "wt", "", size, field="direction")
    u = reader.vector(doc, "u", "", size, field="speed")
    if None in (rows, wn, wt, u):
        return None
    matrix = np.array(rows)
    if not np.allclose(matrix, matrix.T, rtol=1e-12, atol=0.0):
        return reader.error("mass_matrix", "not symmetric", raw, "a symmetric matrix")
    try:
        np.linalg.cholesky(matrix)
    except np.linalg.LinAlgError:
        return reader.error("mass_matrix", "not positive definite", raw,
                            "a symmetric positive definite matrix")
    inverse = np.linalg.inv(matrix)
    wn_, wt_ = np.array(wn), np.array(wt)
    mnn, mnt, mtt = wn_ @ inverse @ wn_, wn_ @ inverse @ wt_, wt_ @ inverse @ wt_
    if not mnn * mtt - mnt**2 > 1e-12 * mnn * mtt:
        return reader.error("wt", "parallel to wn (no tangential direction)", list(wt),
                            "wn and wt linearly independent")
    return MatrixSystem(mass_matrix=rows, wn=wn, wt=wt, u=u)


def read_two_sled(reader: TableReader, doc):
    if not reader.require(doc, "parameters", ""):
        return None
    table = doc["parameters"]
    if not isinstance(table, dict):
        return reader.error("parameters", "must be a table", table, ", ".join(TWO_SLED_KEYS))
    reader.keys(table, "parameters", TWO_SLED_KEYS, "[parameters] of a two-sled system")
    values = {}
    for key in ("gamma", "delta"):
        values[key] = reader.number(table, key, "parameters", low=-math.pi / 2, low_open=True,
                                    allowed="a steering angle in rad, |angle| < π/2")
        if values[key] is not None and not abs(values[key]) < math.pi / 2:
            values[key] = reader.error(f"parameters.{key}", "out of range", values[key],
                                       "a steering angle in rad, |angle| < π/2")
    for key, field in (("m", "two_sled_mass"), ("l", "two_sled_length")):
        if key in table:
            values[key] = reader.number(table, key, "parameters", low=0.0, low_open=True,
                                        field=field)
    for key in ("s", "c", "q3", "q6"):
        if key in table:
            values[key] = reader.number(table, key, "parameters", field="two_sled_offset")
    if "u" in table:
        values["u"] = reader.vector(table, "u", "parameters", 4, field="speed")
    if any(v is None for v in values.values()):
        return None
    return MappingProxyType(values)
