"""harness.run.files: atomic writes, their temporaries' names, the directory made on need."""

from __future__ import annotations

import itertools
import os
import time

import pytest

from harness.run import files
from harness.run.cache import ResultCache


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
    assert os.stat(temporary).st_mode & 0o777 == 0o600  # as mkstemp makes it
    assert cache.clean_temporaries() == 0  # a writer may still own it
    os.utime(temporary, (time.time() - 3600, time.time() - 3600))
    assert cache.clean_temporaries() == 1 and not os.path.exists(temporary)
