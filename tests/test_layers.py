"""The layers of the code, enforced: a module imports only from its own layer or below, at
module level or inside a function alike (an import inside a function is still a dependency).

The layers, lowest first (README, 'Layout'):

0. ``planar_impact`` -- the theory, numpy only;
1. ``harness.bounds``, ``collector``, ``processes``, ``inputs``, ``laws`` -- shared tools;
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

There is no exception: any import against the order fails this test, which names it.

An import of the project's own modules sits at module level (an import inside a function hides
a dependency from the reader and kept cycles importable), except in the few modules of
:data:`INNER_IMPORTS_ALLOWED`, each with its reason; third-party optional dependencies
(matplotlib, the engines' bindings, scipy, dask, pyarrow, pandas) may be imported late.
"""

from __future__ import annotations

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
LAYERS = (
    ("planar_impact",),
    ("harness.bounds", "harness.collector", "harness.processes", "harness.inputs",
     "harness.laws"),
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
        for candidate in candidates:  # every name: `from X import a, b` may import two modules
            while candidate and candidate not in known:
                candidate = candidate.rpartition(".")[0]
            if candidate and candidate not in (name, "harness"):
                targets.add(candidate)
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
                against.append(f"{name} imports {target}")
    assert not against, "imports against the layers:\n" + "\n".join(against)


#: Packages and modules that import at module level only: an import inside a function hides a
#: dependency from the reader (and kept cycles importable). Optional dependencies are the one
#: reason to import late; none of these has any.
MODULE_LEVEL_IMPORTS_ONLY = ("harness.store", "harness.scenarios", "harness.engines.facts",
                             "harness.scene.features", "harness.run.command",
                             "harness.run.runner", "harness.run.plan", "harness.run.tasks",
                             "harness.run.point_records", "harness.run.scenario_records",
                             "harness.run.gates")


def test_these_import_at_module_level_only():
    late = []
    for name, path in sorted(modules().items()):
        if not any(name == member or name.startswith(member + ".")
                   for member in MODULE_LEVEL_IMPORTS_ONLY):
            continue
        for function in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(function, (ast.FunctionDef, ast.AsyncFunctionDef)):
                late += [f"{name}:{node.lineno} in {function.name}()"
                         for node in ast.walk(function)
                         if isinstance(node, (ast.Import, ast.ImportFrom))]
    assert not late, "imports inside functions:\n" + "\n".join(late)


#: Where an import of a project module may sit inside a function, and why. Nothing else:
#: an import of ``harness`` or ``planar_impact`` inside a function anywhere else fails
#: :func:`test_project_modules_are_imported_at_module_level`.
#: Empty now: every project import sits at module level.
INNER_IMPORTS_ALLOWED: dict[str, str] = {}

#: The modules (exactly these, not their submodules) that import by name at run time
#: (``importlib.import_module``), each with its reason: the command dispatcher is the one
#: exception for the project's own modules; the others import optional dependencies.
DYNAMIC_IMPORTS_ALLOWED: dict[str, str] = {
    "harness.cli": "the command dispatcher: imports only the chosen command's module "
                   "(COMMANDS), so `impact-harness --help` imports no command",
    "harness.engines": "the engine registry: an adapter is imported when its engine is "
                       "loaded, since each needs an optional binding (pymunk, pybullet, "
                       "mujoco, Box2D) that may be absent",
    "harness.engines.quiet": "import_quietly: imports an engine's optional binding by name "
                             "with the C library's start-up output dropped",
}


def allowed(name: str, table: dict[str, str]) -> bool:
    return any(name == member or name.startswith(member + ".") for member in table)


def late_project_imports(name: str, path: Path) -> list[str]:
    """``name:line in function()`` for each import of a project module inside a function of
    ``path``, and each ``importlib.import_module``/``__import__`` call inside one."""
    late = []
    for function in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if not isinstance(function, (ast.FunctionDef, ast.AsyncFunctionDef)):
            continue
        for node in ast.walk(function):
            if isinstance(node, ast.Import):
                project = any(alias.name.split(".")[0] in ("harness", "planar_impact")
                              for alias in node.names)
            elif isinstance(node, ast.ImportFrom):
                project = bool(node.level) or (node.module or "").split(".")[0] in (
                    "harness", "planar_impact")
            elif isinstance(node, ast.Call):
                called = ast.unparse(node.func)
                project = (called in ("importlib.import_module", "import_module", "__import__")
                           and name not in DYNAMIC_IMPORTS_ALLOWED)
            else:
                continue
            if project:
                late.append(f"{name}:{node.lineno} in {function.name}()")
    return sorted(set(late))


def test_project_modules_are_imported_at_module_level():
    late = []
    for name, path in sorted(modules().items()):
        if not allowed(name, INNER_IMPORTS_ALLOWED):
            late += late_project_imports(name, path)
    assert not late, ("imports of the project's modules inside functions (lift them; a cycle "
                      "this makes is the defect: move the shared thing down a layer):\n"
                      + "\n".join(late))


def test_the_allowed_inner_imports_name_modules_that_exist():
    known = modules()
    for table in (INNER_IMPORTS_ALLOWED, DYNAMIC_IMPORTS_ALLOWED):
        for member, reason in table.items():
            assert member in known and reason, member


def test_the_late_import_check_sees_an_inner_and_a_dynamic_import(tmp_path):
    module = tmp_path / "probe.py"
    module.write_text("import importlib\n\n\ndef f():\n    from . import views\n"
                      "    import harness.scene\n    return importlib.import_module('x')\n")
    assert late_project_imports("harness.report.probe", module) == [
        "harness.report.probe:5 in f()", "harness.report.probe:6 in f()",
        "harness.report.probe:7 in f()"]
    assert late_project_imports("harness.cli", module) == [
        "harness.cli:5 in f()", "harness.cli:6 in f()"]


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


def test_the_check_sees_every_module_of_one_from_import(tmp_path):
    # `from X import a, b` imports both: the check once stopped at the first that resolved
    module = tmp_path / "probe.py"
    module.write_text("from harness.store import cache, packs\n"
                      "from harness import bounds, report\n")
    known = {**modules(), "harness.scene.probe": module}
    found = imports("harness.scene.probe", module, known)
    assert {"harness.store.cache", "harness.store.packs", "harness.bounds",
            "harness.report"} <= found
