"""The keys of the scenario texts that passed every check, kept in one file beside the result
cache's entries.

A scenario's point checks (the second-feature strike check above all) cost about a
millisecond per file, much of a warm run of a large library. Their outcome depends only on
the file's text and on a context the caller gives (:mod:`harness.scenarios.checks`: the code,
as :func:`harness.store.identity.code_version` hashes it, the checks' limits and which
engines are installed), so a text that passed is remembered under ``sha256`` of both: the
file is read again (TOML, the table checks), its point checks are not. A file with problems
is checked again each time (its errors are listed then).

The store is ``root/passed-checks.json`` (in the result cache's directory): plain JSON, the
keys only -- nothing read from it is unpickled or evaluated, a key only ever skips checks of
a text whose hash it is, and the store is believed only under the cache's seal
(:mod:`harness.store.sealing`: a key planted in it would skip a bad file's checks). It is
replaced atomically; it keeps the keys of one code version and context only (a store of
another is emptied when next written), and ``impact-harness cache info|prune|clear`` count
and remove it with the cache's entries. One that cannot be read is empty (every file is
checked again) and said in :attr:`PassedChecks.problems`. Disabled (``root=None``) nothing
is remembered."""

from __future__ import annotations

import hashlib
import json
from pathlib import Path
from typing import Any, Callable

from harness.inputs import read_bytes
from harness.store.cache import ResultCache
from harness.store.cache_directory import SCENARIO_CHECKS_STORE
from harness.store.files import write_text_atomically
from harness.store.identity import code_version
from harness.store.sealing import KeyProblem, Seal


class PassedChecks:
    """The keys of the texts that passed, at ``root`` (None: disabled), in the context
    ``context(root)`` spells (what an outcome depends on besides the text; asked once, at the
    first key)."""

    FILE_NAME = SCENARIO_CHECKS_STORE
    FORMAT = 3

    def __init__(self, root=None, context: Callable[[Path], str] | None = None):
        self.root = None if root is None else Path(root)
        self.problems: list[str] = []
        self._passed: set[str] | None = None
        self._added = False
        self._spell_context = context
        self._context: str | None = None

    @property
    def path(self) -> Path | None:
        return None if self.root is None else self.root / self.FILE_NAME

    def key(self, text: str) -> str | None:
        """The key of a scenario text (None when disabled)."""
        if self.root is None:
            return None
        return hashlib.sha256(f"{self._context_text()}\0{text}".encode()).hexdigest()

    def _context_text(self) -> str:
        if self._context is None:
            self._context = "" if self._spell_context is None else self._spell_context(self.root)
        return self._context

    def _load(self) -> set[str]:
        if self._passed is None:
            self._passed = set()
            try:
                stored = json.loads(read_bytes(self.path))
                if not isinstance(stored, dict):
                    raise ValueError("not a store of passed checks")
                Seal(self.root).check(stored)  # a key in it skips checks: believed if sealed
                if (stored.get("format") != self.FORMAT
                        or not isinstance(stored.get("passed"), list)
                        or not all(isinstance(k, str) and len(k) == 64
                                   for k in stored["passed"])):
                    raise ValueError("not a store of passed checks")
                if stored.get("context") == self._context_text():
                    self._passed = set(stored["passed"])
            except FileNotFoundError:
                pass
            except (OSError, ValueError) as error:  # any damage: every file checked again
                self.problems.append(f"{self.path}: {type(error).__name__}: {error}")
                self._added = True  # replaced by a good one
        return self._passed

    def passed(self, key: str | None) -> bool:
        return key is not None and key in self._load()

    def scenario(self, key: str | None) -> Any:
        """None: the store keeps no scenarios (each file is read again; see the module)."""
        return None

    def add(self, key: str | None, scenario: Any = None) -> None:
        """Remember that the text of ``key`` passed (``scenario``, read from it, is not
        kept)."""
        if key is not None and key not in self._load():
            self._passed.add(key)
            self._added = True

    def save(self) -> None:
        """Write the store when it gained keys; a store that cannot be written is a problem
        said, never an error (the next run checks again)."""
        if self.root is None or not self._added:
            return
        stored = {"format": self.FORMAT, "code_version": code_version(),
                  "context": self._context_text(), "passed": sorted(self._passed or ())}
        try:
            if not self.root.is_dir():
                ResultCache(self.root, version="").make_root()  # made here: marked as ours
            text = json.dumps(Seal(self.root).sealed(stored))
            write_text_atomically(self.path, text, prefix=".checks-")
        except (OSError, KeyProblem) as error:
            self.problems.append(f"{self.path}: cannot write: {error}")
        self._added = False


__all__ = ["PassedChecks"]
