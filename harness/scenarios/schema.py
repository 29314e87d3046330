"""The scenario file schema: the names, keys and limits every scenario module shares.

Law and preset names come from their one home (``planar_impact.LAWS``, the engine
registry), the two-sled defaults from ``planar_impact.builders.two_sleds``. Engine names are
not fixed here: a file's are checked against the registry when it is read.
"""

from __future__ import annotations

import inspect
import re
from pathlib import Path

import planar_impact

# The bounds of the work one file may ask for and of every knob, one table for every way a
# value is set (harness/bounds.py): re-exported, the scenario modules read them here.
from harness.bounds import BOUNDS, LIMITS, limit  # noqa: F401
from harness.engines import PRESET_ROLES
from harness.laws import REGISTRY as LAW_REGISTRY
from planar_impact import builders

SCENARIO_DIR = Path(__file__).resolve().parent.parent.parent / "scenarios"
PROJECT_DIR = SCENARIO_DIR.parent


def recorded_path(path: Path | str) -> str:
    """A path (a scenario file, the result cache) as results record it: relative to the
    project for one inside it (a committed report names no machine's directory), absolute
    otherwise."""
    resolved = Path(path).resolve()
    if resolved.is_relative_to(PROJECT_DIR):
        return resolved.relative_to(PROJECT_DIR).as_posix()
    return str(resolved)


def recorded_location(text: str) -> Path:
    """The file a results file's recorded path names (:func:`recorded_path`'s inverse)."""
    path = Path(text)
    return path if path.is_absolute() else PROJECT_DIR / path

#: Impact laws, by the names of ``planar_impact.LAWS``.
LAWS: tuple[str, ...] = planar_impact.LAWS
#: Collision types each law reports (the law registry's, harness/laws.py): Poisson/Stronge
#: 1–5, Newton laws 1 stick, 2 reverse sliding, 3 forward sliding.
LAW_TYPES = {entry.name: entry.collision_types for entry in LAW_REGISTRY}
# No ENGINES here: the engines a file may name are the registry's at the time it is read
# (harness.engines.engine_names), those registered at run time included.
PRESETS = PRESET_ROLES
SYSTEMS = ("bodies", "two-sled", "matrix")
ANALYTIC_SYSTEMS = ("two-sled", "matrix")
SHAPE_FIELDS = {
    "disk": ("radius",),
    "rod": ("length", "radius"),
    "box": ("width", "height"),
    "polygon": ("vertices",),
    "ellipse": ("semi_x", "semi_y"),
}
#: Largest |gap| (m) allowed between bodies that must touch, unless a file sets ``gap_tolerance``.
DEFAULT_GAP_TOLERANCE = 1e-6
#: Two closest points closer than this (m) in height count as a second contact point: a body
#: must be turned at least this much away from lying flat to be a one-point contact.
ONE_POINT_TOLERANCE = 1e-4
#: ``contacts``: ``"one"`` (default), a single contact point; ``"simultaneous"``, a face lying
#: flat (two or more points within ONE_POINT_TOLERANCE), compared with the m-contact laws.
CONTACT_KINDS = ("one", "simultaneous")
TWO_SLED_KEYS = ("gamma", "delta", "m", "l", "s", "c", "q3", "q6", "u")
#: The two-sled parameters' defaults, from the builder's own signature (one source of truth).
TWO_SLED_DEFAULTS = {
    name: parameter.default
    for name, parameter in inspect.signature(builders.two_sleds).parameters.items()
    if parameter.default is not inspect.Parameter.empty
}
BODY_KEYS = ("name", "shape", "mass", "inertia", "angle_deg", "velocity", "angular_velocity",
             "position")
BODY_SWEEP_FIELDS = ("mass", "inertia", "angle_deg", "angular_velocity", "velocity.x",
                     "velocity.y")
