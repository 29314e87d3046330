"""Scenario files: TOML descriptions of one impact (or a sweep of impacts), read and checked.

A scenario is a TOML file under ``scenarios/`` (format in ``scenarios/README.md``) read into
a frozen :class:`Scenario`. Three kinds of system:

* ``bodies`` (the default): one body against the fixed ground (``[ground]``) or two free
  bodies, given as ``[[body]]`` tables. The harness builds a :class:`harness.scene.Scene`
  for the engines and, through :mod:`harness.geometry` and ``planar_impact.builders``, the
  analytic problem for the laws.
* ``two-sled``: the paper's Section 5 system, analytic only (``[parameters]``).
* ``matrix``: ``mass_matrix``, ``wn``, ``wt`` and ``u`` given directly, analytic only.

An optional ``[sweep]`` varies one parameter; :meth:`Scenario.points` lists every point with
its scene (or analytic problem). Every problem in a file is reported as a
:class:`ScenarioError` naming the file, the key (dotted path), the value and what is allowed.

>>> from harness.scenarios import load_scenarios
>>> for scenario in load_scenarios(tags="quick"):                       # doctest: +SKIP
...     for point, scene in scenario.points():
...         problem = scenario.analytic_problem(point)
...         result = problem.solve(mu=scenario.friction_at(point),
...                                e=scenario.restitution_at(point), hypothesis="poisson")
"""

from __future__ import annotations

import difflib
import math
import re
import tomllib
from dataclasses import dataclass, field, replace
from pathlib import Path
from types import MappingProxyType
from typing import Any, Iterable, Mapping, Union

import numpy as np

from harness import geometry
from harness.scene import Body, Box, Contact, Disk, Polygon, Rod, Scene

SCENARIO_DIR = Path(__file__).resolve().parent.parent / "scenarios"

#: Impact laws by the names of ``planar_impact.HYPOTHESES``.
LAWS = ("newton", "poisson", "stronge", "stronge-paper", "newton-lcp")
#: Collision types each law reports: Poisson/Stronge 1–5, Newton laws 1 stick, 2 reverse
#: sliding, 3 forward sliding.
LAW_TYPES = {
    "newton": (1, 2, 3),
    "poisson": (1, 2, 3, 4, 5),
    "stronge": (1, 2, 3, 4, 5),
    "stronge-paper": (1, 2, 3, 4, 5),
    "newton-lcp": (1, 2, 3),
}
ENGINES = ("pymunk", "pybullet", "mujoco")
PRESETS = ("defaults", "accurate")
SYSTEMS = ("bodies", "two-sled", "matrix")
ANALYTIC_SYSTEMS = ("two-sled", "matrix")
SHAPE_FIELDS = {
    "disk": ("radius",),
    "rod": ("length", "radius"),
    "box": ("width", "height"),
    "polygon": ("vertices",),
}
#: Largest |gap| (m) allowed between bodies that must touch, unless a file sets ``gap_tolerance``.
DEFAULT_GAP_TOLERANCE = 1e-6
#: Two closest points closer than this (m) in height count as a second contact point: a body
#: must be turned at least this much away from lying flat to be a one-point contact.
ONE_POINT_TOLERANCE = 1e-4
TWO_SLED_KEYS = ("gamma", "delta", "m", "l", "s", "c", "q3", "q6", "u")
TWO_SLED_DEFAULTS = {
    "m": 3.0,
    "l": 1.0,
    "s": 0.75,
    "c": -0.5,
    "q3": math.pi / 4,
    "q6": 7 * math.pi / 4,
    "u": (1.0, 0.1, 1.0, 0.1),
}
BODY_KEYS = ("name", "shape", "mass", "inertia", "angle_deg", "velocity", "angular_velocity",
             "position")
BODY_SWEEP_FIELDS = ("mass", "inertia", "angle_deg", "angular_velocity", "velocity.x",
                     "velocity.y")
TOP_KEYS = {
    "bodies": ("name", "description", "tags", "system", "restitution", "friction", "engines",
               "laws", "ground", "body", "gap_tolerance", "sweep", "expect", "engine_settings"),
    "two-sled": ("name", "description", "tags", "system", "restitution", "friction", "laws",
                 "parameters", "sweep", "expect"),
    "matrix": ("name", "description", "tags", "system", "restitution", "friction", "laws",
               "mass_matrix", "wn", "wt", "u", "sweep", "expect"),
}
ALL_TOP_KEYS = tuple(dict.fromkeys(key for keys in TOP_KEYS.values() for key in keys))
EXPECT_KEYS = ("collision_type", "case", "energy_gain", "gate")
GATE_KEYS = ("law", "max_departure")
NAME_PATTERN = re.compile(r"^[A-Za-z0-9][A-Za-z0-9_.-]*$")
TAG_PATTERN = re.compile(r"^[a-z0-9][a-z0-9-]*$")
DERIVED_TAGS = ("all",)


