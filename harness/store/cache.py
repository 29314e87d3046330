"""Content-addressed cache of results: rerunning an unchanged suite does no engine work.

Home: :func:`default_cache_dir` -- ``$IMPACT_HARNESS_CACHE_DIR`` when set, else
``.cache/results`` under the project root (the checkout holding ``pyproject.toml``; ``make
clean`` removes it), else, for an installed harness, ``$XDG_CACHE_HOME/impact-harness``
(``~/.cache/impact-harness``). Never the working directory. Bounded by ``impact-harness cache
prune`` (entries written by other code, or older than ``--older-than`` days) and ``cache
clear``; ``cache info`` shows the size (:mod:`harness.store.cli`).

A record is stored under the key ``sha256(canonical JSON of the payload + code version)``,
where the payload names everything the result depends on (scenario, sweep point, engine and
its version, settings ...) and :func:`~harness.store.identity.code_version` hashes the
source the stored values depend on (:data:`~harness.store.identity.CACHED_CODE`:
``planar_impact``, the store, the engines, the scene, the references and the run modules
that compute what is stored), so a change there invalidates every entry, while a change to
the report, the benchmarks or the CLI keeps the cache::

    cache = ResultCache()                     # default_cache_dir(), or enabled=False for --no-cache
    key = cache.key({"scenario": name, "point": 3, "engine": "pymunk", "version": v, "settings": s})
    record = cache.get(key)
    if record is None:
        record = simulate(...)
        cache.put(key, record)

Files: many records in one pack, ``root/packs/<sha256 of the pack>.pack``
(:meth:`ResultCache.put_many`: an engine chunk's runs, a run's references): a header line
(the code version, and per record its key, size and SHA-256), then the records' JSON one
after the other; a cold run of 1,000 scenario files wrote 16,056 engine runs and 481
references one file each before, 292 packs now. The packs' headers are read into an index
of where each key lies at the first lookup that finds no single entry: once within
:meth:`ResultCache.listed` (a run's lookups), at each such miss outside it (a warm run, whose
scenarios are read whole, reads none). One record on its own at ``root/<key[:2]>/<key>.json``
(:meth:`ResultCache.put`): a header line (the key, the code version, the SHA-256 of what
follows) and the record as JSON; ``<key>.jsonl`` for an entry of
many lines (:meth:`ResultCache.put_lines`: a scenario's records, a header line with their
summary, the sizes of what follows and its SHA-256, then their lines as the results file
holds them). Plain data only: nothing read from the cache is unpickled, evaluated or
imported. Written atomically (a temporary file in the same directory, then ``os.replace``),
so concurrent writers and an interrupted run never leave a half-written entry; a temporary
left by a killed writer is removed by the next run (:meth:`ResultCache.clean_temporaries`).
An unreadable, corrupted or edited file (its checksum differs; in a pack, a record whose
checksum differs, or every record of a pack whose header is not whole) is a miss, and so is an entry
the caller's ``check`` rejects (a record without finite velocities of the right shape): both
are listed in :attr:`ResultCache.rejected`, which the run prints as warnings, and the
result is computed again. Beside the entries, ``root/passed-checks.json`` keeps the keys of
the scenario texts that passed their checks (:class:`harness.store.passed_checks.PassedChecks`);
``cache info``, ``prune`` and ``clear`` count and remove it with them.

The harness deletes only what it made: the cache's root carries the marker file
:data:`CACHE_MARKER`, written when the harness creates the directory (or adopts an empty
one, or one holding only cache entries); ``cache prune`` and ``cache clear`` refuse a
directory without it (exit 2), and remove only the entries they recognise (the shard
directories' ``<64 hex digits>.json``/``.jsonl`` files and temporaries, the checks' store),
never the directory or anything else in it. Packs are recognised the same way: the
``packs`` directory's ``<64 hex digits>.pack`` files and temporaries.
"""

from __future__ import annotations

import hashlib
import itertools
import json
import os
import re
import secrets
import time
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from harness.collector import collector_paused
from harness.store.files import write_parts_atomically, write_text_atomically
from harness.store.identity import Spelled, canonical_json, code_version

