"""Physics-engine adapters: one planar impact in, a typed :class:`EngineRun` out.

Every engine lives in its own module or package behind the contract of
:mod:`harness.engines.contract` (what an adapter supplies, what the base class does once)
and is imported only when used: ``load_engine("mujoco")`` never imports pymunk or
pybullet, and a missing engine raises :class:`EngineNotInstalled` (an :class:`ImportError`)
that names the engine and the install command while the others keep working.

Adding an engine: write ``harness/engines/<name>_engine.py`` (or a package, as
``harness/engines/box2d/``) with an :class:`Engine` subclass bound to ``ENGINE_CLASS``
(everything the harness knows about the engine is an attribute of that class:
:func:`engine_trait`), check it with
:func:`harness.engines.conformance.check_engine`, and add one line to ``_ENGINE_MODULES``
below, or :func:`register_engine` it at run time. A shipped engine also pins its version in
``pyproject.toml``'s ``harness`` extra and has its section in docs/engines.md (docs/engines.md,
'Adding an engine', has the whole list; tests/engines/test_contract.py checks both).

Presets: every engine has the same two preset *roles* (:data:`PRESET_ROLES`), which the
harness runs, caches and records by: ``defaults`` (what a user of the engine gets) and
``accurate`` (the settings under which the engine does its best at its own law). An engine
whose second preset achieves something narrower gives that role its own name, in
:mod:`harness.engines.preset_names` (beneath the contract, which reads them); users see it
everywhere (:func:`preset_label`, :func:`source_label`) and may type it wherever they name a
preset (:func:`preset_role`). The names live there, not in the adapters, so reports and
scenario files can be read where the engine is not installed.
"""

from __future__ import annotations

import importlib
import json
import os
from collections.abc import Sequence

from harness import bounds
from harness.engines.contract import (
    BLOW_UP_FACTOR,
    NO_IMPULSE_RELATIVE,
    OUT_OF_PLANE_TOLERANCE,
    STATUSES,
    BareStepper,
    ContactPoint,
    ContactStep,
    Engine,
    EngineRun,
    Status,
    StepTiming,
    UnsupportedScene,
    body_extent,
    free_flight_poses,
    geometry_key,
    ke_norm,
)
from harness.engines.preset_names import (
    PRESET_ROLES,
    preset_choices,
    preset_label,
    preset_role,
    renamed_roles,
    source_label,
)
from harness.engines.quiet import import_quietly
from harness.engines.settings import EngineSettingsError

# engine name -> (adapter module, importable package the adapter needs, distribution name);
# the pinned version lives once, in pyproject.toml's `harness` extra (see pinned_requirement).
_ENGINE_MODULES: dict[str, tuple[str, str, str]] = {
    "pymunk": ("harness.engines.pymunk_engine", "pymunk", "pymunk"),
    "pybullet": ("harness.engines.pybullet", "pybullet", "pybullet"),
    "mujoco": ("harness.engines.mujoco", "mujoco", "mujoco"),
    "box2d": ("harness.engines.box2d", "Box2D", "box2d"),
}

ENGINE_NAMES: tuple[str, ...] = tuple(_ENGINE_MODULES)

def pinned_requirement(distribution: str) -> str:
    """``distribution`` as pinned by this project's ``harness`` extra (``"pymunk==7.3.1"``),
    read from the installed project's metadata; the bare name when that is unavailable."""
    from importlib import metadata

    try:
        requirements = metadata.requires("planar-impact-harness") or []
    except metadata.PackageNotFoundError:
        return distribution
    for requirement in requirements:
        spec = requirement.split(";")[0].strip()
        name = spec.split("==")[0].split(">=")[0].strip()
        if name.lower() == distribution.lower():
            return spec
    return distribution


def engine_distribution(name: str) -> str:
    """The distribution (pip name) of shipped engine ``name``'s package (provenance)."""
    return _ENGINE_MODULES[name][2]


class EngineNotInstalled(ImportError):
    """The engine's Python package cannot be imported."""

    def __init__(self, engine: str, reason: str = ""):
        _, package, distribution = _ENGINE_MODULES[engine]
        requirement = pinned_requirement(distribution)
        self.engine = engine
        self.install_command = f"pip install {requirement}"
        message = (
            f"engine {engine!r} is not installed ({reason or f'cannot import {package}'}); "
            f"install it with `{self.install_command}` or all engines with "
            f'`pip install -e ".[harness]"`'
        )
        super().__init__(message, name=package)


