"""Writing a file so that no reader ever sees half of it and no finished file is lost."""

from __future__ import annotations

import itertools
import os
import tempfile
from pathlib import Path
from typing import Iterable

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
        os.replace(temporary, path)
    except BaseException:
        try:
            os.unlink(temporary)
        except OSError:
            pass
        raise
    return path


def _create_temporary(directory: str, prefix: str) -> tuple[int, str]:
    """A new file ``<prefix><pid>-<n>.tmp`` in ``directory`` (mode 0600, as ``mkstemp``
    makes it), opened for writing: ``(descriptor, path)``. ``O_EXCL`` makes it this
    writer's alone; a name already taken is passed over."""
    stem = os.path.join(directory, f"{prefix}{os.getpid()}-")
    for _ in range(_NAMED_TRIES):
        temporary = f"{stem}{next(_TEMPORARY_NUMBERS)}.tmp"
        try:
            return os.open(temporary, _CREATE, 0o600), temporary
        except FileExistsError:
            continue
    return tempfile.mkstemp(prefix=prefix, suffix=".tmp", dir=directory or os.curdir)