TOP_KEYS = {
    "bodies": ("name", "description", "tags", "system", "restitution", "friction", "engines",
               "laws", "ground", "body", "gap_tolerance", "expect_sequence", "contacts",
               "sweep", "expect",
               "engine_settings"),
    "two-sled": ("name", "description", "tags", "system", "restitution", "friction", "laws",
                 "parameters", "sweep", "expect"),
    "matrix": ("name", "description", "tags", "system", "restitution", "friction", "laws",
               "mass_matrix", "wn", "wt", "u", "sweep", "expect"),
}
EXPECT_KEYS = ("collision_type", "case", "energy_gain", "gate")
GATE_KEYS = ("law", "max_departure")
NAME_PATTERN = re.compile(r"^[A-Za-z0-9][A-Za-z0-9_.-]*$")
#: A character a description may not hold: the C0 and C1 control characters (NUL, newline,
#: carriage return, tab, escape ...) and the line and paragraph separators: a description is
#: one line of text in the reports, the results file and a terminal.
CONTROL_CHARACTER = re.compile("[\x00-\x1f\x7f-\x9f\u2028\u2029]")
DESCRIPTION_ALLOWED = "one line of text, without control characters (no NUL, newline or tab)"
TAG_PATTERN = re.compile(r"^[a-z0-9][a-z0-9-]*$")
DERIVED_TAGS = ("all",)

#: Supported magnitudes of the numeric fields: ``(smallest, largest)`` allowed |value| (a
#: smallest of 0 allows zero). Every number must also be 0 or at least :data:`TINY` in
#: magnitude. Outside these the solver or an engine overflows, underflows or loses its
#: conditioning (a 1e300 kg mass squares to infinity; a 5e-324 kg one inverts to it); inside
#: them the mass matrix's condition number stays below about 1e16 / 1e4 (masses and lengths
#: each span 8 decades at most), so the laws keep several correct digits.
MAGNITUDES: dict[str, tuple[float, float]] = {
    "mass": (1e-4, 1e4),  # kg
    "inertia": (1e-10, 1e4),  # kg m^2
    "length": (1e-4, 1e2),  # m: radius, length, width, height, semi-axes
    "coordinate": (0.0, 1e3),  # m: position, polygon vertex
    "speed": (0.0, 1e3),  # m/s: velocity components
    "angular_velocity": (0.0, 1e4),  # rad/s
    "angle_deg": (0.0, 1e4),  # degrees
    "friction": (0.0, 1e3),  # mu
    "restitution": (0.0, 1.0),  # e
    "gap_tolerance": (1e-12, 1e-2),  # m
    "max_departure": (1e-15, 1e6),  # relative, dimensionless
    "matrix": (0.0, 1e6),  # mass-matrix entries
    "direction": (0.0, 1e3),  # wn, wt entries
    "two_sled_mass": (1e-4, 1e4),  # kg, parameters.m
    "two_sled_length": (1e-4, 1e2),  # m, parameters.l
    "two_sled_offset": (0.0, 1e3),  # parameters.s, c, q3, q6
}
#: Any non-zero number smaller in magnitude than this is refused (subnormals, 1e-300 ...).
TINY = 1e-12
#: Sweep parameter -> its MAGNITUDES entry (body parameters by their last part).
SWEEP_MAGNITUDE = {
    # restitution: check_points names the sweep point of a value outside 0 … 1
    "friction": "friction", "mass": "mass",
    "inertia": "inertia", "angle_deg": "angle_deg", "angular_velocity": "angular_velocity",
    "velocity.x": "speed", "velocity.y": "speed", "radius": "length", "length": "length",
    "width": "length", "height": "length", "semi_x": "length", "semi_y": "length",
    "parameters.m": "two_sled_mass",
    "parameters.l": "two_sled_length", "parameters.s": "two_sled_offset",
    "parameters.c": "two_sled_offset", "parameters.q3": "two_sled_offset",
    "parameters.q6": "two_sled_offset",
}
