"""Every number the README and docs/ state about results equals what its command gives today
(harness.report.stated); and the marking, check and rewrite themselves.

The ``library`` source (the validation suite's counts) is checked in
tests/run/test_suite_invariants.py, on the run of the library that module already makes.
"""

from __future__ import annotations

from argparse import Namespace

import pytest

from harness.report import findings_command, stated

STATED = [s for path in stated.texts() for s in stated.stated_in(path)]
COMPUTED_HERE = sorted(set(stated.SOURCES) - {"library"})


def test_every_marker_names_a_known_source_and_every_source_is_stated():
    assert {s.source for s in STATED} == set(stated.SOURCES)


@pytest.mark.parametrize("source", COMPUTED_HERE)
def test_the_stated_numbers_are_what_the_command_gives(source, load_or_skip):
    """Regenerates the source's numbers and compares them with the text; on a failure run
    ``impact-harness findings --write --only SOURCE`` and review the change."""
    if source == "mujoco-gain":
        load_or_skip("mujoco")
    if source == "experiments":  # the Fazeli drops, never committed; a row per engine
        import os

        from harness.engines import ENGINE_NAMES
        from harness.experiments import registry

        if not os.environ.get(registry.FAZELI_2017.env_var):
            pytest.skip(f"the Fazeli et al. 2017 files are not redistributable: set "
                        f"{registry.FAZELI_2017.env_var} to a copy to check these numbers")
        for name in ENGINE_NAMES:
            load_or_skip(name)
    if source in ("ellipse-contact", "stress"):  # a row per engine
        from harness.engines import ENGINE_NAMES

        for name in ENGINE_NAMES:
            load_or_skip(name)
    numbers = stated.compute([source])
    assert stated.differences([s for s in STATED if s.source == source], numbers) == []


TEXT = """The law gains in 2.25%<!-- stated findings.share -->
of 1,000<!-- stated findings.count -->.

<!-- begin stated findings.table -->

| a | b |
|---|---|
| 1 | 2 |

<!-- end stated -->
"""


def test_check_finds_a_stale_number_and_write_replaces_only_the_marked_ones(tmp_path):
    path = tmp_path / "marked.txt"
    path.write_text(TEXT)
    found = stated.stated_in(path)
    assert [(s.key, s.value, s.block) for s in found] == [
        ("findings.share", "2.25%", False), ("findings.count", "1,000", False),
        ("findings.table", "| a | b |\n|---|---|\n| 1 | 2 |", True)]
    numbers = {"findings.share": "2.31%", "findings.count": "1,000",
               "findings.table": "| a |\n|---|"}
    wrong = stated.differences(found, numbers)
    assert len(wrong) == 2 and "findings.share states '2.25%'" in wrong[0] and "2.31%" in wrong[0]
    assert "findings.table" in wrong[1]
    assert stated.rewrite(path, numbers)
    assert path.read_text() == TEXT.replace("2.25%", "2.31%").replace(
        "| a | b |\n|---|---|\n| 1 | 2 |", "| a |\n|---|")
    assert stated.differences(stated.stated_in(path), numbers) == []
    assert not stated.rewrite(path, numbers)  # nothing left to change


def test_a_key_the_source_does_not_give_is_reported():
    (number,) = [s for s in STATED if s.key == "table3.printed"][:1]
    renamed = stated.Stated(number.path, number.line, "table3.cells", number.value, False)
    (line,) = stated.differences([renamed], {"table3.printed": number.value})
    assert "table3.cells is not a number" in line


@pytest.mark.parametrize("text", ["in 2.25% <!-- stated findings.share -->",
                                  "<!-- begin stated findings.table -->\n| a |\n"])
def test_a_marker_without_its_number_or_its_end_is_refused(tmp_path, text):
    path = tmp_path / "marked.txt"
    path.write_text(text)
    with pytest.raises(ValueError, match="marked.txt:1: a 'stated' marker"):
        stated.stated_in(path)


def test_a_source_whose_inputs_are_absent_is_said_not_checked(monkeypatch, capsys):
    """Without a copy of the Fazeli drops the experiments' numbers cannot be checked:
    findings says so on stderr and checks the rest, never a silent pass of them."""
    from harness.experiments import registry

    monkeypatch.delenv(registry.FAZELI_2017.env_var, raising=False)
    args = Namespace(check=True, write=False, only=["experiments"], count=10, seed=0)
    assert findings_command.main(args) == 0
    error = capsys.readouterr().err
    assert "experiments: not checked:" in error and registry.FAZELI_2017.env_var in error
    with pytest.raises(stated.Unavailable):
        stated.compute(["experiments"])


def test_findings_check_refuses_an_unknown_source_in_one_line(capsys):
    args = Namespace(check=True, write=False, only=["tabel3"], count=10, seed=0)
    assert findings_command.main(args) == 2
    error = capsys.readouterr().err
    assert error.count("\n") == 1 and "--only tabel3" in error and "table3" in error
