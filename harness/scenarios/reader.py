"""Reading a scenario file: TOML -> a checked :class:`harness.scenarios.model.Scenario`.

Every problem in a file is collected with its dotted key and raised as one
:class:`harness.scenarios.errors.ScenarioError` naming the file, the key, the value and what
is allowed.
"""

from __future__ import annotations

import math
import tomllib
from dataclasses import replace
from pathlib import Path
from types import MappingProxyType
from typing import Any, Iterable, Mapping

import numpy as np

from harness import bounds, inputs
from harness.engines import preset_role, renamed_roles, source_label
from harness.scenarios import checks
from harness.scenarios.checks import check_engine_settings, check_points
from harness.scenarios.errors import NO_VALUE, ScenarioError, suggest
from harness.scenarios.model import (
    BodySpec,
    Expectation,
    Gate,
    MatrixSystem,
    Scenario,
    SweepSpec,
    sweep_parameters,
)
from harness.scenarios.schema import (
    BODY_KEYS,
    BOUNDS,
    CONTACT_KINDS,
    CONTROL_CHARACTER,
    DEFAULT_GAP_TOLERANCE,
    DERIVED_TAGS,
    DESCRIPTION_ALLOWED,
    ENGINES,
    EXPECT_KEYS,
    GATE_KEYS,
    LAW_TYPES,
    LAWS,
    MAGNITUDES,
    NAME_PATTERN,
    PRESETS,
    SHAPE_FIELDS,
    SWEEP_MAGNITUDE,
    SYSTEMS,
    TAG_PATTERN,
    TINY,
    TOP_KEYS,
    TWO_SLED_KEYS,
    limit,
)
from harness.scene import Box, Disk, Ellipse, Polygon, Rod

#: Largest |value| of a number whose field has no MAGNITUDES entry.
LARGEST_NUMBER = 1e12


def magnitude_text(field: str | None) -> str:
    """What :data:`MAGNITUDES` allows for ``field``, for error messages."""
    small, large = MAGNITUDES[field] if field else (0.0, LARGEST_NUMBER)
    small = max(small, TINY)
    zero = "0 or " if MAGNITUDES.get(field, (0.0,))[0] == 0.0 else ""
    return f"{zero}{small:g} <= |value| <= {large:g}"


