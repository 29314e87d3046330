"""``impact-harness engines``: every engine the registry holds, whether it is installed here
(and why not), its presets, and its settings with their units, each preset's value and the
bounds every way of setting them shares (:data:`harness.bounds.BOUNDS`).

Everything is read from the registry (:func:`harness.engines.engine_names`, each adapter's
class): an engine added to it (a fifth one, or one registered at run time) is listed with no
change here. ``--bounds`` prints the whole table of bounds instead (every knob: engine
settings, command-line options, population values) as Markdown, the text of
docs/bounds.md (a test keeps them the same).
"""

from __future__ import annotations

import argparse
import json
import re
import sys
from importlib import metadata

from harness import bounds
from harness.engines import (
    EngineNotInstalled,
    engine_class,
    engine_distribution,
    engine_names,
    preset_label,
)

#: A unit at the start of a setting's documentation (``"m, geom margin: ..."``).
_LEADING_UNIT = re.compile(r"^(s|m|m/s|1/s)(?: \([^)]*\))?, ")


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--bounds", action="store_true",
                        help="print the table of every knob's bounds (Markdown: "
                             "docs/bounds.md) instead of the engines")


def main(args) -> int:
    print(bounds_markdown() if args.bounds else engines_text(), end="")
    sys.stdout.flush()
    return 0


def engines_text() -> str:
    """Each registered engine: installed or why not, its presets, its settings."""
    blocks = []
    for name in engine_names():
        try:
            adapter = engine_class(name)
        except EngineNotInstalled as error:
            blocks.append(f"{name}: NOT INSTALLED ({error})\n  its presets and settings are "
                          "listed once it is installed\n")
            continue
        blocks.append(_engine_block(name, adapter))
    return "\n".join(blocks)


def _engine_block(name: str, adapter) -> str:
    lines = [f"{name}: installed{_version(name)}"]
    if adapter.description:
        lines.append(f"  {_first_sentence(adapter.description)}")
    presets = list(adapter.presets)
    why = adapter.preset_why if isinstance(adapter.preset_why, dict) else {}
    lines.append("  presets:")
    for role in presets:
        label = preset_label(name, role) or role
        shown = label if label == role else f"{label} (role {role})"
        lines.append(f"    {shown}: {why.get(role, '')}".rstrip(": "))
    lines.append("  settings (unit; value per preset; allowed):")
    engine = adapter()
    values = {role: engine.settings(role) for role in presets}
    for key, documented in adapter.setting_docs.items():
        unit = _unit(key, documented)
        per_preset = ", ".join(f"{preset_label(name, role) or role} {_value(values[role][key])}"
                               for role in presets)
        bound = bounds.BOUNDS.get(key)
        allowed = (bound.allowed() if bound is not None
                   else "as its meaning says (a flag or a name, checked by the adapter)")
        lines.append(f"    {key}{f' [{unit}]' if unit else ''}: {per_preset}; allowed: "
                     f"{allowed}")
        lines.append(f"      {_LEADING_UNIT.sub('', documented)}")
    return "\n".join(lines) + "\n"


def _version(name: str) -> str:
    try:
        return f" ({engine_distribution(name)} {metadata.version(engine_distribution(name))})"
    except (KeyError, metadata.PackageNotFoundError):  # registered at run time
        return ""


def _first_sentence(text: str) -> str:
    sentence = re.split(r"(?<=\.)\s", " ".join(text.split()), maxsplit=1)[0]
    return sentence if len(sentence) <= 200 else sentence[:197] + "..."


def _unit(key: str, documented: str) -> str:
    bound = bounds.BOUNDS.get(key)
    if bound is not None and bound.unit:
        return bound.unit
    found = _LEADING_UNIT.match(documented)
    return found.group(1) if found else ""


def _value(value) -> str:
    if value is None:
        return "(engine's default)"
    if isinstance(value, float):
        return f"{value:.6g}"
    return json.dumps(value)


def bounds_markdown() -> str:
    """The table of :data:`harness.bounds.BOUNDS` (and the limits the environment raises),
    as Markdown."""
    rows = ["| knob | allowed | why |", "|---|---|---|"]
    for knob, bound in bounds.BOUNDS.items():
        why = bound.why or "; ".join(entry.why for entry in bound.elements or () if entry.why)
        rows.append(f"| `{knob}` | {bound.allowed()} | {why} |")
    limits = ["| limit | value | environment variable | the variable's range |",
              "|---|---|---|---|"]
    for name, value in bounds.LIMITS.items():
        low, high = bounds.LIMIT_RANGES[name]
        limits.append(f"| `{name}` | {bounds._spelled(value)} | "
                      f"`IMPACT_HARNESS_{name.upper()}` | {bounds._spelled(low)} … "
                      f"{bounds._spelled(high)} |")
    return ("# Bounds of every knob\n\n"
            "<!-- generated by `impact-harness engines --bounds` from harness/bounds.py; "
            "tests/test_bounds.py keeps it the same -->\n\n"
            "Every value a user sets is checked against this one table before any work, "
            "whichever way it is set: an engine setting in a scenario file's "
            "`[engine_settings]`, by `--set ENGINE.KEY=VALUE` or through the Python API; a "
            "command's numeric option; a population file's `sides` and `max_attempts`. A "
            "value outside it is refused in one line naming where it came from, the key, the "
            "value and what is allowed (exit status 2). A population's other values are "
            "bounded by the magnitudes a scenario file allows (harness/scenarios/schema.py, "
            "`MAGNITUDES`). `impact-harness engines` lists each engine's settings with their "
            "bounds and each preset's values.\n\n"
            + "\n".join(rows) + "\n\n"
            "Some bounds name a limit, which the environment may move within a range (a "
            "value outside it, or not a number, is refused before any work, exit 2):\n\n"
            + "\n".join(limits) + "\n")


__all__ = ["add_arguments", "bounds_markdown", "engines_text", "main"]
