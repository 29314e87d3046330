"""Engines imported without what their C code prints: pybullet writes ``pybullet build time:
...`` straight to the process's file descriptors (past ``sys.stdout``/``sys.stderr``) when it
is imported, so ``validate``, ``run`` and ``bench`` carried the line in their output."""

from __future__ import annotations

import contextlib
import ctypes
import importlib
import os
import sys
from collections.abc import Iterator
from types import ModuleType

#: The file descriptors C code prints to: standard output and standard error.
C_OUTPUTS = (1, 2)


def _flush_c_stdio() -> None:
    """Flush C's ``stdout``/``stderr`` buffers (into a pipe, ``stdout`` is written only when
    full or at exit: what was printed would reach the real output later)."""
    try:
        ctypes.CDLL(None).fflush(None)
    except (OSError, AttributeError, TypeError):  # no C library to ask
        pass


@contextlib.contextmanager
def c_output_dropped() -> Iterator[None]:
    """Inside, file descriptors 1 and 2 point at ``os.devnull``: what C code prints there is
    dropped. ``sys.stdout`` and ``sys.stderr`` are flushed before and work as before after;
    a Python exception raised inside still propagates (it is not printed here)."""
    saved = {}
    try:
        for stream in (sys.stdout, sys.stderr):
            if stream is not None:
                stream.flush()
        for fd in C_OUTPUTS:
            saved[fd] = os.dup(fd)
    except (OSError, ValueError, AttributeError):  # no such descriptors: nothing to hide
        for copy in saved.values():
            os.close(copy)
        yield
        return
    try:
        with open(os.devnull, "wb") as devnull:
            for fd in C_OUTPUTS:
                os.dup2(devnull.fileno(), fd)
        yield
    finally:
        _flush_c_stdio()
        for fd, copy in saved.items():
            os.dup2(copy, fd)
            os.close(copy)


def import_quietly(name: str) -> ModuleType:
    """``importlib.import_module(name)``, with C's output dropped (:func:`c_output_dropped`)
    while the module is first imported."""
    module = sys.modules.get(name)
    if module is not None:  # None marks a module that must fail to import: it does below
        return module
    with c_output_dropped():
        return importlib.import_module(name)


__all__ = ["c_output_dropped", "import_quietly"]
