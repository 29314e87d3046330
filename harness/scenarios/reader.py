"""Reading a scenario file: TOML -> a checked :class:`harness.scenarios.model.Scenario`.

Every problem in a file is collected with its dotted key and raised as one
:class:`harness.scenarios.errors.ScenarioError` naming the file, the key, the value and what
is allowed.
"""

from __future__ import annotations

import tomllib
from dataclasses import replace
from pathlib import Path
from types import MappingProxyType
from typing import Any, Mapping

from harness import inputs
from harness.engines import engine_names
from harness.scenarios import checks
from harness.scenarios.checks import check_points
from harness.scenarios.errors import ScenarioError
from harness.scenarios.model import Scenario
from harness.scenarios.run_reader import read_engine_settings, read_expect, read_sweep
from harness.scenarios.schema import (
    CONTACT_KINDS,
    DEFAULT_GAP_TOLERANCE,
    DERIVED_TAGS,
    LAWS,
    NAME_ALLOWED,
    NAME_PATTERN,
    SYSTEMS,
    TAG_PATTERN,
    TOP_KEYS,
)
from harness.scenarios.system_reader import read_bodies, read_matrix, read_two_sled
from harness.scenarios.table_reader import TableReader
from harness.scene import Ellipse


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
                         allowed=NAME_ALLOWED)
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
        bodies = read_bodies(reader, doc, ground)
        # The engines registered now (those added at run time too); a file naming none runs
        # every one of them, spelled out so that its definition (and digest) says which.
        registered = engine_names()
        engines = reader.names(doc, "engines", "", registered, default=registered)
    elif system == "two-sled":
        parameters = read_two_sled(reader, doc)
    else:
        matrix = read_matrix(reader, doc)

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
        sweep = read_sweep(reader, doc, scenario)
        if sweep is None:
            raise ScenarioError(errors=reader.errors)
        scenario = replace(scenario, sweep=sweep)
    if "engine_settings" in doc:
        scenario = replace(scenario, engine_settings=read_engine_settings(
            reader, doc["engine_settings"], scenario))
    if "expect" in doc:
        scenario = replace(scenario, expect=read_expect(reader, doc, scenario))
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