# --------------------------------------------------------------------------------------------
# Errors
# --------------------------------------------------------------------------------------------
_NO_VALUE = object()


def _show(value: Any) -> str:
    text = repr(value)
    return text if len(text) <= 80 else text[:77] + "..."


class ScenarioError(ValueError):
    """A bad scenario file. ``str()`` names the file, the key, the value and what is allowed.

    One error per problem; when a file has several, the first one raised carries them all
    in ``errors`` (each a :class:`ScenarioError`) and its message lists every one.
    """

    def __init__(self, message: str = "", *, path=None, key: str | None = None,
                 value: Any = _NO_VALUE, allowed: str | None = None,
                 errors: Iterable["ScenarioError"] = ()):
        self.path = None if path is None else str(path)
        self.key = key
        self.value = None if value is _NO_VALUE else value
        self.allowed = allowed
        self.problem = message
        self.errors = tuple(errors) or (self,)
        if len(self.errors) > 1:
            text = f"{len(self.errors)} errors:\n" + "\n".join(f"  {e}" for e in self.errors)
        elif self.errors[0] is not self:
            only = self.errors[0]
            self.path, self.key, self.value = only.path, only.key, only.value
            self.allowed, self.problem = only.allowed, only.problem
            text = str(only)
        else:
            text = self._format(value)
        super().__init__(text)

    def _format(self, value) -> str:
        parts = [self.path or "<scenario>"]
        if self.key is not None:
            parts.append(self.key if value is _NO_VALUE else f"{self.key} = {_show(value)}")
        text = ": ".join(parts) + f": {self.problem}"
        if self.allowed:
            text += f" (allowed: {self.allowed})"
        return text


def _suggest(word: str, choices: Iterable[str]) -> str:
    close = difflib.get_close_matches(str(word), list(choices), n=1, cutoff=0.6)
    return f"; did you mean {close[0]!r}?" if close else ""


# --------------------------------------------------------------------------------------------
# The scenario model
# --------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class BodySpec:
    """One ``[[body]]`` table. ``position`` is None when the harness places it on the ground."""

    name: str
    shape: Union[Disk, Rod, Box, Polygon]
    mass: float  # kg
    inertia: float | None = None  # kg m², about the centre of mass; None = uniform density
    angle_deg: float = 0.0  # deg, CCW, of the body's x axis
    velocity: tuple[float, float] = (0.0, 0.0)  # m/s, centre of mass
    angular_velocity: float = 0.0  # rad/s, CCW
    position: tuple[float, float] | None = None  # m, centre of mass

    def body(self, on_ground: bool = False) -> Body:
        """The :class:`harness.scene.Body`; without a position it is put on the ground at x = 0."""
        body = Body(
            name=self.name,
            shape=self.shape,
            mass=self.mass,
            position=self.position if self.position is not None else (0.0, 0.0),
            angle=math.radians(self.angle_deg),
            velocity=self.velocity,
            angular_velocity=self.angular_velocity,
            inertia=self.inertia,
        )
        if on_ground and self.position is None:
            body = geometry.place_on_ground(body)
        return body


@dataclass(frozen=True)
class SweepSpec:
    """``[sweep]``: one parameter over a list of values."""

    parameter: str  # "friction", "restitution", "body.<name>.<field>" or "parameters.<key>"
    values: tuple[float, ...]


@dataclass(frozen=True)
class Gate:
    """A gate the runner enforces: the engine departs from ``law`` by at most ``max_departure``."""

    engine: str
    preset: str | None  # None: every preset
    law: str
    max_departure: float  # relative, kinetic-energy norm

    @property
    def source(self) -> str:
        return self.engine if self.preset is None else f"{self.engine}.{self.preset}"


@dataclass(frozen=True)
class Expectation:
    """``[expect]``: per law, one expected value per sweep point (a single one without sweep)."""

    collision_type: Mapping[str, tuple[int, ...]] = field(
        default_factory=lambda: MappingProxyType({}))
    case: tuple[int, ...] | None = None  # Table 1 row, per point
    energy_gain: Mapping[str, tuple[bool, ...]] = field(
        default_factory=lambda: MappingProxyType({}))
    gates: tuple[Gate, ...] = ()


@dataclass(frozen=True)
class MatrixSystem:
    """``system = "matrix"``: an impact given in generalized speeds."""

    mass_matrix: tuple[tuple[float, ...], ...]
    wn: tuple[float, ...]
    wt: tuple[float, ...]
    u: tuple[float, ...]


@dataclass(frozen=True)
class Point:
    """One point of a scenario: ``index`` into the sweep, the swept parameter and its value.

    A scenario without sweep has the single point ``Point(0, None, None)`` whose label is "".
    """

    index: int
    parameter: str | None = None
    value: float | None = None

    @property
    def label(self) -> str:
        return "" if self.parameter is None else f"{self.parameter}={self.value:g}"

    def __str__(self) -> str:
        return self.label


