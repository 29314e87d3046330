"""Fixtures shared by the engine tests."""

from __future__ import annotations

import pytest

from harness.engines import EngineNotInstalled, load_engine


@pytest.fixture(scope="session")
def load_or_skip():
    """``load_or_skip(name)``: the engine ``name``, or the test skipped if it is not installed."""

    def load(name: str):
        try:
            return load_engine(name)
        except EngineNotInstalled as error:
            pytest.skip(f"{name} not installed: {error}")

    return load
