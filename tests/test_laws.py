"""The law registry (harness/laws.py): one entry per law of ``planar_impact.LAWS``, read
everywhere; no other module keeps its own list of the laws; each law keeps what its entry
promises on broad random families."""

from __future__ import annotations

import ast
import dataclasses
import json
import re
from pathlib import Path

import numpy as np
import pytest

import planar_impact as pi
from harness import laws
from harness.report import compare, findings, table3, views
from harness.report.experiments import LAW_COLOURS, LAW_LINES
from harness.scenarios import cli as scenarios_cli
from harness.scenarios.schema import LAW_TYPES
from harness.scene.random_problems import random_problems
from planar_impact import contact_space, fastpath, law_table
from planar_impact.process import PROCESS_LAWS
from planar_impact.solver import energy_gain_decision

ROOT = Path(__file__).resolve().parents[1]
# The one place allowed to spell out every law (the solver's names are planar_impact's own).
REGISTRY_FILE = ROOT / "harness" / "laws.py"


def test_the_registry_holds_each_solved_law_once():
    assert sorted(laws.LAW_NAMES) == sorted(pi.LAWS)
    assert len(set(laws.LAW_NAMES)) == len(laws.REGISTRY)
    assert laws.law("poisson").label == "Poisson"
    with pytest.raises(ValueError, match=r"unknown law 'hertz'; allowed: poisson, stronge"):
        laws.law("hertz")
    assert laws.law_order("no-such-law") == len(laws.LAW_NAMES)  # unknown names sort last
    # A law drawn as a path of the impulse process (Table 3's figure walks it) is one the
    # process walks.
    assert {entry.name for entry in laws.REGISTRY if entry.process} == set(PROCESS_LAWS)


def test_the_registry_presents_the_laws_of_the_solvers_table():
    # planar_impact's one table of laws and solvers is pi.LAWS; the harness's registry
    # presents exactly those laws, and each law's reverse-sliding types (the solver's
    # q > 0 check) are among the types its registry entry says it reports.
    assert pi.LAWS == tuple(law_table.LAW_TABLE)
    assert set(laws.LAW_NAMES) == set(law_table.LAW_TABLE)
    for name, solvers in law_table.LAW_TABLE.items():
        assert callable(solvers.rows) and callable(solvers.row), name
        assert solvers.reverse_types, name
        assert set(solvers.reverse_types) <= set(laws.law(name).collision_types), name


def test_each_law_s_two_solvers_give_one_answer_in_its_types():
    # Both paths of every law of the table (solve_batch: its rows solver; fastpath.law_answer:
    # its scalar solver) agree bit for bit, in the registry's types; tests/theory/
    # test_fastpath.py holds them to it over broad families.
    rng = np.random.default_rng(36)
    size = 64
    rows = {"mnn": rng.uniform(0.5, 2.0, size), "mnt": rng.uniform(-0.6, 0.6, size),
            "mtt": rng.uniform(0.8, 2.0, size), "vn": -rng.uniform(0.1, 2.0, size),
            "vt": rng.uniform(0.0, 3.0, size)}
    for name in law_table.LAW_TABLE:
        batch = pi.solve_batch(**rows, mu=0.4, e=0.6, law=name)
        solved = 0
        for i in np.flatnonzero(batch.status == 0):
            row = [float(rows[key][i]) for key in ("mnn", "mnt", "mtt", "vn", "vt")]
            delta = row[0] * row[2] - row[1] * row[1]
            answer = fastpath.law_answer(name, *row, 0.4, 0.6, delta)
            assert answer is not None, (name, i)
            assert answer[0] == batch.normal_impulse[i], (name, i)
            assert answer[1] == batch.tangential_impulse[i], (name, i)
            assert answer[5] in laws.law(name).collision_types, (name, i)
            solved += 1
        assert solved > size // 2, name