class TableReader:
    """Reads one parsed TOML document, collecting every error with its dotted key."""

    def __init__(self, path):
        self.path = path
        self.errors: list[ScenarioError] = []

    def error(self, key, problem, value=NO_VALUE, allowed=None):
        self.errors.append(ScenarioError(problem, path=self.path, key=key, value=value,
                                         allowed=allowed))
        return None

    def keys(self, table: Mapping, prefix: str, allowed: Iterable[str], what: str):
        allowed = tuple(allowed)
        for key in table:
            if key not in allowed:
                dotted = f"{prefix}.{key}" if prefix else key
                self.error(dotted, f"unknown key in {what}{suggest(key, allowed)}",
                           table[key], ", ".join(allowed))

    def require(self, table: Mapping, key: str, prefix: str) -> bool:
        if key not in table:
            dotted = f"{prefix}.{key}" if prefix else key
            self.error(dotted, "missing required key")
            return False
        return True

    def number(self, table, key, prefix, *, default=NO_VALUE, low=None, high=None,
               low_open=False, allowed=None, field=None):
        dotted = f"{prefix}.{key}" if prefix else key
        if key not in table:
            if default is NO_VALUE:
                if allowed is None:
                    bounds = []
                    if low is not None:
                        bounds.append(f"> {low:g}" if low_open else f">= {low:g}")
                    bounds += [f"<= {high:g}"] if high is not None else []
                    allowed = "a number" + (" " + " and ".join(bounds) if bounds else "")
                return self.error(dotted, "missing required key", allowed=allowed)
            return default
        value = table[key]
        return self.check_number(dotted, value, low=low, high=high, low_open=low_open,
                                 allowed=allowed, field=field)

    def check_number(self, dotted, value, *, low=None, high=None, low_open=False, allowed=None,
                     field=None):
        """``float(value)`` when a number within the bounds and the supported magnitude of
        ``field`` (:data:`MAGNITUDES`), else an error (and ``None``)."""
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            return self.error(dotted, f"must be a number, not {type(value).__name__}", value,
                              allowed or "a finite number")
        try:
            number = float(value)
        except OverflowError:  # an integer beyond the largest float
            return self.error(dotted, "out of the supported range", value,
                              magnitude_text(field))
        if not math.isfinite(number):
            return self.error(dotted, "must be finite", value, allowed or "a finite number")
        value = number
        if low is not None and (value <= low if low_open else value < low):
            bound = f"> {low:g}" if low_open else f">= {low:g}"
            text = allowed or (f"{bound}" if high is None else f"{bound} and <= {high:g}")
            return self.error(dotted, "out of range", value, text)
        if high is not None and value > high:
            text = allowed or (f"<= {high:g}" if low is None else f"{low:g} … {high:g}")
            return self.error(dotted, "out of range", value, text)
        small, large = MAGNITUDES[field] if field else (0.0, LARGEST_NUMBER)
        if abs(value) > large or (value != 0.0 and abs(value) < max(small, TINY)):
            return self.error(dotted, "out of the supported range", value,
                              magnitude_text(field))
        return value

    def vector(self, table, key, prefix, length, *, default=NO_VALUE, field=None):
        dotted = f"{prefix}.{key}" if prefix else key
        if key not in table:
            if default is NO_VALUE:
                return self.error(dotted, "missing required key",
                                  allowed=f"a list of {length} numbers")
            return default
        value = table[key]
        if not isinstance(value, list) or (length is not None and len(value) != length):
            size = "" if length is None else f"{length} "
            return self.error(dotted, f"must be a list of {size}numbers", value,
                              f"e.g. {[0.0] * (length or 2)}")
        numbers = [self.check_number(f"{dotted}[{i}]", v, field=field)
                   for i, v in enumerate(value)]
        return None if any(n is None for n in numbers) else tuple(numbers)

    def string(self, table, key, prefix, *, default=NO_VALUE, choices=None, pattern=None,
               allowed=None):
        dotted = f"{prefix}.{key}" if prefix else key
        if key not in table:
            if default is NO_VALUE:
                return self.error(dotted, "missing required key",
                                  allowed=allowed or (", ".join(choices) if choices else None))
            return default
        value = table[key]
        if not isinstance(value, str):
            return self.error(dotted, f"must be a string, not {type(value).__name__}", value,
                              allowed or (", ".join(choices) if choices else "a string"))
        if choices is not None and value not in choices:
            return self.error(dotted, f"unknown value{suggest(value, choices)}", value,
                              ", ".join(choices))
        if pattern is not None and not pattern.match(value):
            return self.error(dotted, "not a valid name", value, allowed)
        return value

    def line_of_text(self, table, key, prefix, *, default=NO_VALUE):
        """A string (as :meth:`string`) that is one line of text: no control character
        (:data:`CONTROL_CHARACTER`)."""
        value = self.string(table, key, prefix, default=default)
        if isinstance(value, str):
            bad = CONTROL_CHARACTER.search(value)
            if bad:
                dotted = f"{prefix}.{key}" if prefix else key
                return self.error(dotted, f"holds the control character {bad.group()!r} at "
                                  f"offset {bad.start()}", value, DESCRIPTION_ALLOWED)
        return value

    def names(self, table, key, prefix, choices, *, default):
        dotted = f"{prefix}.{key}" if prefix else key
        if key not in table:
            return default
        value = table[key]
        if not isinstance(value, list) or not all(isinstance(v, str) for v in value):
            return self.error(dotted, "must be a list of strings", value, ", ".join(choices))
        bad = [v for v in value if v not in choices]
        for v in bad:
            self.error(f"{dotted}", f"unknown name {v!r}{suggest(v, choices)}", value,
                       ", ".join(choices))
        if bad:
            return None
        if len(set(value)) != len(value):
            return self.error(dotted, "lists a name twice", value, ", ".join(choices))
        return tuple(value)


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
                         allowed="letters, digits, '_', '-' and '.'")
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


