"""Physics-engine adapters: one planar impact in, post-impact velocities and diagnostics out.

Every engine (pymunk, pybullet, MuJoCo) lives in its own module behind the contract below and
is imported only when used: ``load_engine("mujoco")`` never imports pymunk or pybullet, and a
missing engine raises :class:`EngineNotInstalled` (an :class:`ImportError`) that names the
engine and the install command while the others keep working.

The contract
------------
An adapter is an :class:`Engine` subclass. It provides

``name`` : str
    One of :data:`ENGINE_NAMES`.
``version`` : str
    The engine package's version (for result provenance).
``presets`` : Mapping[str, Mapping[str, object]]
    Exactly two presets, ``"defaults"`` and ``"accurate"``, each a complete settings dict
    (plain JSON-able values) with the same keys:

    * ``defaults`` -- what a user gets out of the box: engine defaults, with only the pair's
      ``e`` and ``μ`` and the geometry set.
    * ``accurate`` -- the settings under which the engine solves its own contact law as
      exactly as it can (see each module's docstring for the law and the knobs).
``setting_docs`` : Mapping[str, str]
    One line per setting key: meaning, unit, engine default.
``settings(preset="accurate", overrides=None) -> dict``
    A fresh copy of the preset with ``overrides`` applied. An unknown key raises
    :class:`EngineSettingsError` (a :class:`ValueError`) naming the engine, the key and the
    allowed keys; a value of the wrong type or out of range raises it too.
``run(scene, settings=None, *, preset="accurate", overrides=None) -> EngineRun``
    Simulates the impact window of ``scene`` (a :class:`harness.scene.Scene`) and returns an
    :class:`EngineRun`. ``settings`` is a complete settings dict (as returned by
    ``settings()``); when it is ``None`` the preset with the overrides is used.
``close()``
    Releases cached clients/models (optional; also done at interpreter exit).

Input: the scene
    One body against the fixed ground half-space ``y <= 0`` (normal ``+y``) or two free bodies.
    Shapes: ``Disk(radius)``; ``Rod(length, radius)`` -- a capsule whose end-cap centres lie at
    ``(±length/2, 0)`` in the body frame; ``Box(width, height)``, ``width`` along body x;
    ``Polygon(points)``, convex, counter-clockwise, about the centre of mass. Mass, inertia
    (``Body.moment_of_inertia``: the explicit value or the uniform-density one), pose
    (centre-of-mass position, angle of the body x axis, CCW), centre-of-mass velocity and
    angular velocity (CCW positive). The pair's restitution ``e`` and friction ``μ`` are
    ``Scene.restitution`` and ``Scene.friction``.

What every adapter guarantees
    * The pair gets exactly ``e`` and ``μ`` whatever the engine's combining rule: pymunk and
      pybullet multiply the two shapes' values, so the partner (ground, or the second body)
      gets 1 and the first body ``e``, ``μ``; MuJoCo takes the maximum of the frictions, so
      the partner gets 0. (MuJoCo has no restitution coefficient: ``e`` enters only through
      the ``accurate`` preset's damping ratio.) The tests measure this.
    * Only the impact window is simulated: gravity off, no rendering. The scene's poses are
      the configuration at first touch. The adapter starts the bodies
      ``settings["approach_steps"]`` time steps of free flight before that configuration
      (exact straight-line, constant-rate rewind; 0 = the engine's first collision detection
      sees the bodies touching, whatever the engine's order of position update and
      collision detection). Stepping stops one step after separation (a step, after contact
      began, in which the engine reports no contact or no normal impulse/force), or at
      ``settings["max_steps"]``, which is then reported.
    * Clients, spaces and models are cached per geometry and reused; per-run state (contact
      caches, warm starts, solver data) is cleared, so identical inputs give bit-identical
      outputs, also after a different scene ran in between.
    * Motion stays planar. pymunk is 2-D. pybullet: each body is a fixed-base chain
      prismatic x -> prismatic z -> revolute y. MuJoCo: slide x, slide z, hinge y with an
      explicit ``<inertial>``. The scene's (x, y) plane is the engine's x-z plane; a
      revolute/hinge joint about +y turns clockwise in the x-z view, so the engine's joint
      angle and rate are ``-θ`` and ``-ω``. The adapter measures out-of-plane drift.

Output: :class:`EngineRun`
    Post-impact ``(v_x, v_y, ω)`` of every body in the scene's frame and sign conventions,
    and the diagnostics listed on the class. ``status`` is one of :data:`STATUSES`.

Settings
    Plain dicts of JSON-able values. Every knob that changes accuracy or cost is a named
    setting (time step, iterations, sub-steps, thresholds, ERP, slop, solref/solimp, cone
    type, step cap ...). Keys common to all engines: ``time_step`` (s), ``max_steps`` and
    ``approach_steps``. A value ``None`` means "the engine's own default, not set".
"""

