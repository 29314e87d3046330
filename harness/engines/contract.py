"""The engine contract: what an adapter supplies, what the base class does once for all.

(Over 600 lines because this docstring is the written contract, ~150 lines, and
:class:`Engine` is one class: its hooks, settings, caches and run loop. What it uses lives
apart: the run's result and status in ``run_result``, what is worked out from a scene alone
in ``scene_setup``, the loop's state and bookkeeping in ``run_loop``.)

An engine adapter turns one planar impact (a :class:`harness.scene.Scene`) into post-impact
velocities. As scipy's ``OdeSolver.step`` does the bookkeeping around a solver's
``_step_impl``, :class:`Engine` runs the impact and finishes the run; an adapter writes only
what differs between engines.

What an adapter supplies (an :class:`Engine` subclass)
-------------------------------------------------------
Class attributes

``name``, ``version``
    The name the registry lists it by (``engine_names()``); the engine package's version
    (provenance).
``presets``
    Exactly ``"defaults"`` (what a user gets out of the box: engine defaults, only the pair's
    ``e``, ``μ`` and the geometry set) and ``"accurate"`` (the settings under which the
    engine solves its own contact law as exactly as it can), each a complete dict of plain
    JSON-able values with the same keys. ``None`` as a value means "the engine's default".
``setting_docs``
    One line per setting key: meaning, unit, engine default. Keys common to all engines:
    ``time_step`` (s), ``max_steps`` and ``approach_steps``.
``timing``
    A :class:`StepTiming`: where the engine detects contacts within a step, which sets how
    far before the touching pose the base class starts the bodies (see below).
``no_impulse_relative``
    A step whose normal impulse is at most this fraction of the run's largest counts as
    carrying none (default :data:`NO_IMPULSE_RELATIVE`; 0.0 for an engine whose forces fade
    continuously and reach exactly 0, such as MuJoCo's soft contact).
``max_worlds``
    How many built worlds to keep (``None``: one per key, never evicted).
``description``, ``preset_why``, ``plot_style``, ``speed_caps``, ``own_law``,
``bench_reference``, ``bench_impacts``, ``bench_impact_seconds``, ``bench_sweep``,
``time_step_overrides``, ``rounding``, ``impulse_band``, ``soft_contact``,
``restitution_unused``, ``reference_statuses``, ``native_2d``, ``survey_left_out``,
``calibration_knobs``, ``no_calibration_knobs_why``
    What the rest of the harness knows about the engine (report text and style, verdicts'
    speed caps, bench profile, test expectations, the default survey's pairs), each with a
    default below, read through the registry (``harness.engines.engine_trait``;
    docs/engines.md, 'The engine contract') and checked by
    :func:`harness.engines.conformance.check_engine`.

Methods (``world`` is whatever the adapter builds; the base class only passes it back)

``_build(scene, settings, *, contacts=True) -> world``
    A world holding the ground (``scene.ground``) and the scene's bodies with their shapes,
    masses and inertias. ``contacts=False``: for :meth:`Engine.bare_stepper`, no contact
    reporting needed. Worlds are cached by :meth:`_world_key` (default: the geometry).
``_prepare(world, scene, settings, start, weights) -> prepared``
    Everything a reset needs that depends only on the scene and the settings: the engine's
    own form of the start state ``start`` (one :data:`BodyState` per body, in the run frame),
    ``e``, ``μ`` and the per-run settings. ``weights``: the scene's checked ``(mass,
    moment of inertia)`` per body (:func:`check_scene`; a polygon's inertia is not cheap to
    compute again). Computed once per (scene, settings) pair.
``_reset(world, prepared) -> dict``
    Make the world hold the prepared settings, ``e``, ``μ`` and start state, with fresh
    per-run state (contact caches, warm starts): identical inputs must give bit-identical
    outputs, also after another scene ran. Returns the run's ``derived`` values (a new dict:
    values the adapter computed from the settings, e.g. MuJoCo's damping ratio).
``_advance(world)``
    One engine step, nothing else (the benchmark's bare stepping).
``_step(world) -> RawContacts | None``
    One engine step, then the contact it left: ``None`` when the engine reports no active
    contact, else the tuple ``(points, normal, impulse, normal_impulse)`` (see
    :data:`RawContacts`), in the run frame.
``_read_poses(world) -> tuple[Pose, ...]``, ``_read_velocities(world) -> tuple[Velocity, ...]``
    Every body's ``(x, y, θ)`` (run frame) and ``(v_x, v_y, ω)`` now, in the scene's sign
    conventions. Poses are read at every step with contact (the records), velocities where
    a step without impulse must be told from a separation, and at the end.
``_out_of_plane_drift(world) -> float | None``
    Largest distance (m) a body point left the plane (3-D engines); ``None`` for 2-D ones.
``_notes(scene, settings) -> tuple[str, ...]``
    Engine remarks on this run's set-up (default none).
``_run_notes(world) -> tuple[str, ...]``
    Engine remarks known only once the run is over, read from the world after the loop
    (default none): what the engine did to this run that the set-up cannot tell, such as
    Box2D clipping a velocity to its per-step translation cap.
``_validate_engine_settings(settings)``, ``_world_key(scene, settings)``,
``_release(world)``
    Engine-specific value checks; the world cache key (a dict key: hashable for every
    scene, e.g. a tuple of floats and strings, never a list or an array); freeing an
    evicted world.

Optional, for :meth:`Engine.run_many` (many independent impacts in one world; an adapter
without them runs the impacts one by one)

``_build_many(plans) -> (batch, worlds, derived)``
    One world holding every plan's impact at its start state (``plan.prepared``, computed
    with ``world=None``), one view per impact that ``_read_poses``, ``_read_velocities``
    and ``_out_of_plane_drift`` accept, and each run's ``derived``.
``_step_many(batch, active) -> {slot: RawContacts}``
    One step of the whole batch; the contact of every active impact that has one.
``_many_chunks(plans)``, ``_retire(batch, slot)``, ``_release_many(batch)``
    Which plans' impacts share a batch; taking a finished impact out; freeing a batch.
``_runs_alone(settings) -> bool``
    Whether impacts under these (checked) settings must run one by one (default ``False``).

What the base class does, once for every engine
-----------------------------------------------
* Settings: presets, overrides, validation (``settings()``, ``validate_settings()``), the
  scene's checks (:class:`UnsupportedScene`).
* The run frame: the scene translated so that the bodies' mean x (and, without ground and
  where ``timing.recentre_y``, mean y) is 0 -- a symmetry of the problem that keeps the
  engines' coordinates small.
* The start state: the scene's poses are those at first touch; the bodies start
  ``approach_steps + timing.lead_steps - timing.overlap`` steps of exact free flight earlier
  (straight lines, constant rates), so that with ``approach_steps = 0`` the engine's first
  collision detection sees the bodies touching.
* Caches: worlds per :meth:`_world_key`, plans (start state, prepared form, energy weights)
  per (scene, settings) pair of objects, remembered only for a checked immutable scene and a
  settings dict the caller reuses.
* The loop: step until the contact ends -- a step, after contact began, with no contact, or
  whose normal impulse is at most ``no_impulse_relative`` of the largest while no contact
  point still closes (relative normal velocity below ``-1e-9`` of the scene's largest speed)
  -- or ``max_steps``. A scene whose reference is a sequence of impacts sets
  ``Scene.run_until`` (s, the sequence's last impact after the first contact): a separation
  ends the run only from ``ceil(run_until / time_step) +`` :data:`SEQUENCE_MARGIN_STEPS`
  steps after the first contact on, so that every engine runs the whole sequence (a later
  contact is recorded and resolved like the first; the run ends separated or at the cap).
* The run's bookkeeping from the raw records: first contact and its normal; contact steps;
  distinct in-plane points per step (3-D engines report a prism's edge as two points at ±y);
  largest penetration; the summed impulse on body B projected onto the first normal and onto
  ``t = (n_y, -n_x)`` (from momentum, ``m_B·Δv_B``, where the engine reports no impulse: exact
  with no other forces); kinetic energy before and after; the :class:`Status` and its reason;
  the notes; the typed :class:`EngineRun` with every :class:`ContactStep` in the scene frame.
* :meth:`Engine.run_many`: the same loop and bookkeeping for every impact of a batch, in
  lockstep; the runs equal :meth:`Engine.run`'s bit for bit (tests/engines/test_run_many.py).
* :meth:`Engine.bare_stepper`: reset and stepping without any of the above (the benchmark).

Input: the scene
    One body against the fixed ground half-space ``y <= 0`` (normal ``+y``) or two free
    bodies. Shapes: ``Disk(radius)``; ``Rod(length, radius)``, a capsule with end-cap centres
    at ``(±length/2, 0)`` in the body frame; ``Box(width, height)``, ``width`` along body x;
    ``Polygon(points)``, convex, counter-clockwise, about the centre of mass;
    ``Ellipse(semi_x, semi_y, vertex_at)`` (MuJoCo's ellipsoid; elsewhere its placed
    ``stand_in()`` polygon), against the ground only. Mass, inertia
    (``Body.moment_of_inertia``), pose (centre-of-mass position, angle of the body x axis,
    CCW), centre-of-mass velocity and angular velocity (CCW positive). The pair's ``e`` and
    ``μ`` are ``Scene.restitution`` and ``Scene.friction``.

What every adapter guarantees
    * The pair gets exactly ``e`` and ``μ`` whatever the engine's combining rule (the partner
      of ``bodies[0]`` gets the neutral value of the rule). The tests measure this.
    * Physics :func:`harness.engines.conformance.check_engine` checks under every preset:
      the reported normal points out of the ground (from A into B) and, with the impulses
      along it and ``t``, explains the change of speeds (``M Δu = Jᵀ P`` within ``rounding
      + impulse_band·|P|``); each reported contact point is where the scene touches body
      B; friction is used (μ > 0 changes the slip, μ = 0 does not) and a sliding disk's
      friction impulse is μ times the normal one; restitution is used and a direct impact
      separates at e times its approach speed (unless ``restitution_unused`` says why not);
      the ``accurate`` preset meets ``own_law``, checked where the laws part (an engine that
      builds neither the 45° rod nor the box claims ``converged``).
    * A scene the engine cannot build raises :class:`UnsupportedScene` (a ``ValueError``)
      from ``_build`` or the checks, before any stepping: the runner records it as skipped,
      check_engine and the contract tests skip that scene; a disk on the ground must run.

Shipping an adapter (docs/engines.md, 'Adding an engine')
    The adapter module (or package) binding ``ENGINE_CLASS``; one line in the registry
    (``_ENGINE_MODULES`` in ``harness/engines/__init__.py``: module, importable package,
    distribution); the engine's exact version pinned in ``pyproject.toml``'s ``harness``
    extra, or in an extra of its own where its wheels do not install everywhere (Drake's
    ``drake``; the install message and provenance read it there); its section in
    docs/engines.md. Generic tests (tests/engines/test_contract.py) iterate the registry and
    read the traits above, never an engine's name; ``check_engine`` must return ``[]``.
    * Only the impact window is simulated: gravity off, no rendering.
    * Motion stays planar; a 3-D engine maps the scene's (x, y) to its x-z plane with joints
      or equivalent, and measures the drift out of it.
"""

