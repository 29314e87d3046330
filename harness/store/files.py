"""Writing a file so that no reader ever sees half of it and no finished file is lost, only
ever over a regular file (never a device, a directory or a symbolic link), with the
permissions the user's umask gives a new file (0644 under the usual 022).

:func:`output_file_problem` and :func:`output_directory_problem` say, before any work, why
an output path the user gave cannot be written (a command exits 2 with that line).
"""

from __future__ import annotations

import hashlib
import io
import itertools
import json
import os
import stat
import sys
import tempfile
from pathlib import Path
from typing import Iterable

from harness.store.sealing import Seal

#: Numbers the temporaries of this process (with its pid: a unique name without the random
#: draw of ``tempfile.mkstemp``, a sizeable share of a small cache entry's write).
_TEMPORARY_NUMBERS = itertools.count()
#: Names a temporary is tried under before falling back to ``tempfile.mkstemp``: a name is
#: taken only by a file a dead process of the same pid left (or another host's process).
_NAMED_TRIES = 4
_CREATE = os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_CLOEXEC", 0)


def write_text_atomically(path: Path | str, text: str, *, prefix: str | None = None,
                          make_parent: bool = False) -> Path | str:
    """Write ``text`` to ``path`` through a unique temporary file in the same directory and
    an atomic rename: two writers each replace the file whole, a kill leaves at most a
    ``.tmp`` file (which its owner cleans up), never a half-written ``path``.

    ``make_parent`` creates the directory when it is missing (only then: an existing one
    costs no ``mkdir``), once more if it vanishes between the ``mkdir`` and the temporary
    file (a cache removed with ``rm -rf`` during a run). Returns ``path``.
    """
    return write_bytes_atomically(path, text.encode("utf-8"), prefix=prefix,
                                  make_parent=make_parent)


def write_bytes_atomically(path: Path | str, data: bytes, *, prefix: str | None = None,
                           make_parent: bool = False) -> Path | str:
    """:func:`write_text_atomically` for bytes (one ``write`` call, unbuffered)."""

    def write(descriptor: int) -> None:
        view = memoryview(data)
        while view:  # a write may take a part only
            view = view[os.write(descriptor, view):]

    return _replace_atomically(path, write, prefix, make_parent)


def write_parts_atomically(path: Path | str, parts: Iterable[bytes | str], *,
                           prefix: str | None = None, make_parent: bool = False) -> Path | str:
    """:func:`write_text_atomically` of the concatenation of ``parts`` (bytes, or text
    written as UTF-8), written one after the other through a buffer: a large file is never
    built whole in memory first, and many small parts cost few ``write`` calls."""

    def write(descriptor: int) -> None:
        with open(descriptor, "wb", closefd=False) as handle:
            for part in parts:
                handle.write(part.encode("utf-8") if isinstance(part, str) else part)

    return _replace_atomically(path, write, prefix, make_parent)


def _replace_atomically(path: Path | str, write, prefix: str | None,
                        make_parent: bool) -> Path | str:
    """Make a temporary beside ``path``, ``write(descriptor)`` its content, rename it to
    ``path``; the temporary is removed when anything fails (see
    :func:`write_text_atomically`)."""
    directory, name = os.path.split(os.fspath(path))
    prefix = prefix or f".{name}-"
    for attempt in (1, 2, 3):
        try:
            descriptor, temporary = _create_temporary(directory, prefix)
            break
        except FileNotFoundError:  # no directory yet, or removed after the mkdir
            if attempt == 3 or not make_parent:
                raise
            os.makedirs(directory or os.curdir, exist_ok=True)
    try:
        try:
            write(descriptor)
        finally:
            os.close(descriptor)
        problem = _replaceable_problem(path)
        if problem:  # never replace a device, a directory or a link with a file
            raise NotRegularFile(f"{os.fspath(path)}: {problem}")
        os.replace(temporary, path)
    except BaseException:
        try:
            os.unlink(temporary)
        except OSError:
            pass
        raise
    return path


