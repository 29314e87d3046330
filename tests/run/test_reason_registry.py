"""Verdict reasons have one registry, ``harness.run.verdicts.REASONS`` (name -> meaning, in
the order a run's status is named by): every reason the judges give is registered there,
and docs/verdicts.md's table lists exactly those, in that order."""

from __future__ import annotations

import ast
import re
from pathlib import Path

from harness.run.verdicts import REASONS, REMARKS

ROOT = Path(__file__).resolve().parents[2]
VERDICTS = ROOT / "harness" / "run" / "verdicts"


def _given_names() -> set[str]:
    """Reason names the judges spell out: ``Reason("name", ...)`` and the batched judge's
    ``fails["name"]``."""
    names = set()
    for path in VERDICTS.glob("*.py"):
        for node in ast.walk(ast.parse(path.read_text("utf-8"))):
            if (isinstance(node, ast.Call) and getattr(node.func, "id", None) == "Reason"
                    and node.args and isinstance(node.args[0], ast.Constant)):
                names.add(node.args[0].value)
            if (isinstance(node, ast.Subscript) and getattr(node.value, "id", None) == "fails"
                    and isinstance(node.slice, ast.Constant)):
                names.add(node.slice.value)
    return names


def test_every_reason_given_is_registered():
    given = _given_names()
    assert given, "the scan found no reason: it reads nothing"
    assert given <= set(REASONS) | set(REMARKS), sorted(given - set(REASONS) - set(REMARKS))
    assert not set(REASONS) & set(REMARKS)
    assert all(isinstance(text, str) and text for text in (*REASONS.values(),
                                                          *REMARKS.values()))


def test_the_docs_table_lists_the_registered_reasons_in_order():
    text = (ROOT / "docs" / "verdicts.md").read_text("utf-8")
    table = text[text.index("| reason | fails when | measured against |"):]
    table = table[:table.index("\n\n")]
    listed = [name for line in table.splitlines()[2:]
              for name in re.findall(r"`([a-z-]+)`", line.split("|")[1])]
    assert listed == list(REASONS)