from __future__ import annotations

import abc
import copy
import importlib
import math
import numbers
from dataclasses import dataclass, field
from typing import Any, Iterable, Mapping, Sequence

import numpy as np

from harness.scene import Scene

ENGINE_NAMES: tuple[str, ...] = ("pymunk", "pybullet", "mujoco")

# engine name -> (adapter module, importable package the adapter needs, pinned requirement)
_ENGINE_MODULES: dict[str, tuple[str, str, str]] = {
    "pymunk": ("harness.engines.pymunk_engine", "pymunk", "pymunk==7.3.1"),
    "pybullet": ("harness.engines.pybullet_engine", "pybullet", "pybullet==3.2.7"),
    "mujoco": ("harness.engines.mujoco_engine", "mujoco", "mujoco==4.0.0"),
}

PRESET_NAMES: tuple[str, ...] = ("defaults", "accurate")

#: ``EngineRun.status`` values, in the order they are decided (the first that applies wins).
STATUSES: dict[str, str] = {
    "blow-up": "non-finite velocities, or kinetic-energy norm above 1e3 times the input's",
    "no-contact": "the engine never reported a contact within the step cap",
    "no-separation": "still in contact when the step cap was hit",
    "out-of-plane": "a body left the plane by more than 1e-9 m (pybullet/MuJoCo)",
    "multi-contact": "more than one distinct contact point in the plane at once: the scene "
    "is outside one-point impact theory",
    "ok": "one contact point, separated within the cap, finite results",
}

# Relative size of a step's normal impulse (against the largest step's) below which the
# step counts as "no impulse": rounding noise of re-solving a resting contact is ~1e-16.
NO_IMPULSE_RELATIVE = 1e-12
# Kinetic-energy-norm growth that counts as a blow-up (an impact cannot multiply it by 1e3).
BLOW_UP_FACTOR = 1e3
# Out-of-plane displacement (m) above which a run is flagged: planar joints keep it at 0.
OUT_OF_PLANE_TOLERANCE = 1e-9


class EngineNotInstalled(ImportError):
    """The engine's Python package cannot be imported."""

    def __init__(self, engine: str, reason: str = ""):
        module, package, requirement = _ENGINE_MODULES[engine]
        self.engine = engine
        self.install_command = f"pip install {requirement}"
        message = (
            f"engine {engine!r} is not installed ({reason or f'cannot import {package}'}); "
            f"install it with `{self.install_command}` or all engines with "
            f'`pip install -e ".[harness]"`'
        )
        super().__init__(message, name=package)


class EngineSettingsError(ValueError):
    """An unknown setting key, or a value of the wrong type or range."""


class UnsupportedScene(ValueError):
    """The engine cannot build this scene (the reason is in the message)."""


