"""Many scenario files for the pipeline benchmark: copies of the library with perturbed values.

``python -m harness.bench.many_scenarios DIR [--count 1000] [--seed 0]`` writes ``count``
scenario files into ``DIR``: the library's files (scenarios/) in turn, each copy renamed
``<name>-<k>`` and with its ``restitution``, ``friction`` and every body's ``velocity``
scaled by a seeded factor in [0.9, 1.1] (restitution and friction kept in [0, 1]). The
copies drop ``[expect]``: the expectations were worked out for the original values. Every
copy is a valid scenario of the same kind (ground or two bodies, sweep or single point),
so ``impact-harness run DIR`` and ``report`` see a library of ``count`` scenarios.

Measured with it (the commands are in the README): ``impact-harness run`` + ``report``
cold (fresh cache and output) and warm (everything cached, figures up to date).
"""

from __future__ import annotations

import argparse
import tomllib
from pathlib import Path

import numpy as np

from harness import bounds
from harness.scenarios.library import scenario_files
from harness.store.files import write_text_atomically

SPREAD = 0.1  # relative perturbation of the perturbed values


def perturbed_copies(count: int, seed: int = 0) -> list[tuple[str, dict]]:
    """``count`` ``(file name, scenario table)`` pairs."""
    originals = [tomllib.loads(path.read_text(encoding="utf-8")) for path in scenario_files()]
    rng = np.random.default_rng(seed)
    copies = []
    for index in range(count):
        table = tomllib.loads(_dumps(originals[index % len(originals)]))  # a deep copy
        table.pop("expect", None)
        table["name"] = f"{table['name']}-{index:04d}"

        def factor() -> float:
            return float(rng.uniform(1.0 - SPREAD, 1.0 + SPREAD))

        for key in ("restitution", "friction"):
            if key in table:
                table[key] = min(1.0, table[key] * factor())
        for body in table.get("body", []):
            if "velocity" in body:
                body["velocity"] = [value * factor() for value in body["velocity"]]
        copies.append((f"{table['name']}.toml", table))
    return copies


def write_copies(directory: Path, count: int, seed: int = 0) -> list[Path]:
    """Write :func:`perturbed_copies` into ``directory``; returns the paths."""
    directory.mkdir(parents=True, exist_ok=True)
    paths = []
    for file_name, table in perturbed_copies(count, seed):
        path = directory / file_name
        write_text_atomically(path, _dumps(table))  # never through a link
        paths.append(path)
    return paths


def _value(value) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, (int, float)):
        return repr(value)
    if isinstance(value, str):
        return '"' + value.replace("\\", "\\\\").replace('"', '\\"') + '"'
    if isinstance(value, list):
        return "[" + ", ".join(_value(item) for item in value) + "]"
    if isinstance(value, dict):
        return "{ " + ", ".join(f"{_key(k)} = {_value(v)}" for k, v in value.items()) + " }"
    raise TypeError(f"cannot write {type(value).__name__} as TOML")


def _key(key: str) -> str:
    return key if key.replace("_", "").replace("-", "").isalnum() else _value(key)


def _is_tables(value) -> bool:
    return isinstance(value, list) and bool(value) and all(isinstance(v, dict) for v in value)


def _dumps(table: dict, prefix: str = "") -> str:
    """The TOML text of a table read by ``tomllib`` (scalars, arrays, tables, arrays of
    tables: what scenario files hold)."""
    lines = [f"{_key(k)} = {_value(v)}" for k, v in table.items()
             if not isinstance(v, dict) and not _is_tables(v)]
    for key, value in table.items():
        name = f"{prefix}{_key(key)}"
        if isinstance(value, dict):
            lines += ["", f"[{name}]", _dumps(value, name + ".")]
        elif _is_tables(value):
            for item in value:
                lines += ["", f"[[{name}]]", _dumps(item, name + ".")]
    return "\n".join(lines)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("directory", type=Path)
    parser.add_argument("--count", type=bounds.option("count"), default=1000)
    parser.add_argument("--seed", type=bounds.option("seed"), default=0)
    args = parser.parse_args(argv)
    paths = write_copies(args.directory, args.count, args.seed)
    print(f"wrote {len(paths)} scenario files to {args.directory}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
