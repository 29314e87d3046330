"""Population files: TOML declaring a family of scenes and how each parameter is distributed.

Format (docs/populations.md has the whole of it)::

    name = "rod-ground"
    description = "A thin rod landing on one end."
    [ground]                                   # one body on the ground; else two [[body]]
    restitution = { uniform = [0.0, 1.0] }
    friction = { uniform = [0.0, 1.2] }
    [approach]                                 # velocity of B's centre of mass relative to A
    speed = { log_uniform = [0.3, 3.0] }       # m/s
    direction_deg = { uniform = [-75.0, 75.0] }  # from straight in (−n) towards +t
    [[body]]
    name = "rod"
    shape = "rod"
    length = { uniform = [0.3, 2.0] }
    radius = 0.005
    mass = 1.0
    angle_deg = { uniform = [2.0, 88.0] }
    angular_velocity = { uniform = [-3.0, 3.0] }

Every numeric parameter is a *distribution*: a plain number (fixed), or a one-key table
``{ uniform = [low, high] }``, ``{ log_uniform = [low, high] }`` or ``{ choice = [a, b, …] }``.
A file is read into the frozen :class:`Population`; every problem is collected and raised as
one :class:`harness.scenarios.errors.ScenarioError` naming the file, the key, the value and
what is allowed (the scenario files' error style, through their
:class:`harness.scenarios.table_reader.TableReader`).
"""

from __future__ import annotations

import math
import tomllib
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from harness import inputs
from harness.scenarios.errors import NO_VALUE, OptionError, ScenarioError, suggest
from harness.scenarios.schema import BOUNDS, NAME_ALLOWED, NAME_PATTERN, TAG_PATTERN
from harness.scenarios.table_reader import TableReader

#: The shipped populations, beside ``scenarios/`` at the repository root.
POPULATION_DIR = Path(__file__).resolve().parent.parent.parent / "populations"

KINDS = ("uniform", "log_uniform", "choice")
SHAPES = ("disk", "rod", "box", "polygon")
#: Shape keys per shape; a polygon is regular, given by its number of sides and the radius
#: of the circle through its vertices.
SHAPE_KEYS = {
    "disk": ("radius",),
    "rod": ("length", "radius"),
    "box": ("width", "height"),
    "polygon": ("sides", "circumradius"),
}
#: The keys of every shape: checked against a body's shape only when the shape is known.
ANY_SHAPE_KEYS = tuple(dict.fromkeys(key for keys in SHAPE_KEYS.values() for key in keys))
BODY_KEYS = ("name", "shape", "mass", "angle_deg", "angular_velocity")
TOP_KEYS = ("name", "description", "tags", "ground", "restitution", "friction", "mass_ratio",
            "approach", "placement", "body", "max_attempts")
APPROACH_KEYS = ("speed", "direction_deg")
PLACEMENT_KEYS = ("direction_deg",)
#: Draws allowed per accepted sample before the population is declared unusable.
DEFAULT_MAX_ATTEMPTS = 200


@dataclass(frozen=True)
class Distribution:
    """One parameter's distribution: ``kind`` is ``fixed``, ``uniform``, ``log_uniform`` or
    ``choice``; ``values`` the number, the bounds ``(low, high)`` or the choices."""

    kind: str
    values: tuple[float, ...]

    def draw(self, rng) -> float:
        """One value from ``rng`` (a ``numpy.random.Generator``); fixed values draw nothing."""
        if self.kind == "fixed":
            return self.values[0]
        if self.kind == "uniform":
            return float(rng.uniform(self.values[0], self.values[1]))
        if self.kind == "log_uniform":
            low, high = math.log(self.values[0]), math.log(self.values[1])
            return float(math.exp(rng.uniform(low, high)))
        return self.values[int(rng.integers(len(self.values)))]

    @property
    def low(self) -> float:
        return min(self.values)

    @property
    def high(self) -> float:
        return max(self.values)