def _read_bodies(reader: TableReader, doc, ground: bool):
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


def _read_matrix(reader: TableReader, doc):
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


def _read_two_sled(reader: TableReader, doc):
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


def _read_sweep(reader: TableReader, doc, scenario: Scenario) -> SweepSpec | None:
    table = doc["sweep"]
    if not isinstance(table, dict):
        return reader.error("sweep", "must be a table", table, "parameter, values")
    reader.keys(table, "sweep", ("parameter", "values"), "[sweep]")
    allowed = sweep_parameters(scenario)
    parameter = reader.string(table, "parameter", "sweep", choices=allowed)
    if not reader.require(table, "values", "sweep"):
        return None
    raw = table["values"]
    most = int(limit("max_sweep_points"))
    list_help = (f"a list of numbers or {{start, stop, num}} (2 <= num <= {most}; "
                 "IMPACT_HARNESS_MAX_SWEEP_POINTS raises the bound)")
    field = _sweep_field(parameter)
    if isinstance(raw, dict):
        reader.keys(raw, "sweep.values", ("start", "stop", "num"), "sweep.values")
        start = reader.number(raw, "start", "sweep.values", field=field)
        stop = reader.number(raw, "stop", "sweep.values", field=field)
        num = raw.get("num")
        if isinstance(num, bool) or not isinstance(num, int) or not 2 <= num <= most:
            reader.error("sweep.values.num", f"must be an integer >= 2 and <= {most}", num,
                         list_help)
            return None
        if None in (start, stop):
            return None
        values = tuple(float(v) for v in np.linspace(start, stop, num))
    elif isinstance(raw, list) and len(raw) > most:
        return reader.error("sweep.values", f"lists {len(raw)} values", f"<{len(raw)} values>",
                            list_help)
    elif isinstance(raw, list) and raw:
        numbers = [reader.check_number(f"sweep.values[{i}]", v, field=field)
                   for i, v in enumerate(raw)]
        if None in numbers:
            return None
        values = tuple(numbers)
    else:
        return reader.error("sweep.values", "must be a non-empty list or a table", raw,
                            list_help)
    if len(set(values)) != len(values):
        return reader.error("sweep.values", "repeats a value", list(values), "distinct values")
    if parameter is None:
        return None
    return SweepSpec(parameter=parameter, values=values)


def _sweep_field(parameter) -> str | None:
    """The :data:`MAGNITUDES` entry that bounds the values of a sweep ``parameter``."""
    if not isinstance(parameter, str):
        return None
    if parameter in SWEEP_MAGNITUDE:
        return SWEEP_MAGNITUDE[parameter]
    if parameter.startswith("parameters."):  # the two sleds' steering angles (rad)
        return None
    for suffix, field in SWEEP_MAGNITUDE.items():  # body.<name>.<field>
        if parameter.endswith("." + suffix):
            return field
    return None


def _per_point(reader, dotted, raw, count, check, allowed):
    """A scalar (the same at every point) or a list with one entry per point."""
    if isinstance(raw, list):
        if len(raw) != count:
            return reader.error(dotted, f"has {len(raw)} entries for {count} sweep points", raw,
                                f"one value, or a list of {count}")
        items = raw
    else:
        items = [raw] * count
    for i, item in enumerate(items):
        if not check(item):
            key = dotted if not isinstance(raw, list) else f"{dotted}[{i}]"
            return reader.error(key, "bad value", item, allowed)
    return tuple(items)