@dataclass(frozen=True)
class EngineRun:
    """One impact simulated by one engine.

    Equality compares everything but ``wall_time_s``: two runs of identical inputs compare
    equal (bit-identical floats).
    """

    engine: str
    engine_version: str
    scene_name: str
    preset: str | None  # None when a custom settings dict was passed
    settings: Mapping[str, Any]  # the settings actually used (complete, JSON-able)
    velocities: tuple[tuple[float, float, float], ...]  # per body (v_x m/s, v_y m/s, ω rad/s)
    status: str  # one of STATUSES
    steps: int  # steps simulated
    contact_steps: int  # steps in which the engine reported a contact
    first_contact_step: int | None  # 1-based step of the first contact, None if never
    max_contact_points: int  # most distinct in-plane contact points seen in one step
    max_penetration: float  # m, largest penetration depth seen (>= 0)
    separated: bool  # contact began and then ended within the cap
    step_cap_hit: bool
    # First contact's unit normal in the scene frame, from body A (or the ground) into body B
    # (the single body of a ground scene, else bodies[1]).
    contact_normal: tuple[float, float] | None
    # Contact impulse on body B (N s) summed over the run, along contact_normal and along
    # t = (n_y, -n_x) (so +x for the ground); None where the engine does not expose it.
    normal_impulse: float | None
    tangential_impulse: float | None
    out_of_plane_drift: float | None  # m; None for 2-D engines
    derived: Mapping[str, Any] = field(default_factory=dict)  # values computed from settings
    notes: tuple[str, ...] = ()
    wall_time_s: float = field(default=0.0, compare=False)  # s, build/reuse + stepping + readout

    @property
    def u_after(self) -> np.ndarray:
        """Post-impact generalised speeds, ``(v_x, v_y, ω)`` per body in scene order."""
        return np.array([value for body in self.velocities for value in body], dtype=float)

    @property
    def flagged(self) -> bool:
        return self.status != "ok"