def test_a_law_named_without_its_solvers_is_refused_not_solved_as_another(monkeypatch):
    # Both dispatch points once ended in an `else` that ran Stronge's process: a law added to
    # pi.LAWS without its branches was solved as Stronge, silently. LAWS is now the table's
    # names, but a name that reaches a path without its table entry still ends in an error.
    monkeypatch.setattr(contact_space, "LAWS", (*pi.LAWS, "unbranched"))
    problem = dict(mass_matrix=np.eye(2), wn=np.array([1.0, 0.0]), wt=np.array([0.0, 1.0]),
                   u=np.array([-1.0, 0.5]), mu=0.3, e=0.5)
    with pytest.raises(NotImplementedError, match=r"law 'unbranched' is in planar_impact's "
                                                  r"LAWS but fastpath.law_answer finds no "
                                                  r"solver of it in law_table.LAW_TABLE"):
        pi.solve(**problem, law="unbranched")
    batch = {"mnn": np.array([1.0]), "mnt": np.array([0.0]), "mtt": np.array([1.0]),
             "vn": np.array([-1.0]), "vt": np.array([0.5]), "mu": 0.3, "e": 0.5}
    with pytest.raises(NotImplementedError, match=r"contact_space.contact_space_solution finds "
                                                  r"no solver"):
        pi.solve_batch(**batch, law="unbranched")


def test_every_place_reads_the_registry():
    assert views.LAW_ORDER == compare.LAWS == findings.ENERGY_LAWS == laws.LAW_NAMES
    assert views.HEADLINE_LAWS == laws.HEADLINE_LAWS
    for entry in laws.REGISTRY:
        assert views.LAW_STYLE[entry.name] == (entry.colour, entry.line, entry.label)
        assert LAW_COLOURS[entry.name] == entry.colour and LAW_LINES[entry.name] == entry.line
        assert LAW_TYPES[entry.name] == entry.collision_types
        if entry.name in table3.LAW_STYLES:
            assert table3.LAW_STYLES[entry.name] == (entry.colour, entry.line, entry.marker)
    template = scenarios_cli.scenario_template("check", "disk", False)
    assert "# laws = " + json.dumps(list(pi.LAWS)) in template  # the solver's names


# Per-law literals kept on purpose, each with its reason: (file, the laws it keys) -> why.
KEPT = {("harness/report/table3.py", ("newton", "poisson", "stronge")):
        "the titles of the paper's Table 3 row groups as the paper prints them (its three "
        "hypotheses, 'stronge' being its mapping), not the harness's labels",
        ("harness/report/table3.py", ("poisson", "stronge", "stronge-paper")):
        "Routh's diagram picks the Table 3 rows of the paper's Stronge block and walks Poisson's "
        "process at e_i for the paper's Stronge mapping: how that mapping is drawn, not a "
        "list of the laws",
        ("harness/report/stated.py", ("newton", "poisson", "stronge-paper")):
        "the three laws the paper's two-contact proposal serves, with the shorter labels "
        "docs/multi-contact.md's stated table prints (found by the stricter detector; left to "
        "the report's owner: reading the registry's labels would change that table)"}


_WORD = re.compile(r"[A-Za-z][\w-]*")  # a law's name is a word of letters, digits and '-'


def _law_literals(tree: ast.AST) -> list[tuple[int, tuple[str, ...], str]]:
    """Literals that copy the law list: a collection holding every law, or every law but one
    (a copy made before the last law was added), a per-law table (a dict, or a list of
    pairs, keyed by three or more laws), a text (a template, a message) spelling every law
    out, or a function that dispatches on three or more laws by name."""
    every = set(laws.LAW_NAMES)
    found = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Dict):
            keys = {key.value for key in node.keys if isinstance(key, ast.Constant)} & every
            if len(keys) >= 3:
                found.append((node.lineno, tuple(sorted(keys)), "a table keyed by laws"))
        elif isinstance(node, (ast.Tuple, ast.List, ast.Set)):
            names = _names(node.elts) & every
            firsts = _names(item.elts[0] for item in node.elts
                            if isinstance(item, (ast.Tuple, ast.List)) and item.elts) & every
            if len(names) >= len(every) - 1:
                what = "every law listed" if names == every else "every law but one listed"
                found.append((node.lineno, tuple(sorted(names)), what))
            elif len(firsts) >= 3:
                found.append((node.lineno, tuple(sorted(firsts)), "a table keyed by laws"))
        elif isinstance(node, ast.Constant) and isinstance(node.value, str):
            if every <= set(_WORD.findall(node.value)):
                found.append((node.lineno, tuple(sorted(every)), "every law in a text"))
        elif isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            compared = set()
            for inner in ast.walk(node):
                if isinstance(inner, ast.Compare):
                    for side in (inner.left, *inner.comparators):
                        compared |= _names([side] if isinstance(side, ast.Constant)
                                           else getattr(side, "elts", ()))
            if len(compared & every) >= 3:
                found.append((node.lineno, tuple(sorted(compared & every)),
                              f"a dispatch on laws by name in {node.name}()"))
    return found


