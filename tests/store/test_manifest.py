"""What an output directory may lose (issue 37, item 3): a file is removed only when the
harness's manifest records it with the hash of what was written and it still holds that;
a directory the harness makes inside ``--out`` is never written through a link."""

from __future__ import annotations

import hashlib
import json

import pytest

from harness import cli
from harness.report import WRITTEN
from harness.store.files import (
    NotRegularFile,
    inner_directory_problem,
    keep_manifest,
    make_inner_directory,
)
from harness.store.sealing import Seal


@pytest.fixture
def seal(tmp_path_factory) -> Seal:
    """A seal whose key lies apart from the directory written (as the result cache's)."""
    return Seal(tmp_path_factory.mktemp("key-home"))


def _figure(directory, name, content=b"png") -> None:
    (directory / name).write_bytes(content)


def test_a_figure_written_then_no_longer_wanted_is_removed(tmp_path, seal):
    _figure(tmp_path, "a.png")
    _figure(tmp_path, "b.png")
    keep_manifest(tmp_path, WRITTEN, {"a.png", "b.png"}, (".png",), seal)
    assert keep_manifest(tmp_path, WRITTEN, {"a.png"}, (".png",), seal) == ["b.png"]
    assert sorted(p.name for p in tmp_path.iterdir()) == [WRITTEN, "a.png"]


def test_names_planted_in_a_manifest_are_never_removed(tmp_path, seal):
    victim = tmp_path / "victim.txt"
    victim.write_text("the user's")
    (tmp_path / "figures").mkdir()
    figures = tmp_path / "figures"
    _figure(figures, "users.png", b"mine")
    planted = {"format": 2, "written": {
        "users.png": hashlib.sha256(b"something else").hexdigest(),  # not what it holds
        "../victim.txt": hashlib.sha256(b"the user's").hexdigest(),  # not a plain name
        str(victim): hashlib.sha256(b"the user's").hexdigest(),
        WRITTEN: "0" * 64}}
    (figures / WRITTEN).write_text(json.dumps(planted))
    assert keep_manifest(figures, WRITTEN, set(), (".png", ".svg"), seal) == []
    assert victim.read_text() == "the user's" and (figures / "users.png").read_bytes() == b"mine"
    # the old format (a list of names, as a planted one of issue 37 was) removes nothing
    (figures / WRITTEN).write_text(json.dumps(["users.png"]))
    assert keep_manifest(figures, WRITTEN, set(), (".png",), seal) == []
    assert (figures / "users.png").exists()


def test_a_file_replaced_by_the_user_or_by_a_link_is_kept(tmp_path, seal):
    _figure(tmp_path, "a.png")
    _figure(tmp_path, "b.png")
    keep_manifest(tmp_path, WRITTEN, {"a.png", "b.png"}, (".png",), seal)
    (tmp_path / "a.png").write_bytes(b"the user's own figure")
    (tmp_path / "outside.png").write_bytes(b"png")
    (tmp_path / "b.png").unlink()
    (tmp_path / "b.png").symlink_to(tmp_path / "outside.png")  # same bytes, through a link
    assert keep_manifest(tmp_path, WRITTEN, set(), (".png",), seal) == []
    assert (tmp_path / "a.png").exists() and (tmp_path / "b.png").is_symlink()


def test_a_manifest_that_is_a_link_is_not_read_nor_written_through(tmp_path, seal):
    elsewhere = tmp_path / "elsewhere.json"
    _figure(tmp_path, "a.png")
    elsewhere.write_text(json.dumps({"format": 2, "written": {
        "a.png": hashlib.sha256(b"png").hexdigest()}}))
    (tmp_path / WRITTEN).symlink_to(elsewhere)
    with pytest.raises(NotRegularFile):
        keep_manifest(tmp_path, WRITTEN, set(), (".png",), seal)
    assert (tmp_path / "a.png").exists() and json.loads(elsewhere.read_text())["written"]