_HARNESS_DIR = Path(__file__).resolve().parent.parent  # harness/, from harness/store/

#: Between two lines of an entry of many lines (:meth:`ResultCache.put_lines`): the record
#: lines of a results file (:mod:`harness.run.records`), which a warm run copies as stored.
LINE_SEPARATOR = ",\n"

CACHE_FORMAT = 2  # bump when the record layout changes (2: SHA-256 checked, no pickle)

#: Environment variable that moves the cache (tests, shared machines).
CACHE_DIR_VARIABLE = "IMPACT_HARNESS_CACHE_DIR"
#: A temporary file older than this (s) belongs to a writer that died: removed.
STALE_TEMPORARY_S = 60.0
#: The scenario checks' store in the cache's directory
#: (:class:`harness.store.passed_checks.PassedChecks`), and the names it had before (removed by
#: ``prune`` and ``clear`` unread: the pickle is never loaded).
SCENARIO_CHECKS_STORE = "passed-checks.json"
OLD_CHECKS_STORES = ("scenario-checks.json", "scenario-checks.pickle")
#: The file that marks a directory as a cache the harness made (see the module docstring).
CACHE_MARKER = "IMPACT-HARNESS-CACHE"
_MARKER_TEXT = ("impact-harness result cache: made by the harness; `impact-harness cache "
                "clear` removes its entries\n")
#: An entry's name in its shard directory, and a shard directory's name.
_ENTRY_NAME = re.compile(r"[0-9a-f]{64}\.jsonl?")
_SHARD_NAME = re.compile(r"[0-9a-f]{2}")
#: The directory of the packs in the root (:meth:`ResultCache.put_many`), a pack's name in it,
#: and the most records one pack holds (a run's main process buffers at most as many).
PACK_DIRECTORY = "packs"
_PACK_NAME = re.compile(r"[0-9a-f]{64}\.pack")
PACK_SIZE = 512


class NotOurCache(Exception):
    """A directory that is not a cache the harness made: nothing in it is removed."""


def default_cache_dir() -> Path:
    """The cache's one home; see the module docstring."""
    override = os.environ.get(CACHE_DIR_VARIABLE)
    if override:
        return Path(override).expanduser().resolve()
    project = _HARNESS_DIR.parent
    if (project / "pyproject.toml").is_file():
        return project / ".cache" / "results"
    base = os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache"
    return Path(base) / "impact-harness"


#: The stand-in of :meth:`ResultCache.slot_key`'s slot (a random string, spelled as json
#: spells it).
_SLOT = Spelled(f"slot{secrets.token_hex(16)}")