@dataclass(frozen=True)
class Scenario:
    """A scenario file, parsed and checked. Build scenes and problems per :class:`Point`."""

    name: str
    description: str
    tags: tuple[str, ...]
    restitution: float  # e
    friction: float  # μ
    system: str = "bodies"  # one of SYSTEMS
    ground: bool = False
    bodies: tuple[BodySpec, ...] = ()
    parameters: Mapping[str, Any] = field(default_factory=lambda: MappingProxyType({}))
    matrix: MatrixSystem | None = None
    engines: tuple[str, ...] = ()
    laws: tuple[str, ...] = LAWS
    sweep: SweepSpec | None = None
    expect: Expectation = field(default_factory=Expectation)
    engine_settings: Mapping[str, Mapping[str, Any]] = field(
        default_factory=lambda: MappingProxyType({}))
    gap_tolerance: float = DEFAULT_GAP_TOLERANCE  # m
    path: Path | None = None

    # -- points ------------------------------------------------------------------------------
    @property
    def analytic_only(self) -> bool:
        return self.system in ANALYTIC_SYSTEMS

    def point_list(self) -> list[Point]:
        if self.sweep is None:
            return [Point(0)]
        return [Point(i, self.sweep.parameter, value) for i, value in enumerate(self.sweep.values)]

    def points(self) -> list[tuple[Point, Union[Scene, Any]]]:
        """``(point, scene)`` per point; analytic-only systems give the ImpactProblem instead."""
        if self.analytic_only:
            return [(point, self.analytic_problem(point)) for point in self.point_list()]
        return [(point, self.scene(point)) for point in self.point_list()]

    def point(self, which: Union[Point, int, None] = None) -> Point:
        """Resolve ``which`` (a Point, an index, or None for a scenario without sweep)."""
        points = self.point_list()
        if which is None:
            if len(points) != 1:
                raise ScenarioError(
                    f"has a sweep of {len(points)} points: say which point",
                    path=self.path, key="sweep", allowed="a Point or an index")
            return points[0]
        index = which.index if isinstance(which, Point) else int(which)
        if not 0 <= index < len(points):
            raise ScenarioError("point index out of range", path=self.path, key="point",
                                value=index, allowed=f"0 … {len(points) - 1}")
        return points[index]

    def at(self, which: Union[Point, int, None] = None) -> "Scenario":
        """This scenario with the sweep value of ``which`` applied and the sweep removed."""
        point = self.point(which)
        if self.sweep is None:
            return self
        return _apply(replace(self, sweep=None, expect=Expectation()), point.parameter,
                      point.value)

    def restitution_at(self, which=None) -> float:
        return self.at(which).restitution

    def friction_at(self, which=None) -> float:
        return self.at(which).friction

    # -- what the sources get ----------------------------------------------------------------
    def scene(self, which: Union[Point, int, None] = None) -> Scene | None:
        """The :class:`harness.scene.Scene` at a point (None for analytic-only systems)."""
        if self.analytic_only:
            return None
        fixed = self.at(which)
        bodies = tuple(spec.body(on_ground=fixed.ground) for spec in fixed.bodies)
        return Scene(bodies=bodies, restitution=fixed.restitution, friction=fixed.friction,
                     ground=fixed.ground, name=self.name)

    def contact(self, which: Union[Point, int, None] = None,
                tolerance: float = geometry.DEFAULT_TOLERANCE) -> Contact | None:
        scene = self.scene(which)
        return None if scene is None else geometry.scene_contact(scene, tolerance)

    def analytic_problem(self, which: Union[Point, int, None] = None):
        """The ``planar_impact.ImpactProblem`` (mass_matrix, wn, wt, u) at a point."""
        from planar_impact import builders

        fixed = self.at(which)
        if fixed.system == "matrix":
            matrix = fixed.matrix
            return builders.ImpactProblem(
                mass_matrix=np.array(matrix.mass_matrix, dtype=float),
                wn=np.array(matrix.wn, dtype=float), wt=np.array(matrix.wt, dtype=float),
                u=np.array(matrix.u, dtype=float))
        if fixed.system == "two-sled":
            parameters = {**TWO_SLED_DEFAULTS, **fixed.parameters}
            return builders.two_sleds(**parameters)
        scene = fixed.scene()
        contact = geometry.scene_contact(scene)
        return geometry.impact_problem(scene, contact.point, contact.normal)

    def solve(self, which=None, law: str = "poisson"):
        """Solve the analytic problem at a point under one law (``planar_impact.solve``)."""
        fixed = self.at(which)
        return self.analytic_problem(which).solve(mu=fixed.friction, e=fixed.restitution,
                                                  hypothesis=law)

    # -- expectations ------------------------------------------------------------------------
    def expected_collision_type(self, law: str, which=None) -> int | None:
        values = self.expect.collision_type.get(law)
        return None if values is None else values[self.point(which).index]

    def expected_case(self, which=None) -> int | None:
        cases = self.expect.case
        return None if cases is None else cases[self.point(which).index]

    def expected_energy_gain(self, law: str, which=None) -> bool | None:
        values = self.expect.energy_gain.get(law)
        return None if values is None else values[self.point(which).index]

    def gates_for(self, engine: str, preset: str) -> tuple[Gate, ...]:
        return tuple(g for g in self.expect.gates
                     if g.engine == engine and g.preset in (None, preset))

    def __str__(self) -> str:
        return self.name