# ---------------------------------------------------------------------- registry
_LOADED: dict[str, Engine] = {}


def load_engine(name: str) -> Engine:
    """The adapter for ``name`` (one shared instance per process, caches reused).

    Raises ``ValueError`` for a name not in :func:`engine_names` and
    :class:`EngineNotInstalled` when the engine's package cannot be imported.
    """
    if name in _LOADED:
        return _LOADED[name]
    engine = engine_class(name)()
    _LOADED[name] = engine
    return engine


# Engines registered at run time (register_engine): name -> adapter class. Tests and adapter
# authors use it to run an engine that is not one of the shipped modules.
_REGISTERED: dict[str, type[Engine]] = {}


def register_engine(name: str, engine_class: type[Engine]) -> None:
    """Make ``engine_class`` loadable as engine ``name`` in this process (tests, adapter
    authors trying an adapter); undo it with :func:`unregister_engine`. Refuses a name that
    is already taken or a class that is not an :class:`Engine` named ``name``."""
    if name in _ENGINE_MODULES or name in _REGISTERED:
        raise ValueError(f"engine {name!r} is already registered")
    if not (isinstance(engine_class, type) and issubclass(engine_class, Engine)):
        raise ValueError(f"engine {name!r}: {engine_class!r} is not an Engine subclass")
    if engine_class.name != name:
        raise ValueError(f"engine {name!r}: its class is named {engine_class.name!r}")
    _REGISTERED[name] = engine_class


def unregister_engine(name: str) -> None:
    """Undo :func:`register_engine` (a shipped engine cannot be removed)."""
    if name not in _REGISTERED:
        raise ValueError(f"engine {name!r} was not registered with register_engine")
    del _REGISTERED[name]
    _LOADED.pop(name, None)


def engine_names() -> tuple[str, ...]:
    """The shipped engines (:data:`ENGINE_NAMES`) and then those registered at run time."""
    return (*ENGINE_NAMES, *_REGISTERED)


def engine_class(name: str) -> type[Engine]:
    """The adapter class of engine ``name``, not instantiated (imports its module). Raises
    ``ValueError`` for an unknown name, :class:`EngineNotInstalled` when its package is
    missing."""
    if name in _REGISTERED:
        return _REGISTERED[name]
    if name not in _ENGINE_MODULES:
        raise ValueError(f"unknown engine {name!r}; allowed: {list(engine_names())}")
    module_name, package, _ = _ENGINE_MODULES[name]
    try:
        import_quietly(package)  # pybullet prints its build time from C
    except ImportError as error:  # the engine itself is missing or broken
        raise EngineNotInstalled(name, f"{type(error).__name__}: {error}") from error
    return importlib.import_module(module_name).ENGINE_CLASS


def engine_trait(name: str, trait: str):
    """What the harness knows about engine ``name``: the class attribute ``trait``
    (``description``, ``preset_why``, ``plot_style``, ``speed_caps``; docs/engines.md, 'The
    engine contract'). An engine that is unknown or not installed here gets the contract's
    default."""
    try:
        return getattr(engine_class(name), trait)
    except (ValueError, EngineNotInstalled):
        return getattr(Engine, trait)


def install_fingerprint(name: str) -> str | None:
    """What identifies the installed package of engine ``name``, found without importing it:
    the file its import loads (path, size, modification time) and its distribution's
    version; None when no such package is found (then :func:`load_engine` fails at once).

    A reinstall, upgrade or removal changes it, so what was learnt by loading the adapter
    (its version, its settings) can be kept under it (:mod:`harness.engines.facts`).
    """
    from importlib import metadata, util

    if name in _REGISTERED:  # no package of its own: its class identifies it
        registered = _REGISTERED[name]
        return json.dumps([registered.__module__, registered.__qualname__, registered.version])
    _, package, distribution = _ENGINE_MODULES[name]
    try:
        spec = util.find_spec(package)
    except (ImportError, ValueError):
        return None
    if spec is None or not spec.origin or not os.path.isfile(spec.origin):
        return None
    stat = os.stat(spec.origin)
    try:
        version = metadata.version(distribution)
    except metadata.PackageNotFoundError:
        version = None
    return json.dumps([spec.origin, stat.st_size, stat.st_mtime_ns, version])


