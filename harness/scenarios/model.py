"""The scenario model: frozen dataclasses for a scenario file and its sweep points.

A :class:`Scenario` builds, per :class:`Point`, the :class:`harness.scene.Scene` the engines
get and the ``planar_impact.ImpactProblem`` the laws get.
"""

from __future__ import annotations

import copy
import hashlib
import math
from dataclasses import dataclass, field, fields, replace
from functools import cached_property
from pathlib import Path
from types import MappingProxyType
from typing import Any, Mapping, Union

import numpy as np

from harness.engines import engine_names, source_label
from harness.scenarios.errors import ScenarioError
from harness.scenarios.schema import (
    ANALYTIC_SYSTEMS,
    BODY_SWEEP_FIELDS,
    DEFAULT_GAP_TOLERANCE,
    LAWS,
    SHAPE_FIELDS,
    TWO_SLED_DEFAULTS,
    TWO_SLED_KEYS,
)
from harness.scene import Body, Box, Contact, Disk, Ellipse, Polygon, Rod, Scene, geometry
from harness.store.identity import canonical_json
from planar_impact import builders

#: Where a :class:`Scenario` keeps its scenes by point index (:meth:`Scenario.scene`).
_KEPT_SCENES = "_scenes"


@dataclass(frozen=True)
class BodySpec:
    """One ``[[body]]`` table. ``position`` is None when the harness places it on the ground."""

    name: str
    shape: Union[Disk, Rod, Box, Polygon, Ellipse]
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
        if on_ground:  # an ellipse's stand-in polygon: a vertex on its first contact point
            body = geometry.place_stand_in(body)
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
    preset: str | None  # a preset role (never an engine's name for it); None: every preset
    law: str
    max_departure: float  # relative, kinetic-energy norm

    @property
    def source(self) -> str:
        """``"pymunk"``, ``"pymunk.accurate"``, ``"mujoco.matched-bounce"``: as users write it."""
        return source_label(self.engine, self.preset)


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
    # True: the file knows a second feature strikes within the impact (validate allows it)
    expect_sequence: bool = False
    # "simultaneous": the file declares a face lying flat (several contact points at once)
    contacts: str = "one"
    path: Path | None = None

    # -- identity ----------------------------------------------------------------------------
    @cached_property
    def definition_digest(self) -> str:
        """sha256 of every field but the file's ``path`` spelled as canonical JSON
        (:func:`harness.store.identity.canonical_json`): what a scenario's records depend on (the
        runner's cache key of them). Spelled once per scenario object and kept with it (in the
        store of passed checks too, :meth:`located` copies it): a warm run of a large library
        spent a tenth of its time spelling definitions. ``TypeError`` for a value without a
        canonical spelling."""
        definition = {f.name: getattr(self, f.name) for f in fields(self) if f.name != "path"}
        return hashlib.sha256(canonical_json(definition).encode()).hexdigest()

    def located(self, path: Path | None) -> "Scenario":
        """This scenario read from the file ``path``: a copy with its path set, keeping what
        was computed of it (:attr:`definition_digest`, which the path does not change)."""
        located = copy.copy(self)
        object.__setattr__(located, "path", path)  # frozen; path is in no cached value
        return located

    # -- points ------------------------------------------------------------------------------
    @property
    def analytic_only(self) -> bool:
        return self.system in ANALYTIC_SYSTEMS

    def engines_among(self, wanted) -> list[str]:
        """The engines of ``wanted`` (in its order) this scenario runs: those its ``engines``
        allow (every engine when it names none); none for an analytic-only system."""
        if self.analytic_only:
            return []
        allowed = self.engines or engine_names()  # engines registered at run time too
        return [name for name in wanted if name in allowed]

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
        return apply_sweep_value(replace(self, sweep=None, expect=Expectation()), point.parameter,
                      point.value)

    def restitution_at(self, which=None) -> float:
        return self.at(which).restitution

    def friction_at(self, which=None) -> float:
        return self.at(which).friction

    # -- what the sources get ----------------------------------------------------------------
    def scene(self, which: Union[Point, int, None] = None) -> Scene | None:
        """The :class:`harness.scene.Scene` at a point (None for analytic-only systems).

        Built once per point and kept with this scenario object, outside its fields and its
        pickles (the scene is immutable): the checks, the run's plan, its references and its
        records each ask for every point's scene, several times over.
        """
        if self.analytic_only:
            return None
        point = self.point(which)
        scenes = self.__dict__.get(_KEPT_SCENES)
        if scenes is None:
            scenes = {}
            object.__setattr__(self, _KEPT_SCENES, scenes)  # frozen: not a field
        scene = scenes.get(point.index)
        if scene is None:
            fixed = self.at(point)
            bodies = tuple(spec.body(on_ground=fixed.ground) for spec in fixed.bodies)
            scene = scenes[point.index] = Scene(
                bodies=bodies, restitution=fixed.restitution, friction=fixed.friction,
                ground=fixed.ground, name=self.name)
        return scene

    def kept_scenes(self) -> dict:
        """The scenes :meth:`scene` has built and kept so far, by point index (to send them
        with a pickle of this scenario, which leaves them out)."""
        return dict(self.__dict__.get(_KEPT_SCENES) or {})

    def keep_scenes(self, scenes: Mapping[int, Scene]) -> None:
        """Keep ``scenes`` (by point index, as :meth:`kept_scenes` gives them: built by this
        scenario's :meth:`scene` elsewhere, in a worker) as if built here."""
        object.__setattr__(self, _KEPT_SCENES, dict(scenes))  # frozen: not a field

    def __getstate__(self) -> dict:
        """Pickled and copied without the scenes :meth:`scene` kept (built again on demand)."""
        state = dict(self.__dict__)
        state.pop(_KEPT_SCENES, None)
        return state

    def contact(self, which: Union[Point, int, None] = None,
                tolerance: float = geometry.DEFAULT_TOLERANCE) -> Contact | None:
        scene = self.scene(which)
        return None if scene is None else geometry.scene_contact(scene, tolerance)

    def analytic_problem(self, which: Union[Point, int, None] = None):
        """The ``planar_impact.ImpactProblem`` (mass_matrix, wn, wt, u) at a point."""
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
        scene = self.scene(which)  # fixed.scene(): kept with this scenario, not with fixed
        contact = geometry.scene_contact(scene)
        return geometry.impact_problem(scene, contact.point, contact.normal)

    def solve(self, which=None, law: str = "poisson"):
        """Solve the analytic problem at a point under one law (``planar_impact.solve``)."""
        fixed = self.at(which)
        return self.analytic_problem(which).solve(mu=fixed.friction, e=fixed.restitution,
                                                  law=law)

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


def apply_sweep_value(scenario: Scenario, parameter: str, value: float) -> Scenario:
    """``scenario`` with the sweep ``parameter`` set to ``value``."""
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
