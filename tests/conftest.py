"""Shared test configuration, and the ``load_or_skip`` and ``survey_identity`` fixtures of the
engine tests.

Hypothesis runs derandomized (the same examples on every run, here and in CI), so a
property test fails or passes for a reason in the code, never by the draw of a seed; set
``HYPOTHESIS_PROFILE=explore`` to search with fresh random examples.
"""

from __future__ import annotations

import importlib.util
import os
from pathlib import Path

import pytest
from hypothesis import settings

settings.register_profile("deterministic", derandomize=True, deadline=None)
settings.register_profile("explore", deadline=None)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "deterministic"))


@pytest.fixture(scope="session")
def load_or_skip():
    """``load_or_skip(name)``: the engine ``name``, or the test skipped if it is not installed."""

    from harness.engines import EngineNotInstalled, load_engine

    def load(name: str):
        try:
            return load_engine(name)
        except EngineNotInstalled as error:
            pytest.skip(f"{name} not installed: {error}")

    return load


@pytest.fixture(scope="session")
def survey_identity():
    """tests/engines/survey_identity.py, the helper of the survey identity tests, loaded by path
    (the tests are not a package)."""
    path = Path(__file__).parent / "engines" / "survey_identity.py"
    spec = importlib.util.spec_from_file_location("survey_identity", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module
