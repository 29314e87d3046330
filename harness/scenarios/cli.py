"""``impact-harness validate FILE…`` and ``impact-harness new NAME --shape …``.

``validate`` reads each scenario file, checks every key and every sweep point (bodies touch,
approach, one contact point), and, unless ``--no-solve``, compares the ``[expect]`` collision
types with the solver. It prints ``OK`` per good file and every error with its file, key,
value and what is allowed; the exit status is 2 (bad input) if any file is bad.

``new`` writes a commented starting file that validates as written.
"""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

from harness.engines import engine_names
from harness.scenarios.checks import check_expectations
from harness.scenarios.errors import ScenarioError
from harness.scenarios.library import scenario_files
from harness.scenarios.reader import load_scenario
from harness.scenarios.schema import LAWS, NAME_PATTERN, SCENARIO_DIR
from harness.store.files import (
    make_output_directory,
    output_directory_problem,
    output_file_problem,
    write_text_atomically,
)

SHAPES = ("disk", "rod", "box", "polygon", "ellipse")


# --------------------------------------------------------------------------------------------
# validate
# --------------------------------------------------------------------------------------------
def add_validate_arguments(parser: argparse.ArgumentParser,
                           files_help: str = "scenario files or directories (default: every "
                                             "file in scenarios/)") -> None:
    parser.add_argument("files", nargs="*", metavar="FILE", help=files_help)
    parser.add_argument("--no-solve", action="store_true",
                        help="only check the files; do not compare [expect] with the solver")
    parser.add_argument("-q", "--quiet", action="store_true", help="print errors only")


def main_validate(args: argparse.Namespace) -> int:
    files = scenario_files(args.files or None)
    if not files:
        print(f"no scenario files found in {', '.join(args.files) or SCENARIO_DIR}",
              file=sys.stderr)
        return 2
    bad, names = 0, {}
    for path in files:
        errors: list[str] = []
        try:
            scenario = load_scenario(path)
        except ScenarioError as error:
            errors = [str(e) for e in error.errors]
        else:
            if scenario.name in names:
                errors.append(str(ScenarioError(
                    f"the name is already used by {names[scenario.name]}", path=path,
                    key="name", value=scenario.name, allowed="a name unique among the files")))
            names.setdefault(scenario.name, path)
            if not args.no_solve and not errors:
                errors += check_expectations(scenario)
        if errors:
            bad += 1
            for message in errors:
                print(f"ERROR {message}")
        elif not args.quiet:
            points = len(scenario.point_list())
            sweep = f", {points} sweep points" if scenario.sweep else ""
            tags = ", ".join(scenario.tags) or "no tags"
            print(f"OK    {path}  ({scenario.name}: {scenario.system}{sweep}; {tags})")
    if not args.quiet or bad:
        print(f"{len(files) - bad} of {len(files)} scenario files OK"
              + (f", {bad} with errors" if bad else ""))
    return 2 if bad else 0


# --------------------------------------------------------------------------------------------
# new
# --------------------------------------------------------------------------------------------
def add_new_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("name", metavar="NAME",
                        help="scenario name (letters, digits, '_', '-', '.'); "
                        "the file is NAME.toml")
    parser.add_argument("--shape", choices=SHAPES, default="disk",
                        help="shape of the (first) body (default: disk)")
    kind = parser.add_mutually_exclusive_group()
    kind.add_argument("--ground", dest="two_body", action="store_false",
                      help="one body against the fixed ground (default)")
    kind.add_argument("--two-body", dest="two_body", action="store_true",
                      help="two free bodies: the shape, struck by a disk")
    parser.set_defaults(two_body=False)
    where = parser.add_mutually_exclusive_group()
    where.add_argument("--out", type=Path, default=None,
                       help="directory to write to (default: the current directory, so that a "
                       "draft never joins the library and its tests unasked)")
    where.add_argument("--library", action="store_true",
                       help=f"write into the library ({SCENARIO_DIR}), which `run` and the "
                       "tests read; without [expect] the tests check only what it declares")
    parser.add_argument("--force", action="store_true", help="overwrite an existing file")


_SHAPE_LINES = {
    "disk": ['shape = "disk"', "radius = 0.1               # m"],
    "rod": ['shape = "rod"              # a capsule along the body x axis',
            "length = 1.0               # m, between the centres of the end caps",
            "radius = 0.005             # m, of the end caps (half the thickness)"],
    "box": ['shape = "box"', "width = 0.2                # m, along the body x axis",
            "height = 0.1               # m, along the body y axis"],
    "polygon": ['shape = "polygon"          # convex; vertices counter-clockwise, in m',
                "# The harness moves the vertices so that their centroid is the body origin.",
                "vertices = [[-0.1, -0.05], [0.1, -0.05], [0.0, 0.1]]"],
    "ellipse": ['shape = "ellipse"          # against the ground only',
                "semi_x = 0.035             # m, along the body x axis",
                "semi_y = 0.025             # m, along the body y axis"],
}
# Ground scenes: an angle that gives one contact point (no face lying flat) and a velocity
# that approaches the ground at about 1 m/s.
_GROUND_POSE = {"disk": (0.0, "[1.0, -1.0]"), "rod": (45.0, "[0.5, -1.0]"),
                "box": (30.0, "[1.0, -1.0]"), "polygon": (25.0, "[0.8, -1.0]"),
                "ellipse": (30.0, "[0.5, -1.0]")}
