"""The engine registry: every engine's pin comes from the one place it is written."""

from __future__ import annotations

import tomllib
from pathlib import Path

from harness.engines import ENGINE_NAMES, pinned_requirement


def test_every_engine_is_pinned_in_the_harness_extra_and_the_registry_reads_that_pin():
    pyproject = tomllib.loads((Path(__file__).parents[2] / "pyproject.toml").read_text())
    extras = pyproject["project"]["optional-dependencies"]
    pins = {spec.split("==")[0].lower(): spec for spec in extras["harness"] if "==" in spec}
    # Drake in an extra of its own, which the Makefile installs in a step allowed to fail
    # (wheels for glibc >= 2.34 x86_64/aarch64 Linux and macOS only): docs/engines.md, 'Drake'
    assert extras["drake"] == ["drake==1.51.1"] and "drake" not in pins
    pins["drake"] = extras["drake"][0]
    for engine in ENGINE_NAMES:
        assert engine in pins, f"{engine} is not pinned in the harness extra"
        assert pinned_requirement(engine) == pins[engine]
