"""``impact-harness validate [FILE|DIR ...]``: check scenario files and population files.

A command on top of both formats (scenario files: harness/scenarios; population files of the
survey: harness/survey/population.py), so neither layer needs the other. A file is read as a
population when it sits in a directory named ``populations`` or has an ``[approach]`` table
(every population has one, no scenario does); everything else is checked as a scenario file.
Each bad file is reported as one line per problem (file, key, value, what is allowed).

Exit status: 0 every file is OK; 2 a file has errors (or none was found).
"""

from __future__ import annotations

import argparse
import re
import sys
from pathlib import Path

from harness.scenarios import cli as scenarios_cli
from harness.scenarios.errors import ScenarioError
from harness.survey.population import load_population

#: A population's ``[approach]`` table header, at the start of a line.
APPROACH_TABLE = re.compile(rb"^\s*\[\s*approach\s*\]", re.MULTILINE)
#: Bytes read to tell a population from a scenario file (the loaders read and bound the rest).
SNIFF_BYTES = 1 << 16


def add_arguments(parser: argparse.ArgumentParser) -> None:
    scenarios_cli.add_validate_arguments(
        parser, files_help="scenario or population files, or directories of them (default: "
                           "every file in scenarios/)")
    parser.description = __doc__.split("\n\n")[0].strip("`: ").replace("``", "")


def is_population(path: Path) -> bool:
    """True for a population file (see the module docstring); False for anything else,
    including what cannot be read here (the scenario check reports it)."""
    if path.parent.name == "populations":
        return True
    try:
        if not path.is_file():
            return False
        with path.open("rb") as handle:
            return APPROACH_TABLE.search(handle.read(SNIFF_BYTES)) is not None
    except OSError:
        return False


def expand(items: list[str]) -> tuple[list[Path], list[str]]:
    """The population files among ``items`` (a directory counts for its ``*.toml`` files)
    and the other items, unchanged, for the scenario check."""
    populations, others = [], []
    for item in items:
        path = Path(item)
        try:
            is_directory = path.is_dir()
        except OSError:  # a name too long, a loop of links: the scenario check says so
            others.append(item)
            continue
        if is_directory:
            files = sorted(path.glob("*.toml"))
            if files and all(is_population(f) for f in files):
                populations += files
                continue
        elif is_population(path):
            populations.append(path)
            continue
        others.append(item)
    return list(dict.fromkeys(populations)), others


def main(args: argparse.Namespace) -> int:
    populations, others = expand(list(args.files or []))
    bad = 0
    for path in populations:
        try:
            population = load_population(path)
        except ScenarioError as error:
            bad += 1
            for message in getattr(error, "errors", None) or [error]:
                print(f"ERROR {message}")
            continue
        if not args.quiet:
            bodies = ", ".join(f"{body.name} ({body.shape})" for body in population.bodies)
            print(f"OK    {path}  (population {population.name}: {bodies})")
    if populations and (not args.quiet or bad):
        print(f"{len(populations) - bad} of {len(populations)} population files OK"
              + (f", {bad} with errors" if bad else ""))
    code = 2 if bad else 0
    if others or not populations:  # no file named: the scenario library, as before
        args.files = others
        code = max(code, scenarios_cli.main_validate(args))
    sys.stdout.flush()
    return code


__all__ = ["add_arguments", "is_population", "main"]
