"""Scenario errors: one message names the file, the key, the value and what is allowed."""

from __future__ import annotations

import difflib
from typing import Any, Iterable

#: Errors of one file listed at most; the rest are counted in one more line.
MAX_LISTED_ERRORS = 20
#: Marks "no value given" (None is a value a file may hold).
NO_VALUE = object()


def show_value(value: Any) -> str:
    """``repr(value)``, a table or a list as the file writes it (``{ iterations = 50 }``,
    not Python's ``{'iterations': 50}``), cut to 80 characters for a one-line message."""
    text = toml_value(value) if isinstance(value, (dict, list, tuple)) else repr(value)
    return text if len(text) <= 80 else text[:77] + "..."


def toml_value(value: Any) -> str:
    """``value`` as TOML writes it inline: tables ``{ key = value, … }``, arrays ``[1, 2]``,
    strings in double quotes, booleans ``true``/``false``."""
    if isinstance(value, dict):
        inner = ", ".join(f"{key} = {toml_value(item)}" for key, item in value.items())
        return f"{{ {inner} }}" if inner else "{}"
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(toml_value(item) for item in value) + "]"
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, str):
        return '"' + value.replace("\\", "\\\\").replace('"', '\\"') + '"'
    return repr(value)


class ScenarioError(ValueError):
    """A bad scenario file. ``str()`` names the file, the key, the value and what is allowed.

    One error per problem; when a file has several, the first one raised carries them all
    in ``errors`` (each a :class:`ScenarioError`) and its message lists every one.
    """

    def __init__(self, message: str = "", *, path=None, key: str | None = None,
                 value: Any = NO_VALUE, allowed: str | None = None,
                 errors: Iterable["ScenarioError"] = ()):
        self.path = None if path is None else str(path)
        self.key = key
        self.value = None if value is NO_VALUE else value
        self.allowed = allowed
        self.problem = message
        self.errors = tuple(errors) or (self,)
        total = len(self.errors)
        if total > MAX_LISTED_ERRORS:  # 100,000 unknown tables printed 100,000 lines
            hidden = total - MAX_LISTED_ERRORS
            self.errors = (*self.errors[:MAX_LISTED_ERRORS],
                           ScenarioError(f"{hidden} more errors not shown (fix those above "
                                         "first)", path=self.errors[0].path))
        if len(self.errors) > 1:
            text = f"{total} errors:\n" + "\n".join(f"  {e}" for e in self.errors)
        elif self.errors[0] is not self:
            only = self.errors[0]
            self.path, self.key, self.value = only.path, only.key, only.value
            self.allowed, self.problem = only.allowed, only.problem
            text = str(only)
        else:
            text = self._format(value)
        super().__init__(text)

    def __reduce__(self):
        """Pickled as it is (the forked checks send their errors back): its fields and
        message kept, where the default would call ``__init__`` again with the message."""
        return _unpickled, (type(self), self.args), self.__dict__

    def _format(self, value) -> str:
        parts = [self.path or "<scenario>"]
        if self.key is not None:
            parts.append(self.key if value is NO_VALUE else f"{self.key} = {show_value(value)}")
        text = ": ".join(parts) + f": {self.problem}"
        if self.allowed:
            text += f" (allowed: {self.allowed})"
        return text


class OptionError(ScenarioError):
    """A bad command-line option or argument rather than a file's key: named as typed,
    ``--tags 'nosuchtag': no scenario has this tag (allowed: ...)``, with no file."""

    def _format(self, value) -> str:
        text = self.key or "<option>"
        if value is not NO_VALUE:
            text += f" {show_value(value)}"
        text += f": {self.problem}"
        if self.allowed:
            text += f" (allowed: {self.allowed})"
        return text


def _unpickled(cls: type, args: tuple) -> ScenarioError:
    return cls.__new__(cls, *args)  # its fields follow (__reduce__'s state)


def suggest(word: str, choices: Iterable[str]) -> str:
    """"; did you mean ...?" for the closest of ``choices``, or ""."""
    close = difflib.get_close_matches(str(word), list(choices), n=1, cutoff=0.6)
    return f"; did you mean {close[0]!r}?" if close else ""