class Engine(abc.ABC):
    """Base class of the adapters: settings handling shared, ``_run`` per engine."""

    name: str = ""
    version: str = ""
    presets: Mapping[str, Mapping[str, Any]] = {}
    setting_docs: Mapping[str, str] = {}
    _last_checked: tuple | None = None  # (settings passed, resolved copy, preset)
    _last_scene: Scene | None = None  # the last scene that passed the checks

    # ------------------------------------------------------------------ settings
    def settings(self, preset: str = "accurate", overrides: Mapping[str, Any] | None = None) -> dict:
        """A complete settings dict: ``preset`` with ``overrides`` applied and checked."""
        if preset not in self.presets:
            raise EngineSettingsError(
                f"engine {self.name!r}: unknown preset {preset!r}; allowed: {sorted(self.presets)}"
            )
        # Deep: list values (MuJoCo's solref, solimp) must not alias the preset's.
        resolved = copy.deepcopy(dict(self.presets[preset]))
        for key, value in (overrides or {}).items():
            self._check_key(key)
            resolved[key] = copy.deepcopy(value)  # the caller's lists stay the caller's
        self.validate_settings(resolved)
        return resolved

    def _check_key(self, key: str) -> None:
        if key not in self.setting_docs:
            raise EngineSettingsError(
                f"engine {self.name!r}: unknown setting {key!r}; allowed: {sorted(self.setting_docs)}"
            )

    def validate_settings(self, settings: Mapping[str, Any]) -> None:
        """Raise :class:`EngineSettingsError` for unknown or missing keys and bad values."""
        for key in settings:
            self._check_key(key)
        missing = sorted(set(self.setting_docs) - set(settings))
        if missing:
            raise EngineSettingsError(f"engine {self.name!r}: settings lack {missing}")
        _check_number(self.name, settings, "time_step", low=0.0, strict=True)
        _check_int(self.name, settings, "max_steps", low=1)
        _check_number(self.name, settings, "approach_steps", low=0.0)
        self._validate_engine_settings(settings)

    def _validate_engine_settings(self, settings: Mapping[str, Any]) -> None:
        """Engine-specific value checks (override)."""

    # ------------------------------------------------------------------ running
    def run(
        self,
        scene: Scene,
        settings: Mapping[str, Any] | None = None,
        *,
        preset: str = "accurate",
        overrides: Mapping[str, Any] | None = None,
    ) -> EngineRun:
        """Simulate the impact window of ``scene``; see the module docstring."""
        if settings is None:
            resolved = self.settings(preset, overrides)
            used_preset: str | None = preset if not overrides else None
        else:
            if overrides:
                raise EngineSettingsError(
                    f"engine {self.name!r}: pass either a settings dict or overrides, not both"
                )
            cached = self._last_checked  # the fast path of _checked, inlined
            if cached is not None and cached[0] is settings and cached[1] == settings:
                resolved, used_preset = cached[1], cached[2]
            else:
                resolved, used_preset = self._checked(settings)
        if scene is not self._last_scene:
            _check_scene(self.name, scene)
            # Checked once per scene object: only a hashable (immutable) scene is remembered.
            self._last_scene = scene if _immutable(scene) else None
        return self._run(scene, resolved, used_preset)

    def _checked(self, settings: Mapping[str, Any]) -> tuple[dict, str | None]:
        """A validated private copy of ``settings`` and the preset it equals (or None).

        The last dict checked is remembered: a runner passing the same settings to many
        runs pays for the checks once (a dict comparison guards against later mutation).
        """
        cached = self._last_checked
        if cached is not None and cached[0] is settings and cached[1] == settings:
            return cached[1], cached[2]
        # Deep, so that an in-place edit of a list value fails the fast path's comparison.
        resolved = copy.deepcopy(dict(settings))
        self.validate_settings(resolved)
        used_preset = next(
            (name for name, values in self.presets.items() if dict(values) == resolved), None
        )
        self._last_checked = (settings, resolved, used_preset)
        return resolved, used_preset

    @abc.abstractmethod
    def _run(self, scene: Scene, settings: dict, preset: str | None) -> EngineRun:
        """Engine-specific simulation (settings already validated)."""

    def close(self) -> None:
        """Release cached engine resources."""


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


# ---------------------------------------------------------------------- shared helpers
def free_flight_poses(scene: Scene, time_s: float) -> list[tuple[float, float, float]]:
    """Poses ``(x, y, θ)`` of every body after ``time_s`` of free flight (negative: before)."""
    poses = []
    for body in scene.bodies:
        vx, vy = body.velocity
        poses.append(
            (
                body.position[0] + vx * time_s,
                body.position[1] + vy * time_s,
                body.angle + body.angular_velocity * time_s,
            )
        )
    return poses


def ke_norm(scene: Scene, u: Sequence[float] | np.ndarray) -> float:
    """Kinetic-energy norm ``sqrt(uᵀ M u)`` of generalised speeds ``u`` of ``scene``."""
    total = 0.0
    for index, body in enumerate(scene.bodies):
        vx, vy, omega = (float(v) for v in u[3 * index : 3 * index + 3])
        total += body.mass * (vx * vx + vy * vy) + body.moment_of_inertia * omega * omega
    return math.sqrt(total)


def body_extent(shape) -> float:
    """Largest distance (m) of a point of ``shape`` from its body origin."""
    kind = shape.kind
    if kind == "disk":
        return float(shape.radius)
    if kind == "rod":
        return float(shape.length / 2.0 + shape.radius)
    vertices = shape.vertices()
    return float(np.max(np.hypot(vertices[:, 0], vertices[:, 1])))


def count_planar_points(points: Iterable[tuple[float, float]], scale: float) -> int:
    """Number of distinct in-plane points (closer than ``1e-6·scale`` count as one).

    A 3-D engine may report a prism's edge touching the ground as two points at ±y; they
    are the same point of the planar problem.
    """
    tolerance = 1e-6 * max(scale, 1e-12)
    distinct: list[tuple[float, float]] = []
    for x, y in points:
        if all(abs(x - a) > tolerance or abs(y - b) > tolerance for a, b in distinct):
            distinct.append((x, y))
    return len(distinct)


