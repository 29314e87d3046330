"""The engine registry: every engine's pin comes from the one place it is written."""

from __future__ import annotations

import tomllib
from pathlib import Path

from harness.engines import ENGINE_NAMES, pinned_requirement


def test_every_engine_is_pinned_in_the_harness_extra_and_the_registry_reads_that_pin():
    pyproject = tomllib.loads((Path(__file__).parents[2] / "pyproject.toml").read_text())
    extra = pyproject["project"]["optional-dependencies"]["harness"]
    pins = {spec.split("==")[0].lower(): spec for spec in extra if "==" in spec}
    for engine in ENGINE_NAMES:
        assert engine in pins, f"{engine} is not pinned in the harness extra"
        assert pinned_requirement(engine) == pins[engine]
