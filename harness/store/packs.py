"""The cache's packs: many records in one file, ``root/packs/<sha256 of the pack>.pack``
(:meth:`harness.store.cache.ResultCache.put_many`: an engine chunk's runs, a run's
references), and the index of where each packed record lies, read from the packs' headers.

A pack is a header line (the code version, and per record its key, size and SHA-256), then
the records' JSON one after the other (the module docstring of :mod:`harness.store.cache`
has the whole layout). :class:`PendingPuts` gathers a run's records into packs.
"""

from __future__ import annotations

import hashlib
import json
import os
import re
import stat
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

from harness.bounds import limit
from harness.store.sealing import Seal

if TYPE_CHECKING:  # the cache writes packs; a pack never needs the cache to be made
    from harness.store.cache import ResultCache

#: The longest header line read (512 records' keys, sizes and digests take about 70 kB).
MAX_HEADER_BYTES = 2**20

#: The directory of the packs in the root (:meth:`ResultCache.put_many`), a pack's name in it,
#: and the most records one pack holds (a run's main process buffers at most as many).
PACK_DIRECTORY = "packs"
PACK_NAME = re.compile(r"[0-9a-f]{64}\.pack")
PACK_SIZE = 512


@dataclass(frozen=True)
class Pack:
    """One pack's file: its ``name`` (its content's SHA-256), its ``header`` line and the
    records' ``bodies``, with each record's key, size and SHA-256 as the header gives them."""

    name: str
    header: bytes
    bodies: list[bytes]
    keys: list[str]
    sizes: list[int]
    digests: list[str]


def make_pack(items: Sequence[tuple[str, dict]], version: str,
              encode: Callable[[dict], str], seal: Callable[[dict], dict | None]
              ) -> Pack | None:
    """The pack of ``items`` (``(key, record)``), each record's JSON made by ``encode``, its
    header sealed by ``seal`` (:mod:`harness.store.sealing`; None: no pack, the key is not
    believed)."""
    keys = [key for key, _ in items]
    bodies = [encode(record).encode("utf-8") for _, record in items]
    sizes = [len(body) for body in bodies]
    digests = [hashlib.sha256(body).hexdigest() for body in bodies]
    sealed = seal({"code_version": version, "keys": keys, "sizes": sizes, "sha256": digests})
    if sealed is None:
        return None
    header = json.dumps(sealed, separators=(",", ":")).encode("utf-8") + b"\n"
    digest = hashlib.sha256(header)
    for body in bodies:
        digest.update(body)
    return Pack(f"{digest.hexdigest()}.pack", header, bodies, keys, sizes, digests)


class PackIndex:
    """Where each packed record of one cache root lies: key -> (pack path, offset, size,
    SHA-256), from the headers of the packs read so far (or written by this cache)."""

    def __init__(self, root, version: str, seal: Seal) -> None:
        self.root = root
        self.version = version
        self.seal = seal  # a header is indexed only when its seal verifies
        # key -> (pack path, offset, size, SHA-256) of the packed records, from the headers
        # of the packs named in read (read, or rejected)
        self.where: dict[str, tuple[str, int, int, str]] = {}
        self.read: set[str] = set()
        self.listed = False  # within ResultCache.listed(): the packs' directory was read

    def written(self, path: str, pack: Pack) -> None:
        """Index the records of ``pack``, just written at ``path``."""
        self.add(path, pack.header, pack.keys, pack.sizes, pack.digests)
        self.read.add(pack.name)

    def add(self, path: str, header: bytes, keys: list, sizes: list, digests: list) -> None:
        offset = len(header)
        for key, size, sha256 in zip(keys, sizes, digests):
            self.where[key] = (path, offset, size, sha256)
            offset += size

    def entry(self, key: str, within_listing: bool, rejected: list[str]
              ) -> tuple[str, int, int, str] | None:
        """Where ``key`` lies in a pack, or None. The packs' headers not read yet are read
        at a miss: once within :meth:`ResultCache.listed` (``within_listing``: the packs
        written meanwhile by other processes are not seen; its own are), at every miss
        outside it. A pack that cannot be read is listed in ``rejected``."""
        found = self.where.get(key)
        if found is not None or self.listed:
            return found
        self.listed = within_listing
        directory = os.path.join(self.root, PACK_DIRECTORY)
        try:
            names = os.listdir(directory)
        except OSError:  # none yet, or not a directory: nothing packed
            return None
        for name in names:
            if name in self.read or not PACK_NAME.fullmatch(name):
                continue
            self.read.add(name)
            path = os.path.join(directory, name)
            try:
                self.read_header(path)
            except (OSError, ValueError) as error:  # UnicodeDecodeError is a ValueError
                rejected.append(f"{path}: {error}")
        return self.where.get(key)

    def read_header(self, path: str) -> None:
        """Index the records of the pack at ``path`` (those of this code version only: the
        keys of another hold another version anyway); ``ValueError`` when its header is not
        a pack's or its size is not the one the header gives."""
        with open_regular(path) as handle:
            line = handle.readline(MAX_HEADER_BYTES)
            size = os.fstat(handle.fileno()).st_size
        if not line.endswith(b"\n"):
            raise ValueError("not a cache pack (no header line)")
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
        if any(n > limit("max_cache_entry_bytes") for n in sizes):
            raise ValueError("a record larger than the cache reads")
        self.seal.check(header)
        self.add(path, line, keys, sizes, digests)


def open_regular(path: str):
    """``path`` opened for reading in binary, without blocking on a FIFO or a device:
    ``ValueError`` when it is not a regular file."""
    descriptor = os.open(path, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0)
                         | getattr(os, "O_CLOEXEC", 0))
    if not stat.S_ISREG(os.fstat(descriptor).st_mode):
        os.close(descriptor)
        raise ValueError("not a regular file")
    return os.fdopen(descriptor, "rb")


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