def decide_status(
    scene: Scene,
    velocities: Sequence[Sequence[float]],
    *,
    contact_seen: bool,
    separated: bool,
    max_contact_points: int,
    out_of_plane_drift: float | None,
) -> str:
    """The :data:`STATUSES` entry for a finished run."""
    return status_from(
        energy_weights(scene),
        energy_before(scene),
        velocities,
        contact_seen=contact_seen,
        separated=separated,
        max_contact_points=max_contact_points,
        out_of_plane_drift=out_of_plane_drift,
    )


def multi_contact_note(points: int) -> str:
    """The run note every adapter gives when a step saw more than one contact point (the scene
    is then outside one-point theory)."""
    return f"{points} distinct in-plane contact points in one step"


def geometry_key(scene: Scene) -> tuple:
    """What an engine model depends on: ground or not, and per body its shape, mass and
    inertia (not its state, ``e`` or ``μ``). Adapters key their reusable models by it."""
    parts = []
    for body in scene.bodies:
        shape = body.shape
        if shape.kind == "disk":
            geometry = (shape.radius,)
        elif shape.kind == "rod":
            geometry = (shape.length, shape.radius)
        else:
            geometry = tuple(map(tuple, shape.vertices().tolist()))
        parts.append((shape.kind, geometry, float(body.mass), float(body.moment_of_inertia)))
    return (scene.ground, tuple(parts))


def energy_weights(scene: Scene) -> tuple[tuple[float, float], ...]:
    """``(mass, moment of inertia)`` per body: the scene constants :func:`status_from` needs."""
    return tuple((body.mass, body.moment_of_inertia) for body in scene.bodies)


def energy_before(scene: Scene) -> float:
    """Twice the kinetic energy of the scene's input state (the blow-up reference)."""
    before = 0.0
    for body in scene.bodies:
        (ux, uy), uw = body.velocity, body.angular_velocity
        before += body.mass * (ux * ux + uy * uy) + body.moment_of_inertia * uw * uw
    return before


_BLOW_UP_SQUARED = BLOW_UP_FACTOR**2


def status_from(
    weights: Sequence[tuple[float, float]],
    before: float,
    velocities: Sequence[Sequence[float]],
    *,
    contact_seen: bool,
    separated: bool,
    max_contact_points: int,
    out_of_plane_drift: float | None,
) -> str:
    """:func:`decide_status` from precomputed :func:`energy_weights` and :func:`energy_before`
    (adapters cache them per scene)."""
    after = 0.0
    for (mass, inertia), (vx, vy, omega) in zip(weights, velocities):
        after += mass * (vx * vx + vy * vy) + inertia * omega * omega
    # With positive masses and inertias a finite sum means finite velocities: test them
    # one by one only when it is not.
    if not math.isfinite(after) and not all(math.isfinite(v) for body in velocities for v in body):
        return "blow-up"
    if after > _BLOW_UP_SQUARED * max(before, 1e-300):
        return "blow-up"
    if not contact_seen:
        return "no-contact"
    if not separated:
        return "no-separation"
    if out_of_plane_drift is not None and out_of_plane_drift > OUT_OF_PLANE_TOLERANCE:
        return "out-of-plane"
    if max_contact_points > 1:
        return "multi-contact"
    return "ok"


def run_from_fields(values: dict) -> EngineRun:
    """An :class:`EngineRun` from a dict holding every field, for the adapters' hot path.

    The frozen dataclass ``__init__`` sets each of its ~20 fields through
    ``object.__setattr__`` (~3 µs, as much as a whole pymunk impact); this takes the dict as
    the instance's attributes (~0.3 µs). The result is an ordinary EngineRun.
    """
    run = _new_object(EngineRun)
    _set_attribute(run, "__dict__", values)
    return run


