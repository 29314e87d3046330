"""Physics-engine adapters: one planar impact in, a typed :class:`EngineRun` out.

Every engine lives in its own module behind the contract of :mod:`harness.engines.contract`
(what an adapter supplies, what the base class does once) and is imported only when used:
``load_engine("mujoco")`` never imports pymunk or pybullet, and a missing engine raises
:class:`EngineNotInstalled` (an :class:`ImportError`) that names the engine and the install
command while the others keep working.

Adding an engine: write ``harness/engines/<name>_engine.py`` with an :class:`Engine`
subclass bound to ``ENGINE_CLASS``, and add one line to ``_ENGINE_MODULES`` below.
"""

from __future__ import annotations

import importlib

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
    nearest_feature,
)
from harness.engines.settings import EngineSettingsError

# engine name -> (adapter module, importable package the adapter needs, pinned requirement)
_ENGINE_MODULES: dict[str, tuple[str, str, str]] = {
    "pymunk": ("harness.engines.pymunk_engine", "pymunk", "pymunk==7.3.1"),
    "pybullet": ("harness.engines.pybullet_engine", "pybullet", "pybullet==3.2.7"),
    "mujoco": ("harness.engines.mujoco_engine", "mujoco", "mujoco==4.0.0"),
    "box2d": ("harness.engines.box2d_engine", "Box2D", "box2d==2.3.10"),
}

ENGINE_NAMES: tuple[str, ...] = tuple(_ENGINE_MODULES)

PRESET_NAMES: tuple[str, ...] = ("defaults", "accurate")


class EngineNotInstalled(ImportError):
    """The engine's Python package cannot be imported."""

    def __init__(self, engine: str, reason: str = ""):
        _, package, requirement = _ENGINE_MODULES[engine]
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

    Raises ``ValueError`` for a name not in :data:`ENGINE_NAMES` and
    :class:`EngineNotInstalled` when the engine's package cannot be imported.
    """
    if name not in _ENGINE_MODULES:
        raise ValueError(f"unknown engine {name!r}; allowed: {list(ENGINE_NAMES)}")
    if name in _LOADED:
        return _LOADED[name]
    module_name, package, _ = _ENGINE_MODULES[name]
    try:
        importlib.import_module(package)
    except ImportError as error:  # the engine itself is missing or broken
        raise EngineNotInstalled(name, f"{type(error).__name__}: {error}") from error
    module = importlib.import_module(module_name)
    engine = module.ENGINE_CLASS()
    _LOADED[name] = engine
    return engine


def available_engines() -> dict[str, str | None]:
    """``{engine: None}`` when it loads, else ``{engine: reason}`` (with the install command)."""
    report: dict[str, str | None] = {}
    for name in ENGINE_NAMES:
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
    "PRESET_NAMES",
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
    "free_flight_poses",
    "geometry_key",
    "ke_norm",
    "load_engine",
    "nearest_feature",
]