def test_an_inner_directory_that_is_a_link_is_refused(tmp_path):
    target = tmp_path / "target"
    target.mkdir()
    out = tmp_path / "out"
    out.mkdir()
    (out / "figures").symlink_to(target)
    assert "symbolic link" in inner_directory_problem(out, "figures")
    with pytest.raises(NotRegularFile):
        make_inner_directory(out, "figures")
    assert inner_directory_problem(out, "missing") is None
    assert make_inner_directory(out, "missing", "deeper").is_dir()


def _symlinked_figures(tmp_path):
    target = tmp_path / "target"
    target.mkdir()
    (target / "theirs.png").write_bytes(b"theirs")
    (target / WRITTEN).write_text(json.dumps(["theirs.png"]))
    out = tmp_path / "out"
    out.mkdir()
    (out / "figures").symlink_to(target)
    return out, target


def test_report_refuses_a_symlinked_figures_directory_before_any_work(tmp_path, capsys):
    out, target = _symlinked_figures(tmp_path)
    results = tmp_path / "r.json"
    results.write_text("{}")
    status = cli.main(["report", "--results", str(results), "--out", str(out)])
    err = capsys.readouterr().err
    assert status == 2 and "symbolic link" in err and "figures" in err
    assert sorted(p.name for p in target.iterdir()) == [WRITTEN, "theirs.png"]
    assert sorted(p.name for p in out.iterdir()) == ["figures"]


def test_survey_refuses_a_symlinked_figures_directory_before_any_work(tmp_path, capsys):
    out, target = _symlinked_figures(tmp_path)
    status = cli.main(["survey", "disk-disk", "--samples", "2", "--engines", "pymunk",
                       "--out", str(out)])
    err = capsys.readouterr().err
    assert status == 2 and "symbolic link" in err
    assert sorted(p.name for p in target.iterdir()) == [WRITTEN, "theirs.png"]


def test_a_file_is_removed_by_name_only_as_written(tmp_path, seal):
    from harness.store.files import remove_written

    (tmp_path / "settings.json").write_text("{}")
    keep_manifest(tmp_path, ".written.json", {"settings.json"}, (".parquet",), seal)
    (tmp_path / "settings.json").write_text('{"the user": "edited it"}')
    assert not remove_written(tmp_path, ".written.json", "settings.json", seal)
    assert (tmp_path / "settings.json").exists()
    (tmp_path / "settings.json").write_text("{}")
    assert remove_written(tmp_path, ".written.json", "settings.json", seal)
    assert not (tmp_path / "settings.json").exists()
    assert not remove_written(tmp_path, ".written.json", "../elsewhere", seal)


def test_a_planted_manifest_with_the_right_hash_of_a_users_file_removes_nothing(
        tmp_path, seal, capsys):
    """Fourth round: a manifest planted in figures/ that recorded the right SHA-256 of the
    user's own file got it removed; only a manifest sealed by the key (kept apart from the
    directory) is believed, and one that is not is said once."""
    _figure(tmp_path, "mine.png", b"the user's own figure")
    planted = {"format": 2, "written": {
        "mine.png": hashlib.sha256(b"the user's own figure").hexdigest()}}
    (tmp_path / WRITTEN).write_text(json.dumps(planted))
    assert keep_manifest(tmp_path, WRITTEN, set(), (".png",), seal) == []
    assert (tmp_path / "mine.png").read_bytes() == b"the user's own figure"
    assert capsys.readouterr().err.count("nothing it lists is removed") == 1
    # sealed by another key (a manifest copied from elsewhere, a key of its own): kept too
    other = Seal(tmp_path / "other-key")
    (tmp_path / "other-key").mkdir()
    (tmp_path / WRITTEN).write_text(json.dumps(other.sealed(planted)))
    assert keep_manifest(tmp_path, WRITTEN, set(), (".png",), seal) == []
    assert (tmp_path / "mine.png").exists()
    # the same manifest sealed by this key: what the harness wrote, removed
    (tmp_path / WRITTEN).write_text(json.dumps(seal.sealed(planted)))
    assert keep_manifest(tmp_path, WRITTEN, set(), (".png",), seal) == ["mine.png"]
    assert not (tmp_path / "mine.png").exists()
