"""The examples users copy first must run: the package docstring and the README's snippet."""

from __future__ import annotations

import doctest
import re
from pathlib import Path

import planar_impact


def test_package_docstring_example_runs():
    failures, tried = doctest.testmod(planar_impact, verbose=False)
    assert tried > 0 and failures == 0


def test_readme_solver_snippet_runs_and_prints_what_it_says():
    readme = (Path(__file__).parent.parent / "README.md").read_text()
    snippet = re.search(r"## The solver in five lines\n\n```python\n(.*?)```", readme, re.S).group(1)
    namespace: dict = {}
    exec(compile(snippet.replace("print(", "_ = ("), "README", "exec"), namespace)
    result = namespace["result"]
    assert result.collision_type == 3
    assert round(result.energy_change, 3) == -0.341