class ResultCache:
    """Results on disk, keyed by a content hash of what they depend on.

    Parameters
    ----------
    root
        Directory of the cache (created on the first ``put``); default
        :func:`default_cache_dir`.
    enabled
        ``False`` (the runner's ``--no-cache``): ``get`` always misses, ``put`` writes nothing.
    version
        Code version mixed into every key (default: :func:`code_version`); tests pass their own.
    """

    def __init__(self, root: Path | str | None = None, enabled: bool = True,
                 version: str | None = None):
        self.root = default_cache_dir() if root is None else Path(root)
        self.enabled = bool(enabled)
        self.version = code_version() if version is None else version
        self.hits = 0
        self.misses = 0
        self.rejected: list[str] = []  # "<entry path>: <why>" of entries read as a miss
        self._root_seen = False  # whether this cache looked at its root's marker yet
        # shard -> the names in its directory, while listed() is active (None: not listed)
        self._listing: dict[str, set[str] | None] | None = None
        # key -> (pack path, offset, size, SHA-256) of the packed records, from the headers
        # of the packs named in _packs_read (read, or rejected)
        self._packed: dict[str, tuple[str, int, int, str]] = {}
        self._packs_read: set[str] = set()
        self._packs_listed = False  # within listed(): the packs' directory was read

    @contextmanager
    def listed(self) -> Iterator[None]:
        """Within: whether an entry exists is read from a listing of its shard's directory,
        made at the first lookup there, not by opening the file: the misses of a cold run
        (thousands of entries that are not there) cost a set lookup each. An entry another
        process writes meanwhile is a miss (its run simulated again); those this cache puts
        are listed."""
        self._listing, self._packs_listed = {}, False
        try:
            yield
        finally:
            self._listing, self._packs_listed = None, False

    def _unlisted(self, key: str, suffix: str) -> bool:
        """True when :meth:`listed` is active and the shard's listing lacks the entry."""
        if self._listing is None:
            return False
        shard = key[:2]
        if shard not in self._listing:
            try:
                self._listing[shard] = set(os.listdir(self.root / shard))
            except FileNotFoundError:
                self._listing[shard] = set()
            except OSError:  # not listed: the entries are opened
                self._listing[shard] = None
        names = self._listing[shard]
        return names is not None and f"{key}{suffix}" not in names

    def _list(self, shard: str, name: str) -> None:
        """Add an entry this cache wrote (file ``name`` in directory ``shard``) to its
        shard's listing, when one is made."""
        if self._listing is not None and self._listing.get(shard) is not None:
            self._listing[shard].add(name)

    def key(self, payload: dict) -> str:
        """sha256 hex of the canonical JSON of ``payload`` plus the code version."""
        return hashlib.sha256(self._key_text(payload).encode()).hexdigest()

    def _key_text(self, payload: dict) -> str:
        return canonical_json(
            {"payload": payload, "code_version": self.version, "format": CACHE_FORMAT}
        )

    def slot_key(self, payload: dict, slot: str) -> Callable[[Spelled], str]:
        """The :meth:`key` of ``payload`` with a :class:`Spelled` value in ``slot``, as a
        function of that value: ``slot_key(payload, slot)(spelled) == key({**payload, slot:
        spelled})``, the text around the slot spelled and hashed once (a run's engine runs of
        one engine and settings differ in their scene only)."""
        pieces = self._key_text({**payload, slot: _SLOT}).split(_SLOT.text)
        if len(pieces) != 2:  # cannot be: the slot's stand-in is random
            raise ValueError("a payload holds the stand-in of a slot")
        head, tail = hashlib.sha256(pieces[0].encode()), pieces[1].encode()

        def key(spelled: Spelled) -> str:
            digest = head.copy()
            digest.update(spelled.text.encode())
            digest.update(tail)
            return digest.hexdigest()

        return key

    def path(self, key: str) -> Path:
        return Path(self._path_text(key))

    def _path_text(self, key: str) -> str:
        """Where the entry ``key`` lies, as text (a cold run's thousands of puts would pay
        as much for pathlib objects as for their writes)."""
        return os.path.join(self.root, key[:2], f"{key}.json")

    def get(self, key: str, check=None, *, count: bool = True) -> dict | None:
        """The stored record, or ``None`` (a miss) when absent, disabled or unreadable.

        The entry must be whole: its key, and the SHA-256 of the record's text as stored (an
        entry changed after it was written is a miss). ``check(record)`` returns ``None``
        for a usable record or a reason it is not; a rejected or unreadable entry is a miss
        and is listed in :attr:`rejected`. With ``count=False`` the lookup stays out of
        :attr:`stats` (which count engine runs).
        """
        if not count:
            hits, misses = self.hits, self.misses
            try:
                return self.get(key, check)
            finally:
                self.hits, self.misses = hits, misses
        if not self.enabled:
            self.misses += 1
            return None
        path = self._path_text(key)
        try:
            try:  # a single entry first: the packs' index is read only when one is missing
                if self._unlisted(key, ".json"):
                    raise FileNotFoundError(path)
                with open(path, "rb") as handle:
                    raw = handle.read()
                head_end = raw.find(b"\n")
                header = json.loads(raw[:head_end]) if head_end > 0 else None
                if not isinstance(header, dict) or header.get("key") != key:
                    raise ValueError("not a cache entry")
                body, sha256 = memoryview(raw)[head_end + 1:], header.get("sha256")
            except FileNotFoundError:
                packed = self._packed_entry(key)
                if packed is None:
                    raise
                pack, offset, size, sha256 = packed
                path = f"{pack} (record {key[:12]})"
                with open(pack, "rb") as handle:
                    handle.seek(offset)
                    body = handle.read(size)
                if len(body) != size:
                    raise ValueError("truncated") from None
            if sha256 != hashlib.sha256(body).hexdigest():
                raise ValueError("checksum differs: changed after it was written")
            record = json.loads(str(body, "utf-8"))
            if not isinstance(record, dict):
                raise ValueError("not a cache entry")
            reason = None if check is None else check(record)
            if reason is not None:
                raise ValueError(reason)
        except FileNotFoundError:
            self.misses += 1
            return None
        except (OSError, ValueError) as error:  # UnicodeDecodeError is a ValueError
            self.rejected.append(f"{path}: {error}")
            self.misses += 1
            return None
        self.hits += 1
        return record

    def put(self, key: str, record: dict) -> None:
        """Store ``record`` (JSON-able dict) under ``key``; atomic; no-op when disabled.

        Raises ``OSError`` when the entry cannot be written (the caller decides whether that
        matters); the root (marked) and the shard directory are made when missing, again if
        removed under a running writer.
        """
        if not self.enabled:
            return
        body = _ENTRY_ENCODER.encode(record).encode("utf-8")
        header = json.dumps({"key": key, "code_version": self.version,
                             "sha256": hashlib.sha256(body).hexdigest()})
        self._write(self._path_text(key), (header.encode("utf-8"), b"\n", body), key)
        self._list(key[:2], f"{key}.json")

    def put_many(self, items: Sequence[tuple[str, dict]]) -> None:
        """Store each ``(key, record)`` of ``items`` as :meth:`put` does, in one pack (one
        file: see the module docstring), named by its content's SHA-256; atomic (the pack is
        whole or absent); no-op when disabled or empty. More than :data:`PACK_SIZE` records
        make several packs. Raises ``OSError`` as :meth:`put` does."""
        if not self.enabled or not items:
            return
        for start in range(0, len(items), PACK_SIZE):
            self._put_pack(items[start:start + PACK_SIZE])

    def _put_pack(self, items: Sequence[tuple[str, dict]]) -> None:
        keys = [key for key, _ in items]
        bodies = [_ENTRY_ENCODER.encode(record).encode("utf-8") for _, record in items]
        sizes = [len(body) for body in bodies]
        digests = [hashlib.sha256(body).hexdigest() for body in bodies]
        header = json.dumps({"code_version": self.version, "keys": keys, "sizes": sizes,
                             "sha256": digests},
                            separators=(",", ":")).encode("utf-8") + b"\n"
        digest = hashlib.sha256(header)
        for body in bodies:
            digest.update(body)
        name = f"{digest.hexdigest()}.pack"
        path = os.path.join(self.root, PACK_DIRECTORY, name)
        self._write(path, (header, *bodies), name)
        self._index_pack(path, header, keys, sizes, digests)
        self._packs_read.add(name)

    def _index_pack(self, path: str, header: bytes, keys: list, sizes: list,
                    digests: list) -> None:
        offset = len(header)
        for key, size, sha256 in zip(keys, sizes, digests):
            self._packed[key] = (path, offset, size, sha256)
            offset += size

    def _packed_entry(self, key: str) -> tuple[str, int, int, str] | None:
        """Where ``key`` lies in a pack, or None. The packs' headers not read yet are read
        at a miss: once within :meth:`listed` (the packs written meanwhile by other
        processes are not seen; its own are), at every miss outside it."""
        found = self._packed.get(key)
        if found is not None or self._packs_listed:
            return found
        self._packs_listed = self._listing is not None
        directory = os.path.join(self.root, PACK_DIRECTORY)
        try:
            names = os.listdir(directory)
        except OSError:  # none yet, or not a directory: nothing packed
            return None
        for name in names:
            if name in self._packs_read or not _PACK_NAME.fullmatch(name):
                continue
            self._packs_read.add(name)
            path = os.path.join(directory, name)
            try:
                self._read_pack_header(path)
            except (OSError, ValueError) as error:  # UnicodeDecodeError is a ValueError
                self.rejected.append(f"{path}: {error}")
        return self._packed.get(key)

    def _read_pack_header(self, path: str) -> None:
        """Index the records of the pack at ``path`` (those of this code version only: the
        keys of another hold another version anyway); ``ValueError`` when its header is not
        a pack's or its size is not the one the header gives."""
        with open(path, "rb") as handle:
            line = handle.readline()
            size = os.fstat(handle.fileno()).st_size
        header = json.loads(line)
        if not isinstance(header, dict) or header.get("code_version") != self.version:
            if isinstance(header, dict) and isinstance(header.get("code_version"), str):
                return  # another code's: never a key of this one
            raise ValueError("not a cache pack")
        keys, sizes, digests = header.get("keys"), header.get("sizes"), header.get("sha256")
        if not (isinstance(keys, list) and isinstance(sizes, list) and isinstance(digests, list)
                and len(keys) == len(sizes) == len(digests)
                and all(isinstance(key, str) for key in keys)
                and all(isinstance(digest, str) for digest in digests)
                and all(isinstance(n, int) and not isinstance(n, bool) and n >= 0
                        for n in sizes)):
            raise ValueError("not a cache pack")
        if len(line) + sum(sizes) != size:
            raise ValueError("truncated")
        self._index_pack(path, line, keys, sizes, digests)

    def _write(self, path: str, parts: tuple, key: str) -> None:
        """Write an entry's ``parts`` at ``path`` atomically; the shard directory made when
        missing (only then: a cold run puts thousands of small entries, whose mkdir calls
        would cost as much as their writes), and the root first, marked, when it is missing.
        At the first write, a root that exists empty and unmarked is marked (made by the
        caller for the cache); one holding anything else is written into unmarked (the
        caller chose it; ``prepare`` refuses it for a run), so never cleared."""
        if not self._root_seen:
            self._root_seen = True
            try:
                if not self.marked() and self.root.is_dir() and not any(self.root.iterdir()):
                    self.make_root()
            except OSError:
                pass
        for attempt in (1, 2, 3):
            try:
                write_parts_atomically(path, parts, prefix=f".{key[:8]}-")
                return
            except FileNotFoundError:
                if attempt == 3:
                    raise
                if not os.path.isdir(self.root):
                    self.make_root()
                os.makedirs(os.path.dirname(path), exist_ok=True)

    # ----------------------------------------------------------------------------------------
    # The root and its marker: what tells the harness the directory is its own
    # ----------------------------------------------------------------------------------------
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
        if name in (SCENARIO_CHECKS_STORE, *OLD_CHECKS_STORES):
            return path.is_file() and not path.is_symlink()
        if name == PACK_DIRECTORY and path.is_dir() and not path.is_symlink():
            return all(_PACK_NAME.fullmatch(inner) or _is_temporary(inner)
                       for inner in os.listdir(path))
        if not (_SHARD_NAME.fullmatch(name) and path.is_dir() and not path.is_symlink()):
            return False
        return all(_ENTRY_NAME.fullmatch(inner) or _is_temporary(inner)
                   for inner in os.listdir(path))

    def _require_marked(self) -> None:
        if not self.marked():
            raise NotOurCache(f"{self.root}: not a cache the harness made (no {CACHE_MARKER} "
                              "file in it): nothing removed")

    def lines_path(self, key: str) -> Path:
        return self.root / key[:2] / f"{key}.jsonl"

    def get_lines(self, key: str, check=None) -> list[tuple[Any, str]] | None:
        """The ``(value, line)`` pairs stored by :meth:`put_lines`, or ``None`` (a miss).

        Outside :attr:`stats`. A file that is not whole (see :meth:`get_block`) or whose
        values ``check(values)`` rejects (``None``: usable, else why not) is a miss listed in
        :attr:`rejected`.
        """
        entry = self.get_block(key)
        if entry is None:
            return None
        _, text, count, _ = entry
        try:
            lines = split_block(text, count)
            values = _parse_lines(lines)
            reason = None if check is None else check(values)
            if reason is not None:
                raise ValueError(reason)
        except ValueError as error:
            self.rejected.append(f"{self.lines_path(key)}: {error}")
            return None
        return list(zip(values, lines))

    def get_block(self, key: str, check_summary=None
                  ) -> tuple[Any, memoryview, int, list[memoryview]] | None:
        """``(summary, text, count, parts)`` stored by :meth:`put_lines`: the ``count`` lines
        as one UTF-8 ``text`` (joined by :data:`LINE_SEPARATOR`, neither decoded nor split:
        a warm run copies it into the results file as it is) and the byte ``parts``, or
        ``None`` (a miss).

        Outside :attr:`stats`. The entry must be whole: its key, the sizes its header gives
        adding up to the file's, and the SHA-256 of the text and the parts as stored (an
        entry changed after it was written is a miss); ``check_summary(summary)`` (``None``:
        usable, else why not) may reject it. A rejected entry is listed in :attr:`rejected`.
        """
        if not self.enabled or self._unlisted(key, ".jsonl"):
            return None
        path = self.lines_path(key)
        try:
            with open(path, "rb") as handle:
                raw = handle.read()
            head_end = raw.find(b"\n")
            header = json.loads(raw[:head_end if head_end >= 0 else len(raw)])
            data = memoryview(raw)  # slices of it copy nothing
            sizes = header.get("sizes") if isinstance(header, dict) else None
            if (not isinstance(header, dict) or header.get("key") != key
                    or not isinstance(header.get("count"), int)
                    or not isinstance(sizes, list) or not sizes
                    or not all(isinstance(size, int) and size >= 0 for size in sizes)):
                raise ValueError("not a cache entry")
            if head_end + 1 + sum(sizes) != len(data):
                raise ValueError("truncated")
            if header.get("sha256") != hashlib.sha256(data[head_end + 1:]).hexdigest():
                raise ValueError("checksum differs: changed after it was written")
            if (sizes[0] == 0) != (header["count"] == 0):
                raise ValueError(f"{header['count']} lines in {sizes[0]} bytes")
            bounds = list(itertools.accumulate(sizes, initial=head_end + 1))
            text, *parts = (data[start:stop] for start, stop in zip(bounds, bounds[1:]))
            summary = header.get("summary")
            reason = None if check_summary is None else check_summary(summary)
            if reason is not None:
                raise ValueError(reason)
        except FileNotFoundError:
            return None
        except (OSError, ValueError) as error:  # UnicodeDecodeError is a ValueError
            self.rejected.append(f"{path}: {error}")
            return None
        return summary, text, header["count"], parts

    def put_lines(self, key: str, lines: Sequence[str], summary: Any = None,
                  parts: Sequence[bytes] = ()) -> None:
        """Store one-line JSON texts under ``key``: a header line (the key, the code version,
        how many lines follow, ``summary``, a JSON-able value the reader gets without reading
        the lines, the sizes of what follows and its SHA-256), then the lines joined by
        :data:`LINE_SEPARATOR` as UTF-8, then the byte ``parts`` as they are; atomic; no-op
        when disabled. A line holding a newline is a ``ValueError``. Raises ``OSError`` as
        :meth:`put` does."""
        if not self.enabled:
            return
        if any("\n" in line for line in lines):
            raise ValueError("a cache line holds a newline")
        text = LINE_SEPARATOR.join(lines).encode("utf-8")
        digest = hashlib.sha256(text)
        for part in parts:
            digest.update(part)
        header = json.dumps({"key": key, "code_version": self.version, "count": len(lines),
                             "sizes": [len(text), *(len(part) for part in parts)],
                             "sha256": digest.hexdigest(), "summary": summary},
                            ensure_ascii=False, allow_nan=False)
        self._write(os.fspath(self.lines_path(key)),
                    (header.encode("utf-8"), b"\n", text, *parts), key)
        self._list(key[:2], f"{key}.jsonl")

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
                if _PACK_NAME.fullmatch(name) and path.is_file() and not path.is_symlink():
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

        Returns ``{"entries", "bytes"}`` removed. An entry that cannot be read is removed too.
        Raises :class:`NotOurCache` (nothing removed) when the root is not marked.
        """
        self._require_marked()
        removed, size, now = 0, 0, time.time()
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
                if old or stale:
                    path.unlink()
                    removed += 1
                    size += status.st_size
            except OSError:
                continue
        return {"entries": removed, "bytes": size}

    def clear(self) -> dict:
        """Remove every entry, the temporaries and the emptied shard directories; the root
        and its marker stay (and anything else in it: never the harness's to remove).
        Raises :class:`NotOurCache` (nothing removed) when the root is not marked."""
        self._require_marked()
        removed, size = 0, 0
        for path in list(self._entries()):
            try:
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
        return {"entries": removed, "bytes": size}

    @property
    def stats(self) -> dict:
        total = self.hits + self.misses
        return {"enabled": self.enabled, "hits": self.hits, "misses": self.misses,
                "hit_rate": self.hits / total if total else 0.0}


class PendingPuts:
    """Records to store, written a pack at a time (:meth:`ResultCache.put_many`): what a
    run's main process stores (the references its workers computed, the engine runs of an
    executor whose workers do not store them) in a few files, not one each. ``put`` writes
    a pack once :data:`PACK_SIZE` wait or the first of them has waited ``max_wait_s`` (a
    process killed outright loses no more than that of finished work); ``flush`` writes the
    rest (the runner calls it when the work ends, however it ends). Both raise ``OSError``
    as :meth:`ResultCache.put` does (the records not written are dropped). ``cache`` None:
    stores nothing."""

    def __init__(self, cache: ResultCache | None, max_wait_s: float = 2.0) -> None:
        self.cache = cache
        self.max_wait_s = max_wait_s
        self.items: list[tuple[str, dict]] = []
        self._first_at = 0.0  # when the first record waiting was put

    def put(self, key: str, record: dict) -> None:
        if self.cache is None or not self.cache.enabled:
            return
        now = time.monotonic()
        if not self.items:
            self._first_at = now
        self.items.append((key, record))
        if len(self.items) >= PACK_SIZE or now - self._first_at >= self.max_wait_s:
            self.flush()

    def flush(self) -> None:
        items, self.items = self.items, []
        if items and self.cache is not None:
            self.cache.put_many(items)


def _is_temporary(name: str) -> bool:
    """A writer's temporary file name (:func:`harness.store.files.write_parts_atomically`)."""
    return name.startswith(".") and name.endswith(".tmp")


