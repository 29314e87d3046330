"""The result cache's directory on disk: its one home (:func:`default_cache_dir`), the marker
that makes it the harness's, what it holds, and its upkeep (``cache info``, ``prune``,
``clear``, the temporaries a killed writer left).

The harness deletes only what it made: the cache's root carries the marker file
:data:`CACHE_MARKER`, written when the harness creates the directory (or adopts an empty
one, or one holding only cache entries); ``cache prune`` and ``cache clear`` refuse a
directory without it (exit 2), and remove only the entries they recognise (the shard
directories' ``<64 hex digits>.json``/``.jsonl`` files and temporaries, the checks' store,
the ``packs`` directory's ``<64 hex digits>.pack`` files and temporaries), never the
directory, its key (:mod:`harness.store.sealing`) or anything else in it. Of those, an
entry is removed only when its seal verifies under the cache's key and the file holds
exactly what the seal covers: a marker planted in a directory of files named like entries
removes none of them (issue 37), and the checks' stores of old names (never sealed) stay
too; what is left is counted.

:func:`output_seal` is the seal, under the same key, of what the harness writes outside its
cache and believes later (a report's cached pieces, the manifests of written files): the key
never lies in the output directory, so whoever can write there cannot forge one.
:mod:`harness.store.cache` has the entries' layout."""

from __future__ import annotations

import hashlib
import itertools
import json
import os
import re
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

from harness.store.files import write_text_atomically
from harness.store.packs import PACK_DIRECTORY, PACK_NAME, open_regular
from harness.store.sealing import KEY_FILE, Seal

_HARNESS_DIR = Path(__file__).resolve().parent.parent  # harness/, from harness/store/

#: Environment variable that moves the cache (tests, shared machines).
CACHE_DIR_VARIABLE = "IMPACT_HARNESS_CACHE_DIR"
#: A temporary file older than this (s) belongs to a writer that died: removed.
STALE_TEMPORARY_S = 60.0
#: The scenario checks' store in the cache's directory
#: (:class:`harness.store.passed_checks.PassedChecks`), and the names it had before (never
#: read: the pickle is never loaded; never sealed, so never removed by name).
SCENARIO_CHECKS_STORE = "passed-checks.json"
OLD_CHECKS_STORES = ("scenario-checks.json", "scenario-checks.pickle")
#: The file that marks a directory as a cache the harness made (see the module docstring).
CACHE_MARKER = "IMPACT-HARNESS-CACHE"
_MARKER_TEXT = ("impact-harness result cache: made by the harness; `impact-harness cache "
                "clear` removes its entries\n")
#: An entry's name in its shard directory, and a shard directory's name.
_ENTRY_NAME = re.compile(r"[0-9a-f]{64}\.jsonl?")
_SHARD_NAME = re.compile(r"[0-9a-f]{2}")


class NotOurCache(Exception):
    """A directory that is not a cache the harness made: nothing in it is removed."""


def default_cache_dir() -> Path:
    """The cache's one home (the module docstring of :mod:`harness.store.cache`)."""
    override = os.environ.get(CACHE_DIR_VARIABLE)
    if override:
        return Path(override).expanduser().resolve()
    project = _HARNESS_DIR.parent
    if (project / "pyproject.toml").is_file():
        return project / ".cache" / "results"
    base = os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache"
    return Path(base) / "impact-harness"


class OutputSeal(Seal):
    """The seal of the default cache (:func:`output_seal`): the cache's directory is made
    (and marked) when a seal is first needed and it is missing."""

    def key(self, create: bool) -> bytes | None:
        if create and not self.root.exists():
            CacheDirectory(self.root, True, "").make_root()
        return super().key(create)


def output_seal() -> Seal:
    """The seal, under the key of the default cache (:func:`default_cache_dir`, which
    ``IMPACT_HARNESS_CACHE_DIR`` moves), of a file the harness writes in an output
    directory and believes on a later run only when the seal verifies."""
    return OutputSeal(default_cache_dir())


