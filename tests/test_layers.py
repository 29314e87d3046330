"""The layers of the code, enforced: a module imports only from its own layer or below, at
module level or inside a function alike (an import inside a function is still a dependency).

The layers, lowest first (README, 'Layout'):

0. ``planar_impact`` -- the theory, numpy only;
1. ``harness.bounds``, ``collector``, ``processes``, ``inputs`` -- shared tools;
2. ``harness.store`` -- storage and identity: atomic files, the result cache;
3. ``harness.scene`` -- the impact to simulate;
4. ``harness.engines``, ``harness.reference`` -- engines behind one contract, reference
   answers the single-contact laws do not give;
5. ``harness.scenarios`` -- scenario files to checked scenarios;
6. ``harness.run`` -- runs, records, verdicts;
7. ``harness.plotting`` -- figures shared by the survey and the report;
8. ``harness.survey``, ``harness.experiments``, ``harness.stress``;
9. ``harness.report``, ``harness.bench``;
10. commands on top: ``harness.suite``, ``harness.validate``, ``harness.cli``.

One exception is written down, with why, in :data:`ALLOWED_UPWARD`; any other import
against the order fails this test, which names it.
"""

from __future__ import annotations

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
LAYERS = (
    ("planar_impact",),
    ("harness.bounds", "harness.collector", "harness.processes", "harness.inputs"),
    ("harness.store",),
    ("harness.scene",),
    ("harness.engines", "harness.reference"),
    ("harness.scenarios",),
    ("harness.run",),
    ("harness.plotting",),
    ("harness.survey", "harness.experiments", "harness.stress"),
    ("harness.report", "harness.bench"),
    ("harness.suite", "harness.validate", "harness.cli"),
)
#: ``(importing package, imported module)`` pairs allowed against the order. The scenario
#: checks keep the point checks that passed in the run's cache (``run.cache``), ask the
#: engines' facts recorded there (``run.engine_facts``) and
#: judge a second feature's strike with the run's verdict geometry (``run.verdicts``): the
#: storage and the verdicts' shape features still live in ``harness.run`` (issue 26: a
#: storage layer below the scenarios, the shape features into ``harness.scene``).
ALLOWED_UPWARD = {
    ("harness.scenarios", "harness.run.engine_facts"),
    ("harness.scenarios", "harness.run.verdicts"),
}


def modules() -> dict[str, Path]:
    """Every module of ``harness`` and ``planar_impact``, by dotted name."""
    found = {}
    for package, base in (("harness", ROOT / "harness"),
                          ("planar_impact", ROOT / "src" / "planar_impact")):
        for path in base.rglob("*.py"):
            parts = (package, *path.relative_to(base).with_suffix("").parts)
            name = ".".join(parts[:-1] if parts[-1] == "__init__" else parts)
            found[name] = path
    return found


def imports(name: str, path: Path, known: dict[str, Path]) -> set[str]:
    """The project's modules ``name`` imports, anywhere in the file."""
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    targets = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Import):
            candidates = [alias.name for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                parts = package.split(".")[:len(package.split(".")) - node.level + 1]
                base = ".".join([*parts, *([node.module] if node.module else [])])
            candidates = [f"{base}.{alias.name}" for alias in node.names] + [base]
        else:
            continue
        for candidate in candidates:
            while candidate and candidate not in known:
                candidate = candidate.rpartition(".")[0]
            if candidate and candidate not in (name, "harness"):
                targets.add(candidate)
                break
    return targets


def layer_of(name: str) -> int:
    for number, members in enumerate(LAYERS):
        if any(name == member or name.startswith(member + ".") for member in members):
            return number
    raise AssertionError(f"{name} is in no layer: add it to LAYERS (and to the README)")


def test_every_import_goes_down_or_across():
    known = modules()
    against = []
    for name, path in sorted(known.items()):
        if name == "harness":
            continue
        for target in sorted(imports(name, path, known)):
            if layer_of(target) > layer_of(name):
                package = next(member for members in LAYERS for member in members
                               if name == member or name.startswith(member + "."))
                if (package, target) not in ALLOWED_UPWARD:
                    against.append(f"{name} imports {target}")
    assert not against, "imports against the layers:\n" + "\n".join(against)


def test_the_exceptions_are_still_needed():
    # an exception no module uses any more is removed from the list, not kept "just in case"
    known = modules()
    used = {(package, target) for package, target in ALLOWED_UPWARD
            for name, path in known.items() if name.startswith(package + ".")
            and target in imports(name, path, known)}
    assert used == ALLOWED_UPWARD


def test_the_theory_library_imports_numpy_and_the_standard_library_only():
    import sys

    allowed = {"numpy", "planar_impact", "__future__"} | set(sys.stdlib_module_names)
    foreign = []
    for path in (ROOT / "src" / "planar_impact").rglob("*.py"):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            names = ([alias.name for alias in node.names] if isinstance(node, ast.Import)
                     else [node.module] if isinstance(node, ast.ImportFrom) and not node.level
                     else [])
            foreign += [f"{path.name}: {n}" for n in names if n.split(".")[0] not in allowed]
    assert not foreign, foreign


def test_the_check_sees_an_import_inside_a_function(tmp_path):
    module = tmp_path / "probe.py"
    module.write_text("def f():\n    from harness.report import views\n")
    known = {**modules(), "harness.scene.probe": module}
    assert "harness.report.views" in imports("harness.scene.probe", module, known)
    assert layer_of("harness.report.views") > layer_of("harness.scene.probe")