def save_figure(figure, path: Path | str, kind: str, **options) -> Path | str:
    """``figure.savefig`` (a matplotlib figure, as ``kind``: ``"png"``, ``"svg"``) into
    memory, then written as :func:`write_bytes_atomically` writes: never through a link or
    onto a device planted at ``path``. Returns ``path``."""
    buffer = io.BytesIO()
    figure.savefig(buffer, format=kind, **options)
    return write_bytes_atomically(path, buffer.getvalue())


def _create_temporary(directory: str, prefix: str) -> tuple[int, str]:
    """A new file ``<prefix><pid>-<n>.tmp`` in ``directory``, opened for writing:
    ``(descriptor, path)``, with the mode a new file gets (0666 less the umask: the file it
    becomes is an ordinary output, not a secret). ``O_EXCL`` makes it this writer's alone;
    a name already taken is passed over."""
    stem = os.path.join(directory, f"{prefix}{os.getpid()}-")
    for _ in range(_NAMED_TRIES):
        temporary = f"{stem}{next(_TEMPORARY_NUMBERS)}.tmp"
        try:
            return os.open(temporary, _CREATE, 0o666), temporary  # the umask applies
        except FileExistsError:
            continue
    descriptor, temporary = tempfile.mkstemp(prefix=prefix, suffix=".tmp",
                                             dir=directory or os.curdir)
    os.fchmod(descriptor, 0o666 & ~_umask())  # mkstemp makes 0600
    return descriptor, temporary


def _umask() -> int:
    """The process's umask (read by setting it and back: there is no other way)."""
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


class NotRegularFile(OSError):
    """An output path holds something other than a regular file: it is not replaced."""


_KINDS = ((stat.S_ISLNK, "a symbolic link"), (stat.S_ISDIR, "a directory"),
          (stat.S_ISCHR, "a character device"), (stat.S_ISBLK, "a block device"),
          (stat.S_ISFIFO, "a named pipe"), (stat.S_ISSOCK, "a socket"))


def _replaceable_problem(path: Path | str) -> str | None:
    """None when ``path`` holds nothing or a regular file, else what it is instead."""
    try:
        mode = os.lstat(path).st_mode
    except FileNotFoundError:
        return None
    except OSError as error:  # a name too long, a loop of links, a file for a directory
        return f"cannot be used: {error.strerror or error}"
    if stat.S_ISREG(mode):
        return None
    kind = next((name for test, name in _KINDS if test(mode)), "not a regular file")
    return f"is {kind}, not a regular file: not replaced"


def replaceable_problem(path: Path | str) -> str | None:
    """Why a file a command writes under a fixed name at ``path`` would not be replaced
    (``None``: nothing is there or a regular file): a link, a directory, a device planted
    there is refused before any work, not found by the write at the end."""
    return _replaceable_problem(path)


def output_file_problem(path: Path | str) -> str | None:
    """Why a file the user named cannot be written at ``path`` (``None``: it can): it must
    be nothing yet or a regular file (not a link, a device or a directory), in a directory
    that exists and takes a new file. Nothing is created or changed."""
    path = Path(path)
    problem = _replaceable_problem(path)
    if problem:
        return problem
    parent = path.parent
    try:
        is_directory = parent.is_dir()
    except OSError as error:
        return f"cannot be used: {error.strerror or error}"
    if not is_directory:
        return (f"its directory {parent} does not exist (create it first: only a directory "
                "the command asks for is ever made)")
    if not os.access(parent, os.W_OK | os.X_OK):
        return f"its directory {parent} is not writable"
    return None


def output_directory_problem(path: Path | str) -> str | None:
    """Why an output directory the user named cannot be used (``None``: it can): it must
    be a directory (a link to one is fine) that takes new files, or nothing yet in an
    existing directory (it is then made, itself only, not its parents)."""
    path = Path(path)
    try:
        return _directory_problem(path)
    except OSError as error:  # a name too long, a loop of links
        return f"cannot be used: {error.strerror or error}"


