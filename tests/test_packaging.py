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
