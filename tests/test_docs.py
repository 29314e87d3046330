"""The examples users copy first must run: the package docstring and the solver snippet of
docs/usage.md."""

from __future__ import annotations

import doctest
import re
from pathlib import Path

import planar_impact


def test_package_docstring_example_runs():
    failures, tried = doctest.testmod(planar_impact, verbose=False)
    assert tried > 0 and failures == 0


def test_readme_solver_snippet_runs_and_prints_what_it_says():
    readme = (Path(__file__).parent.parent / "docs/usage.md").read_text()
    snippet = re.search(r"## The solver in five lines\n\n```python\n(.*?)```", readme,
                        re.S).group(1)
    namespace: dict = {}
    exec(compile(snippet.replace("print(", "_ = ("), "README", "exec"), namespace)
    result = namespace["result"]
    assert result.collision_type == 3
    assert round(result.energy_change, 3) == -0.341


def test_readme_layout_table_matches_the_tree():
    """Every path in the layout table (docs/usage.md) exists, and every package of ``harness/`` and
    every top-level folder of the repository is in the table."""
    root = Path(__file__).parent.parent
    readme = (root / "docs/usage.md").read_text()
    table = re.search(r"## Layout\n(.*?)\n## ", readme, re.S).group(1)
    listed = set(re.findall(r"^\| `([^`]+)`", table, re.M))
    missing = sorted(path for path in listed if not (root / path).exists())
    assert not missing, f"the layout table lists paths that do not exist: {missing}"
    packages = {f"harness/{p.parent.name}/" for p in (root / "harness").glob("*/__init__.py")}
    folders = {"src/planar_impact/", "scenarios/", "populations/", "docs/", "reports/", "tests/"}
    unlisted = sorted((packages | folders) - listed)
    assert not unlisted, f"the layout table misses {unlisted}"
