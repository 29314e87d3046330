"""Which engines are installed, their versions and preset settings, without importing them.

A warm run needs of the engines only what keys and provenance hold: which are installed,
each one's version and its presets' settings. Importing MuJoCo, pybullet, Box2D and pymunk
to learn that took about a second, a third of a warm run of a large library. So what the
loaded adapter reported is kept in the result cache under the engine's
:func:`harness.engines.install_fingerprint` (the file its import loads, with its size and
modification time, and its distribution's version) and the code version every key holds
(which covers the adapters): a reinstall, an upgrade, a removal or an adapter change is a
miss, and the engine is loaded again. An engine whose package is not found, or that fails to
import, is loaded each time (failing is fast) and never kept.
"""

from __future__ import annotations

from contextlib import contextmanager
from dataclasses import dataclass, field
from typing import Iterator, Sequence

from harness import engines as registry
from harness.engines import PRESET_ROLES, EngineNotInstalled, install_fingerprint

#: The cache entries' ``kind``.
ENGINE_FACTS = "engine-facts"


@dataclass
class EngineFacts:
    """``versions`` (installed engines, in the order asked), ``missing`` (engine: why it is
    skipped) and ``settings`` (installed engine: {preset: ``adapter.settings(preset, None)``})."""

    versions: dict[str, str] = field(default_factory=dict)
    missing: dict[str, str] = field(default_factory=dict)
    settings: dict[str, dict[str, dict]] = field(default_factory=dict)


def engine_facts(names: Sequence[str], cache=None) -> EngineFacts:
    """The :class:`EngineFacts` of ``names``, read from ``cache`` (a
    :class:`harness.store.cache.ResultCache`; None or disabled: every engine loaded) where it
    holds them for the installed package, else learnt by loading the adapter and kept."""
    facts = EngineFacts()
    for name in names:
        fingerprint = _fingerprint(name)
        key = None
        if fingerprint is not None and cache is not None and cache.enabled:
            key = cache.key({"kind": ENGINE_FACTS, "engine": name, "install": fingerprint})
            stored = _stored(cache, key, name)
            if stored is not None:
                facts.versions[name], facts.settings[name] = stored
                continue
        try:
            adapter = registry.load_engine(name)  # looked up at call time (tests replace it)
        except EngineNotInstalled as error:
            facts.missing[name] = str(error)
            continue
        facts.versions[name] = adapter.version
        facts.settings[name] = {preset: adapter.settings(preset, None) for preset in PRESET_ROLES}
        if key is not None:
            try:  # plain JSON (the settings are numbers, strings, booleans and lists)
                cache.put(key, {"kind": ENGINE_FACTS, "engine": name,
                                "version": adapter.version, "settings": facts.settings[name]})
            except (OSError, TypeError, ValueError):  # not kept: the next run loads it again
                pass
    return facts


#: Each engine's install fingerprint while :func:`fingerprints_remembered` is active.
_FINGERPRINTS: dict[str, str | None] | None = None


@contextmanager
def fingerprints_remembered() -> Iterator[None]:
    """Within: each engine's :func:`install_fingerprint` found once (a command asks twice,
    for the scenario checks' context and for the run; each is a search of the installed
    packages' metadata)."""
    global _FINGERPRINTS
    previous, _FINGERPRINTS = _FINGERPRINTS, {}
    try:
        yield
    finally:
        _FINGERPRINTS = previous


def _fingerprint(name: str) -> str | None:
    if _FINGERPRINTS is None:
        return install_fingerprint(name)
    if name not in _FINGERPRINTS:
        _FINGERPRINTS[name] = install_fingerprint(name)
    return _FINGERPRINTS[name]


def _stored(cache, key: str, name: str) -> tuple[str, dict] | None:
    """``(version, settings)`` kept under ``key``, or None (absent or not of that shape)."""
    record = cache.get(key, count=False)
    if record is None or record.get("engine") != name:
        return None
    version, settings = record.get("version"), record.get("settings")
    if not (isinstance(version, str) and isinstance(settings, dict)
            and set(settings) == set(PRESET_ROLES)
            and all(isinstance(values, dict) for values in settings.values())):
        return None
    return version, settings
