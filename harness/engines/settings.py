"""Checks of engine setting values, shared by the adapters' ``_validate_engine_settings``.

Each raises :class:`EngineSettingsError` naming the engine, the key and what was expected.
``allow_none``: ``None`` (the engine's own default, not set) passes.
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Iterable, Mapping
from typing import Any


class EngineSettingsError(ValueError):
    """An unknown setting key, or a value of the wrong type or range."""


def check_number(engine: str, settings: Mapping[str, Any], key: str, *, low=None, high=None,
                 strict: bool = False, allow_none: bool = False) -> None:
    """A finite real number, ``>= low`` (``> low`` when ``strict``) and ``<= high``."""
    value = settings[key]
    if value is None and allow_none:
        return
    if isinstance(value, bool) or not isinstance(value, numbers.Real) or not math.isfinite(value):
        raise EngineSettingsError(
            f"engine {engine!r}: setting {key!r} must be a finite number, got {value!r}")
    if low is not None and (value <= low if strict else value < low):
        raise EngineSettingsError(
            f"engine {engine!r}: setting {key!r} must be {'>' if strict else '>='} {low}, "
            f"got {value!r}"
        )
    if high is not None and value > high:
        raise EngineSettingsError(
            f"engine {engine!r}: setting {key!r} must be <= {high}, got {value!r}")


def check_int(engine: str, settings: Mapping[str, Any], key: str, *, low=None,
              allow_none: bool = False) -> None:
    """An integer (not a bool), ``>= low``."""
    value = settings[key]
    if value is None and allow_none:
        return
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        raise EngineSettingsError(
            f"engine {engine!r}: setting {key!r} must be an integer, got {value!r}")
    if low is not None and value < low:
        raise EngineSettingsError(
            f"engine {engine!r}: setting {key!r} must be >= {low}, got {value!r}")


def check_choice(engine: str, settings: Mapping[str, Any], key: str, choices: Iterable,
                 *, allow_none: bool = False) -> None:
    """One of ``choices``."""
    value = settings[key]
    if value is None and allow_none:
        return
    if value not in choices:
        raise EngineSettingsError(
            f"engine {engine!r}: setting {key!r} must be one of {list(choices)}, got {value!r}"
        )


def check_vector(engine: str, settings: Mapping[str, Any], key: str, length: int,
                 *, allow_none: bool = False) -> None:
    """A list or tuple of ``length`` finite real numbers."""
    value = settings[key]
    if value is None and allow_none:
        return
    if (
        not isinstance(value, (list, tuple))
        or len(value) != length
        or not all(isinstance(v, numbers.Real) and not isinstance(v, bool) and math.isfinite(v)
                   for v in value)
    ):
        raise EngineSettingsError(
            f"engine {engine!r}: setting {key!r} must be a list of {length} finite numbers, "
            f"got {value!r}"
        )