# --------------------------------------------------------------------------------------------
# Sweeps
# --------------------------------------------------------------------------------------------
def sweep_parameters(scenario: Scenario) -> tuple[str, ...]:
    """The parameter names a sweep may use in ``scenario``."""
    names = ["friction", "restitution"]
    if scenario.system == "two-sled":
        names += [f"parameters.{key}" for key in TWO_SLED_KEYS if key != "u"]
    for spec in scenario.bodies:
        fields = BODY_SWEEP_FIELDS + tuple(
            f for f in SHAPE_FIELDS[spec.shape.kind] if f != "vertices")
        names += [f"body.{spec.name}.{f}" for f in fields]
    return tuple(names)


def _apply(scenario: Scenario, parameter: str, value: float) -> Scenario:
    if parameter in ("friction", "restitution"):
        return replace(scenario, **{parameter: float(value)})
    head, _, rest = parameter.partition(".")
    if head == "parameters":
        return replace(scenario, parameters=MappingProxyType({**scenario.parameters,
                                                              rest: float(value)}))
    name, _, fieldname = rest.partition(".")
    bodies = []
    for spec in scenario.bodies:
        if spec.name == name:
            if fieldname == "velocity.x":
                spec = replace(spec, velocity=(float(value), spec.velocity[1]))
            elif fieldname == "velocity.y":
                spec = replace(spec, velocity=(spec.velocity[0], float(value)))
            elif fieldname in BODY_SWEEP_FIELDS:
                spec = replace(spec, **{fieldname: float(value)})
            else:
                spec = replace(spec, shape=replace(spec.shape, **{fieldname: float(value)}))
        bodies.append(spec)
    return replace(scenario, bodies=tuple(bodies))


# --------------------------------------------------------------------------------------------
# Reading
# --------------------------------------------------------------------------------------------
class _Reader:
    """Reads one parsed TOML document, collecting every error with its dotted key."""

    def __init__(self, path):
        self.path = path
        self.errors: list[ScenarioError] = []

    def error(self, key, problem, value=_NO_VALUE, allowed=None):
        self.errors.append(ScenarioError(problem, path=self.path, key=key, value=value,
                                         allowed=allowed))
        return None

    def keys(self, table: Mapping, prefix: str, allowed: Iterable[str], what: str):
        allowed = tuple(allowed)
        for key in table:
            if key not in allowed:
                dotted = f"{prefix}.{key}" if prefix else key
                self.error(dotted, f"unknown key in {what}{_suggest(key, allowed)}",
                           table[key], ", ".join(allowed))

    def require(self, table: Mapping, key: str, prefix: str) -> bool:
        if key not in table:
            dotted = f"{prefix}.{key}" if prefix else key
            self.error(dotted, "missing required key")
            return False
        return True

    def number(self, table, key, prefix, *, default=_NO_VALUE, low=None, high=None,
               low_open=False, allowed=None):
        dotted = f"{prefix}.{key}" if prefix else key
        if key not in table:
            if default is _NO_VALUE:
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
                                 allowed=allowed)

    def check_number(self, dotted, value, *, low=None, high=None, low_open=False, allowed=None):
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            return self.error(dotted, f"must be a number, not {type(value).__name__}", value,
                              allowed or "a finite number")
        value = float(value)
        if not math.isfinite(value):
            return self.error(dotted, "must be finite", value, allowed or "a finite number")
        if low is not None and (value <= low if low_open else value < low):
            bound = f"> {low:g}" if low_open else f">= {low:g}"
            text = allowed or (f"{bound}" if high is None else f"{bound} and <= {high:g}")
            return self.error(dotted, "out of range", value, text)
        if high is not None and value > high:
            text = allowed or (f"<= {high:g}" if low is None else f"{low:g} … {high:g}")
            return self.error(dotted, "out of range", value, text)
        return value

    def vector(self, table, key, prefix, length, *, default=_NO_VALUE):
        dotted = f"{prefix}.{key}" if prefix else key
        if key not in table:
            if default is _NO_VALUE:
                return self.error(dotted, "missing required key",
                                  allowed=f"a list of {length} numbers")
            return default
        value = table[key]
        if not isinstance(value, list) or (length is not None and len(value) != length):
            size = "" if length is None else f"{length} "
            return self.error(dotted, f"must be a list of {size}numbers", value,
                              f"e.g. {[0.0] * (length or 2)}")
        numbers = [self.check_number(f"{dotted}[{i}]", v) for i, v in enumerate(value)]
        return None if any(n is None for n in numbers) else tuple(numbers)

    def string(self, table, key, prefix, *, default=_NO_VALUE, choices=None, pattern=None,
               allowed=None):
        dotted = f"{prefix}.{key}" if prefix else key
        if key not in table:
            if default is _NO_VALUE:
                return self.error(dotted, "missing required key",
                                  allowed=allowed or (", ".join(choices) if choices else None))
            return default
        value = table[key]
        if not isinstance(value, str):
            return self.error(dotted, f"must be a string, not {type(value).__name__}", value,
                              allowed or (", ".join(choices) if choices else "a string"))
        if choices is not None and value not in choices:
            return self.error(dotted, f"unknown value{_suggest(value, choices)}", value,
                              ", ".join(choices))
        if pattern is not None and not pattern.match(value):
            return self.error(dotted, "not a valid name", value, allowed)
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
            self.error(f"{dotted}", f"unknown name {v!r}{_suggest(v, choices)}", value,
                       ", ".join(choices))
        if bad:
            return None
        if len(set(value)) != len(value):
            return self.error(dotted, "lists a name twice", value, ", ".join(choices))
        return tuple(value)


