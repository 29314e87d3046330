"""harness.store.files: atomic writes, their temporaries' names, the directory made on need."""

from __future__ import annotations

import itertools
import os
import stat
import time

import pytest

from harness.store import files
from harness.store.cache import ResultCache


def test_parts_and_bytes_are_written_whole_and_leave_no_temporary(tmp_path):
    files.write_parts_atomically(tmp_path / "a", (b"head\n", "t\u00eaxt", b"", b"tail"))
    files.write_bytes_atomically(str(tmp_path / "b"), b"x" * 300_000)
    files.write_text_atomically(tmp_path / "a", "replaced")  # an existing file replaced
    assert (tmp_path / "a").read_text(encoding="utf-8") == "replaced"
    assert (tmp_path / "b").read_bytes() == b"x" * 300_000
    assert sorted(path.name for path in tmp_path.iterdir()) == ["a", "b"]


def test_a_failed_write_removes_its_temporary_and_keeps_the_old_file(tmp_path):
    (tmp_path / "a").write_bytes(b"old")

    def parts():
        yield b"new"
        raise RuntimeError("the writer dies")

    with pytest.raises(RuntimeError):
        files.write_parts_atomically(tmp_path / "a", parts())
    assert [path.name for path in tmp_path.iterdir()] == ["a"]
    assert (tmp_path / "a").read_bytes() == b"old"


def test_a_missing_directory_is_made_only_when_asked(tmp_path):
    with pytest.raises(FileNotFoundError):
        files.write_bytes_atomically(tmp_path / "new" / "a", b"1")
    files.write_bytes_atomically(tmp_path / "new" / "a", b"1", make_parent=True)
    assert (tmp_path / "new" / "a").read_bytes() == b"1"


def test_a_put_into_an_existing_shard_makes_no_directory(tmp_path, monkeypatch):
    cache = ResultCache(tmp_path)
    first, second = (cache.key({"n": n}) for n in range(2))
    second = first[:2] + second[2:]  # the same shard
    cache.put(first, {"status": "ok"})

    def refuse(*args, **kwargs):
        raise AssertionError("mkdir of an existing shard")

    monkeypatch.setattr(os, "makedirs", refuse)
    cache.put(second, {"status": "ok", "n": 2})
    assert cache.get(second) == {"status": "ok", "n": 2}


def test_a_taken_temporary_name_is_passed_over(tmp_path, monkeypatch):
    """A temporary of the same name (left by a dead process that had this pid) is neither
    written into nor removed."""
    monkeypatch.setattr(files, "_TEMPORARY_NUMBERS", itertools.count())
    for tries in (1, files._NAMED_TRIES):  # the next name, then mkstemp's
        for path in tmp_path.iterdir():
            path.unlink()
        monkeypatch.setattr(files, "_TEMPORARY_NUMBERS", itertools.count())
        taken = [tmp_path / f".x-{os.getpid()}-{number}.tmp" for number in range(tries)]
        for path in taken:
            path.write_bytes(b"theirs")
        files.write_bytes_atomically(tmp_path / "a", b"mine", prefix=".x-")
        assert (tmp_path / "a").read_bytes() == b"mine"
        assert all(path.read_bytes() == b"theirs" for path in taken)
        assert len(list(tmp_path.iterdir())) == tries + 1


def test_the_temporaries_of_a_killed_writer_are_what_the_cache_cleans(tmp_path):
    cache = ResultCache(tmp_path)
    shard = tmp_path / cache.key({"n": 1})[:2]
    shard.mkdir()
    descriptor, temporary = files._create_temporary(str(shard), ".abcdef12-")
    os.close(descriptor)  # the writer killed before its rename
    assert os.stat(temporary).st_mode & 0o777 == 0o666 & ~files._umask()
    assert cache.clean_temporaries() == 0  # a writer may still own it
    os.utime(temporary, (time.time() - 3600, time.time() - 3600))
    assert cache.clean_temporaries() == 1 and not os.path.exists(temporary)


# --------------------------------------------------------------------------------------------
# Written only over regular files, with the permissions a new file gets (issue 23, item 2)
# --------------------------------------------------------------------------------------------
@pytest.mark.parametrize("mask", [0o022, 0o077, 0o002])
def test_a_written_file_has_the_mode_the_umask_gives(tmp_path, monkeypatch, mask):
    """0644 under the usual umask (never mkstemp's 0600), by the named temporary and by
    mkstemp's fallback when every name is taken."""
    monkeypatch.setattr(files, "_TEMPORARY_NUMBERS", itertools.count())
    for number in range(files._NAMED_TRIES):
        (tmp_path / f".y-{os.getpid()}-{number}.tmp").write_bytes(b"")
    previous = os.umask(mask)
    try:
        fallback = files.write_text_atomically(tmp_path / "fallback", "{}", prefix=".y-")
        named = files.write_text_atomically(tmp_path / "r.json", "{}")
    finally:
        os.umask(previous)
    assert os.stat(named).st_mode & 0o777 == 0o666 & ~mask
    assert os.stat(fallback).st_mode & 0o777 == 0o666 & ~mask


def test_a_device_a_directory_or_a_link_is_never_replaced(tmp_path):
    target = tmp_path / "theirs.txt"
    target.write_text("theirs")
    link = tmp_path / "link.json"
    link.symlink_to(target)
    directory = tmp_path / "dir.json"
    directory.mkdir()
    fifo = tmp_path / "pipe.json"
    os.mkfifo(fifo)
    for path, kind in ((link, "a symbolic link"), (directory, "a directory"),
                       (fifo, "a named pipe")):
        assert files.output_file_problem(path).startswith(f"is {kind}")
        with pytest.raises(files.NotRegularFile, match=kind):
            files.write_text_atomically(path, "mine")
    assert target.read_text() == "theirs" and link.is_symlink()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["dir.json", "link.json", "pipe.json",
                                                          "theirs.txt"]  # no temporary left
    device = tmp_path / "null"
    try:  # a character device of /dev/null's numbers (where this user may make one)
        os.mknod(device, stat.S_IFCHR | 0o666, os.makedev(1, 3))
    except PermissionError:
        return
    assert files.output_file_problem(device).startswith("is a character device")
    with pytest.raises(files.NotRegularFile, match="a character device"):
        files.write_text_atomically(device, "mine")
    assert stat.S_ISCHR(os.lstat(device).st_mode)


def test_an_output_file_needs_an_existing_directory(tmp_path):
    assert files.output_file_problem(tmp_path / "r.json") is None
    problem = files.output_file_problem(tmp_path / "new" / "r.json")
    assert "does not exist" in problem and not (tmp_path / "new").exists()


def test_an_output_directory_is_made_itself_only(tmp_path):
    assert files.output_directory_problem(tmp_path / "out") is None
    assert "does not exist" in files.output_directory_problem(tmp_path / "a" / "out")
    (tmp_path / "file").write_text("x")
    assert files.output_directory_problem(tmp_path / "file") == "is a regular file, not a directory"
    files.make_output_directory(tmp_path / "out")
    assert (tmp_path / "out").is_dir() and not (tmp_path / "a").exists()
