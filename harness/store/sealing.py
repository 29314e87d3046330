"""The cache's seal: what the cache says is believed only if a keyed check covers all of it.

A SHA-256 in an entry's header only tells that the body was not damaged by accident: anyone
who can write the cache can edit a header (a gate flipped to pass) or a body and recompute
it (issue 37, item 4). Every header the cache writes (a single entry's, a scenario's entry
of many lines, a pack's, the checks' store) therefore carries ``mac``: the HMAC-SHA256,
under a key of this cache, of the header's canonical JSON without ``mac``; the header holds
the SHA-256 of every byte that follows it, so the seal covers header and body alike. A
header whose seal does not verify is a miss (recomputed), listed with the other rejected
entries.

The key is 32 random bytes, spelled in hex, in :data:`KEY_FILE` in the cache's root, made
at the first write with mode 0600 (created whole under a temporary name, then linked into
place: two writers racing keep the first). It is believed only when it is a regular file
(never a link), owned by this user, readable by nobody else, and 64 hex digits; otherwise
nothing in the cache is believed and nothing is written to it (:class:`KeyProblem`, said
once among the rejected entries: remove the file and the next run makes a new key). A
missing key on a read means no entry can be believed (each is a miss; the next write makes
the key). The key never leaves the cache's directory and is never printed.
"""

from __future__ import annotations

import hashlib
import hmac
import json
import os
import secrets
import stat
from pathlib import Path

#: The key's file in the cache's root.
KEY_FILE = "cache.key"
_KEY_HEX_DIGITS = 64
_OPEN_KEY = (os.O_RDONLY | getattr(os, "O_NOFOLLOW", 0) | getattr(os, "O_NONBLOCK", 0)
             | getattr(os, "O_CLOEXEC", 0))


class KeyProblem(ValueError):
    """The cache's key file cannot be believed: nothing in the cache is."""


class Seal:
    """The seal of the cache at ``root``: :meth:`sealed` adds ``mac`` to a header,
    :meth:`check` verifies one. The key is read (or, when ``create``, made) once."""

    def __init__(self, root: Path | str) -> None:
        self.root = Path(root)
        self._key: bytes | None = None

    @property
    def path(self) -> Path:
        return self.root / KEY_FILE

    def key(self, create: bool) -> bytes | None:
        """The key; ``None`` when there is none and ``create`` is false. Raises
        :class:`KeyProblem` when the file is not one to believe, ``OSError`` when it cannot
        be made."""
        if self._key is None:
            try:
                self._key = _read_key(self.path)
            except FileNotFoundError:
                if not create:
                    return None
                self._key = _make_key(self.path)
        return self._key

    def sealed(self, header: dict) -> dict:
        """``header`` with its ``mac`` (the key made when missing; a ``mac`` it holds is
        replaced)."""
        unsealed = {name: value for name, value in header.items() if name != "mac"}
        return {**unsealed, "mac": _mac(self.key(create=True), unsealed)}

    def check(self, header: dict) -> None:
        """``ValueError`` unless ``header`` carries the ``mac`` of this cache's key."""
        key = self.key(create=False)
        if key is None:
            raise ValueError(f"no key ({KEY_FILE}) to check its seal by: not believed")
        mac = header.get("mac")
        unsealed = {name: value for name, value in header.items() if name != "mac"}
        if not isinstance(mac, str) or not hmac.compare_digest(mac, _mac(key, unsealed)):
            raise ValueError("seal does not verify (header or body changed after it was "
                             "written, or written without this cache's key)")


def _mac(key: bytes, header: dict) -> str:
    text = json.dumps(header, sort_keys=True, separators=(",", ":"), ensure_ascii=False,
                      allow_nan=False)
    return hmac.new(key, text.encode("utf-8"), hashlib.sha256).hexdigest()


def _read_key(path: Path) -> bytes:
    try:
        descriptor = os.open(path, _OPEN_KEY)
    except FileNotFoundError:
        raise
    except OSError as error:  # a link (O_NOFOLLOW: ELOOP), no permission
        raise KeyProblem(f"{path}: cannot be read as the cache's key "
                         f"({error.strerror or error})") from None
    try:
        status = os.fstat(descriptor)
        if not stat.S_ISREG(status.st_mode):
            raise KeyProblem(f"{path}: not a regular file")
        if status.st_uid != os.geteuid():
            raise KeyProblem(f"{path}: owned by another user")
        if status.st_mode & 0o077:
            raise KeyProblem(f"{path}: readable or writable by others (mode "
                             f"{stat.S_IMODE(status.st_mode):04o}, allowed: 0600)")
        text = os.read(descriptor, _KEY_HEX_DIGITS + 1)
    finally:
        os.close(descriptor)
    try:
        key = bytes.fromhex(text.decode("ascii"))
    except ValueError:
        key = b""
    if len(key) * 2 != _KEY_HEX_DIGITS or len(text) != _KEY_HEX_DIGITS:
        raise KeyProblem(f"{path}: not a key ({_KEY_HEX_DIGITS} hex digits)")
    return key


def _make_key(path: Path) -> bytes:
    """A new key at ``path``, or the one another writer made first."""
    key = secrets.token_bytes(_KEY_HEX_DIGITS // 2)
    temporary = path.with_name(f".{KEY_FILE}-{os.getpid()}-{secrets.token_hex(4)}.tmp")
    descriptor = os.open(temporary, os.O_WRONLY | os.O_CREAT | os.O_EXCL
                         | getattr(os, "O_NOFOLLOW", 0), 0o600)
    try:
        try:
            os.fchmod(descriptor, 0o600)
            os.write(descriptor, key.hex().encode("ascii"))
        finally:
            os.close(descriptor)
        try:
            os.link(temporary, path)  # never replaces: the first writer's key stays
        except FileExistsError:
            return _read_key(path)
    finally:
        os.unlink(temporary)
    return key


__all__ = ["KEY_FILE", "KeyProblem", "Seal"]