def _read_shape(reader: _Reader, table, prefix):
    kind = reader.string(table, "shape", prefix, choices=tuple(SHAPE_FIELDS))
    if kind is None:
        return None
    if kind == "disk":
        radius = reader.number(table, "radius", prefix, low=0.0, low_open=True)
        return None if radius is None else Disk(radius)
    if kind == "rod":
        length = reader.number(table, "length", prefix, low=0.0, low_open=True)
        radius = reader.number(table, "radius", prefix, low=0.0, low_open=True)
        return None if None in (length, radius) else Rod(length, radius)
    if kind == "box":
        width = reader.number(table, "width", prefix, low=0.0, low_open=True)
        height = reader.number(table, "height", prefix, low=0.0, low_open=True)
        return None if None in (width, height) else Box(width, height)
    return _read_polygon(reader, table, prefix)


def _read_polygon(reader: _Reader, table, prefix):
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
        xy = [reader.check_number(f"{dotted}[{i}]", c) for c in vertex]
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


def _read_body(reader: _Reader, table, index: int, ground: bool) -> BodySpec | None:
    prefix = f"body[{index}]"
    if not isinstance(table, dict):
        return reader.error(prefix, "must be a table", table, "[[body]] tables")
    name = reader.string(table, "name", prefix, pattern=NAME_PATTERN,
                         allowed="letters, digits, '_', '-' and '.'")
    if name is not None:
        prefix = f"body.{name}"
    kind = table.get("shape")
    shape_keys = SHAPE_FIELDS.get(kind, ()) if isinstance(kind, str) else ()
    reader.keys(table, prefix, BODY_KEYS + shape_keys,
                f"a {kind} body" if shape_keys else "a body")
    shape = _read_shape(reader, table, prefix)
    mass = reader.number(table, "mass", prefix, low=0.0, low_open=True)
    inertia = reader.number(table, "inertia", prefix, default=None, low=0.0, low_open=True)
    angle_deg = reader.number(table, "angle_deg", prefix, default=0.0)
    velocity = reader.vector(table, "velocity", prefix, 2, default=(0.0, 0.0))
    angular_velocity = reader.number(table, "angular_velocity", prefix, default=0.0)
    if ground:
        position = reader.vector(table, "position", prefix, 2, default=None)
    else:
        position = reader.vector(table, "position", prefix, 2)
    values = (name, shape, mass, angle_deg, velocity, angular_velocity)
    if any(v is None for v in values) or (not ground and position is None):
        return None
    return BodySpec(name=name, shape=shape, mass=mass, inertia=inertia, angle_deg=angle_deg,
                    velocity=velocity, angular_velocity=angular_velocity, position=position)


def _read_bodies(reader: _Reader, doc, ground: bool):
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


def _read_matrix(reader: _Reader, doc):
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
            numbers = [reader.check_number(f"mass_matrix[{i}][{j}]", v)
                       for j, v in enumerate(row)]
            rows.append(None if None in numbers else tuple(numbers))
        rows = None if None in rows else tuple(rows)
    size = len(rows) if rows else None
    wn = reader.vector(doc, "wn", "", size)
    wt = reader.vector(doc, "wt", "", size)
    u = reader.vector(doc, "u", "", size)
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