def _names(nodes) -> set:
    return {node.value for node in nodes
            if isinstance(node, ast.Constant) and isinstance(node.value, str)}


def test_no_module_keeps_its_own_copy_of_the_laws():
    copies = []
    for path in sorted((ROOT / "harness").rglob("*.py")):
        if path == REGISTRY_FILE:
            continue
        where = str(path.relative_to(ROOT))
        copies += [f"{where}:{line}: {what} {list(names)}"
                   for line, names, what in _law_literals(ast.parse(path.read_text("utf-8")))
                   if (where, names) not in KEPT]
    assert not copies, "read harness.laws instead: " + "; ".join(copies)
    # The results schema does not enumerate the laws (a record's law is a string there, so a
    # results file of a newer law still validates): it keeps no copy to fall out of step.
    schema = (ROOT / "docs" / "results.schema.json").read_text("utf-8")
    assert not all(f'"{name}"' in schema for name in laws.LAW_NAMES)


def test_the_copy_detector_finds_a_copy():
    # The test above can fail: a module with its own law order, style table or per-law
    # branches is found. Written from the registry, so that adding a law leaves it right.
    every, first, second, third = (list(laws.LAW_NAMES), *laws.LAW_NAMES[:3])
    source = "\n".join([
        f"ORDER = {tuple(every)!r}",  # 1
        f"STYLE = {dict.fromkeys(every[:3], 1)!r}",  # 2
        f"PAIR = {(first, second)!r}",  # 3: two laws, a choice of its own (not flagged)
        f"TEXT = {'laws = ' + json.dumps(every[::-1])!r}",  # 4
        f"STALE = {every[:-1]!r}",  # 5: the list from before the last law was added
        f"WORDS = {' '.join(every)!r}.split()",  # 6
        f"PAIRS = dict({[(name, 0) for name in every[:3]]!r})",  # 7
        "def colour(law):",  # 8
        f"    if law == {first!r}:",
        "        return 1",
        f"    return 2 if law in ({second!r}, {third!r}) else 3",
        "def label(law):",  # 12: two laws, not a dispatch on the list
        f"    return 1 if law == {first!r} else 2 if law == {second!r} else 3",
    ]) + "\n"
    assert sorted(line for line, _, _ in _law_literals(ast.parse(source))) == [1, 2, 4, 5, 6,
                                                                               7, 8]


#: Where a module may compare a value with a law's name, each with its reason. Everywhere
#: else in src/planar_impact/ and harness/ a law's properties are read from its line of
#: ``planar_impact.law_table.LAW_TABLE`` or its :data:`harness.laws.REGISTRY` entry (or a
#: named role such as ``verdicts.ENGINE_LAW``), so a law added there is solved and shown by
#: the same code as the others. A folder (ending in /) holds for every module under it.
NAME_BRANCHES_KEPT = {
    "src/planar_impact/process.py": "the independent method: the impulse process walked "
    "with each law's own rule for the end of a phase (Newton's v_n target, Poisson's "
    "(1 + e) I_nc, Stronge's energy), the laws' definitions themselves",
    "src/planar_impact/simultaneous/": "the m-contact laws (docs/multi-contact.md): a set of "
    "their own whose names repeat some of these",
    "harness/report/": "what the report draws of a particular law: the paper's Table 3 rows "
    "and its Stronge mapping, Routh's diagram, the engines' law beside the headline ones",
    "harness/bench/": "what is timed per law and its independent check (newton-lcp has no "
    "process to walk, the paper's mapping walks Poisson's at e_i)",
    "harness/experiments/": "Poisson against Stronge on the measured drops, the question "
    "docs/experiments.md asks of those two laws",
    "harness/scenarios/checks.py": "a scenario's expected case is Table 1's row, Poisson's",
}


