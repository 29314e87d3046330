"""pyproject.toml: what pip and the build backend read without warnings."""

from __future__ import annotations

import re
import tomllib
from pathlib import Path

PYPROJECT = Path(__file__).resolve().parents[1] / "pyproject.toml"


def test_license_is_an_spdx_expression_with_a_backend_that_reads_it():
    """The table form (``{ text = "MIT" }``) is deprecated (setuptools warns on every
    build); the string form needs setuptools 77 or later (PEP 639)."""
    document = tomllib.loads(PYPROJECT.read_text(encoding="utf-8"))
    assert document["project"]["license"] == "MIT"
    assert document["build-system"]["build-backend"] == "setuptools.build_meta"
    setuptools = next(r for r in document["build-system"]["requires"]
                      if r.startswith("setuptools"))
    minimum = re.fullmatch(r"setuptools>=(\d+)(\.\d+)*", setuptools)
    assert minimum and int(minimum.group(1)) >= 77, setuptools
    assert not any(c.startswith("License ::") for c in document["project"].get("classifiers", []))


def _setuptools() -> dict:
    return tomllib.loads(PYPROJECT.read_text(encoding="utf-8"))["tool"]["setuptools"]


def _package_directories(config: dict) -> dict[str, Path]:
    """Every directory holding an ``__init__.py`` under the mapped roots, by dotted name."""
    root = PYPROJECT.parent
    found = {}
    for top, directory in config["package-dir"].items():
        for init in (root / directory).rglob("__init__.py"):
            parts = init.parent.relative_to(root / directory).parts
            found[".".join((top, *parts))] = init.parent
    return found


def test_every_package_is_listed_and_nothing_else():
    """A package missing from ``packages`` is missing from the wheel (harness.reference was)."""
    config = _setuptools()
    assert sorted(config["packages"]) == sorted(_package_directories(config))


def test_data_files_are_package_data_not_packages():
    """Each file of a package that is not Python is matched by ``package-data``, and only
    ``package-data`` brings files in: a data directory (harness/report/data) is no package,
    and setuptools' manifest would otherwise bring it in and warn that it is one."""
    config = _setuptools()
    assert config["include-package-data"] is False
    packages = _package_directories(config)
    assert not set(config["package-data"]) - set(packages)
    unmatched = []
    for name, directory in packages.items():
        for path in directory.rglob("*"):
            if not path.is_file() or path.suffix in (".py", ".pyc") or "__pycache__" in path.parts:
                continue
            owner = max((other for other, folder in packages.items()
                         if path.is_relative_to(folder)), key=len)
            inner = path.relative_to(packages[owner])
            if owner == name and not any(inner.match(pattern) for pattern
                                         in config["package-data"].get(owner, [])):
                unmatched.append(f"{owner}: {inner}")
    assert not unmatched, unmatched