def _directory_problem(path: Path) -> str | None:
    if path.is_dir():
        if not os.access(path, os.W_OK | os.X_OK):
            return "is not a writable directory"
        return None
    if os.path.lexists(path):
        kind = _replaceable_problem(path) or "is a regular file"
        return f"{kind.split(',')[0]}, not a directory"
    if not path.parent.is_dir():
        return (f"its parent {path.parent} does not exist (create it first: only the named "
                "directory itself is made)")
    if not os.access(path.parent, os.W_OK | os.X_OK):
        return f"cannot be made: {path.parent} is not writable"
    return None


def inner_directory_problem(base: Path | str, *names: str) -> str | None:
    """Why the directory ``base/names[0]/names[1]/...`` a command writes into beneath the
    output directory the user named cannot be used (``None``: it can; missing parts are
    made by :func:`make_inner_directory`): each part that exists must be a directory itself,
    never a symbolic link (a link planted at ``out/figures`` would have every figure written,
    and old ones removed, wherever it points)."""
    path = Path(base)
    for name in names:
        path = path / name
        try:
            mode = os.lstat(path).st_mode
        except FileNotFoundError:
            return None
        except OSError as error:
            return f"{path}: cannot be used: {error.strerror or error}"
        if not stat.S_ISDIR(mode):
            kind = next((what for test, what in _KINDS if test(mode)), "a file")
            return (f"{path}: is {kind}, not a directory: nothing is written through it "
                    "(remove it, or choose another --out)")
    return None


def make_inner_directory(base: Path | str, *names: str) -> Path:
    """The directory ``base/names...`` (see :func:`inner_directory_problem`), each missing
    part made; :class:`NotRegularFile` when a part is a link or not a directory."""
    path = Path(base)
    for name in names:
        path = path / name
        try:
            path.mkdir()
        except FileExistsError:
            pass
        mode = os.lstat(path).st_mode
        if not stat.S_ISDIR(mode):
            raise NotRegularFile(inner_directory_problem(base, *names) or f"{path}: changed")
    return path


#: The format of a manifest of written files (:func:`keep_manifest`); an older one (a bare
#: list of names) removes nothing.
MANIFEST_FORMAT = 2
#: Largest manifest read (a report of 10,000 scenarios lists about 40,000 figures).
MAX_MANIFEST_BYTES = 16 * 2**20
_OPEN_NO_LINK = (os.O_RDONLY | getattr(os, "O_NOFOLLOW", 0) | getattr(os, "O_NONBLOCK", 0)
                 | getattr(os, "O_CLOEXEC", 0))


def regular_file_sha256(path: Path | str) -> str | None:
    """The SHA-256 of the regular file at ``path`` (never through a link), or None when it
    is missing, a link or anything but a regular file."""
    try:
        descriptor = os.open(path, _OPEN_NO_LINK)
    except OSError:
        return None
    try:
        if not stat.S_ISREG(os.fstat(descriptor).st_mode):
            return None
        digest = hashlib.sha256()
        with open(descriptor, "rb", closefd=False) as handle:
            for block in iter(lambda: handle.read(2**20), b""):
                digest.update(block)
        return digest.hexdigest()
    finally:
        os.close(descriptor)