@dataclass(frozen=True)
class BodyDistribution:
    """One ``[[body]]``: its shape kind and every parameter's distribution."""

    name: str
    shape: str
    shape_parameters: tuple[tuple[str, Distribution], ...]  # in SHAPE_KEYS order
    mass: Distribution | None  # kg; None for body B when the population gives mass_ratio
    angle_deg: Distribution
    angular_velocity: Distribution  # rad/s, CCW


@dataclass(frozen=True)
class Population:
    """A family of impacts, read from one population file."""

    name: str
    description: str
    tags: tuple[str, ...]
    ground: bool
    bodies: tuple[BodyDistribution, ...]  # 1 with ground, else 2 (A then B)
    restitution: Distribution
    friction: Distribution
    speed: Distribution  # m/s, of B's centre of mass relative to A's
    direction_deg: Distribution  # velocity direction from −n towards +t
    mass_ratio: Distribution | None = None  # m_B / m_A, two-body populations only
    placement_deg: Distribution | None = None  # direction from A's centre to B's, two bodies
    max_attempts: int = DEFAULT_MAX_ATTEMPTS
    path: str | None = None


# ---------------------------------------------------------------------------------- reading
def _distribution(reader: TableReader, table: Mapping, key: str, prefix: str, *,
                  low: float | None = None, high: float | None = None, low_open: bool = False,
                  integer: bool = False, default: Any = NO_VALUE,
                  field: str | None = None) -> Distribution | None:
    """The distribution of ``key``: each number within ``low`` … ``high`` and within the
    magnitudes a scenario file allows for ``field`` (:data:`MAGNITUDES`), so that a
    population never samples a scene its scenario file would refuse."""
    dotted = f"{prefix}.{key}" if prefix else key
    allowed_bounds = _bounds_text(low, high, low_open)
    allowed = (f"a number{allowed_bounds} or one of {{ uniform = [low, high] }}, "
               f"{{ log_uniform = [low, high] }}, {{ choice = [a, b, ...] }}")
    if integer:
        allowed = f"an integer{allowed_bounds} or {{ choice = [3, 4, ...] }}"
    if key not in table:
        if default is NO_VALUE:
            return reader.error(dotted, "missing required key", allowed=allowed)
        return default
    raw = table[key]

    def number(where: str, value) -> float | None:
        if integer and (isinstance(value, bool) or not isinstance(value, int)):
            return reader.error(where, "must be an integer", value, allowed)
        return reader.check_number(where, value, low=low, high=high, low_open=low_open,
                                   field=field)

    if not isinstance(raw, dict):
        value = number(dotted, raw)
        return None if value is None else Distribution("fixed", (value,))
    kinds = ("choice",) if integer else KINDS
    if len(raw) != 1 or next(iter(raw)) not in kinds:
        name = next(iter(raw), "")
        return reader.error(dotted, f"unknown distribution{suggest(name, kinds)}", raw, allowed)
    kind, values = next(iter(raw.items()))
    where = f"{dotted}.{kind}"
    if not isinstance(values, list) or not values:
        return reader.error(where, "must be a non-empty list", values, allowed)
    numbers = [number(f"{where}[{i}]", v) for i, v in enumerate(values)]
    if any(n is None for n in numbers):
        return None
    if kind in ("uniform", "log_uniform"):
        if len(numbers) != 2 or not numbers[0] < numbers[1]:
            return reader.error(where, "needs [low, high] with low < high", values,
                                "two numbers, low < high")
        if kind == "log_uniform" and not numbers[0] > 0.0:
            return reader.error(where, "log_uniform needs positive bounds", values, "0 < low")
    if integer:
        numbers = [int(n) for n in numbers]
    return Distribution(kind, tuple(numbers))


def _bounds_text(low, high, low_open) -> str:
    parts = []
    if low is not None:
        parts.append(f"> {low:g}" if low_open else f">= {low:g}")
    if high is not None:
        parts.append(f"<= {high:g}")
    return (" " + " and ".join(parts)) if parts else ""