def _name_branches(tree: ast.AST) -> list[tuple[int, str]]:
    """Comparisons with a law's name: ``x == "law"``, ``x != "law"``, ``x in ("law", ...)``,
    ``"law" in x`` and ``case "law":`` (the name as a literal on either side)."""
    every = set(pi.LAWS)
    found = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Compare):
            sides = [node.left, *node.comparators]
            names = set().union(*(_names([side] if isinstance(side, ast.Constant)
                                         else getattr(side, "elts", ())) for side in sides))
            if names & every:
                found.append((node.lineno, ast.unparse(node)))
        elif isinstance(node, ast.MatchValue) and _names([node.value]) & every:
            found.append((node.lineno, f"case {ast.unparse(node.value)}"))
    return found


def _kept_branches(where: str) -> bool:
    return any(where == kept or (kept.endswith("/") and where.startswith(kept))
               for kept in NAME_BRANCHES_KEPT)


def test_no_module_branches_on_a_laws_name():
    """``solve`` and the fast path once reported ``restitution_poisson`` by ``law ==
    "newton-lcp"``: now a field of the law table (``poisson_restitution``)."""
    branches = []
    for folder in (ROOT / "src" / "planar_impact", ROOT / "harness"):
        for path in sorted(folder.rglob("*.py")):
            where = str(path.relative_to(ROOT))
            if path == REGISTRY_FILE or _kept_branches(where):
                continue
            branches += [f"{where}:{line}: {text}"
                         for line, text in _name_branches(ast.parse(path.read_text("utf-8")))]
    assert not branches, ("read the law's line of law_table.LAW_TABLE or its harness.laws "
                          "entry instead: " + "; ".join(branches))
    # every exemption names something that exists and still branches (no stale reason)
    for kept in NAME_BRANCHES_KEPT:
        paths = ([ROOT / kept] if not kept.endswith("/")
                 else sorted((ROOT / kept).rglob("*.py")))
        assert any(_name_branches(ast.parse(path.read_text("utf-8"))) for path in paths), kept


def test_the_name_branch_detector_finds_a_branch():
    first, second, last = pi.LAWS[0], pi.LAWS[1], pi.LAWS[-1]
    source = "\n".join([
        f"lcp = law == {last!r}",  # 1
        f"e = None if {last!r} == law else 1",  # 2
        f"if law != {first!r}: pass",  # 3
        f"ok = law in ({first!r}, {second!r})",  # 4
        f"gain = gains.get({last!r}) if {last!r} in gains else None",  # 5
        "match law:",  # 6
        f"    case {second!r}: pass",  # 7
        "same = law == other_law",  # 8: two variables, no name
        f"label = {{{first!r}: 1}}[law]",  # 9: a lookup, not a comparison
        "text = law == 'stronge-pape'",  # 10: not a law's name
    ]) + "\n"
    assert sorted(line for line, _ in _name_branches(ast.parse(source))) == [1, 2, 3, 4, 5, 7]
    assert _kept_branches("harness/report/views.py") and not _kept_branches("harness/run/x.py")