def _read_expect(reader: TableReader, doc, scenario: Scenario) -> Expectation:
    table = doc["expect"]
    if not isinstance(table, dict):
        reader.error("expect", "must be a table", table, ", ".join(EXPECT_KEYS))
        return Expectation()
    reader.keys(table, "expect", EXPECT_KEYS, "[expect]")
    count = 1 if scenario.sweep is None else len(scenario.sweep.values)
    collision_types, energy_gain, case, gates = {}, {}, None, []

    def law_table(key):
        raw = table.get(key, {})
        if not isinstance(raw, dict):
            reader.error(f"expect.{key}", "must be a table of law = value", raw,
                         ", ".join(scenario.laws))
            return {}
        reader.keys(raw, f"expect.{key}", scenario.laws, f"expect.{key} (laws of this scenario)")
        return {law: value for law, value in raw.items() if law in scenario.laws}

    for law, raw in law_table("collision_type").items():
        types = LAW_TYPES[law]
        values = _per_point(reader, f"expect.collision_type.{law}", raw, count,
                            lambda v, types=types: not isinstance(v, bool) and v in types,
                            f"{', '.join(map(str, types))} for {law}")
        if values is not None:
            collision_types[law] = values
    for law, raw in law_table("energy_gain").items():
        values = _per_point(reader, f"expect.energy_gain.{law}", raw, count,
                            lambda v: isinstance(v, bool), "true or false")
        if values is not None:
            energy_gain[law] = values
    if "case" in table:
        case = _per_point(reader, "expect.case", table["case"], count,
                          lambda v: not isinstance(v, bool) and v in (1, 2, 3, 4, 5),
                          "a Table 1 row, 1 … 5")
    if "gate" in table:
        gates = _read_gates(reader, table["gate"], scenario)
    return Expectation(collision_type=MappingProxyType(collision_types), case=case,
                       energy_gain=MappingProxyType(energy_gain), gates=tuple(gates))


def _read_gates(reader: TableReader, raw, scenario: Scenario) -> list[Gate]:
    if not isinstance(raw, dict):
        reader.error("expect.gate", "must be a table", raw,
                     '"engine.preset" = { law = ..., max_departure = ... }')
        return []
    if scenario.analytic_only:
        reader.error("expect.gate", "an analytic-only system runs no engine", raw,
                     "no gates for two-sled or matrix systems")
        return []
    entries = []
    for key, value in raw.items():
        engine, _, preset = key.partition(".")
        if isinstance(value, dict) and "law" not in value and not preset:
            # Unquoted  pymunk.accurate = {...}  parses as a nested table.
            entries += [(f"{engine}.{p}", engine, p, v) for p, v in value.items()]
        else:
            entries.append((key, engine, preset or None, value))
    sources = ", ".join([*scenario.engines,
                         *(source_label(e, p) for e in scenario.engines for p in PRESETS)])
    gates = []
    for key, engine, preset, value in entries:
        dotted = f"expect.gate.{key}"
        if engine in scenario.engines and preset in renamed_roles(engine):
            # A renamed role's old name (mujoco.accurate): say what it is called now.
            reader.error(dotted, f"{engine} calls this preset "
                         f"{source_label(engine, preset)!r}", value,
                         f'"{source_label(engine, preset)}" = {{ ... }}')
            continue
        if engine in scenario.engines and preset is not None:
            try:
                preset = preset_role(engine, preset)  # the name users see -> its role
            except ValueError:
                pass  # reported below as unknown
        if engine not in scenario.engines or (preset is not None and preset not in PRESETS):
            reader.error(dotted, f"unknown engine or preset{suggest(key, sources.split(', '))}",
                         value, sources)
            continue
        if not isinstance(value, dict):
            reader.error(dotted, "must be a table", value, "{ law = ..., max_departure = ... }")
            continue
        reader.keys(value, dotted, GATE_KEYS, "a gate")
        law = reader.string(value, "law", dotted, choices=LAWS)
        largest = reader.number(value, "max_departure", dotted, low=0.0, low_open=True,
                                field="max_departure")
        if law is not None and largest is not None:
            gates.append(Gate(engine=engine, preset=preset, law=law, max_departure=largest))
    return gates


def _read_engine_settings(reader: TableReader, raw, scenario: Scenario):
    if not isinstance(raw, dict):
        reader.error("engine_settings", "must be a table of engine tables", raw,
                     ", ".join(ENGINES))
        return MappingProxyType({})
    reader.keys(raw, "engine_settings", scenario.engines, "[engine_settings] (engines of this "
                "scenario)")
    settings = {}
    for engine, table in raw.items():
        if engine not in scenario.engines:
            continue
        if not isinstance(table, dict):
            reader.error(f"engine_settings.{engine}", "must be a table", table,
                         "setting = value pairs")
            continue
        if _check_work_bounds(reader, engine, table):
            check_engine_settings(reader, engine, table)
        settings[engine] = MappingProxyType(dict(table))
    return MappingProxyType(settings)


