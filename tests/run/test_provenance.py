"""The git block of the provenance: generated outputs are no change of the source."""

from __future__ import annotations

import shutil
import subprocess

import pytest

from harness.run.provenance import git_commit

pytestmark = pytest.mark.skipif(shutil.which("git") is None, reason="needs git")


def _git(cwd, *argv):
    subprocess.run(["git", "-c", "user.name=t", "-c", "user.email=t@t", *argv], cwd=cwd,
                   check=True, capture_output=True)


@pytest.fixture
def tree(tmp_path):
    """A committed tree with a source file and a generated report."""
    (tmp_path / "harness").mkdir()
    (tmp_path / "harness" / "code.py").write_text("x = 1\n")
    (tmp_path / "reports").mkdir()
    (tmp_path / "reports" / "index.html").write_text("report\n")
    _git(tmp_path, "init", "-q")
    _git(tmp_path, "add", ".")
    _git(tmp_path, "commit", "-q", "-m", "start")
    return tmp_path


def test_a_clean_tree_is_clean(tree):
    block = git_commit(tree)
    assert block["dirty"] is False and len(block["commit"]) == 40


def test_regenerated_reports_are_no_change_of_the_source(tree):
    (tree / "reports" / "index.html").write_text("report, regenerated\n")
    assert git_commit(tree)["dirty"] is False
    # asked from a subdirectory too
    assert git_commit(tree / "harness")["dirty"] is False


def test_a_changed_source_file_is(tree):
    (tree / "harness" / "code.py").write_text("x = 2\n")
    (tree / "reports" / "index.html").write_text("report, regenerated\n")
    assert git_commit(tree)["dirty"] is True
    assert git_commit(tree / "harness")["dirty"] is True


def test_a_file_named_like_the_outputs_elsewhere_counts(tree):
    (tree / "harness" / "reports").mkdir()
    (tree / "harness" / "reports" / "notes.txt").write_text("a\n")
    _git(tree, "add", ".")
    _git(tree, "commit", "-q", "-m", "notes")
    (tree / "harness" / "reports" / "notes.txt").write_text("b\n")
    assert git_commit(tree)["dirty"] is True



def test_the_reports_caches_are_ignored():
    """The report's caches change whenever the results file is written anew (the digests
    are keyed by its exact lines): committed, they would leave a regenerated clone modified.
    Nothing needs them there: a figure's PNG carries its own inputs digest."""
    from pathlib import Path

    from harness.report.fragments import CACHE_FILE, DIGESTS_FILE

    root = Path(__file__).resolve().parents[2]
    if not (root / ".git").exists():
        pytest.skip("not a git checkout")
    for name in (CACHE_FILE, DIGESTS_FILE):
        ignored = subprocess.run(["git", "check-ignore", "-q", f"reports/{name}"], cwd=root)
        assert ignored.returncode == 0, f"reports/{name} is not in .gitignore"