from __future__ import annotations

import abc
import copy
import math
import time
from collections import OrderedDict
from collections.abc import Callable, Iterable, Mapping, Sequence
from typing import Any

from harness import bounds
from harness.collector import collector_paused
from harness.engines.preset_names import preset_role
from harness.engines.run_loop import (
    APPROACH_RELATIVE,
    NO_IMPULSE_RELATIVE,
    SAME_POINT_RELATIVE,
    SEQUENCE_MARGIN_STEPS,
    Plan,
    Progress,
    count_planar_points,
    tally,
)
from harness.engines.run_result import (
    BLOW_UP_FACTOR,
    OUT_OF_PLANE_TOLERANCE,
    STATUSES,
    BodyState,
    ContactPoint,
    ContactRecord,
    ContactStep,
    EngineRun,
    Pose,
    RawContacts,
    Status,
    Velocity,
    decide_status,
    multi_contact_note,
    run_from_fields,
)
from harness.engines.scene_setup import (
    StepTiming,
    UnsupportedScene,
    check_scene,
    energy_before,
    energy_weights,
    free_flight_poses,
    geometry_key,
    is_immutable,
    ke_norm,
    start_states,
)
from harness.engines.settings import EngineSettingsError, check_int, check_number
from harness.scene import Scene
from harness.scene.features import body_extent