def _check_work_bounds(reader: TableReader, engine: str, table: Mapping) -> bool:
    """Every setting within its bounds (:data:`harness.bounds.BOUNDS`: the step cap and the
    time step, so that a run ends, the approach and the solver's iterations); False if not.
    The same table bounds ``--set`` and the Python API (``Engine.settings``)."""
    ok = True
    for key, value in table.items():
        reason = bounds.problem(key, value)
        if reason is not None:
            ok = reader.error(f"engine_settings.{engine}.{key}", "out of range", value,
                              BOUNDS[key].allowed())
    return ok is not None


def parse_scenario(doc: Mapping[str, Any], path=None, *, checks_key: str | None = None
                   ) -> Scenario:
    """Check a parsed TOML document and build its :class:`Scenario` (raises ScenarioError).

    ``checks_key`` (:meth:`harness.store.passed_checks.PassedChecks.key` of the file's text):
    the point checks are skipped when that text passed them before, and remembered when it
    passes now.
    """
    reader = TableReader(path)
    system = reader.string(doc, "system", "", default="bodies", choices=SYSTEMS)
    if system is None:
        raise ScenarioError(errors=reader.errors)
    reader.keys(doc, "", TOP_KEYS[system],
                "a scenario file" if system == "bodies" else f'a system = "{system}" file')
    name = reader.string(doc, "name", "", pattern=NAME_PATTERN,
                         allowed="letters, digits, '_', '-' and '.'")
    description = reader.line_of_text(doc, "description", "", default="")
    tags = _read_tags(reader, doc)
    restitution = reader.number(doc, "restitution", "", low=0.0, high=1.0, field="restitution")
    friction = reader.number(doc, "friction", "", low=0.0, field="friction")
    laws = reader.names(doc, "laws", "", LAWS, default=LAWS)
    gap_tolerance = reader.number(doc, "gap_tolerance", "", default=DEFAULT_GAP_TOLERANCE,
                                  low=0.0, low_open=True, field="gap_tolerance")
    expect_sequence = doc.get("expect_sequence", False)
    if not isinstance(expect_sequence, bool):
        reader.error("expect_sequence", "must be true or false", expect_sequence, "true, false")
        expect_sequence = False
    contacts = reader.string(doc, "contacts", "", default="one", choices=CONTACT_KINDS)

    ground, bodies, parameters, matrix = False, (), MappingProxyType({}), None
    engines = ()
    if system == "bodies":
        raw_ground = doc.get("ground", False)
        if isinstance(raw_ground, dict):
            reader.keys(raw_ground, "ground", (), "[ground] (the fixed half-space y <= 0 has no"
                        " settings)")
            ground = True
        elif isinstance(raw_ground, bool):
            ground = raw_ground
        else:
            reader.error("ground", "must be a table or true/false", raw_ground,
                         "[ground] (an empty table) or ground = true")
        bodies = _read_bodies(reader, doc, ground)
        engines = reader.names(doc, "engines", "", ENGINES, default=ENGINES)
    elif system == "two-sled":
        parameters = _read_two_sled(reader, doc)
    else:
        matrix = _read_matrix(reader, doc)

    required = (name, description, tags, restitution, friction, laws, gap_tolerance, bodies,
                parameters, engines)
    if system == "matrix":
        required += (matrix,)
    if expect_sequence and bodies and any(isinstance(spec.shape, Ellipse) for spec in bodies):
        reader.error("expect_sequence", "an ellipse has no corners to strike in sequence "
                     "(its one contact rolls)", True, "false (the default) with an ellipse")
    if reader.errors or any(value is None for value in required):
        raise ScenarioError(errors=reader.errors)

    scenario = Scenario(name=name, description=description, tags=tags, restitution=restitution,
                        friction=friction, system=system, ground=ground, bodies=bodies,
                        parameters=parameters, matrix=matrix, engines=engines, laws=laws,
                        gap_tolerance=gap_tolerance, expect_sequence=expect_sequence,
                        contacts=contacts or "one",
                        path=None if path is None else Path(path))
    if "sweep" in doc:
        sweep = _read_sweep(reader, doc, scenario)
        if sweep is None:
            raise ScenarioError(errors=reader.errors)
        scenario = replace(scenario, sweep=sweep)
    if "engine_settings" in doc:
        scenario = replace(scenario, engine_settings=_read_engine_settings(
            reader, doc["engine_settings"], scenario))
    if "expect" in doc:
        scenario = replace(scenario, expect=_read_expect(reader, doc, scenario))
    if not reader.errors and not checks.passed_checks.passed(checks_key):
        check_points(reader, scenario)
        if not reader.errors:
            checks.passed_checks.add(checks_key, scenario)
    if reader.errors:
        raise ScenarioError(errors=reader.errors)
    return scenario