def _read_two_sled(reader: _Reader, doc):
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
    for key in ("m", "l"):
        if key in table:
            values[key] = reader.number(table, key, "parameters", low=0.0, low_open=True)
    for key in ("s", "c", "q3", "q6"):
        if key in table:
            values[key] = reader.number(table, key, "parameters")
    if "u" in table:
        values["u"] = reader.vector(table, "u", "parameters", 4)
    if any(v is None for v in values.values()):
        return None
    return MappingProxyType(values)


def _read_sweep(reader: _Reader, doc, scenario: Scenario) -> SweepSpec | None:
    table = doc["sweep"]
    if not isinstance(table, dict):
        return reader.error("sweep", "must be a table", table, "parameter, values")
    reader.keys(table, "sweep", ("parameter", "values"), "[sweep]")
    allowed = sweep_parameters(scenario)
    parameter = reader.string(table, "parameter", "sweep", choices=allowed)
    if not reader.require(table, "values", "sweep"):
        return None
    raw = table["values"]
    list_help = "a list of numbers or {start, stop, num} (num >= 2)"
    if isinstance(raw, dict):
        reader.keys(raw, "sweep.values", ("start", "stop", "num"), "sweep.values")
        start = reader.number(raw, "start", "sweep.values")
        stop = reader.number(raw, "stop", "sweep.values")
        num = raw.get("num")
        if isinstance(num, bool) or not isinstance(num, int) or num < 2:
            reader.error("sweep.values.num", "must be an integer >= 2", num, list_help)
            return None
        if None in (start, stop):
            return None
        values = tuple(float(v) for v in np.linspace(start, stop, num))
    elif isinstance(raw, list) and raw:
        numbers = [reader.check_number(f"sweep.values[{i}]", v) for i, v in enumerate(raw)]
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


def _read_expect(reader: _Reader, doc, scenario: Scenario) -> Expectation:
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


def _read_gates(reader: _Reader, raw, scenario: Scenario) -> list[Gate]:
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
                         *(f"{e}.{p}" for e in scenario.engines for p in PRESETS)])
    gates = []
    for key, engine, preset, value in entries:
        dotted = f"expect.gate.{key}"
        if engine not in scenario.engines or (preset is not None and preset not in PRESETS):
            reader.error(dotted, f"unknown engine or preset{_suggest(key, sources.split(', '))}",
                         value, sources)
            continue
        if not isinstance(value, dict):
            reader.error(dotted, "must be a table", value, "{ law = ..., max_departure = ... }")
            continue
        reader.keys(value, dotted, GATE_KEYS, "a gate")
        law = reader.string(value, "law", dotted, choices=LAWS)
        limit = reader.number(value, "max_departure", dotted, low=0.0, low_open=True)
        if law is not None and limit is not None:
            gates.append(Gate(engine=engine, preset=preset, law=law, max_departure=limit))
    return gates


def _read_engine_settings(reader: _Reader, raw, scenario: Scenario):
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
        _check_engine_settings(reader, engine, table)
        settings[engine] = MappingProxyType(dict(table))
    return MappingProxyType(settings)


def _check_engine_settings(reader: _Reader, engine: str, table: Mapping[str, Any]) -> None:
    """Check override keys and values with the engine's adapter, when it can be imported."""
    try:
        from harness.engines import load_engine

        adapter = load_engine(engine)
    except Exception:  # not installed, or no adapter yet: the runner reports it
        return
    docs = getattr(adapter, "setting_docs", {})
    known = tuple(sorted(docs))
    for key, value in table.items():
        if known and key not in docs:
            reader.error(f"engine_settings.{engine}.{key}",
                         f"unknown {engine} setting{_suggest(key, known)}", value,
                         ", ".join(known))
            return
    for preset in PRESETS:
        try:
            adapter.settings(preset, dict(table))
        except ValueError as error:
            reader.error(f"engine_settings.{engine}", f"rejected by {engine}: {error}",
                         dict(table), f"values the {engine} adapter accepts")
            return


def _check_points(reader: _Reader, scenario: Scenario) -> None:
    """Every point must be a touching, approaching, one-point contact with e, μ in range."""
    for point in scenario.point_list():
        where = f" at sweep point {point.label}" if point.label else ""
        fixed = scenario.at(point)
        if not 0.0 <= fixed.restitution <= 1.0:
            reader.error("sweep.values", f"restitution out of range{where}", fixed.restitution,
                         "0 … 1")
            continue
        if not fixed.friction >= 0.0:
            reader.error("sweep.values", f"friction out of range{where}", fixed.friction, ">= 0")
            continue
        if fixed.system == "bodies":
            _check_bodies(reader, fixed, where)
        else:
            _check_analytic(reader, scenario, point, where)