def parse_overrides(items: Sequence[str],
                    engines: Sequence[str] | None = None) -> dict[str, dict]:
    """``["pymunk.iterations=50", ...]`` (``--set``) -> ``{"pymunk": {"iterations": 50}}``.

    A value is read as JSON (``50``, ``1e-4``, ``true``, ``null``, ``[0.02, 1]``), else kept
    as a string (``Euler``). Each is checked against the engine's settings under every preset
    before any work; the first bad one raises ``ValueError`` with a one-line message naming
    the engine, the key, the value and what is allowed. An engine that is not installed here
    is checked for its name only (its runs are skipped anyway). ``engines``: those selected
    (None: every engine registered now, :func:`engine_names`).
    """
    registered = engine_names()
    engines = registered if engines is None else engines
    overrides: dict[str, dict] = {}
    for item in items:
        target, equals, text = item.partition("=")
        engine_name, dot, key = target.strip().partition(".")
        where = f"--set {item}"
        if not equals or not dot or not key:
            raise ValueError(f"{where}: expected ENGINE.KEY=VALUE, e.g. pymunk.iterations=50")
        if engine_name not in registered:
            raise ValueError(f"{where}: engine {engine_name!r}, key {key!r}, value {text!r}: "
                             f"unknown engine; allowed: {', '.join(registered)}")
        if engine_name not in engines:
            raise ValueError(f"{where}: engine {engine_name!r}, key {key!r}, value {text!r}: "
                             f"engine not selected; allowed: {', '.join(engines)} (--engines)")
        try:
            value = json.loads(text)
        except ValueError:
            value = text
        try:
            engine = load_engine(engine_name)
        except EngineNotInstalled:
            overrides.setdefault(engine_name, {})[key] = value
            continue
        if key not in engine.setting_docs:
            raise ValueError(f"{where}: engine {engine_name!r}, key {key!r}, value {text!r}: "
                             f"unknown setting; allowed: {', '.join(sorted(engine.setting_docs))}")
        reason = bounds.problem(key, value)  # the same table as a file's [engine_settings]
        if reason is not None:
            raise ValueError(f"{where}: engine {engine_name!r}, key {key!r}, value {text!r}: "
                             f"{reason}")
        candidate = {**overrides.get(engine_name, {}), key: value}
        for preset in PRESET_ROLES:
            try:
                engine.settings(preset, candidate)
            except ValueError as error:
                # The settings' own message names the engine, the key and the value.
                raise ValueError(f"{where} (preset {preset}): {error}; allowed: "
                                 f"{engine.setting_docs[key]}") from None
        overrides[engine_name] = candidate
    return overrides


def available_engines() -> dict[str, str | None]:
    """``{engine: None}`` when it loads, else ``{engine: reason}`` (with the install command),
    for every engine registered now."""
    report: dict[str, str | None] = {}
    for name in engine_names():
        try:
            load_engine(name)
            report[name] = None
        except EngineNotInstalled as error:
            report[name] = str(error)
    return report


__all__ = [
    "BLOW_UP_FACTOR",
    "ENGINE_NAMES",
    "NO_IMPULSE_RELATIVE",
    "OUT_OF_PLANE_TOLERANCE",
    "PRESET_ROLES",
    "STATUSES",
    "BareStepper",
    "ContactPoint",
    "ContactStep",
    "Engine",
    "EngineNotInstalled",
    "EngineRun",
    "EngineSettingsError",
    "Status",
    "StepTiming",
    "UnsupportedScene",
    "available_engines",
    "body_extent",
    "engine_class",
    "engine_distribution",
    "engine_names",
    "engine_trait",
    "free_flight_poses",
    "geometry_key",
    "install_fingerprint",
    "ke_norm",
    "load_engine",
    "parse_overrides",
    "preset_choices",
    "preset_label",
    "preset_role",
    "register_engine",
    "renamed_roles",
    "source_label",
    "unregister_engine",
]