def keep_manifest(directory: Path | str, manifest_name: str, wanted: Iterable[str],
                  suffixes: tuple[str, ...], seal: Seal) -> list[str]:
    """Record the files ``wanted`` (names in ``directory``) as written by the harness, and
    remove those an earlier manifest recorded that are no longer wanted; returns the names
    removed.

    A file is removed only when the manifest in ``directory`` (``manifest_name``, a regular
    file, never a link) is sealed by ``seal`` (the HMAC of :mod:`harness.store.sealing`
    under a key kept outside ``directory``,
    :func:`harness.store.cache_directory.output_seal`), names it with the SHA-256 of what
    was written, the name is a plain name with one of ``suffixes``, and the file is still a
    regular file holding exactly that: a name planted in a manifest -- even with the right
    hash of a user's file --, a file the user put in its place, a link, are never removed
    (issue 37, item 3). A manifest there that is not sealed removes nothing, said once on
    stderr. The new manifest lists each wanted file present with its SHA-256, sealed
    (unsealed when the key cannot be had: it then removes nothing), written atomically."""
    directory = Path(directory)
    manifest = directory / manifest_name
    recorded = _read_manifest(manifest, seal)
    wanted = set(wanted)
    removed = []
    for name in sorted(set(recorded) - wanted):
        if (os.path.basename(name) != name or name in ("", ".", "..")
                or not name.endswith(suffixes) or name == manifest_name):
            continue
        path = directory / name
        if regular_file_sha256(path) == recorded[name]:
            try:
                os.unlink(path)
                removed.append(name)
            except OSError:
                continue
    written = {}
    for name in sorted(wanted):
        digest = regular_file_sha256(directory / name)
        if digest is not None:
            written[name] = digest
    stored = {"format": MANIFEST_FORMAT, "written": written}
    try:
        stored = seal.sealed(stored)
    except (OSError, ValueError) as error:  # KeyProblem is a ValueError
        _warn_once(manifest, f"cannot be sealed ({error}): the next run removes nothing "
                   "it lists")
    write_text_atomically(manifest, json.dumps(stored, indent=0) + "\n")
    return removed


#: The manifests :func:`_warn_once` spoke of in this process.
_WARNED: set[str] = set()


def _warn_once(manifest: Path, what: str) -> None:
    if os.fspath(manifest) not in _WARNED:
        _WARNED.add(os.fspath(manifest))
        print(f"impact-harness: warning: {manifest}: {what}", file=sys.stderr)


def _read_manifest(manifest: Path, seal: Seal) -> dict[str, str]:
    """``{name: SHA-256}`` of a manifest :func:`keep_manifest` wrote (a regular file, never
    read through a link, of bounded size, sealed by ``seal``); empty when there is none or
    it is not one (said once when it is there but not sealed)."""
    try:
        descriptor = os.open(manifest, _OPEN_NO_LINK)
        try:
            status = os.fstat(descriptor)
            if not stat.S_ISREG(status.st_mode) or status.st_size > MAX_MANIFEST_BYTES:
                return {}
            stored = json.loads(os.read(descriptor, MAX_MANIFEST_BYTES + 1))
        finally:
            os.close(descriptor)
    except (OSError, ValueError):  # none, a link, damaged: nothing is removed
        return {}
    if not (isinstance(stored, dict) and stored.get("format") == MANIFEST_FORMAT
            and isinstance(stored.get("written"), dict)):
        return {}
    try:
        seal.check(stored)
    except ValueError as error:  # KeyProblem too
        _warn_once(manifest, f"not sealed by the harness, nothing it lists is removed ({error})")
        return {}
    return {name: digest for name, digest in stored["written"].items()
            if isinstance(name, str) and isinstance(digest, str)}


def remove_written(directory: Path | str, manifest_name: str, name: str, seal: Seal) -> bool:
    """Remove ``directory/name`` when the manifest there, sealed by ``seal``, records it and
    it still holds what was written (:func:`keep_manifest`'s rule); whether it was
    removed."""
    directory = Path(directory)
    recorded = _read_manifest(directory / manifest_name, seal).get(name)
    if recorded is None or os.path.basename(name) != name or name == manifest_name:
        return False
    if regular_file_sha256(directory / name) != recorded:
        return False
    try:
        os.unlink(directory / name)
    except OSError:
        return False
    return True


def make_output_directory(path: Path | str) -> Path:
    """Make the output directory ``path`` (itself only) when it is missing; returns it."""
    path = Path(path)
    if not path.is_dir():
        path.mkdir()
    return path
