"""Shared test configuration, and the ``load_or_skip`` and ``survey_identity`` fixtures of the
engine tests.

Hypothesis runs derandomized (the same examples on every run, here and in CI), so a
property test fails or passes for a reason in the code, never by the draw of a seed; set
``HYPOTHESIS_PROFILE=explore`` to search with fresh random examples.

Mark ``@pytest.mark.kernel_sensitive`` (or ``pytestmark = pytest.mark.kernel_sensitive`` for a
whole module) every test whose outcome rests on arithmetic that BLAS, libm or SIMD kernels
round differently on another CPU: a pin of stored results, a count, a decision, a finding.
Each such comparison says which kind it is (docs/verdicts.md, 'Same answers on every CPU'):
bit for bit (IEEE operations only, no BLAS product), within a derived forward error bound
(tests/error_bounds.py), or a decision with a tolerance band. ``make test`` runs those tests
again under every OpenBLAS core type the CPU can execute, and with numpy's SIMD dispatch off
(tests/other_kernels.py, which also runs them by hand); mark ``blas_free`` as well those
whose arithmetic takes no BLAS product (they then run once more, with SIMD off, not under each
core type). The kernels in use head every run's output (:func:`pytest_report_header`). Keep
them quick: they run up to eight times.
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


def pytest_report_header(config) -> list[str]:
    """The BLAS kernel and numpy's SIMD targets of this run (tests/other_kernels.py changes
    them)."""
    try:
        from numpy._core._multiarray_umath import __cpu_dispatch__, __cpu_features__
    except ImportError:  # numpy < 2
        from numpy.core._multiarray_umath import __cpu_dispatch__, __cpu_features__

    try:
        from threadpoolctl import threadpool_info

        blas = [f"{info.get('internal_api')} {info.get('architecture')}"
                for info in threadpool_info() if info.get("user_api") == "blas"]
    except ImportError:  # threadpoolctl comes with the harness extra
        blas = []
    simd = [target for target in __cpu_dispatch__ if __cpu_features__.get(target)]
    return [f"kernels: BLAS {', '.join(blas) or 'unknown'}; numpy SIMD targets in use: "
            f"{' '.join(simd) or 'none (baseline only)'}"]


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


@pytest.fixture
def toy_engine(monkeypatch):
    """The test-only engine of tests/engines/toy_engine.py, registered for the test as the
    only engine the harness lists (the shipped ones hidden from
    :func:`harness.engines.engine_names`): a command that runs every engine then runs the toy
    alone, in seconds. Yields its name."""
    from harness import engines as registry
    from tests.engines.toy_engine import ToyEngine

    monkeypatch.setattr(registry, "ENGINE_NAMES", ())
    registry.register_engine("toy", ToyEngine)
    try:
        yield "toy"
    finally:
        registry.unregister_engine("toy")


@pytest.fixture
def plans_of():
    """``plans_of(engine, scenes, preset)``: the plans ``Engine.run_many`` makes of
    ``scenes`` under ``preset`` before it asks the adapter for its batches
    (``_many_chunks``)."""
    from harness.engines.scene_setup import check_scene

    def plans(engine, scenes, preset: str) -> list:
        settings, _ = engine._resolve(engine.settings(preset), preset, None)
        return [engine._new_plan(scene, settings, None, None, check_scene(engine.name, scene))
                for scene in scenes]

    return plans


@pytest.fixture
def toy_beside_the_others():
    """The test-only engine of tests/engines/toy_engine.py registered beside the shipped
    ones (where a scenario's gates name those), unregistered after. Yields its name."""
    from harness import engines as registry
    from tests.engines.toy_engine import ToyEngine

    registry.register_engine("toy", ToyEngine)
    try:
        yield "toy"
    finally:
        registry.unregister_engine("toy")
    assert "toy" not in registry.engine_names()
