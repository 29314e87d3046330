"""Content-addressed cache of results: rerunning an unchanged suite does no engine work.

Home: :func:`~harness.store.cache_directory.default_cache_dir` --
``$IMPACT_HARNESS_CACHE_DIR`` when set, else ``.cache/results`` under the project root (the
checkout holding ``pyproject.toml``; ``make clean`` removes it), else, for an installed
harness, ``$XDG_CACHE_HOME/impact-harness`` (``~/.cache/impact-harness``). Never the working
directory. Bounded by ``impact-harness cache prune`` (entries written by other code, or older
than ``--older-than`` days) and ``cache clear``; ``cache info`` shows the size
(:mod:`harness.store.cli`).

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
Every header carries the cache's seal (:mod:`harness.store.sealing`: an HMAC under a key
made with mode 0600 in the root, over the header, which holds the SHA-256 of what follows),
so a header or a body edited after it was written, its checksum recomputed or not, is not
believed. Reads are bounded (``max_cache_entry_bytes`` of :mod:`harness.bounds`), of regular
files only. An unreadable, corrupted, edited or unsealed file (its seal does not verify, its
checksum differs; in a pack, a record whose checksum differs, or every record of a pack
whose header is not whole or not sealed) is a miss, and so is an entry
the caller's ``check`` rejects (a record without finite velocities of the right shape): both
are listed in :attr:`ResultCache.rejected`, which the run prints as warnings, and the
result is computed again. Beside the entries, ``root/passed-checks.json`` keeps the keys of
the scenario texts that passed their checks (:class:`harness.store.passed_checks.PassedChecks`);
``cache info``, ``prune`` and ``clear`` count and remove it with them.

The harness deletes only what it made (the marker file, :mod:`harness.store.cache_directory`).

The modules: this one (keys, lookups, entries of one record or of many lines),
:mod:`harness.store.packs` (the packs, their index, :class:`~harness.store.packs.PendingPuts`),
:mod:`harness.store.cache_directory` (the root, its marker, ``info``, ``prune``, ``clear``).
"""

from __future__ import annotations

import hashlib
import itertools
import json
import os
import secrets
import stat
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from harness.collector import collector_paused
from harness.inputs import read_bytes
from harness.store.cache_directory import CacheDirectory
from harness.store.files import NotRegularFile, write_parts_atomically
from harness.store.identity import Spelled, canonical_json, code_version
from harness.store.packs import PACK_DIRECTORY, PACK_SIZE, PackIndex, make_pack, open_regular
from harness.store.sealing import KeyProblem, Seal

#: Between two lines of an entry of many lines (:meth:`ResultCache.put_lines`): the record
#: lines of a results file (:mod:`harness.run.records`), which a warm run copies as stored.
LINE_SEPARATOR = ",\n"

CACHE_FORMAT = 3  # bump when the record layout changes (2: SHA-256 checked, no pickle;
#                  3: every header sealed, harness.store.sealing)

#: The stand-in of :meth:`ResultCache.slot_key`'s slot (a random string, spelled as json
#: spells it).
_SLOT = Spelled(f"slot{secrets.token_hex(16)}")