# Two-body scenes: the shape at the origin (angle 0) and the top of it where a disk of
# radius 0.05 m touches it: (x, y) of the disk centre.
_STRIKE_POINT = {"disk": ("[0.075, 0.12990381056766578]", "# 0.15 m from a's centre at 60 degrees"),
                 "rod": ("[0.3, 0.055]", "# 0.005 + 0.05 above the rod's axis"),
                 "box": ("[0.03, 0.1]", "# 0.05 + 0.05 above the box's centre"),
                 "polygon": ("[0.0, 0.15]", "# on the apex, 0.1 + 0.05 above the centroid")}


def _toml_names(names) -> str:
    """``["pymunk", "box2d"]``: names as a TOML array of strings."""
    return "[" + ", ".join(f'"{name}"' for name in names) + "]"


def scenario_template(name: str, shape: str, two_body: bool = False) -> str:
    """The text of a commented starting scenario file (it validates as written)."""
    shape_lines = "\n".join(_SHAPE_LINES[shape])
    head = f'''# Scenario file: see scenarios/README.md for every key, and run
#   impact-harness validate {name}.toml
# after editing. Units: m, kg, s, rad/s; angles in degrees (angle_deg); y points up.
name = "{name}"
description = "A {shape} {'struck by a disk' if two_body else 'hitting the ground'} (edit me)."
tags = ["custom"]          # e.g. "quick", "slip-reversal"; "all" is implied
restitution = 0.5          # e, in [0, 1]
friction = 0.3             # mu, >= 0
# engines = {_toml_names(engine_names())}   # default: every registered engine
# laws = {_toml_names(LAWS)}   # default: all
'''
    if not two_body:
        angle, velocity = _GROUND_POSE[shape]
        body = f'''
[ground]                   # the fixed half-space y <= 0, normal +y

[[body]]
name = "{shape}"
{shape_lines}
mass = 1.0                 # kg
# inertia = 0.005          # kg m^2 about the centre of mass; default: uniform density
angle_deg = {angle}           # CCW angle of the body x axis; avoid faces lying flat
velocity = {velocity}     # m/s, centre of mass; must approach the ground (v_n < 0)
angular_velocity = 0.0     # rad/s, CCW
# position = [0.0, 0.1]    # m; omitted: the harness puts the lowest point on y = 0
'''
        sweep_parameter, sweep_values = (
            ("friction", "{ start = 0.0, stop = 1.0, num = 5 }") if shape == "disk"
            else (f"body.{shape}.angle_deg", f"[{angle - 15:.1f}, {angle:.1f}, {angle + 15:.1f}]"))
    else:
        strike, comment = _STRIKE_POINT[shape]
        body = f'''
# Two free bodies (no [ground]); the contact normal points from the first body into the
# second. Positions are required and the bodies must touch (|gap| <= 1e-6 m).
[[body]]
name = "a"
{shape_lines}
mass = 1.0                 # kg
angle_deg = 0.0
position = [0.0, 0.0]      # m, centre of mass
velocity = [0.0, 0.0]      # m/s

[[body]]
name = "b"
shape = "disk"
radius = 0.05
mass = 0.5
position = {strike}   {comment}
velocity = [0.3, -1.0]     # m/s: must approach body a (v_n < 0)
angular_velocity = 0.0
'''
        sweep_parameter, sweep_values = "friction", "{ start = 0.0, stop = 1.0, num = 5 }"
    tail = f'''
# [sweep]                  # optional: one parameter over several values
# parameter = "{sweep_parameter}"
# values = {sweep_values}   # a list, or {{ start = ..., stop = ..., num = ... }}

# [expect]                 # optional: what the laws should give (checked by validate)
# case = 1                 # Table 1 row
# [expect.collision_type]  # Poisson/Stronge 1-5; Newton laws 1 stick, 2 reverse, 3 forward
# poisson = 2
# "newton-lcp" = 1
# [expect.gate]            # optional tolerance the runner enforces (non-zero exit if exceeded)
# "pymunk.accurate" = {{ law = "newton-lcp", max_departure = 1e-6 }}

# [engine_settings.pymunk] # optional overrides of an engine's settings (see its SETTING_DOCS)
# iterations = 50
'''
    return head + body + tail


def main_new(args: argparse.Namespace) -> int:
    name = args.name
    if not NAME_PATTERN.match(name):
        print(f"impact-harness new: NAME = {name!r}: not a valid name "
              "(allowed: letters, digits, '_', '-' and '.', starting with a letter or digit)",
              file=sys.stderr)
        return 2
    if args.two_body and args.shape == "ellipse":
        print("impact-harness new: --shape ellipse with --two-body: an ellipse touches only "
              "the ground (allowed: --ground, the default)", file=sys.stderr)
        return 2
    directory = SCENARIO_DIR if args.library else Path(args.out or Path.cwd())
    path = (directory / f"{name}.toml").absolute()  # a link there is not followed
    if os.path.lexists(path) and not args.force:
        print(f"impact-harness new: {path} exists (use --force to overwrite)", file=sys.stderr)
        return 1
    problem = output_directory_problem(directory) or (
        None if not directory.is_dir() else output_file_problem(path))
    if problem:
        print(f"impact-harness new: {path}: {problem}", file=sys.stderr)
        return 2
    make_output_directory(directory)  # the directory asked for (itself only)
    write_text_atomically(path, scenario_template(name, args.shape, args.two_body))
    try:
        load_scenario(path)
    except ScenarioError as error:  # pragma: no cover - the templates are tested
        print(f"impact-harness new: the generated file does not validate:\n{error}",
              file=sys.stderr)
        return 1
    print(f"wrote {path}; edit it, then run: impact-harness validate {path} "
          f"&& impact-harness run {path} --json results.json")
    return 0