def _read_body(reader: TableReader, table, index: int, *, mass_from_ratio: bool):
    prefix = f"body[{index}]"
    if not isinstance(table, dict):
        return reader.error(prefix, "must be a table", table, "[[body]] tables")
    name = reader.string(table, "name", prefix, pattern=NAME_PATTERN,
                         allowed=NAME_ALLOWED)
    if name is not None:
        prefix = f"body.{name}"
    shape = reader.string(table, "shape", prefix, choices=SHAPES)
    shape_keys = SHAPE_KEYS.get(shape, ())
    if shape_keys:
        reader.keys(table, prefix, BODY_KEYS + shape_keys, f"a {shape} body")
    else:  # a bad or missing shape is the one error: another shape's keys may be right
        reader.keys(table, prefix, BODY_KEYS + ANY_SHAPE_KEYS, "a body")
    parameters = []
    for key in shape_keys:
        if key == "sides":  # bounded as every knob is (harness/bounds.py)
            low, high = BOUNDS["sides"].range()
            value = _distribution(reader, table, key, prefix, low=low, high=high, integer=True)
        else:
            value = _distribution(reader, table, key, prefix, low=0.0, low_open=True,
                                  field="length")
        parameters.append((key, value))
    if mass_from_ratio:
        if "mass" in table:
            reader.error(f"{prefix}.mass", "body B's mass comes from mass_ratio", table["mass"],
                         "no mass for the second body when mass_ratio is given")
        mass = None
    else:
        mass = _distribution(reader, table, "mass", prefix, low=0.0, low_open=True,
                             field="mass")
    angle = _distribution(reader, table, "angle_deg", prefix, default=Distribution("fixed", (0.0,)),
                          field="angle_deg")
    spin = _distribution(reader, table, "angular_velocity", prefix,
                         default=Distribution("fixed", (0.0,)), field="angular_velocity")
    if name is None or shape is None or any(v is None for _, v in parameters):
        return None
    if (mass is None and not mass_from_ratio) or angle is None or spin is None:
        return None
    return BodyDistribution(name=name, shape=shape, shape_parameters=tuple(parameters),
                            mass=mass, angle_deg=angle, angular_velocity=spin)


def _table(reader: TableReader, doc, key: str, keys: tuple[str, ...]) -> dict | None:
    if key not in doc:
        reader.error(key, "missing required table", allowed=f"[{key}] with {', '.join(keys)}")
        return None
    table = doc[key]
    if not isinstance(table, dict):
        return reader.error(key, "must be a table", table, f"[{key}] with {', '.join(keys)}")
    reader.keys(table, key, keys, f"[{key}]")
    return table


