"""Writing a file so that no reader ever sees half of it and no finished file is lost."""

from __future__ import annotations

import os
import tempfile
from pathlib import Path
from typing import Iterable


def write_text_atomically(path: Path, text: str, *, prefix: str | None = None,
                          make_parent: bool = False) -> Path:
    """Write ``text`` to ``path`` through a unique temporary file in the same directory and
    an atomic rename: two writers each replace the file whole, a kill leaves at most a
    ``.tmp`` file (which its owner cleans up), never a half-written ``path``.

    ``make_parent`` creates the directory first, once more if it vanishes between the
    ``mkdir`` and the temporary file (a cache removed with ``rm -rf`` during a run).
    """
    return write_bytes_atomically(path, text.encode("utf-8"), prefix=prefix,
                                  make_parent=make_parent)


def write_bytes_atomically(path: Path, data: bytes, *, prefix: str | None = None,
                           make_parent: bool = False) -> Path:
    """:func:`write_text_atomically` for bytes."""
    return write_parts_atomically(path, (data,), prefix=prefix, make_parent=make_parent)


def write_parts_atomically(path: Path, parts: Iterable[bytes | str], *,
                           prefix: str | None = None, make_parent: bool = False) -> Path:
    """:func:`write_text_atomically` of the concatenation of ``parts`` (bytes, or text
    written as UTF-8), written one after the other: a large file is never built whole in
    memory first."""
    path = Path(path)
    prefix = prefix or f".{path.name}-"
    for attempt in (1, 2):
        if make_parent:
            path.parent.mkdir(parents=True, exist_ok=True)
        try:
            descriptor, temporary = tempfile.mkstemp(prefix=prefix, suffix=".tmp",
                                                     dir=path.parent)
            break
        except FileNotFoundError:  # the directory was removed after mkdir
            if attempt == 2 or not make_parent:
                raise
    try:
        with os.fdopen(descriptor, "wb") as handle:
            for part in parts:
                handle.write(part.encode("utf-8") if isinstance(part, str) else part)
        os.replace(temporary, path)
    except BaseException:
        try:
            os.unlink(temporary)
        except OSError:
            pass
        raise
    return path