# The contract's names, where the adapters and the registry import them from (the modules
# above hold them: run_result, scene_setup, run_loop).
__all__ = [
    "APPROACH_RELATIVE", "BENCH_REFERENCE_LABEL", "BLOW_UP_FACTOR", "NO_IMPULSE_RELATIVE",
    "OUT_OF_PLANE_TOLERANCE", "SAME_POINT_RELATIVE", "SEQUENCE_MARGIN_STEPS", "STATUSES",
    "BareStepper", "BodyState", "ContactPoint", "ContactRecord", "ContactStep", "Engine",
    "EngineRun", "Pose", "RawContacts", "Status", "StepTiming", "UnsupportedScene", "Velocity",
    "body_extent", "check_scene", "count_planar_points", "decide_status", "energy_before",
    "energy_weights", "free_flight_poses", "geometry_key", "ke_norm", "multi_contact_note",
    "start_states",
]

#: MuJoCo's label of its converged reference setting (own_law "converged"; an engine names
#: its own in ``Engine.bench_reference``).
BENCH_REFERENCE_LABEL = "RK4 contact_steps=400 (reference)"
_MAX_PLANS = 256  # (scene, settings) pairs remembered; the cache is emptied when full
_DETACHED = object()  # _plan_for's world for run_many: the plan gets no world of its own
_clock = time.perf_counter
_set_attribute: Callable = object.__setattr__


class BareStepper:
    """Reset and step an engine with none of the run's bookkeeping (the benchmark's baseline).

    ``reset()`` is the adapter's own per-run reset to the run's start state; ``step(n)``
    calls the engine's step ``n`` times. The world is the stepper's own (built without
    contact reporting where the engine allows); :meth:`close` frees it. ``build_cpu_s``:
    the CPU seconds building the world took, apart from the run's preparation (which may
    measure the scene in the world, as Box2D's speed probe does: a user's own loop, which
    the survey bench times, knows its settings and never does that).
    """

    def __init__(self, engine: Engine, world, prepared, build_cpu_s: float = 0.0) -> None:
        self._engine, self._world, self._prepared = engine, world, prepared
        self.build_cpu_s = build_cpu_s

    def reset(self) -> None:
        self._engine._reset(self._world, self._prepared)

    def step(self, count: int) -> None:
        advance, world = self._engine._advance, self._world
        for _ in range(count):
            advance(world)

    def velocities(self) -> tuple:
        """The bodies' velocities now, as the adapter reads them at a run's end (what a
        user's own loop reads after its steps)."""
        return self._engine._read_velocities(self._world)

    def close(self) -> None:
        if self._world is not None:
            self._engine._release(self._world)
            self._world = None