def _check_bodies(reader: _Reader, fixed: Scenario, where: str) -> None:
    for spec in fixed.bodies:
        for key, value in (("mass", spec.mass), ("inertia", spec.inertia)):
            if value is not None and not value > 0.0:
                reader.error(f"body.{spec.name}.{key}", f"must be positive{where}", value, "> 0")
                return
        for key in SHAPE_FIELDS[spec.shape.kind]:
            value = getattr(spec.shape, key, None)
            if isinstance(value, float) and not value > 0.0:
                reader.error(f"body.{spec.name}.{key}", f"must be positive{where}", value, "> 0")
                return
    scene = fixed.scene()
    contact = geometry.scene_contact(scene, tolerance=ONE_POINT_TOLERANCE)
    exact = geometry.scene_contact(scene)
    placed = [s for s in fixed.bodies if s.position is not None]
    position_key = (f"body.{placed[-1].name}.position" if placed else "body")
    positions = [list(s.position) for s in placed]
    if abs(exact.gap) > fixed.gap_tolerance:
        state = "apart" if exact.gap > 0 else "overlapping"
        reader.error(position_key, f"bodies must touch{where}: measured gap {exact.gap:.6g} m "
                     f"({state})", positions if len(positions) > 1 else positions[0],
                     f"|gap| <= gap_tolerance = {fixed.gap_tolerance:g} m")
        return
    if contact.point_count > 1:
        angles = {s.name: s.angle_deg for s in fixed.bodies}
        reader.error(f"body.{fixed.bodies[-1].name}.angle_deg",
                     f"{contact.point_count} contact points within {ONE_POINT_TOLERANCE:g} m"
                     f"{where} (a face lies flat on a face): outside one-point impact theory",
                     angles, "a pose with a single closest point: turn the body")
        return
    vn, _ = geometry.contact_velocity(scene, exact)
    if not vn < 0.0:
        reader.error(f"body.{fixed.bodies[-1].name}.velocity",
                     f"the bodies do not approach{where}: contact normal velocity v_n = "
                     f"{vn:.6g} m/s", [list(s.velocity) for s in fixed.bodies],
                     "velocities giving v_n < 0 along the normal "
                     f"{np.round(exact.normal, 6).tolist()} (from A into B)")


def _check_analytic(reader: _Reader, scenario: Scenario, point: Point, where: str) -> None:
    try:
        problem = scenario.analytic_problem(point)
    except ImportError:  # pragma: no cover - planar_impact is part of this project
        return
    except (TypeError, ValueError) as error:
        reader.error("parameters" if scenario.system == "two-sled" else "mass_matrix",
                     f"cannot build the problem{where}: {error}")
        return
    vn = float(np.asarray(problem.wn) @ np.asarray(problem.u))
    if not vn < 0.0:
        key = "parameters.u" if scenario.system == "two-sled" else "u"
        reader.error(key, f"no approach{where}: v_n = wn·u = {vn:.6g}",
                     list(np.asarray(problem.u)), "speeds giving wn·u < 0")