def split_block(text: bytes | memoryview, count: int) -> list[str]:
    """The ``count`` lines of a block of text that :meth:`ResultCache.put_lines` stored
    (``ValueError`` when it holds another number of lines)."""
    lines = str(text, "utf-8").split(LINE_SEPARATOR) if count else []
    if len(lines) != count:
        raise ValueError(f"{len(lines)} lines, not {count}")
    return lines


def _parse_lines(lines: list[str]) -> list:
    """Each line's JSON value, parsed with the cyclic garbage collector paused: the
    containers of a scenario's records set it off again and again, each time walking all
    those read so far (a warm run reads every scenario's records), though none is garbage."""
    with collector_paused():
        return [json.loads(line) for line in lines]


def _json_default(value: Any) -> Any:
    if hasattr(value, "tolist"):
        return value.tolist()
    if isinstance(value, Path):
        return value.as_posix()
    raise TypeError(f"cache record holds a value that is not JSON-able: {type(value).__name__}")


#: The encoder of :meth:`ResultCache.put`'s entries (what ``json.dumps(entry,
#: default=_json_default)`` writes), made once: ``json.dumps`` with a ``default`` builds a
#: new encoder per call. No check for cycles (a record is a tree, made by the runner; one
#: holding a cycle would end in a ``RecursionError`` instead of a ``ValueError``).
_ENTRY_ENCODER = json.JSONEncoder(default=_json_default, check_circular=False)


__all__ = ["CACHE_DIR_VARIABLE", "CACHE_MARKER", "LINE_SEPARATOR", "PACK_DIRECTORY", "PACK_SIZE",
           "NotOurCache", "PendingPuts", "ResultCache", "default_cache_dir"]