class ResultCache(CacheDirectory):
    """Results on disk, keyed by a content hash of what they depend on.

    Parameters
    ----------
    root
        Directory of the cache (created on the first ``put``); default
        :func:`~harness.store.cache_directory.default_cache_dir`.
    enabled
        ``False`` (the runner's ``--no-cache``): ``get`` always misses, ``put`` writes nothing.
    version
        Code version mixed into every key (default: :func:`code_version`); tests pass their own.
    """

    def __init__(self, root: Path | str | None = None, enabled: bool = True,
                 version: str | None = None):
        super().__init__(root, enabled, code_version() if version is None else version)
        self.hits = 0
        self.misses = 0
        self.rejected: list[str] = []  # "<entry path>: <why>" of entries read as a miss
        self._root_seen = False  # whether this cache looked at its root's marker yet
        # shard -> the names in its directory, while listed() is active (None: not listed)
        self._listing: dict[str, set[str] | None] | None = None
        self._real_directories: set[str] = set()  # shards seen to be directories, not links
        self.seal = Seal(self.root)  # the keyed check of every header (harness.store.sealing)
        self._packs = PackIndex(self.root, self.version, self.seal)  # where packed records lie

    def _untrusted(self, error: KeyProblem) -> None:
        """The key cannot be believed: nothing is read from the cache or written to it from
        now on, said once among the rejected entries."""
        self.rejected.append(f"{error}: nothing in the cache is believed or written (remove "
                             "the file: the next run makes a new key)")
        self.enabled = False

    def _sealed(self, header: dict) -> dict | None:
        """``header`` sealed for writing, or None when the key cannot be believed (the root
        made first when missing: the key lies in it)."""
        self._first_write()
        try:
            try:
                return self.seal.sealed(header)
            except FileNotFoundError:  # no root yet, or removed under a running writer
                self.make_root()
                return self.seal.sealed(header)
        except KeyProblem as error:
            self._untrusted(error)
            return None

    def _first_write(self) -> None:
        """At the first write, a root that exists empty and unmarked is marked (made by the
        caller for the cache); one holding anything else is written into unmarked (the
        caller chose it; ``prepare`` refuses it for a run), so never cleared."""
        if not self._root_seen:
            self._root_seen = True
            try:
                if not self.marked() and self.root.is_dir() and not any(self.root.iterdir()):
                    self.make_root()
            except OSError:
                pass

    @contextmanager
    def listed(self) -> Iterator[None]:
        """Within: whether an entry exists is read from a listing of its shard's directory,
        made at the first lookup there, not by opening the file: the misses of a cold run
        (thousands of entries that are not there) cost a set lookup each. An entry another
        process writes meanwhile is a miss (its run simulated again); those this cache puts
        are listed."""
        self._listing, self._packs.listed = {}, False
        try:
            yield
        finally:
            self._listing, self._packs.listed = None, False

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
                raw = read_bytes(path, cap_name="max_cache_entry_bytes")
                head_end = raw.find(b"\n")
                header = json.loads(raw[:head_end]) if head_end > 0 else None
                if not isinstance(header, dict) or header.get("key") != key:
                    raise ValueError("not a cache entry")
                self.seal.check(header)
                body, sha256 = memoryview(raw)[head_end + 1:], header.get("sha256")
            except FileNotFoundError:
                packed = self._packs.entry(key, self._listing is not None, self.rejected)
                if packed is None:
                    raise
                pack, offset, size, sha256 = packed
                path = f"{pack} (record {key[:12]})"
                with open_regular(pack) as handle:
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
        except KeyProblem as error:
            self._untrusted(error)
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
        sealed = self._sealed({"key": key, "code_version": self.version,
                               "sha256": hashlib.sha256(body).hexdigest()})
        if sealed is None:
            return
        header = json.dumps(sealed)
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
            pack = make_pack(items[start:start + PACK_SIZE], self.version, _ENTRY_ENCODER.encode,
                             self._sealed)
            if pack is None:
                return
            path = os.path.join(self.root, PACK_DIRECTORY, pack.name)
            self._write(path, (pack.header, *pack.bodies), pack.name)
            self._packs.written(path, pack)

    def _write(self, path: str, parts: tuple, key: str) -> None:
        """Write an entry's ``parts`` at ``path`` atomically; the shard directory made when
        missing (only then: a cold run puts thousands of small entries, whose mkdir calls
        would cost as much as their writes), and the root first, marked, when it is missing
        (:meth:`_first_write`)."""
        self._first_write()
        directory = os.path.dirname(path)
        for attempt in (1, 2, 3):
            try:
                if directory not in self._real_directories:
                    self._check_directory(directory)
                write_parts_atomically(path, parts, prefix=f".{key[:8]}-")
                return
            except FileNotFoundError:
                if attempt == 3:
                    raise
                if not os.path.isdir(self.root):
                    self.make_root()
                os.makedirs(os.path.dirname(path), exist_ok=True)
    def _check_directory(self, directory: str) -> None:
        """Raise :class:`NotRegularFile` when the shard (or packs) directory ``directory`` is
        a symbolic link or not a directory: an entry is never written through a link planted
        in the cache (it would land wherever the link points). ``FileNotFoundError`` when it
        is missing. Looked at once per directory and process."""
        mode = os.lstat(directory).st_mode
        if not stat.S_ISDIR(mode):
            what = "a symbolic link" if stat.S_ISLNK(mode) else "not a directory"
            raise NotRegularFile(f"{directory}: is {what}, not a directory of the cache: "
                                 "no entry is written through it")
        self._real_directories.add(directory)

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
            raw = read_bytes(path, cap_name="max_cache_entry_bytes")
            head_end = raw.find(b"\n")
            header = json.loads(raw[:head_end if head_end >= 0 else len(raw)])
            data = memoryview(raw)  # slices of it copy nothing
            sizes = header.get("sizes") if isinstance(header, dict) else None
            if (not isinstance(header, dict) or header.get("key") != key
                    or not isinstance(header.get("count"), int)
                    or not isinstance(sizes, list) or not sizes
                    or not all(isinstance(size, int) and size >= 0 for size in sizes)):
                raise ValueError("not a cache entry")
            self.seal.check(header)
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
        except KeyProblem as error:
            self._untrusted(error)
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
        sealed = self._sealed({"key": key, "code_version": self.version, "count": len(lines),
                               "sizes": [len(text), *(len(part) for part in parts)],
                               "sha256": digest.hexdigest(), "summary": summary})
        if sealed is None:
            return
        header = json.dumps(sealed, ensure_ascii=False, allow_nan=False)
        self._write(os.fspath(self.lines_path(key)),
                    (header.encode("utf-8"), b"\n", text, *parts), key)
        self._list(key[:2], f"{key}.jsonl")
    @property
    def stats(self) -> dict:
        total = self.hits + self.misses
        return {"enabled": self.enabled, "hits": self.hits, "misses": self.misses,
                "hit_rate": self.hits / total if total else 0.0}


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


__all__ = ["CACHE_FORMAT", "LINE_SEPARATOR", "ResultCache", "split_block"]