_new_object = object.__new__
_set_attribute = object.__setattr__


def _immutable(scene: Scene) -> bool:
    """Whether ``scene`` hashes, i.e. holds only immutable values (tuples, numbers, str)."""
    try:
        hash(scene)
    except TypeError:
        return False
    return True


def _check_scene(engine: str, scene: Scene) -> None:
    for body in scene.bodies:
        if body.shape.kind not in ("disk", "rod", "box", "polygon"):
            raise UnsupportedScene(f"engine {engine!r}: unknown shape {body.shape.kind!r}")
        for field in ("position", "velocity"):
            vector = getattr(body, field)
            if len(vector) != 2:
                raise UnsupportedScene(
                    f"engine {engine!r}: body {body.name!r} {field} must be (x, y) in the plane, "
                    f"got {tuple(vector)!r}"
                )
        values = [body.mass, body.moment_of_inertia, *body.position, body.angle, *body.velocity,
                  body.angular_velocity]
        if not all(math.isfinite(v) for v in values) or body.mass <= 0 or body.moment_of_inertia <= 0:
            raise UnsupportedScene(
                f"engine {engine!r}: body {body.name!r} needs finite state and positive mass "
                f"and inertia (mass {body.mass}, inertia {body.moment_of_inertia})"
            )
    if not (0.0 <= scene.restitution <= 1.0) or scene.friction < 0:
        raise UnsupportedScene(
            f"engine {engine!r}: needs 0 <= e <= 1 and μ >= 0, got e {scene.restitution}, "
            f"μ {scene.friction}"
        )


def _check_number(engine, settings, key, *, low=None, high=None, strict=False, allow_none=False):
    value = settings[key]
    if value is None and allow_none:
        return
    if isinstance(value, bool) or not isinstance(value, numbers.Real) or not math.isfinite(value):
        raise EngineSettingsError(f"engine {engine!r}: setting {key!r} must be a finite number, got {value!r}")
    if low is not None and (value <= low if strict else value < low):
        raise EngineSettingsError(
            f"engine {engine!r}: setting {key!r} must be {'>' if strict else '>='} {low}, got {value!r}"
        )
    if high is not None and value > high:
        raise EngineSettingsError(f"engine {engine!r}: setting {key!r} must be <= {high}, got {value!r}")


def _check_int(engine, settings, key, *, low=None, allow_none=False):
    value = settings[key]
    if value is None and allow_none:
        return
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        raise EngineSettingsError(f"engine {engine!r}: setting {key!r} must be an integer, got {value!r}")
    if low is not None and value < low:
        raise EngineSettingsError(f"engine {engine!r}: setting {key!r} must be >= {low}, got {value!r}")


def _check_choice(engine, settings, key, choices, *, allow_none=False):
    value = settings[key]
    if value is None and allow_none:
        return
    if value not in choices:
        raise EngineSettingsError(
            f"engine {engine!r}: setting {key!r} must be one of {list(choices)}, got {value!r}"
        )


def _check_vector(engine, settings, key, length, *, allow_none=False):
    value = settings[key]
    if value is None and allow_none:
        return
    if (
        not isinstance(value, (list, tuple))
        or len(value) != length
        or not all(isinstance(v, numbers.Real) and not isinstance(v, bool) and math.isfinite(v) for v in value)
    ):
        raise EngineSettingsError(
            f"engine {engine!r}: setting {key!r} must be a list of {length} finite numbers, got {value!r}"
        )


__all__ = [
    "ENGINE_NAMES",
    "PRESET_NAMES",
    "STATUSES",
    "Engine",
    "EngineRun",
    "EngineNotInstalled",
    "EngineSettingsError",
    "UnsupportedScene",
    "available_engines",
    "load_engine",
    "free_flight_poses",
    "ke_norm",
    "run_from_fields",
]
