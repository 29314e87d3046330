"""The scenario file schema: the names, keys and limits every scenario module shares.

Law, engine and preset names come from their one home (``planar_impact.HYPOTHESES``, the
engine registry); the two-sled defaults from ``planar_impact.builders.two_sleds``.
"""

from __future__ import annotations

import inspect
import re
from pathlib import Path

from planar_impact import HYPOTHESES, builders

from harness.engines import ENGINE_NAMES, PRESET_NAMES

SCENARIO_DIR = Path(__file__).resolve().parent.parent.parent / "scenarios"

#: Impact laws, by the names of ``planar_impact.HYPOTHESES``.
LAWS = HYPOTHESES
#: Collision types each law reports: Poisson/Stronge 1–5, Newton laws 1 stick, 2 reverse
#: sliding, 3 forward sliding.
LAW_TYPES = {
    "newton": (1, 2, 3),
    "poisson": (1, 2, 3, 4, 5),
    "stronge": (1, 2, 3, 4, 5),
    "stronge-paper": (1, 2, 3, 4, 5),
    "newton-lcp": (1, 2, 3),
}
ENGINES = ENGINE_NAMES
PRESETS = PRESET_NAMES
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
ALL_TOP_KEYS = tuple(dict.fromkeys(key for keys in TOP_KEYS.values() for key in keys))
EXPECT_KEYS = ("collision_type", "case", "energy_gain", "gate")
GATE_KEYS = ("law", "max_departure")
NAME_PATTERN = re.compile(r"^[A-Za-z0-9][A-Za-z0-9_.-]*$")
TAG_PATTERN = re.compile(r"^[a-z0-9][a-z0-9-]*$")
DERIVED_TAGS = ("all",)
