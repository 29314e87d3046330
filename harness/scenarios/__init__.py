"""Scenario files: TOML descriptions of one impact (or a sweep of impacts), read and checked.

A scenario is a TOML file under ``scenarios/`` (format in ``scenarios/README.md``) read into a
frozen :class:`Scenario`. Three kinds of system:

* ``bodies`` (the default): one body against the fixed ground (``[ground]``) or two free
  bodies, given as ``[[body]]`` tables. The harness builds a :class:`harness.scene.Scene`
  for the engines and, through :mod:`harness.scene.geometry` and ``planar_impact.builders``,
  the analytic problem for the laws.
* ``two-sled``: the paper's Section 5 system, analytic only (``[parameters]``).
* ``matrix``: ``mass_matrix``, ``wn``, ``wt`` and ``u`` given directly, analytic only.

Modules, in the order data flows through them:

* :mod:`~harness.scenarios.schema` -- names, keys and limits;
* :mod:`~harness.scenarios.errors` -- :class:`ScenarioError`;
* :mod:`~harness.scenarios.model` -- the frozen dataclasses and their sweep points;
* :mod:`~harness.scenarios.table_reader` -- typed reads of a TOML document's keys, every
  problem collected;
* :mod:`~harness.scenarios.system_reader` -- the bodies, the matrix system or the two sleds;
* :mod:`~harness.scenarios.run_reader` -- ``[sweep]``, ``[expect]``, ``[engine_settings]``;
* :mod:`~harness.scenarios.reader` -- TOML to a :class:`Scenario`, from the readers above;
* :mod:`~harness.scenarios.checks` -- physics of every point, engine settings, ``[expect]``;
* :mod:`~harness.scenarios.library` -- the library under ``scenarios/`` and its tag sets;
* :mod:`~harness.scenarios.cli` -- ``impact-harness validate`` and ``new``.

>>> from harness.scenarios import load_scenarios
>>> for scenario in load_scenarios(tags="quick"):                       # doctest: +SKIP
...     for point, scene in scenario.points():
...         problem = scenario.analytic_problem(point)
...         result = problem.solve(mu=scenario.friction_at(point),
...                                e=scenario.restitution_at(point), law="poisson")
"""

from harness.scenarios.checks import check_expectations
from harness.scenarios.errors import ScenarioError
from harness.scenarios.library import load_scenarios, parse_tags, scenario_files, tag_sets
from harness.scenarios.model import (
    BodySpec,
    Expectation,
    Gate,
    MatrixSystem,
    Point,
    Scenario,
    SweepSpec,
    sweep_parameters,
)
from harness.scenarios.reader import load_scenario, parse_scenario
from harness.scenarios.schema import (
    LAW_TYPES,
    LAWS,
    ONE_POINT_TOLERANCE,
    PRESETS,
    SCENARIO_DIR,
    TWO_SLED_DEFAULTS,
)

__all__ = [
    "LAWS", "LAW_TYPES", "ONE_POINT_TOLERANCE", "PRESETS", "SCENARIO_DIR",
    "TWO_SLED_DEFAULTS", "BodySpec", "Expectation", "Gate", "MatrixSystem", "Point",
    "Scenario", "ScenarioError", "SweepSpec", "check_expectations", "load_scenario",
    "load_scenarios", "parse_scenario", "parse_tags", "scenario_files", "sweep_parameters",
    "tag_sets",
]
