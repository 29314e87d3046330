"""The cache's code version hashes only the code the cached values depend on
(harness/store/identity.py, ``CACHED_CODE``): editing the report keeps every entry."""

from __future__ import annotations

from pathlib import Path

import pytest

from harness.store import identity
from harness.store.cache import ResultCache


def _tree(root: Path) -> tuple[Path, Path]:
    """A project with one file per part of the harness: (harness dir, planar_impact dir)."""
    files = ["src/planar_impact/solver.py", "harness/__init__.py",
             "harness/engines/pymunk_engine.py", "harness/scene/model.py",
             "harness/reference/event_driven.py", "harness/run/__init__.py",
             "harness/store/cache.py", "harness/run/runner.py", "harness/run/references.py",
             "harness/run/tasks.py", "harness/run/plan.py", "harness/run/point_records.py",
             "harness/run/gates.py", "harness/run/scenario_records.py",
             "harness/run/command.py",
             "harness/run/metrics.py", "harness/run/verdicts/single.py", "harness/run/history.py",
             "harness/run/records.py", "harness/scenarios/model.py",
             "harness/run/provenance.py", "harness/report/html.py",
             "harness/bench/solver.py", "harness/cli.py"]
    for name in files:
        (root / name).parent.mkdir(parents=True, exist_ok=True)
        (root / name).write_text(f"# {name}\nx = 1\n")
    return root / "harness", root / "src" / "planar_impact"


def _version(harness_dir: Path, package: Path) -> str:
    identity.code_version_of.cache_clear()
    return identity.code_version_of(
        identity.cached_code_sources(harness_dir, planar_impact_dir=package))


@pytest.mark.parametrize("edited", ["harness/report/html.py", "harness/bench/solver.py",
                                    "harness/cli.py", "harness/run/provenance.py",
                                    "harness/run/command.py"])
def test_editing_code_the_cache_does_not_depend_on_keeps_the_key(tmp_path, edited):
    harness_dir, package = _tree(tmp_path)
    before = _version(harness_dir, package)
    (tmp_path / edited).write_text("x = 2\n")
    assert _version(harness_dir, package) == before
    assert ResultCache(tmp_path, version=before).key({"a": 1}) == \
        ResultCache(tmp_path, version=_version(harness_dir, package)).key({"a": 1})


@pytest.mark.parametrize("edited", ["src/planar_impact/solver.py",
                                    "harness/engines/pymunk_engine.py", "harness/scene/model.py",
                                    "harness/reference/event_driven.py", "harness/run/tasks.py",
                                    "harness/run/point_records.py", "harness/run/runner.py",
                                    "harness/run/references.py", "harness/run/metrics.py",
                                    "harness/run/verdicts/single.py", "harness/scenarios/model.py",
                                    "harness/store/cache.py"])
def test_editing_code_a_cached_value_depends_on_changes_the_key(tmp_path, edited):
    harness_dir, package = _tree(tmp_path)
    before = _version(harness_dir, package)
    (tmp_path / edited).write_text("x = 2\n")
    assert _version(harness_dir, package) != before


def test_a_new_engine_module_changes_the_key(tmp_path):
    harness_dir, package = _tree(tmp_path)
    before = _version(harness_dir, package)
    (harness_dir / "engines" / "box2d_engine.py").write_text("y = 1\n")
    assert _version(harness_dir, package) != before


def test_a_new_engine_package_changes_the_key(tmp_path):
    # An engine may be a package (harness/engines/box2d/): its modules are hashed too.
    harness_dir, package = _tree(tmp_path)
    before = _version(harness_dir, package)
    (harness_dir / "engines" / "box2d").mkdir()
    (harness_dir / "engines" / "box2d" / "adapter.py").write_text("y = 1\n")
    assert _version(harness_dir, package) != before


def test_a_listed_source_that_is_missing_is_an_error(tmp_path):
    harness_dir, package = _tree(tmp_path)
    (harness_dir / "run" / "metrics.py").unlink()
    with pytest.raises(FileNotFoundError, match="metrics.py"):
        _version(harness_dir, package)


def test_every_listed_source_exists_in_this_checkout():
    for source in identity.cached_code_sources():
        assert source.exists(), source
