"""The tables of a scenario file that say how its runs go and what they must show, read once
the system is known: ``[sweep]``, ``[expect]`` with its gates, ``[engine_settings]``.
"""

from __future__ import annotations

from types import MappingProxyType
from typing import Mapping

import numpy as np

from harness import bounds
from harness.engines import engine_names, preset_role, renamed_roles, source_label
from harness.scenarios.checks import check_engine_settings
from harness.scenarios.errors import suggest
from harness.scenarios.model import Expectation, Gate, Scenario, SweepSpec, sweep_parameters
from harness.scenarios.schema import (
    BOUNDS,
    EXPECT_KEYS,
    GATE_KEYS,
    LAW_TYPES,
    LAWS,
    PRESETS,
    SWEEP_MAGNITUDE,
    limit,
)
from harness.scenarios.table_reader import TableReader


def read_sweep(reader: TableReader, doc, scenario: Scenario) -> SweepSpec | None:
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


def read_expect(reader: TableReader, doc, scenario: Scenario) -> Expectation:
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


def read_engine_settings(reader: TableReader, raw, scenario: Scenario):
    if not isinstance(raw, dict):
        reader.error("engine_settings", "must be a table of engine tables", raw,
                     ", ".join(scenario.engines or engine_names()))
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
