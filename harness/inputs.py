"""Reading a file the user hands over: only a regular file, of bounded size, UTF-8, nested
to a bounded depth, so that a bad input is one clear line and never a hang or a crash.

``validate /dev/zero`` read for ever, a FIFO blocked, a scenario nested 1,200 deep broke
the parser's recursion (an "internal error", exit 3). Each refusal here raises
:class:`InputError` (a ``ValueError``) with what is wrong and what is allowed; the callers
(scenario, population and results readers) add the file's name.

Shared by the scenarios, the survey and the run, which must not depend on each other for it.
"""

from __future__ import annotations

import os
import re
import stat
import tomllib

from harness.bounds import limit


class InputError(ValueError):
    """A file that is not an input the harness reads: not a regular file, too large, not
    UTF-8, nested too deep. The message says what and what is allowed."""


#: Deepest nesting of tables and arrays (or JSON objects and lists) read: a scenario's
#: deepest is 3, a results file's 5; code walking a document recursively needs headroom
#: below Python's recursion limit (1,000).
MAX_DEPTH = 64
#: Most parts of one dotted key (``a.b.c`` has 3), in a table header or before ``=``: a
#: scenario's longest has 3. ``tomllib`` takes time quadratic in a key's parts (a 120 kB
#: dotted key took 40-66 s to refuse, issue 37), so they are counted before it runs.
MAX_KEY_PARTS = 32

#: What the structure check of :func:`check_structure` looks at, outside strings and
#: comments: strings (skipped whole), comments, brackets, dots, and what ends a key.
_TOKENS = re.compile("|".join((  # each string ends at its end, or at the text's end (or,
    # one on one line, its line's) when unterminated: every match advances, none is retried
    r'"""(?:[^\\]|\\.)*?(?:"""|\Z)',  # multi-line basic string, escapes skipped
    r"'''.*?(?:'''|\Z)",  # multi-line literal string
    r'"(?:[^"\\\n]|\\.)*"?',  # basic string
    r"'[^'\n]*'?",  # literal string
    r"#[^\n]*",  # comment
    r"[\[\]{}.=,\n]",  # what the check counts
)), re.DOTALL)


def read_bytes(path, *, cap_name: str = "max_input_bytes") -> bytes:
    """The bytes of the regular file ``path`` (:func:`read_bytes_and_status`)."""
    return read_bytes_and_status(path, cap_name=cap_name)[0]


def read_bytes_and_status(path, *, cap_name: str = "max_input_bytes"
                          ) -> tuple[bytes, os.stat_result]:
    """The bytes of the regular file ``path``, at most ``limit(cap_name)`` of them, and its
    ``os.fstat`` as it was opened.

    Opened without blocking (a FIFO, a device or a directory is refused, not read); raises
    ``OSError`` when it cannot be opened (missing, no permission) and :class:`InputError`
    when it is not a regular file or is larger than the cap.
    """
    cap = int(limit(cap_name))
    descriptor = os.open(path, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0)
                         | getattr(os, "O_CLOEXEC", 0))
    try:
        status = os.fstat(descriptor)
        if stat.S_ISDIR(status.st_mode):
            raise InputError("is a directory, not a file")
        if not stat.S_ISREG(status.st_mode):
            raise InputError("not a regular file (a device, a pipe or a socket); allowed: "
                             "a regular file")
        if status.st_size > cap:
            raise InputError(_too_large(status.st_size, cap, cap_name))
        with os.fdopen(descriptor, "rb", closefd=False) as handle:
            data = handle.read(cap + 1)
        if len(data) > cap:  # grew while read
            raise InputError(_too_large(len(data), cap, cap_name))
        return data, status
    finally:
        os.close(descriptor)


def _too_large(size: int, cap: int, cap_name: str) -> str:
    return (f"{size} bytes, larger than the {cap} bytes allowed "
            f"(IMPACT_HARNESS_{cap_name.upper()} raises it)")


def decode(data: bytes) -> str:
    """``data`` as UTF-8 text; :class:`InputError` naming the first bad byte otherwise."""
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as error:
        raise InputError(f"not UTF-8 text: byte {data[error.start]:#04x} at offset "
                         f"{error.start}; allowed: text encoded in UTF-8") from None


def read_text(path, *, cap_name: str = "max_input_bytes") -> str:
    """:func:`read_bytes` decoded as UTF-8 (:func:`decode`)."""
    return decode(read_bytes(path, cap_name=cap_name))


def parse_toml(text: str) -> dict:
    """``tomllib.loads(text)``, nested at most :data:`MAX_DEPTH` deep, with keys of at most
    :data:`MAX_KEY_PARTS` parts. Raises ``tomllib.TOMLDecodeError`` for bad TOML and
    :class:`InputError` for too deep a one; the structure is checked in one pass over the
    text before the parser sees it (:func:`check_structure`), so the time taken is linear
    in the text's size."""
    check_structure(text)
    try:
        document = tomllib.loads(text)
    except RecursionError:
        raise InputError(_too_deep()) from None
    except tomllib.TOMLDecodeError:
        raise
    except ValueError as error:  # an integer of more than 4,300 digits, which int() refuses
        raise InputError(f"a value that cannot be read ({str(error).split(':')[0][:80]}); "
                         "allowed: integers of at most 4300 digits") from None
    check_depth(document)
    return document


def check_structure(text: str) -> None:
    """:class:`InputError` when the TOML ``text``, read in one linear pass outside strings
    and comments, nests brackets more than :data:`MAX_DEPTH` deep or has a dotted key of
    more than :data:`MAX_KEY_PARTS` parts (dots between two of ``[ ] { } = , newline``).
    An unterminated string is read as text: the parser refuses the file anyway."""
    depth = dots = 0
    for token in _TOKENS.finditer(text):
        mark = token.group()
        if mark == ".":
            dots += 1
            if dots >= MAX_KEY_PARTS:
                line = text.count("\n", 0, token.start()) + 1
                raise InputError(f"a dotted key of more than {MAX_KEY_PARTS} parts at line "
                                 f"{line}; allowed: at most {MAX_KEY_PARTS} parts")
            continue
        if mark in "[{":
            depth += 1
            if depth > MAX_DEPTH:
                raise InputError(_too_deep())
        elif mark in "]}":
            depth = max(depth - 1, 0)
        elif mark[0] in "\"'#":
            continue  # a string or a comment: a key's quoted part leaves the count as it is
        dots = 0


def check_depth(document, most: int = MAX_DEPTH) -> None:
    """:class:`InputError` when dicts and lists nest more than ``most`` deep (walked
    without recursion)."""
    stack = [(document, 1)]
    while stack:
        value, depth = stack.pop()
        if isinstance(value, dict):
            children = value.values()
        elif isinstance(value, list):
            children = value
        else:
            continue
        if depth > most:
            raise InputError(_too_deep(most))
        stack.extend((child, depth + 1) for child in children
                     if isinstance(child, (dict, list)))


def _too_deep(most: int = MAX_DEPTH) -> str:
    return f"nested too deep; allowed: tables and arrays at most {most} deep"


__all__ = ["MAX_DEPTH", "MAX_KEY_PARTS", "InputError", "check_depth", "check_structure",
           "decode", "parse_toml", "read_bytes",
           "read_bytes_and_status", "read_text"]