def parse_population(doc: Mapping[str, Any], path=None) -> Population:
    """A :class:`Population` from a parsed TOML document; raises :class:`ScenarioError`."""
    reader = TableReader(path)
    reader.keys(doc, "", TOP_KEYS, "a population file")
    name = reader.string(doc, "name", "", pattern=NAME_PATTERN,
                         allowed=NAME_ALLOWED)
    description = reader.line_of_text(doc, "description", "", default="")
    tags = doc.get("tags", [])
    if not isinstance(tags, list) or not all(isinstance(t, str) and TAG_PATTERN.match(t)
                                             for t in tags):
        reader.error("tags", "must be a list of tags", tags,
                     "lower-case letters, digits and '-'")
        tags = []
    ground = "ground" in doc
    if ground and doc["ground"] != {}:
        reader.error("ground", "takes no keys", doc["ground"], "an empty [ground] table")
    restitution = _distribution(reader, doc, "restitution", "", low=0.0, high=1.0,
                                field="restitution")
    friction = _distribution(reader, doc, "friction", "", low=0.0, field="friction")
    approach = _table(reader, doc, "approach", APPROACH_KEYS) or {}
    speed = _distribution(reader, approach, "speed", "approach", low=0.0, low_open=True,
                          field="speed")
    direction = _distribution(reader, approach, "direction_deg", "approach", low=-90.0,
                              high=90.0)
    if direction is not None and (direction.low <= -90.0 or direction.high >= 90.0):
        reader.error("approach.direction_deg", "the centre of mass must move towards the partner",
                     list(direction.values), "-90 < direction_deg < 90")
    mass_ratio = placement = None
    if ground:
        for key in ("mass_ratio", "placement"):
            if key in doc:
                reader.error(key, "only for two free bodies (no [ground])", doc[key],
                             "remove it, or remove [ground]")
    else:
        mass_ratio = _distribution(reader, doc, "mass_ratio", "", low=0.0, low_open=True,
                                   default=None, field="mass_ratio")
        placement_table = _table(reader, doc, "placement", PLACEMENT_KEYS) or {}
        placement = _distribution(reader, placement_table, "direction_deg", "placement",
                                  field="angle_deg")
    attempts = BOUNDS["max_attempts"]  # bounded as every knob is (harness/bounds.py)
    max_attempts = reader.number(doc, "max_attempts", "", default=DEFAULT_MAX_ATTEMPTS,
                                 low=attempts.range()[0], high=attempts.range()[1],
                                 allowed=attempts.allowed())
    if max_attempts is not None and not float(max_attempts).is_integer():
        reader.error("max_attempts", "must be an integer", max_attempts, attempts.allowed())
    raw_bodies = doc.get("body")
    expected = 1 if ground else 2
    bodies = None
    if not isinstance(raw_bodies, list) or len(raw_bodies) != expected:
        count = len(raw_bodies) if isinstance(raw_bodies, list) else (0 if raw_bodies is None
                                                                      else 1)
        what = ("with [ground]: exactly one [[body]]" if ground
                else "without [ground]: exactly two [[body]] tables (A, then B)")
        reader.error("body", f"{count} bodies given", f"<{count} tables>", what)
    else:
        bodies = [_read_body(reader, table, i, mass_from_ratio=(i == 1 and mass_ratio is not None))
                  for i, table in enumerate(raw_bodies)]
        if len(bodies) == 2 and None not in bodies and bodies[0].name == bodies[1].name:
            reader.error("body[1].name", "two bodies share a name", bodies[1].name,
                         "distinct names")
    if reader.errors:
        raise ScenarioError(errors=reader.errors)
    return Population(name=name, description=description, tags=tuple(tags), ground=ground,
                      bodies=tuple(bodies), restitution=restitution, friction=friction,
                      speed=speed, direction_deg=direction, mass_ratio=mass_ratio,
                      placement_deg=placement, max_attempts=int(max_attempts),
                      path=None if path is None else str(path))


def load_population(path) -> Population:
    """Read and check one population file."""
    path = Path(path)
    try:
        doc = inputs.parse_toml(inputs.read_text(path))
    except OSError as error:
        raise ScenarioError(f"cannot read the file: {error.strerror or error}", path=path) \
            from None
    except tomllib.TOMLDecodeError as error:
        raise ScenarioError(f"not valid TOML: {error}", path=path) from None
    except inputs.InputError as error:  # not a regular file, too large, not UTF-8, too deep
        problem, _, allowed = str(error).partition("; allowed: ")
        raise ScenarioError(problem, path=path, allowed=allowed or None) from None
    return parse_population(doc, path)


def population_files(directory=POPULATION_DIR) -> list[Path]:
    """The ``*.toml`` files of ``directory``, sorted by name."""
    return sorted(Path(directory).glob("*.toml"))


def resolve_populations(names_or_paths=()) -> list[Population]:
    """Populations by file path or by name (a file of ``populations/``); all when empty."""
    if not names_or_paths:
        return [load_population(path) for path in population_files()]
    shipped = {path.stem: path for path in population_files()}
    chosen = []
    for item in names_or_paths:
        path = Path(item)
        if path.suffix == ".toml" or path.exists():
            chosen.append(load_population(path))
        elif item in shipped:
            chosen.append(load_population(shipped[item]))
        else:
            raise OptionError(f"no population file{suggest(item, shipped)}", key="POPULATION",
                              value=item, allowed=", ".join(sorted(shipped)) + " or a path")
    names = [population.name for population in chosen]
    duplicated = sorted({name for name in names if names.count(name) > 1})
    if duplicated:
        raise ScenarioError("two populations share a name", key="name", value=duplicated,
                            allowed="distinct population names")
    return chosen
