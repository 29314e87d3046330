"""Every Markdown document the repository cites exists in it, and every quoted section exists.

A citation is a path ending in ``.md`` in any tracked text file (code, tests, scenarios,
docs, generated reports). It resolves against the repository root or the citing file's
folder; a bare file name (no folder) also resolves to a tracked document of that name
anywhere (code names the reports it writes, e.g. ``stress.md``, by file name). A section
is cited by its title in quotes right after the path, as in
``docs/theory.md, 'Stronge's law'`` (single or double quotes; an apostrophe followed by a
letter belongs to the title); the title must be a heading of that document. Sections are
cited by title, never by number: the documents do not number them.
"""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
# Files this test reads as text; binary files (figures) are skipped by their suffix.
TEXT_SUFFIXES = {".py", ".toml", ".md", ".csv", ".html", ".json", ".txt", ".cfg", ".ini", ""}
# This file holds example citations in its checks of the parser below.
SELF = Path(__file__).resolve().relative_to(ROOT).as_posix()

# A path ending in .md, not part of a longer word, a URL or a wider path.
DOCUMENT = r"(?<![\w/.:-])(?P<path>(?:[\w.-]+/)*[\w.-]+\.md)\b"
# An apostrophe inside a single-quoted title is one followed by a letter ("Routh's").
SINGLE_QUOTED = r"'(?P<single>(?:[^'\n]|'(?=[A-Za-z]))+)'"
DOUBLE_QUOTED = r'"(?P<double>[^"\n]+)"'
SECTION = rf"(?:,\s*|\s+)(?:section\s+)?(?:{SINGLE_QUOTED}|{DOUBLE_QUOTED})"
CITATION = re.compile(rf"{DOCUMENT}(?:{SECTION}|(?P<number>\s*§\s*\d+))?")
HEADING = re.compile(r"^#{1,6}\s+(.+?)\s*#*\s*$", re.MULTILINE)


def citations(text: str) -> list[tuple[int, str, str | None, bool]]:
    """``(line, document, section title or None, cited by number)`` for each citation."""
    found = []
    for match in CITATION.finditer(text):
        line = text.count("\n", 0, match.start()) + 1
        title = match.group("single") or match.group("double")
        found.append((line, match.group("path"), title, match.group("number") is not None))
    return found


def headings(markdown: str) -> set[str]:
    """Titles of a Markdown document's headings (outside fenced code blocks)."""
    outside_code = re.sub(r"^```.*?^```", "", markdown, flags=re.MULTILINE | re.DOTALL)
    return {title.strip() for title in HEADING.findall(outside_code)}


def resolve(document: str, citing_file: Path) -> Path | None:
    """The cited file, from the repository root, the citing file's folder or the shipped
    report folder (code names the files a report writes relative to its output folder), or
    for a bare file name the tracked document of that name; None if there is none."""
    for base in (ROOT, citing_file.parent, ROOT / "reports"):
        candidate = (base / document).resolve()
        if candidate.is_file() and candidate.is_relative_to(ROOT):
            return candidate
    if "/" not in document:
        named = [ROOT / name for name in tracked_files() if Path(name).name == document]
        return named[0] if named else None
    return None


def tracked_files() -> list[str]:
    return subprocess.run(["git", "ls-files"], cwd=ROOT, capture_output=True, text=True,
                          check=True).stdout.split()


def tracked_text_files() -> list[Path]:
    files = []
    for name in tracked_files():
        path = ROOT / name
        if name == SELF or path.suffix not in TEXT_SUFFIXES or not path.is_file():
            continue
        files.append(path)
    return files


def citation_problems(path: Path) -> list[str]:
    """What is wrong with the citations in one file (empty when all resolve)."""
    try:
        text = path.read_text(encoding="utf-8")
    except UnicodeDecodeError:  # a binary file without a telling suffix
        return []
    where = path.relative_to(ROOT).as_posix()
    problems = []
    for line, document, title, by_number in citations(text):
        target = resolve(document, path)
        if target is None:
            problems.append(f"{where}:{line}: cites {document}, which is not in the repository")
            continue
        if by_number:
            problems.append(f"{where}:{line}: cites a section of {document} by number; "
                            "cite its title in quotes")
        if title is not None and title not in headings(target.read_text(encoding="utf-8")):
            problems.append(f"{where}:{line}: {document} has no section '{title}'")
    return problems


# ---------------------------------------------------------------------- the parser itself
def test_citation_parser_reads_paths_titles_and_numbers():
    text = ("see docs/theory.md, 'Stronge's law' and docs/engines.md \"MuJoCo\".\n"
            "old: THEORY.md §6; the file scenarios/README.md; a URL https://x.org/a.md\n"
            "harness/data/djerassi-table3.csv cites THEORY.md, section 'Table 3'.")
    assert citations(text) == [
        (1, "docs/theory.md", "Stronge's law", False),
        (1, "docs/engines.md", "MuJoCo", False),
        (2, "THEORY.md", None, True),
        (2, "scenarios/README.md", None, False),
        (3, "THEORY.md", "Table 3", False),
    ]


def test_headings_ignore_code_blocks():
    markdown = "# Title\n\n## Stronge's law\n\n```sh\n# a shell comment\n```\n### Findings ##\n"
    assert headings(markdown) == {"Title", "Stronge's law", "Findings"}


def test_a_missing_document_and_a_missing_section_are_reported(tmp_path, monkeypatch):
    monkeypatch.setattr(sys.modules[__name__], "ROOT", tmp_path)
    (tmp_path / "docs").mkdir()
    (tmp_path / "docs" / "theory.md").write_text("# Theory\n\n## Conventions\n")
    citing = tmp_path / "code.py"
    citing.write_text("# docs/theory.md, 'Conventions'\n# docs/theory.md, 'Nothing'\n"
                      "# docs/missing.md\n# docs/theory.md §2\n")
    assert citation_problems(citing) == [
        "code.py:2: docs/theory.md has no section 'Nothing'",
        "code.py:3: cites docs/missing.md, which is not in the repository",
        "code.py:4: cites a section of docs/theory.md by number; cite its title in quotes",
    ]


# ---------------------------------------------------------------------- the repository
def test_the_docs_hold_the_sections_other_files_cite():
    theory = headings((ROOT / "docs" / "theory.md").read_text(encoding="utf-8"))
    assert {"Conventions", "Contact terms", "Routh's diagram and collision types",
            "Newton's law", "Poisson's law", "Stronge's law", "The paper's Stronge mapping",
            "The velocity-level law (newton-lcp)", "The two-sled example",
            "Table 3 and its errata", "Findings"} <= theory
    engines = headings((ROOT / "docs" / "engines.md").read_text(encoding="utf-8"))
    assert {"The engine contract", "pymunk", "pybullet", "MuJoCo", "Box2D"} <= engines


@pytest.mark.parametrize("path", tracked_text_files(),
                         ids=lambda path: path.relative_to(ROOT).as_posix())
def test_every_cited_document_and_section_exists(path):
    problems = citation_problems(path)
    assert not problems, "\n".join(problems)