class CacheDirectory:
    """The directory of a :class:`~harness.store.cache.ResultCache` (its base class): the
    root, the code version its entries are written by, and whether the cache is enabled."""

    def __init__(self, root: Path | str | None, enabled: bool, version: str) -> None:
        self.root = default_cache_dir() if root is None else Path(root)
        self.enabled = bool(enabled)
        self.version = version

    @property
    def marker(self) -> Path:
        return self.root / CACHE_MARKER

    def marked(self) -> bool:
        """Whether the root carries the cache's marker (a regular file, not a link)."""
        try:
            return os.path.isfile(self.marker) and not os.path.islink(self.marker)
        except OSError:
            return False

    def make_root(self) -> None:
        """Make the root (with its parents: the user named it, or it is the default) and
        mark it as the harness's."""
        self.root.mkdir(parents=True, exist_ok=True)
        write_text_atomically(self.marker, _MARKER_TEXT)

    def prepare(self) -> str | None:
        """Make the cache ready before a run: ``None``, or why the root is not usable.

        A missing root is made and marked; an empty one, or one that holds only what a
        cache holds (shard directories, the checks' store: a cache of a harness before the
        marker), is marked; a marked one is used as it is. A directory holding anything else
        is not a cache the harness made: refused (nothing in it is written or removed).
        """
        try:
            if not self.root.exists():
                self.make_root()
                return None
            if not self.root.is_dir():
                return "is not a directory"
            if self.marked():
                if not os.access(self.root, os.W_OK | os.X_OK):
                    return "cannot write there: not writable"
                return None
            foreign = sorted(name for name in os.listdir(self.root)
                             if not self._cache_like(name))
            if foreign:
                return (f"not a cache the harness made (no {CACHE_MARKER} file, and it holds "
                        f"{foreign[0]!r}{' ...' if len(foreign) > 1 else ''}): choose another "
                        "--cache-dir, or a new or empty directory")
            self.make_root()
        except OSError as error:
            return f"cannot write there: {error.strerror or error}"
        return None

    def _cache_like(self, name: str) -> bool:
        """Whether ``name`` in the root is what a cache holds: a shard directory of entries
        (and temporaries) only, or the checks' store."""
        path = self.root / name
        if name in (SCENARIO_CHECKS_STORE, *OLD_CHECKS_STORES, KEY_FILE):
            return path.is_file() and not path.is_symlink()
        if name == PACK_DIRECTORY and path.is_dir() and not path.is_symlink():
            return all(PACK_NAME.fullmatch(inner) or _is_temporary(inner)
                       for inner in os.listdir(path))
        if not (_SHARD_NAME.fullmatch(name) and path.is_dir() and not path.is_symlink()):
            return False
        return all(_ENTRY_NAME.fullmatch(inner) or _is_temporary(inner)
                   for inner in os.listdir(path))

    def _require_marked(self) -> None:
        if not self.marked():
            raise NotOurCache(f"{self.root}: not a cache the harness made (no {CACHE_MARKER} "
                              "file in it): nothing removed")
    def _entries(self) -> Iterator[Path]:
        """Every entry's path: the keyed entries the shard directories hold (by name: a
        file of any other name is never counted or removed) and the scenario checks'
        stores."""
        if not self.root.is_dir():
            return
        for shard in sorted(os.listdir(self.root)):
            directory = self.root / shard
            if not _SHARD_NAME.fullmatch(shard) or directory.is_symlink():
                continue
            try:
                names = os.listdir(directory)
            except OSError:  # not a directory
                continue
            for name in names:
                path = directory / name
                if _ENTRY_NAME.fullmatch(name) and path.is_file() and not path.is_symlink():
                    yield path
        packs = self.root / PACK_DIRECTORY
        if packs.is_dir() and not packs.is_symlink():
            for name in os.listdir(packs):
                path = packs / name
                if PACK_NAME.fullmatch(name) and path.is_file() and not path.is_symlink():
                    yield path
        for name in (SCENARIO_CHECKS_STORE, *OLD_CHECKS_STORES):
            path = self.root / name
            if path.is_file() and not path.is_symlink():
                yield path

    @staticmethod
    def _stored_version(path: Path) -> Any:
        """The code version an entry was written by (its header line; the checks' store is
        one JSON document; an old store of another name has none)."""
        if path.name in OLD_CHECKS_STORES:
            return None  # never read (the old one was a pickle): removed by prune
        with open(path, "rb") as handle:
            text = handle.read() if path.name == SCENARIO_CHECKS_STORE else handle.readline()
        stored = json.loads(text)
        return stored.get("code_version") if isinstance(stored, dict) else None

    def clean_temporaries(self, older_than_s: float = STALE_TEMPORARY_S) -> int:
        """Remove temporary files older than ``older_than_s`` (left by killed writers)."""
        if not self.enabled or not self.root.is_dir():
            return 0
        removed, now = 0, time.time()
        for temporary in itertools.chain(self.root.glob("??/.*.tmp"),
                                         self.root.glob(f"{PACK_DIRECTORY}/.*.tmp")):
            try:
                if ((_SHARD_NAME.fullmatch(temporary.parent.name)
                     or temporary.parent.name == PACK_DIRECTORY)
                        and not temporary.is_symlink() and not temporary.parent.is_symlink()
                        and now - temporary.stat().st_mtime > older_than_s):
                    temporary.unlink()
                    removed += 1
            except OSError:  # another run removed or replaced it first
                continue
        return removed

    def info(self) -> dict:
        """``{"root", "entries", "bytes", "marked"}`` of the cache on disk."""
        entries, size = 0, 0
        for path in self._entries():
            try:
                size += path.stat().st_size
                entries += 1
            except OSError:
                continue
        return {"root": str(self.root), "entries": entries, "bytes": size,
                "marked": self.marked()}

    def prune(self, max_age_days: float | None = None, other_versions: bool = True) -> dict:
        """Remove entries written by other code (``other_versions``) or older than a bound.

        Returns ``{"entries", "bytes", "left"}``: only an entry whose seal verifies under
        this cache's key (:meth:`_sealed_whole`) is removed; a file named like one that
        does not is left, and counted (as by :meth:`clear`). Raises :class:`NotOurCache`
        (nothing removed) when the root is not marked.
        """
        self._require_marked()
        removed, size, left, now = 0, 0, 0, time.time()
        seal = Seal(self.root)
        self.clean_temporaries()
        for path in list(self._entries()):
            try:
                status = path.stat()
                old = max_age_days is not None and now - status.st_mtime > max_age_days * 86400
                stale = False
                if other_versions and not old:
                    try:
                        stale = self._stored_version(path) != self.version
                    except (OSError, ValueError):  # unreadable, not JSON
                        stale = True
                if not (old or stale):
                    continue
                if not self._sealed_whole(path, seal):
                    left += 1
                    continue
                path.unlink()
                removed += 1
                size += status.st_size
            except OSError:
                continue
        return {"entries": removed, "bytes": size, "left": left}

    def clear(self) -> dict:
        """Remove every entry whose seal verifies under this cache's key (:meth:`_sealed_whole`),
        the temporaries and the emptied shard directories; the root, its marker and its key
        stay, and so does every file the cache cannot tell it wrote (counted in ``left``:
        never the harness's to remove, whatever its name). Returns ``{"entries", "bytes",
        "left"}``. Raises :class:`NotOurCache` (nothing removed) when the root is not
        marked."""
        self._require_marked()
        removed, size, left = 0, 0, 0
        seal = Seal(self.root)
        for path in list(self._entries()):
            try:
                if not self._sealed_whole(path, seal):
                    left += 1
                    continue
                size += path.stat().st_size
                path.unlink()
                removed += 1
            except OSError:
                continue
        self.clean_temporaries(older_than_s=-1.0)
        for shard in os.listdir(self.root):
            if ((_SHARD_NAME.fullmatch(shard) or shard == PACK_DIRECTORY)
                    and not (self.root / shard).is_symlink()):
                try:
                    (self.root / shard).rmdir()  # only when empty
                except OSError:
                    pass
        return {"entries": removed, "bytes": size, "left": left}

    @staticmethod
    def _sealed_whole(path: Path, seal: Seal) -> bool:
        """Whether the file at ``path`` (never read through a link) is what this cache
        wrote: its header's seal verifies under the cache's key and covers every byte of it
        (the SHA-256 of a single entry's or a scenario's body and its key as the name, each
        record of a pack, the checks' store whole)."""
        try:
            with open_regular(os.fspath(path)) as handle:
                data = handle.read()
            if path.name in OLD_CHECKS_STORES:
                return False  # never sealed (nor read: the old one was a pickle)
            if path.name == SCENARIO_CHECKS_STORE:
                stored = json.loads(data)
                if not isinstance(stored, dict):
                    return False
                seal.check(stored)
                return True
            head_end = data.find(b"\n")
            header = json.loads(data[:head_end]) if head_end > 0 else None
            if not isinstance(header, dict):
                return False
            seal.check(header)
            body = memoryview(data)[head_end + 1:]
            if path.parent.name == PACK_DIRECTORY:
                sizes, digests = header.get("sizes"), header.get("sha256")
                if not (isinstance(sizes, list) and isinstance(digests, list)
                        and len(sizes) == len(digests)
                        and all(isinstance(n, int) and n >= 0 for n in sizes)
                        and sum(sizes) == len(body)):
                    return False
                bounds = list(itertools.accumulate(sizes, initial=0))
                return all(hashlib.sha256(body[start:stop]).hexdigest() == digest
                           for start, stop, digest in zip(bounds, bounds[1:], digests))
            return (header.get("key") == path.name.split(".")[0]
                    and header.get("sha256") == hashlib.sha256(body).hexdigest())
        except (OSError, ValueError):  # unreadable, not JSON, no key, seal differs
            return False

def _is_temporary(name: str) -> bool:
    """A writer's temporary file name (:func:`harness.store.files.write_parts_atomically`)."""
    return name.startswith(".") and name.endswith(".tmp")