@pytest.mark.kernel_sensitive  # decisions on 20,000 solutions, outside their derived band
@pytest.mark.parametrize("entry", laws.REGISTRY, ids=lambda entry: entry.name)
def test_each_law_keeps_its_promises_on_random_problems(entry):
    # 20,000 seeded problems over every sign of m_nt and v_t, μ in [0, 2], e in [0, 1]
    # (harness.scene.random_problems: the findings' family).
    problems = random_problems(20_000, seed=36)
    batch = pi.solve_batch(**problems, law=entry.name)
    solved = batch.status == 0
    assert solved.mean() > 0.9
    normal, tangential = batch.normal_impulse[solved], batch.tangential_impulse[solved]
    mu = np.broadcast_to(problems["mu"], batch.status.shape)[solved]
    scale = np.abs(normal) + np.abs(tangential)
    if entry.in_cone:
        assert (normal >= -1e-12 * scale).all()
        assert (np.abs(tangential) <= mu * normal + 1e-9 * scale).all()
    vn = np.broadcast_to(problems["vn"], batch.status.shape)[solved]
    vt = np.broadcast_to(problems["vt"], batch.status.shape)[solved]
    mnn, mnt, mtt = (np.broadcast_to(problems[k], batch.status.shape)[solved]
                     for k in ("mnn", "mnt", "mtt"))
    # The solver's decision (planar_impact.solver.energy_gain_decision): the bar
    # ENERGY_GAIN_BAR of the work, with (A29)'s derived rounding band around it
    # (γ_7 of its terms, test_solver_properties checks it against exact arithmetic). Inside
    # the band the flag could flip on another CPU's rounding: no row may lie there
    # (measured: every row of every law at least 5.2 bands away; the band exceeds the bar
    # itself, 1.7e-12 of the work, on the worst-conditioned rows).
    gained, at_bar = energy_gain_decision(batch.energy_change[solved], normal, tangential,
                                          vn, vt, mnn, mnt, mtt)
    assert not at_bar.any(), np.flatnonzero(at_bar)
    if entry.no_energy_gain:
        assert not gained.any()
    else:  # the promise is withheld because the law does gain energy (README's findings)
        assert gained.any()
    assert set(np.unique(batch.collision_type[solved]).tolist()) <= set(entry.collision_types)


def test_a_broken_promise_is_named_on_the_solution_and_in_the_runner(monkeypatch):
    # Newton's law gains energy on some problems (README's findings): held to Poisson's
    # promise, that solution is named; Poisson's own solution breaks nothing.
    problems = random_problems(2_000, seed=7)
    batch = pi.solve_batch(**problems, law="newton")
    row = int(np.flatnonzero((batch.status == 0) & (batch.energy_change > 1e-6))[0])
    one = {name: float(np.broadcast_to(values, batch.status.shape)[row])
           for name, values in problems.items()}
    mass = np.array([[one["mnn"], one["mnt"]], [one["mnt"], one["mtt"]]])
    problem = dict(mass_matrix=np.linalg.inv(mass), wn=np.array([1.0, 0.0]),
                   wt=np.array([0.0, 1.0]), u=np.array([one["vn"], one["vt"]]))
    newton = pi.solve(**problem, mu=one["mu"], e=one["e"], law="newton")
    assert newton.energy_gained and laws.broken_promises("newton", newton, one["mu"]) == []
    strict = {entry.name: (entry if entry.name != "newton" else
                           dataclasses.replace(entry, no_energy_gain=True))
              for entry in laws.REGISTRY}
    monkeypatch.setattr(laws, "_BY_NAME", strict)
    broken = laws.broken_promises("newton", newton, one["mu"])
    assert len(broken) == 1 and broken[0].startswith("newton promises no energy gain but gains")
    poisson = pi.solve(**problem, mu=one["mu"], e=one["e"], law="poisson")
    assert laws.broken_promises("poisson", poisson, one["mu"]) == []
    outside = dataclasses.replace(poisson, tangential_impulse=2 * one["mu"] * poisson.normal_impulse
                                  + 1.0)
    assert "promises an impulse in the friction cone" in laws.broken_promises(
        "poisson", outside, one["mu"])[0]
    # The runner checks every law solution it keeps: a broken promise is the record's error.
    from harness.run import point_records
    from harness.scenarios import load_scenario

    scenario = load_scenario(ROOT / "scenarios" / "disk-oblique.toml")
    monkeypatch.setattr(point_records, "broken_promises",
                        lambda name, result, mu: ["a promise of the test"] if name == "newton"
                        else [])
    records = point_records.point_records(scenario, scenario.point_list()[0], [], cache=None)
    statuses = {record.law: record.status for record in records}
    assert statuses["newton"] == "error: a promise of the test"
    assert {status for law, status in statuses.items() if law != "newton"} == {"ok"}