class Engine(abc.ABC):
    """Base class of the adapters: settings, caches, the run loop and the result, once."""

    name: str = ""
    version: str = ""
    presets: Mapping[str, Mapping[str, Any]] = {}
    setting_docs: Mapping[str, str] = {}
    timing: StepTiming = StepTiming()
    no_impulse_relative: float = NO_IMPULSE_RELATIVE
    max_worlds: int | None = None
    # What the rest of the harness knows about the engine, read through the registry
    # (harness.engines.engine_trait); checked by harness.engines.conformance.check_engine.
    #: One paragraph: why the engine lands where it does against the laws (the report shows it).
    description: str = ""
    #: preset role -> one line: what the preset changes and why (the report shows it).
    preset_why: Mapping[str, str] = {}
    #: (colour, marker) in every figure; colours from the Okabe–Ito colour-blind-safe palette.
    plot_style: tuple[str, str] = ("#000000", "x")
    #: (largest linear speed m/s, largest angular speed rad/s) the engine clamps to, or None
    #: when it clamps nothing; runs reaching it are flagged clipped (docs/verdicts.md).
    speed_caps: tuple[float, float] | None = None
    #: Absolute agreement (m/s, N s, unit normals) of quantities exact up to the engine's
    #: arithmetic: 1e-9 in double precision; a float32 engine (Box2D) carries a few roundings
    #: of 6e-8 each, so 1e-6 (the contract tests and check_engine hold an engine to it).
    rounding: float = 1e-9
    #: Relative disagreement allowed, beyond ``rounding``, between the change of speeds and
    #: the reported normal and impulses at the scene's contact point (``M Δu = Jᵀ P``,
    #: check_engine's physics): 0 for an engine whose reported impulse is the one it applied
    #: at that point in one step; a contact spread over steps, or applied through a skin,
    #: moves its point (MuJoCo, Box2D's defaults: 2e-2, the verdicts' impulse-residual bar;
    #: Drake's force inside its compliant contact's overlap: 2e-3).
    impulse_band: float = 0.0
    #: The contact is compliant: it lasts many steps with the bodies overlapping (MuJoCo's
    #: soft contact, ~20-50 steps; Drake's, 5-630), so a generic test may not assume a
    #: near-rigid one (a one-step cap leaves it unseparated; its normal and point move
    #: during it).
    soft_contact: bool = False
    #: preset role -> why that preset does not use the pair's e by design (MuJoCo's defaults:
    #: the default solref sets the bounce; Drake's: its default dissipation); check_engine's
    #: restitution check skips it.
    restitution_unused: Mapping[str, str] = {}
    #: ``{(reference scene, preset role): status}`` where a reference scene's run is not
    #: "ok", with the reason in a comment (tests/engines/test_contract.py expects these).
    reference_statuses: Mapping[tuple[str, str], str] = {}
    #: The engine is natively 2-D: no out-of-plane drift to measure (the adapter defines no
    #: ``_out_of_plane_drift``; its runs report ``out_of_plane_drift`` None).
    native_2d: bool = False
    #: The law the engine solves at its accurate limit: a law of the registry
    #: (harness.laws.LAW_NAMES; "newton-lcp" for sequential impulses), or "converged" (its
    #: own run at the finest settings, the sweep point named by ``bench_reference``); the
    #: accuracy bench measures against it, and check_engine holds the ``accurate`` preset of
    #: an engine claiming a law to it.
    own_law: str = "newton-lcp"
    #: own_law "converged": the label of the :meth:`bench_sweep` point that is the engine's
    #: converged limit, present in the quick and the full sweep (MuJoCo:
    #: BENCH_REFERENCE_LABEL); None for an engine whose own law is a law.
    bench_reference: str | None = None
    #: Impacts per reference scene in ``impact-harness bench --engines`` (quick, full):
    #: enough for a stable timing at the engine's speed.
    bench_impacts: tuple[int, int] = (40, 300)
    #: Rough seconds per rod-45 impact under ``accurate``: the executor bench takes the
    #: slowest installed engine (compute, not pickling) and sizes its batch by it.
    bench_impact_seconds: float = 1e-4
    #: preset role -> why ``impact-harness survey`` leaves the engine's pair out unless the
    #: user names presets (``--preset``); the survey's summary lists it with the reason.
    survey_left_out: Mapping[str, str] = {}
    #: The engine's own settings ``impact-harness calibrate`` tries beside the pair's (μ, e),
    #: which every engine takes: ``((setting, values tried), ...)``, each a key of
    #: ``setting_docs`` that every preset accepts at every value. Empty (the default): the
    #: engine cannot be calibrated by a setting of its own, for ``no_calibration_knobs_why``.
    calibration_knobs: tuple[tuple[str, tuple], ...] = ()
    #: Why an engine without ``calibration_knobs`` has none (calibrate prints it).
    no_calibration_knobs_why: str = ("its adapter names no setting of its own to calibrate "
                                     "(Engine.calibration_knobs is empty)")

    @classmethod
    def time_step_overrides(cls, role: str, time_step: float) -> dict:
        """The overrides that run preset ``role`` at ``time_step`` (the stress test's step
        sweep); an engine whose preset ties other settings to the step adjusts them."""
        return {"time_step": time_step}

    @classmethod
    def bench_sweep(cls, quick: bool) -> list[tuple[str, str, dict]]:
        """``[(label, preset, overrides)]``: the settings the accuracy bench measures
        (default: the two presets)."""
        return [("defaults", "defaults", {}), ("accurate", "accurate", {})]
    _last_checked: tuple | None = None  # (settings passed, resolved copy, preset)
    _last_scene: Scene | None = None  # the last scene that passed the checks
    _last_weights: tuple | None = None  # its energy_weights, from the checks
    _worlds: OrderedDict | None = None
    _plans: dict | None = None

    _drift_hook: bool = False  # the adapter defines _out_of_plane_drift
    _run_notes_hook: bool = False  # the adapter defines _run_notes

    def __init_subclass__(cls, **kwargs) -> None:
        super().__init_subclass__(**kwargs)
        cls._drift_hook = cls._out_of_plane_drift is not Engine._out_of_plane_drift
        cls._run_notes_hook = cls._run_notes is not Engine._run_notes

    # ------------------------------------------------------------------ adapter hooks
    @abc.abstractmethod
    def _build(self, scene: Scene, settings: Mapping[str, Any], *, contacts: bool = True):
        """A world holding the scene's ground and bodies (see the module docstring)."""

    @abc.abstractmethod
    def _prepare(self, world, scene: Scene, settings: Mapping[str, Any],
                 start: tuple[BodyState, ...], weights: tuple[tuple[float, float], ...]):
        """The engine's form of the start state, ``e``, ``μ`` and per-run settings
        (``weights``: the scene's checked masses and inertias)."""

    @abc.abstractmethod
    def _reset(self, world, prepared) -> dict:
        """Make ``world`` hold ``prepared`` with fresh per-run state; the run's ``derived``."""

    @abc.abstractmethod
    def _advance(self, world) -> None:
        """One engine step, nothing else."""

    @abc.abstractmethod
    def _step(self, world) -> RawContacts | None:
        """One engine step and the contact it left (``None``: no active contact)."""

    @abc.abstractmethod
    def _read_poses(self, world) -> tuple[Pose, ...]:
        """Every body's ``(x, y, θ)`` now, in the run frame."""

    @abc.abstractmethod
    def _read_velocities(self, world) -> tuple[Velocity, ...]:
        """Every body's ``(v_x, v_y, ω)`` now."""

    def _out_of_plane_drift(self, world) -> float | None:
        """Largest out-of-plane distance (m) of a body point; ``None`` for a 2-D engine."""
        return None

    def _notes(self, scene: Scene, settings: Mapping[str, Any]) -> tuple[str, ...]:
        """Engine remarks on this run's set-up."""
        return ()

    def _run_notes(self, world) -> tuple[str, ...]:
        """Engine remarks on the run just finished, read from ``world`` after the loop."""
        return ()

    def _world_key(self, scene: Scene, settings: Mapping[str, Any]) -> tuple:
        """What a world depends on (default: the geometry, :func:`geometry_key`)."""
        return geometry_key(scene)

    def _release(self, world) -> None:  # noqa: B027 - optional hook, default does nothing
        """Free a world the cache evicts (default: nothing to free)."""

    def _validate_engine_settings(  # noqa: B027 - optional hook, default checks nothing
            self, settings: Mapping[str, Any]) -> None:
        """Engine-specific value checks (override)."""

    # Optional: many independent impacts in one world (run_many). An adapter that defines
    # _build_many defines _step_many too; the others have defaults.
    def _build_many(self, plans: Sequence[Plan]) -> tuple[Any, Sequence[Any], Sequence[dict]]:
        """``(batch, worlds, derived)``: one world stepping every plan's impact (its start
        state ``plan.prepared``), a per-impact view each that ``_read_poses``,
        ``_read_velocities`` and ``_out_of_plane_drift`` accept, and each run's ``derived``."""
        raise NotImplementedError  # the base's marker: this adapter runs one impact at a time

    def _step_many(self, batch, active: Sequence[int]) -> Mapping[int, RawContacts]:
        """One step of the batch; ``{slot: contact}`` for the ``active`` slots with contact."""
        raise NotImplementedError

    def _many_chunks(self, plans: Sequence[Plan]) -> Iterable[Sequence[int]]:
        """Indices of the plans whose impacts share one batch (default: all)."""
        return [range(len(plans))]

    def _retire(self, batch, slot: int) -> None:  # noqa: B027 - optional hook, default keeps it
        """Take a finished impact out of the batch (default: leave it)."""

    def _release_many(self, batch) -> None:  # noqa: B027 - optional hook, default frees nothing
        """Free a batch (default: nothing to free)."""

    def _runs_alone(self, settings: Mapping[str, Any]) -> bool:
        """Whether impacts under ``settings`` must run one by one, not in a batch (default:
        never; e.g. Box2D's sub-stepping, which couples the impacts of one world)."""
        return False

    # ------------------------------------------------------------------ settings
    def settings(self, preset: str = "accurate",
                 overrides: Mapping[str, Any] | None = None) -> dict:
        """A complete settings dict: ``preset`` with ``overrides`` applied and checked.

        ``preset`` is a role (``defaults``, ``accurate``) or the engine's name for one
        (:meth:`preset_label`, e.g. MuJoCo's ``matched-bounce``).
        """
        if preset not in self.presets:
            preset = self._role_named(preset)
        # Deep: list values (MuJoCo's solref, solimp) must not alias the preset's.
        resolved = copy.deepcopy(dict(self.presets[preset]))
        for key, value in (overrides or {}).items():
            self._check_key(key)
            resolved[key] = copy.deepcopy(value)  # the caller's lists stay the caller's
        self.validate_settings(resolved)
        return resolved


    def _role_named(self, name: str) -> str:
        try:
            role = preset_role(self.name, name)
        except ValueError as error:
            raise EngineSettingsError(str(error)) from None
        if role not in self.presets:
            raise EngineSettingsError(
                f"engine {self.name!r}: unknown preset {name!r}; allowed: {sorted(self.presets)}")
        return role

    def _check_key(self, key: str) -> None:
        if key not in self.setting_docs:
            raise EngineSettingsError(
                f"engine {self.name!r}: unknown setting {key!r}; "
                f"allowed: {sorted(self.setting_docs)}"
            )

    def validate_settings(self, settings: Mapping[str, Any]) -> None:
        """Raise :class:`EngineSettingsError` for unknown or missing keys and bad values."""
        for key in settings:
            self._check_key(key)
        missing = sorted(set(self.setting_docs) - set(settings))
        if missing:
            raise EngineSettingsError(f"engine {self.name!r}: settings lack {missing}")
        check_number(self.name, settings, "time_step", low=0.0, strict=True)
        check_int(self.name, settings, "max_steps", low=1)
        check_number(self.name, settings, "approach_steps", low=0.0)
        self._validate_engine_settings(settings)
        for key, value in settings.items():  # the bounds every way of setting them shares
            reason = bounds.problem(key, value)
            if reason is not None:
                raise EngineSettingsError(
                    f"engine {self.name!r}: setting {key!r} = {value!r}: {reason}")

    def _resolve(self, settings, preset, overrides) -> tuple[dict, str | None]:
        if settings is None:
            role = preset if preset in self.presets else self._role_named(preset)
            return self.settings(role, overrides), (role if not overrides else None)
        if overrides:
            raise EngineSettingsError(
                f"engine {self.name!r}: pass either a settings dict or overrides, not both"
            )
        # The last dict checked is remembered: a runner passing the same settings to many
        # runs pays for the checks once (a dict comparison guards against later mutation).
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

    def _checked_scene(self, scene: Scene) -> None:
        if scene is not self._last_scene:
            weights = check_scene(self.name, scene)
            # Checked once per scene object: only a hashable (immutable) scene is remembered.
            immutable = is_immutable(scene)
            self._last_scene = scene if immutable else None
            self._last_weights = weights if immutable else None

    # ------------------------------------------------------------------ caches
    def _world_for(self, scene: Scene, settings: Mapping[str, Any]) -> tuple[Any, tuple]:
        worlds = self._worlds
        if worlds is None:
            worlds = self._worlds = OrderedDict()
        key = self._world_key(scene, settings)
        world = worlds.get(key)
        if world is not None:
            worlds.move_to_end(key)
            return world, key
        world = worlds[key] = self._build(scene, settings)
        while self.max_worlds is not None and len(worlds) > self.max_worlds:
            old_key, old = worlds.popitem(last=False)
            if self._plans:  # plans holding the evicted world go with it
                for plan_key in [k for k, plan in self._plans.items() if plan.world_key == old_key]:
                    del self._plans[plan_key]
            self._release(old)
        return world, key

    def _plan_for(self, scene: Scene, settings: dict, world=None) -> Plan:
        key = (id(scene), id(settings))
        plans = self._plans
        if plans is None:
            plans = self._plans = {}
        plan = plans.get(key)
        # Keyed by object identity; the plan holds both objects, so the ids stay theirs.
        if world is None and plan is not None and plan.scene is scene and plan.settings is settings:
            if self.max_worlds is not None:
                self._worlds.move_to_end(plan.world_key)  # least recently used goes first
            return plan
        cached_world = world is None
        if cached_world:
            world, world_key = self._world_for(scene, settings)
        elif world is _DETACHED:
            world = world_key = None
        else:
            world_key = None
        # The checks computed the inertias (a polygon's costs tens of µs); reuse them.
        weights = self._last_weights if scene is self._last_scene else None
        plan = self._new_plan(scene, settings, world, world_key,
                              weights if weights is not None else energy_weights(scene))
        # Remembered for a checked immutable scene and a settings dict the caller reuses.
        if (cached_world and scene is self._last_scene
                and settings is (self._last_checked or (None, None))[1]):
            if len(plans) >= _MAX_PLANS:
                plans.clear()
            plans[key] = plan
        return plan

    def _new_plan(self, scene: Scene, settings: dict, world, world_key,
                  weights: tuple[tuple[float, float], ...]) -> Plan:
        """The :class:`harness.engines.run_loop.Plan` of ``scene`` under ``settings``
        (``weights``: its :func:`energy_weights`), for ``world`` (``None``: run_many's, built
        with the batch)."""
        plan = Plan(scene, settings, world, world_key)
        plan.shift, start = start_states(scene, settings, self.timing)
        plan.prepared = self._prepare(world, scene, settings, start, weights)
        plan.dt = float(settings["time_step"])
        plan.max_steps = int(settings["max_steps"])
        until = getattr(scene, "run_until", None)
        # steps after the first contact before which a separation does not end the run
        plan.until_steps = (0 if until is None
                            else math.ceil(until / plan.dt) + SEQUENCE_MARGIN_STEPS)
        plan.weights = weights
        bodies = scene.bodies
        # energy_before and the largest of |v_x|, |v_y|, |ω| (Scene.state()'s) in one pass.
        before = 0.0
        speed_scale = 1e-300
        for body, (mass, inertia) in zip(bodies, weights):
            (ux, uy), uw = body.velocity, body.angular_velocity
            before += mass * (ux * ux + uy * uy) + inertia * uw * uw
            for value in (ux, uy, uw):
                value = abs(float(value))
                if value > speed_scale:  # noqa: PLR1730 - hot path
                    speed_scale = value
        plan.before = before
        plan.speed_scale = speed_scale
        notes = self._notes(scene, settings)
        plan.notes = notes if type(notes) is tuple else tuple(notes)
        body_b = bodies[-1]
        plan.body_b_mass = float(body_b.mass)
        plan.body_b_velocity = (body_b.velocity[0], body_b.velocity[1])
        return plan

    def close(self) -> None:
        """Release every cached world and plan."""
        if self._plans:
            self._plans.clear()
        while self._worlds:
            _, world = self._worlds.popitem()
            self._release(world)

    # ------------------------------------------------------------------ running
    def bare_stepper(self, scene: Scene, settings: Mapping[str, Any]) -> BareStepper:
        """Reset and stepping of ``scene`` under ``settings`` without the run's bookkeeping."""
        resolved, _ = self._resolve(settings, "accurate", None)
        self._checked_scene(scene)
        tick = time.process_time()
        world = self._build(scene, resolved, contacts=False)
        build_cpu_s = time.process_time() - tick
        plan = self._plan_for(scene, resolved, world=world)
        return BareStepper(self, world, plan.prepared, build_cpu_s)

    def run(
        self,
        scene: Scene,
        settings: Mapping[str, Any] | None = None,
        *,
        preset: str = "accurate",
        overrides: Mapping[str, Any] | None = None,
    ) -> EngineRun:
        """Simulate the impact window of ``scene``; see the module docstring.

        ``settings`` is a complete settings dict (as ``settings()`` returns); when it is
        ``None`` the preset with the overrides is used.
        """
        start_time = _clock()
        cached = self._last_checked  # _resolve's fast path, inlined (hot)
        if (settings is not None and not overrides and cached is not None
                and cached[0] is settings and cached[1] == settings):
            resolved, used_preset = cached[1], cached[2]
        else:
            resolved, used_preset = self._resolve(settings, preset, overrides)
        if scene is not self._last_scene:
            self._checked_scene(scene)
        plans = self._plans
        plan = plans.get((id(scene), id(resolved))) if plans else None  # _plan_for's hit
        if plan is None or plan.scene is not scene or plan.settings is not resolved:
            plan = self._plan_for(scene, resolved)
        elif self.max_worlds is not None:
            self._worlds.move_to_end(plan.world_key)
        world = plan.world
        derived = self._reset(world, plan.prepared)

        step = self._step
        progress = Progress(plan, self._read_poses, self._read_velocities,
                            self.no_impulse_relative)
        observe = progress.observe
        max_steps = plan.max_steps
        steps = 0
        while steps < max_steps:
            steps += 1
            if observe(step(world), steps, world):
                break
        return self._finish(plan, used_preset, derived, progress, world, steps, start_time)

    def run_many(
        self,
        scenes: Sequence[Scene],
        settings: Mapping[str, Any] | None = None,
        *,
        preset: str = "accurate",
        overrides: Mapping[str, Any] | None = None,
    ) -> list[EngineRun]:
        """:meth:`run` of every scene, in order; the same runs, bit for bit.

        An adapter that can step many independent impacts in one world (``_build_many``)
        runs them so, chunk by chunk (``_many_chunks``), with the loop and the bookkeeping
        of :meth:`run` per impact; any other adapter, or settings the adapter's
        :meth:`_runs_alone` refuses to batch, runs them one by one. ``wall_time_s`` of a
        batched run is its chunk's time shared equally. The cyclic garbage collector is
        paused meanwhile (the many small tuples made cannot be garbage yet).
        """
        with collector_paused():
            if type(self)._build_many is Engine._build_many:
                return [self.run(scene, settings, preset=preset, overrides=overrides)
                        for scene in scenes]
            resolved, used_preset = self._resolve(settings, preset, overrides)
            if self._runs_alone(resolved):
                return [self.run(scene, settings, preset=preset, overrides=overrides)
                        for scene in scenes]
            return self._run_batched(scenes, resolved, used_preset)

    def _run_batched(self, scenes: Sequence[Scene], resolved: dict,
                     used_preset: str | None) -> list[EngineRun]:
        """:meth:`run_many` chunk by chunk in batches (``resolved``: the checked settings)."""
        plans = []
        name, new_plan = self.name, self._new_plan
        last_scene = weights = None
        for scene in scenes:
            if scene is not last_scene:  # a scene given twice in a row is checked once
                weights, last_scene = check_scene(name, scene), scene
            plans.append(new_plan(scene, resolved, None, None, weights))
        runs: list[EngineRun | None] = [None] * len(plans)
        for chunk in self._many_chunks(plans):
            start_time = _clock()
            chunk_plans = [plans[index] for index in chunk]
            batch, worlds, derived = self._build_many(chunk_plans)
            try:
                finished = self._run_chunk(batch, worlds, derived, chunk_plans, used_preset,
                                           start_time)
            finally:
                self._release_many(batch)
            share = (_clock() - start_time) / len(chunk)
            for index, run in zip(chunk, finished):
                _set_attribute(run, "wall_time_s", share)  # compare=False: equality unchanged
                runs[index] = run
        return runs

    def _run_chunk(self, batch, worlds, derived, plans, preset, start_time) -> list[EngineRun]:
        """The loop of :meth:`run` for every impact of one batch, in lockstep."""
        progress = [Progress(plan, self._read_poses, self._read_velocities,
                             self.no_impulse_relative) for plan in plans]
        observers = [one.observe for one in progress]
        finished: list[EngineRun | None] = [None] * len(plans)
        active = list(range(len(plans)))
        max_steps = plans[0].max_steps  # one settings dict for the whole batch
        step_many, finish, retire = self._step_many, self._finish, self._retire
        steps = 0
        while active and steps < max_steps:
            steps += 1
            contact_of = step_many(batch, active).get
            still = []
            for slot in active:
                world = worlds[slot]
                if observers[slot](contact_of(slot), steps, world):
                    finished[slot] = finish(plans[slot], preset, derived[slot], progress[slot],
                                            world, steps, start_time)
                    retire(batch, slot)
                else:
                    still.append(slot)
            active = still
        for slot in active:  # the step cap
            finished[slot] = finish(plans[slot], preset, derived[slot], progress[slot],
                                    worlds[slot], steps, start_time)
        return finished

    def _finish(self, plan: Plan, preset, derived, progress: Progress, world, steps,
                start_time) -> EngineRun:
        """The :class:`EngineRun` of a finished loop (all the run's bookkeeping)."""
        records, first_contact = progress.records, progress.first_contact
        separated, velocities = progress.separated, progress.velocities
        if velocities is None:  # else read after this very step
            velocities = self._read_velocities(world)
        # The base's hooks answer "nothing" without looking: not called (see __init_subclass__).
        drift = self._out_of_plane_drift(world) if self._drift_hook else None
        run_notes = self._run_notes(world) if self._run_notes_hook else ()
        max_points, max_penetration, impulse_x, impulse_y, engine_impulse = tally(records, plan)
        if records:
            normal = records[0][1][1]
            n_x, n_y = normal
            if not engine_impulse:  # from momentum: no other force acts on body B
                mass, (ux, uy) = plan.body_b_mass, plan.body_b_velocity
                impulse_x = mass * (velocities[-1][0] - ux)
                impulse_y = mass * (velocities[-1][1] - uy)
            normal_impulse = impulse_x * n_x + impulse_y * n_y
            tangential_impulse = impulse_x * n_y - impulse_y * n_x
            source = "engine" if engine_impulse else "momentum"
        else:
            normal = normal_impulse = tangential_impulse = source = None
        after = 0.0
        for (mass, inertia), (vx, vy, omega) in zip(plan.weights, velocities):
            after += mass * (vx * vx + vy * vy) + inertia * omega * omega
        status, reason = decide_status(
            plan.before, after, velocities, steps=steps, contact_seen=first_contact is not None,
            separated=separated, max_contact_points=max_points, out_of_plane_drift=drift,
        )
        notes = plan.notes + run_notes if run_notes else plan.notes
        if max_points > 1:
            notes += (multi_contact_note(max_points),)
        return run_from_fields({
            "engine": self.name,
            "engine_version": self.version,
            "scene_name": plan.scene.name,
            "preset": preset,
            "settings": plan.settings,
            "velocities": velocities,
            "status": status,
            "status_reason": reason,
            "steps": steps,
            "contact_steps": len(records),
            "first_contact_step": first_contact,
            "max_contact_points": max_points,
            "max_penetration": max_penetration,
            "separated": separated,
            "step_cap_hit": not separated and steps >= plan.max_steps,
            "contact_normal": normal,
            "normal_impulse": normal_impulse,
            "tangential_impulse": tangential_impulse,
            "impulse_source": source,
            "out_of_plane_drift": drift,
            "energy_before": 0.5 * plan.before,
            "energy_after": 0.5 * after,
            "contact_record": (plan.shift, tuple(records)),
            "derived": derived,
            "notes": notes,
            "wall_time_s": _clock() - start_time,
        })