def _read_tags(reader: TableReader, doc) -> tuple[str, ...] | None:
    raw = doc.get("tags", [])
    allowed = "a list of lower-case words (letters, digits, '-'), e.g. [\"quick\"]"
    if not isinstance(raw, list) or not all(isinstance(t, str) for t in raw):
        return reader.error("tags", "must be a list of strings", raw, allowed)
    ok = True
    for tag in raw:
        if tag in DERIVED_TAGS:
            ok = reader.error("tags", f"{tag!r} is derived (every scenario has it), not written",
                              raw, "tags other than " + ", ".join(DERIVED_TAGS))
        elif not TAG_PATTERN.match(tag):
            ok = reader.error("tags", f"bad tag {tag!r}", raw, allowed)
    if len(set(raw)) != len(raw):
        ok = reader.error("tags", "lists a tag twice", raw, "distinct tags")
    return tuple(raw) if ok is not None else None


def load_scenario(path) -> Scenario:
    """Read and check one scenario file (raises :class:`ScenarioError`)."""
    path = Path(path)
    text = read_scenario_text(path)
    passed, checks_key = passed_before(text, path)
    return passed if passed is not None else scenario_from_text(text, path, checks_key)


def passed_before(text: str, path: Path) -> tuple[Scenario | None, str | None]:
    """``(scenario, checks key)``: the scenario of ``text`` at ``path`` when this very text
    was read and passed every check before (else None), and the key its checks are kept
    under (:data:`harness.scenarios.checks.passed_checks`)."""
    checks_key = checks.passed_checks.key(text)
    passed = checks.passed_checks.scenario(checks_key)
    return (None if passed is None else passed.located(path)), checks_key


def read_scenario_text(path: Path) -> str:
    """The text of a scenario file (raises :class:`ScenarioError`: unreadable, not a regular
    file, too large, not UTF-8: :mod:`harness.inputs`)."""
    try:
        return inputs.read_text(path)
    except OSError as error:
        raise ScenarioError(f"cannot read the file: {error.strerror or error}", path=path,
                            allowed="a readable .toml file") from None
    except inputs.InputError as error:
        problem, _, allowed = str(error).partition("; allowed: ")
        raise ScenarioError(problem, path=path,
                            allowed=allowed or "a TOML file encoded in UTF-8") from None


def scenario_from_text(text: str, path: Path, checks_key: str | None = None) -> Scenario:
    """Parse and check the text of the scenario file ``path`` (raises :class:`ScenarioError`);
    ``checks_key`` as for :func:`parse_scenario`."""
    try:
        doc = inputs.parse_toml(text)
    except tomllib.TOMLDecodeError as error:
        raise ScenarioError(f"not valid TOML: {error}", path=path,
                            allowed="TOML 1.0 (https://toml.io)") from None
    except inputs.InputError as error:
        problem, _, allowed = str(error).partition("; allowed: ")
        raise ScenarioError(problem, path=path, allowed=allowed or None) from None
    return parse_scenario(doc, path, checks_key=checks_key)