def parse_scenario(doc: Mapping[str, Any], path=None) -> Scenario:
    """Check a parsed TOML document and build its :class:`Scenario` (raises ScenarioError)."""
    reader = _Reader(path)
    system = reader.string(doc, "system", "", default="bodies", choices=SYSTEMS)
    if system is None:
        raise ScenarioError(errors=reader.errors)
    reader.keys(doc, "", TOP_KEYS[system],
                "a scenario file" if system == "bodies" else f'a system = "{system}" file')
    name = reader.string(doc, "name", "", pattern=NAME_PATTERN,
                         allowed="letters, digits, '_', '-' and '.'")
    description = reader.string(doc, "description", "", default="")
    tags = _read_tags(reader, doc)
    restitution = reader.number(doc, "restitution", "", low=0.0, high=1.0)
    friction = reader.number(doc, "friction", "", low=0.0)
    laws = reader.names(doc, "laws", "", LAWS, default=LAWS)
    gap_tolerance = reader.number(doc, "gap_tolerance", "", default=DEFAULT_GAP_TOLERANCE,
                                  low=0.0, low_open=True)

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
    if reader.errors or any(value is None for value in required):
        raise ScenarioError(errors=reader.errors)

    scenario = Scenario(name=name, description=description, tags=tags, restitution=restitution,
                        friction=friction, system=system, ground=ground, bodies=bodies,
                        parameters=parameters, matrix=matrix, engines=engines, laws=laws,
                        gap_tolerance=gap_tolerance,
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
    if not reader.errors:
        _check_points(reader, scenario)
    if reader.errors:
        raise ScenarioError(errors=reader.errors)
    return scenario


def _read_tags(reader: _Reader, doc) -> tuple[str, ...] | None:
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
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as error:
        raise ScenarioError(f"cannot read the file: {error.strerror or error}", path=path,
                            allowed="a readable .toml file") from None
    try:
        doc = tomllib.loads(text)
    except tomllib.TOMLDecodeError as error:
        raise ScenarioError(f"not valid TOML: {error}", path=path,
                            allowed="TOML 1.0 (https://toml.io)") from None
    return parse_scenario(doc, path)


def scenario_files(paths_or_dir=None) -> list[Path]:
    """The ``.toml`` files named by ``paths_or_dir`` (files or directories; default: scenarios/)."""
    if paths_or_dir is None:
        paths_or_dir = [SCENARIO_DIR]
    elif isinstance(paths_or_dir, (str, Path)):
        paths_or_dir = [paths_or_dir]
    files = []
    for entry in paths_or_dir:
        entry = Path(entry)
        if entry.is_dir():
            files += sorted(entry.glob("*.toml"))
        else:
            files.append(entry)
    return files


def parse_tags(tags) -> tuple[str, ...] | None:
    """``"quick,slip-reversal"`` or an iterable of names -> a tuple; None/empty -> None."""
    if tags is None:
        return None
    if isinstance(tags, str):
        tags = tags.split(",")
    tags = tuple(t.strip() for t in tags if t and t.strip())
    return tags or None


def load_scenarios(paths_or_dir=None, tags=None) -> list[Scenario]:
    """Load every scenario under ``paths_or_dir`` (default: ``scenarios/``).

    ``tags`` (a comma-separated string or an iterable) keeps the scenarios having any of
    them; ``"all"`` keeps everything. Every file is read before any error is raised, and
    the error lists every bad file. Unknown tags and duplicate names are errors too.
    """
    scenarios, errors = [], []
    for path in scenario_files(paths_or_dir):
        try:
            scenarios.append(load_scenario(path))
        except ScenarioError as error:
            errors += error.errors
    seen: dict[str, Scenario] = {}
    for scenario in scenarios:
        if scenario.name in seen:
            errors.append(ScenarioError(f"the name is already used by {seen[scenario.name].path}",
                                        path=scenario.path, key="name", value=scenario.name,
                                        allowed="a name unique in the library"))
        seen[scenario.name] = scenario
    if errors:
        raise ScenarioError(errors=errors)
    wanted = parse_tags(tags)
    if wanted is None or "all" in wanted:
        return scenarios
    known = tag_sets(scenarios)
    for tag in wanted:
        if tag not in known:
            raise ScenarioError(f"no scenario has this tag{_suggest(tag, known)}", key="tags",
                                value=tag, allowed=", ".join(sorted(known)))
    return [s for s in scenarios if set(s.tags) & set(wanted)]


def tag_sets(scenarios: Iterable[Scenario]) -> dict[str, tuple[str, ...]]:
    """Tag -> scenario names, with the derived set ``"all"`` (every scenario)."""
    scenarios = list(scenarios)
    sets: dict[str, list[str]] = {"all": [s.name for s in scenarios]}
    for scenario in scenarios:
        for tag in scenario.tags:
            sets.setdefault(tag, []).append(scenario.name)
    return {tag: tuple(names) for tag, names in sets.items()}


# --------------------------------------------------------------------------------------------
# Checking the expectations against the solver
# --------------------------------------------------------------------------------------------
def check_expectations(scenario: Scenario) -> list[str]:
    """Compare ``[expect]`` with ``planar_impact``; one message per mismatch (empty: all agree)."""
    import planar_impact

    problems = []
    where = scenario.path or scenario.name
    for point in scenario.point_list():
        at = f" at {point.label}" if point.label else ""
        fixed = scenario.at(point)
        problem = scenario.analytic_problem(point)
        wanted_laws = set(scenario.expect.collision_type) | set(scenario.expect.energy_gain)
        if scenario.expect.case is not None:
            wanted_laws.add("poisson")
        results = {}
        for law in sorted(wanted_laws):
            try:
                results[law] = problem.solve(mu=fixed.friction, e=fixed.restitution,
                                             hypothesis=law)
            except (ValueError, planar_impact.ImpactInputError) as error:
                problems.append(f"{where}: {law}{at}: the solver refused: {error}")
        for law, result in results.items():
            expected = scenario.expected_collision_type(law, point)
            if expected is not None and result.collision_type != expected:
                problems.append(f"{where}: expect.collision_type.{law}{at} = {expected}, but "
                                f"the solver gives {result.collision_type}")
            gain = scenario.expected_energy_gain(law, point)
            if gain is not None and (result.energy_change > 0.0) != gain:
                problems.append(f"{where}: expect.energy_gain.{law}{at} = {str(gain).lower()}, "
                                f"but the energy change is {result.energy_change:.6g} J")
        case = scenario.expected_case(point)
        if case is not None and "poisson" in results and results["poisson"].case != case:
            problems.append(f"{where}: expect.case{at} = {case}, but the solver gives "
                            f"{results['poisson'].case}")
    return problems
