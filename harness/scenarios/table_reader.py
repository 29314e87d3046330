"""The reader of one parsed TOML document: typed reads of its keys (numbers within their
bounds and supported magnitudes, vectors, strings, names), every problem collected with its
dotted key as a :class:`harness.scenarios.errors.ScenarioError`. Scenario files and
population files (:mod:`harness.survey.population`) are read through it.
"""

from __future__ import annotations

import math
from typing import Iterable, Mapping

from harness.scenarios.errors import NO_VALUE, ScenarioError, suggest
from harness.scenarios.schema import (
    CONTROL_CHARACTER,
    DESCRIPTION_ALLOWED,
    MAGNITUDES,
    TINY,
)

#: Largest |value| of a number whose field has no MAGNITUDES entry.
LARGEST_NUMBER = 1e12


def magnitude_text(field: str | None) -> str:
    """What :data:`MAGNITUDES` allows for ``field``, for error messages."""
    small, large = MAGNITUDES[field] if field else (0.0, LARGEST_NUMBER)
    small = max(small, TINY)
    zero = "0 or " if MAGNITUDES.get(field, (0.0,))[0] == 0.0 else ""
    return f"{zero}{small:g} <= |value| <= {large:g}"


class TableReader:
    """Reads one parsed TOML document, collecting every error with its dotted key."""

    def __init__(self, path):
        self.path = path
        self.errors: list[ScenarioError] = []

    def error(self, key, problem, value=NO_VALUE, allowed=None):
        self.errors.append(ScenarioError(problem, path=self.path, key=key, value=value,
                                         allowed=allowed))
        return None

    def keys(self, table: Mapping, prefix: str, allowed: Iterable[str], what: str):
        allowed = tuple(allowed)
        for key in table:
            if key not in allowed:
                dotted = f"{prefix}.{key}" if prefix else key
                self.error(dotted, f"unknown key in {what}{suggest(key, allowed)}",
                           table[key], ", ".join(allowed))

    def require(self, table: Mapping, key: str, prefix: str) -> bool:
        if key not in table:
            dotted = f"{prefix}.{key}" if prefix else key
            self.error(dotted, "missing required key")
            return False
        return True

    def number(self, table, key, prefix, *, default=NO_VALUE, low=None, high=None,
               low_open=False, allowed=None, field=None):
        dotted = f"{prefix}.{key}" if prefix else key
        if key not in table:
            if default is NO_VALUE:
                if allowed is None:
                    bounds = []
                    if low is not None:
                        bounds.append(f"> {low:g}" if low_open else f">= {low:g}")
                    bounds += [f"<= {high:g}"] if high is not None else []
                    allowed = "a number" + (" " + " and ".join(bounds) if bounds else "")
                return self.error(dotted, "missing required key", allowed=allowed)
            return default
        value = table[key]
        return self.check_number(dotted, value, low=low, high=high, low_open=low_open,
                                 allowed=allowed, field=field)

    def check_number(self, dotted, value, *, low=None, high=None, low_open=False, allowed=None,
                     field=None):
        """``float(value)`` when a number within the bounds and the supported magnitude of
        ``field`` (:data:`MAGNITUDES`), else an error (and ``None``)."""
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            return self.error(dotted, f"must be a number, not {type(value).__name__}", value,
                              allowed or "a finite number")
        try:
            number = float(value)
        except OverflowError:  # an integer beyond the largest float
            return self.error(dotted, "out of the supported range", value,
                              magnitude_text(field))
        if not math.isfinite(number):
            return self.error(dotted, "must be finite", value, allowed or "a finite number")
        value = number
        if low is not None and (value <= low if low_open else value < low):
            bound = f"> {low:g}" if low_open else f">= {low:g}"
            text = allowed or (f"{bound}" if high is None else f"{bound} and <= {high:g}")
            return self.error(dotted, "out of range", value, text)
        if high is not None and value > high:
            text = allowed or (f"<= {high:g}" if low is None else f"{low:g} … {high:g}")
            return self.error(dotted, "out of range", value, text)
        small, large = MAGNITUDES[field] if field else (0.0, LARGEST_NUMBER)
        if abs(value) > large or (value != 0.0 and abs(value) < max(small, TINY)):
            return self.error(dotted, "out of the supported range", value,
                              magnitude_text(field))
        return value

    def vector(self, table, key, prefix, length, *, default=NO_VALUE, field=None):
        dotted = f"{prefix}.{key}" if prefix else key
        if key not in table:
            if default is NO_VALUE:
                return self.error(dotted, "missing required key",
                                  allowed=f"a list of {length} numbers")
            return default
        value = table[key]
        if not isinstance(value, list) or (length is not None and len(value) != length):
            size = "" if length is None else f"{length} "
            return self.error(dotted, f"must be a list of {size}numbers", value,
                              f"e.g. {[0.0] * (length or 2)}")
        numbers = [self.check_number(f"{dotted}[{i}]", v, field=field)
                   for i, v in enumerate(value)]
        return None if any(n is None for n in numbers) else tuple(numbers)

    def string(self, table, key, prefix, *, default=NO_VALUE, choices=None, pattern=None,
               allowed=None):
        dotted = f"{prefix}.{key}" if prefix else key
        if key not in table:
            if default is NO_VALUE:
                return self.error(dotted, "missing required key",
                                  allowed=allowed or (", ".join(choices) if choices else None))
            return default
        value = table[key]
        if not isinstance(value, str):
            return self.error(dotted, f"must be a string, not {type(value).__name__}", value,
                              allowed or (", ".join(choices) if choices else "a string"))
        if choices is not None and value not in choices:
            return self.error(dotted, f"unknown value{suggest(value, choices)}", value,
                              ", ".join(choices))
        if pattern is not None and not pattern.match(value):
            return self.error(dotted, "not a valid name", value, allowed)
        return value

    def line_of_text(self, table, key, prefix, *, default=NO_VALUE):
        """A string (as :meth:`string`) that is one line of text: no control character
        (:data:`CONTROL_CHARACTER`)."""
        value = self.string(table, key, prefix, default=default)
        if isinstance(value, str):
            bad = CONTROL_CHARACTER.search(value)
            if bad:
                dotted = f"{prefix}.{key}" if prefix else key
                return self.error(dotted, f"holds the control character {bad.group()!r} at "
                                  f"offset {bad.start()}", value, DESCRIPTION_ALLOWED)
        return value

    def names(self, table, key, prefix, choices, *, default):
        dotted = f"{prefix}.{key}" if prefix else key
        if key not in table:
            return default
        value = table[key]
        if not isinstance(value, list) or not all(isinstance(v, str) for v in value):
            return self.error(dotted, "must be a list of strings", value, ", ".join(choices))
        if not value:  # neither "all" nor "none": engines = [] ran all, laws = [] none
            return self.error(dotted, "an empty list", value,
                              f"one or more of {', '.join(choices)}; leave {key} out for all")
        bad = [v for v in value if v not in choices]
        for v in bad:
            self.error(f"{dotted}", f"unknown name {v!r}{suggest(v, choices)}", value,
                       ", ".join(choices))
        if bad:
            return None
        if len(set(value)) != len(value):
            return self.error(dotted, "lists a name twice", value, ", ".join(choices))
        return tuple(value)
