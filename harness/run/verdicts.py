"""Verdicts: is an engine run a single impact, and if not, why not (docs/verdicts.md).

An engine run is compared with the impact laws only when it *is* one impact at one contact
point. Counting contact points per step is not enough (a second corner that strikes one step
after the first is never counted), so every run is judged from its physics:

* the engine's own status (blow-up, no-contact, no-separation, out-of-plane, multi-contact);
* ``clipped``: a speed at an engine's velocity cap (pybullet clamps every joint speed to
  100 m/s and 100 rad/s; Box2D every body's speed to 2 m and its rate to π/2 rad per step,
  caps the run reports in ``derived``), before or after;
* ``multi-contact``: a second feature of a body touched at some step (from the per-step
  contact records, when the engine provides them);
* ``not-separated``: the contact still closes at the end, ``v_n^S < −tol``;
* ``penetration``: the deepest overlap above a bound scaled to the bodies' size;
* ``impulse-residual``: the change of speeds ``Δu`` is not one impulse at the scene's contact
  point (a second point, or a configuration that moved, supplied part of it);
* ``impulse-mismatch``: the impulse the engine reports differs from the one ``Δu`` implies;
* ``energy-gain``: kinetic energy grew. Attributed to the ``law`` when ``newton-lcp`` (the law
  the sequential-impulse engines solve) gains energy on the same problem, else to the
  ``numerics``. Only a gain from the numerics fails the run: a gain the law predicts is a
  real departure of the law and stays in the averages.

A scene that declares a face lying flat (``contacts = "simultaneous"``) is judged against its
declared contacts instead (:func:`judge_declared`): features outside them, each contact's
separation, the impulses at all of them together, energy against the Newton–Coulomb reference.

Every tolerance is a named field of :class:`Tolerances`, relative to a scale of the scene
(:func:`scene_scales`), so a verdict does not change when the units do.

The inputs are the numbers the runner already holds (:class:`RunNumbers`, built from the
runner's engine output by :func:`numbers_from_output`), plus, optionally, the per-step contact
records (:class:`StepContacts`, or as arrays :class:`ContactTrack`) of engines that keep them.
What a scene alone determines (its scales, Delassus terms, bodies' features:
:class:`SceneTerms`) can be worked out once by :func:`prepare` and passed to :func:`judge` for
every run of that scene (the survey judges each scene once per engine and preset).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import asdict, dataclass, field
from itertools import chain
from operator import itemgetter
from typing import Any

import numpy as np

from harness.engines import Status, body_extent, engine_trait
from harness.run import metrics

#: Reason name -> what it says. Ordered: the first failing reason names the run's status.
REASONS: dict[str, str] = {
    "blow-up": "the engine's status: non-finite or exploding velocities",
    "no-contact": "the engine's status: it never reported a contact",
    "no-separation": "the engine's status: still in contact at its step cap",
    "out-of-plane": "the engine's status: a body left the plane",
    "clipped": "a speed sits at the engine's velocity cap: the engine did not simulate the "
    "scene's speeds",
    "multi-contact": "a second feature touched within the run (which, at which step)",
    "truncated-sequence": "the run ended while a feature still reaches the ground: it is only "
    "the first impacts of the sequence its reference is",
    "not-simultaneous": "on a face declared to strike at once, the declared contacts were "
    "first struck at different steps: a sequence of impacts, not the simultaneous impact",
    "not-separated": "the contact still closes at the end: v_n^S < -tolerance",
    "penetration": "the deepest overlap exceeds the bound scaled to the bodies' size",
    "impulse-residual": "the change of speeds is not one impulse at the contact point",
    "impulse-mismatch": "the engine's impulse differs from the impulse the change of speeds "
    "implies",
    "energy-gain": "kinetic energy grew (attributed to the law when newton-lcp predicts a "
    "gain, else to the numerics; only a numerics gain fails the run)",
}
#: Remarks a verdict lists after its reasons, never failures (not counted as reasons).
REMARKS: dict[str, str] = {
    "at-boundary": "a check's value lies within its rounding band of the check's bound: the "
    "decision (named, with the other) could go either way on another CPU",
}
#: The rounding band of a verdict check (docs/verdicts.md, 'Decisions at a boundary'): a
#: measured value within BOUNDARY_BAND of the larger of its magnitude and its bound's (for
#: not-separated, of the sum of the products forming v_n^S) is at the boundary. The
#: tolerances themselves are 1e-6 to 0.1 of their scales; rounding moves a value by ~1e-16.
BOUNDARY_BAND = 1e-9
#: Reason name -> its place in :data:`REASONS` (a verdict lists its reasons in that order).
_REASON_ORDER = {name: place for place, name in enumerate(chain(REASONS, REMARKS))}
ENGINE_STATUS_REASONS = ("blow-up", "no-contact", "no-separation", "out-of-plane",
                         "multi-contact")
SINGLE_IMPACT = "single-impact"
#: The law a single-contact run's energy gain is attributed to: the engines' own.
ENGINE_LAW = "newton-lcp"
#: The law a run on declared simultaneous contacts is attributed to (the m-contact reference).
NEWTON_COULOMB = "Newton–Coulomb"
#: The law a run of a tilt's sequence of impacts is attributed to (its reference sequence).
SEQUENCE_LAW = "the event-driven sequence with newton-lcp"
FLAGGED = "flagged"



def speed_caps(engine: str) -> tuple[float, float] | None:
    """Measured velocity cap of ``engine`` (largest |v_x|, |v_y| in m/s, largest |ω| in
    rad/s), its adapter's ``speed_caps``; None when it clamps nothing (pybullet clamps at
    100: docs/verdicts.md, 'Velocity caps')."""
    return engine_trait(engine, "speed_caps")


#: A cap an engine computes in single precision (Box2D) holds a clipped speed within a few
#: float32 roundings (6e-8 each) of it: a run-reported cap counts from this fraction below.
RUN_CAP_BAND = 1e-6


@dataclass(frozen=True)
class Tolerances:
    """The verdict's named settings, each relative to a scale of the scene (docs/verdicts.md).

    Attributes
    ----------
    separation : float
        ``not-separated`` when ``v_n^S < −separation·|v_n^A|``.
    penetration : float
        ``penetration`` when the deepest overlap exceeds ``penetration`` times the smallest
        body extent (largest distance from a body's centre of mass to its surface: the
        lever-arm scale of the contact, :func:`body_extent`).
    impulse_residual : float
        ``impulse-residual`` when ``‖Δu − M⁻¹(w_n I_n + w_t I_t)‖_M`` exceeds this fraction of
        the frame-free speed scale (:func:`harness.run.metrics.frame_free_scale`).
    impulse : float
        ``impulse-mismatch`` when ``|I_engine − I_implied|`` exceeds this fraction of the
        impulse scale ``|v_n^A| / m_nn`` (a plastic frictionless impact's impulse).
    energy : float
        ``energy-gain`` when ``ΔE`` exceeds this fraction of the frame-free kinetic energy.
    energy_beyond_law : float
        A gain is the law's when ``newton-lcp`` gains energy too and the engine's gain exceeds
        the law's by at most this fraction of the frame-free kinetic energy; beyond it (or
        with no gain of the law) it is the numerics'.
    cap : float
        A speed counts as at a cap when ``|v| >= (1 − cap)·cap_value``.
    """

    separation: float = 1e-3
    penetration: float = 0.1
    impulse_residual: float = 2e-2
    impulse: float = 5e-2
    energy: float = 1e-6
    energy_beyond_law: float = 1e-2
    cap: float = 1e-9


DEFAULT_TOLERANCES = Tolerances()


@dataclass(frozen=True)
class Reason:
    """One check a run fails (or, for a law-attributed energy gain, a remark)."""

    name: str  # a key of REASONS
    value: float | None  # what was measured (units in ``detail``)
    tolerance: float | None  # the bound it was held against (same units)
    detail: str  # one line: where, which feature, which step, units
    attribution: str | None = None  # energy-gain: "law" or "numerics"
    fails: bool = True  # False: reported, not a failure (a gain the law predicts)

    def as_dict(self) -> dict:
        return asdict(self)


@dataclass(frozen=True)
class Verdict:
    """Every check of one engine run: a single impact only if no reason fails."""

    reasons: tuple[Reason, ...] = ()

    @property
    def failing(self) -> tuple[Reason, ...]:
        return tuple(r for r in self.reasons if r.fails)

    @property
    def single_impact(self) -> bool:
        return not self.failing

    @property
    def label(self) -> str:
        """``"single-impact"`` or ``"flagged"``."""
        return SINGLE_IMPACT if self.single_impact else FLAGGED

    @property
    def names(self) -> tuple[str, ...]:
        """Failing reasons' names, in :data:`REASONS` order."""
        return tuple(r.name for r in self.failing)

    def status(self, engine_status: str) -> str:
        """The record status: the engine's when the verdict keeps it, else the first failing
        reason's name, else ``ok``. (The verdict drops the engine's ``multi-contact`` where it
        judges the features touched instead of counting points.)"""
        return _status(engine_status, self.names)

    def as_list(self) -> list[dict]:
        return [reason.as_dict() for reason in self.reasons]


def _status(engine_status: str, names: Sequence[str]) -> str:
    """:meth:`Verdict.status` of a verdict whose failing reasons are ``names``."""
    judged = engine_status == "ok" or (engine_status in ENGINE_STATUS_REASONS
                                       and engine_status not in names)
    if not judged:
        return engine_status
    return names[0] if names else "ok"


@dataclass(frozen=True)
class StepContacts:
    """One step's contact as an engine recorded it, in the scene frame.

    ``points``: ``(x, y, depth)`` per point (m; depth > 0 overlap); ``bodies``: every body's
    ``(x, y, θ, v_x, v_y, ω)`` after the step. Matches the engines' ``ContactStep``.
    """

    step: int
    points: tuple[tuple[float, float, float], ...]
    bodies: tuple[tuple[float, ...], ...]


class ContactTrack:
    """A run's per-step contact records as arrays, in the scene frame, so that a check looks
    at every point of every step at once.

    ``steps``: ``(R,)`` the step of each record; ``poses``: ``(R, B, 3)`` every body's
    ``(x, y, θ)`` after that step; ``points``: ``(P, 3)`` every point's ``(x, y, depth)`` (m;
    depth > 0 overlap), record by record in order; ``record``: ``(P,)`` the record (row of
    ``steps``) each point belongs to; ``size``: ``P``. A track of an engine run's own record
    (:meth:`from_record`) or of a task's output (:meth:`from_output`) reads its arrays when a
    check first asks for them: most runs need none (a disk's, or one point in all).
    """

    __slots__ = ("_arrays", "_raw", "size")

    def __init__(self, steps: np.ndarray, poses: np.ndarray, points: np.ndarray,
                 record: np.ndarray):
        self._arrays = (steps, poses, points, record)
        self._raw = None
        self.size = len(points)

    @property
    def steps(self) -> np.ndarray:
        return self._read()[0]

    @property
    def poses(self) -> np.ndarray:
        return self._read()[1]

    @property
    def points(self) -> np.ndarray:
        return self._read()[2]

    @property
    def record(self) -> np.ndarray:
        return self._read()[3]

    def _read(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        if self._arrays is None:
            read, raw = self._raw
            self._arrays = read(raw)
            self._raw = None
        return self._arrays

    @classmethod
    def from_steps(cls, records: Sequence[StepContacts]) -> ContactTrack:
        """The track of :class:`StepContacts` records (of each body only ``(x, y, θ)``)."""
        return cls._of([record.step for record in records],
                       [record.points for record in records],
                       [record.bodies for record in records])

    @classmethod
    def from_output(cls, contacts: Sequence[Mapping[str, Any]]) -> ContactTrack:
        """The track of the runner's engine-task output ``contacts`` (dicts with ``step``,
        ``points`` and ``bodies``), read only when asked (as :meth:`from_record`)."""
        track = cls.__new__(cls)
        track._arrays, track._raw = None, (_output_arrays, contacts)
        track.size = sum(len(record["points"]) for record in contacts)
        return track

    @classmethod
    def from_record(cls, contact_record) -> ContactTrack:
        """The track of an ``EngineRun.contact_record`` ``(shift, raw)`` (run frame: scene
        frame + shift), read without building a typed record per step, and only when asked:
        the numbers of ``EngineRun.contacts``, each coordinate less the shift."""
        track = cls.__new__(cls)
        track._arrays, track._raw = None, (_record_arrays, contact_record)
        track.size = sum(len(contacts[0]) for _, contacts, _ in contact_record[1])
        return track

    @classmethod
    def _of(cls, steps: Sequence[int], points, states) -> ContactTrack:
        """The track of per-record steps, point lists and body states."""
        counts = [len(record) for record in points]
        bodies = len(states[0]) if len(states) else 0
        flat_points = np.array([point[:3] for record in points for point in record],
                               dtype=float).reshape(-1, 3)
        poses = np.array([[state[:3] for state in record] for record in states],
                         dtype=float).reshape(len(states), bodies, 3)
        return cls(np.asarray(steps, dtype=np.int64), poses, flat_points,
                   np.repeat(np.arange(len(counts)), counts))


def _output_arrays(contacts: Sequence[Mapping[str, Any]]
                   ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """``(steps, poses, points, record)`` of :class:`ContactTrack` from an engine-task
    output's ``contacts``."""
    return ContactTrack._of([int(record["step"]) for record in contacts],
                            [record["points"] for record in contacts],
                            [record["bodies"] for record in contacts])._arrays


def _record_arrays(contact_record) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """``(steps, poses, points, record)`` of :class:`ContactTrack` from an engine run's raw
    record ``(shift, raw)``."""
    (shift_x, shift_y), raw = contact_record
    steps = np.fromiter((step for step, _, _ in raw), np.int64, len(raw))
    counts = [len(contacts[0]) for _, contacts, _ in raw]
    bodies = len(raw[0][2]) if raw else 0
    # every point is (x, y, depth) and every pose (x, y, θ): each read as one flat run
    points = np.fromiter(chain.from_iterable(chain.from_iterable(
        contacts[0] for _, contacts, _ in raw)), float, 3 * sum(counts)).reshape(-1, 3)
    poses = np.fromiter(chain.from_iterable(chain.from_iterable(
        poses for _, _, poses in raw)), float, 3 * bodies * len(raw))
    poses = poses.reshape(len(raw), bodies, 3)
    shift = np.array([shift_x, shift_y])
    points[:, :2] -= shift
    poses[:, :, :2] -= shift
    return steps, poses, points, np.repeat(np.arange(len(raw)), counts)


def _track(contacts: Sequence[StepContacts] | ContactTrack) -> ContactTrack:
    return contacts if isinstance(contacts, ContactTrack) else ContactTrack.from_steps(contacts)


@dataclass(frozen=True)
class RunNumbers:
    """What a verdict needs from one engine run (all in the scene frame, SI units)."""

    engine: str
    status: str
    u_after: np.ndarray
    max_penetration: float | None = None
    normal_impulse: float | None = None  # engine's, N s on body B along the contact normal
    tangential_impulse: float | None = None
    impulse_source: str | None = None  # "engine" | "momentum" | None (unknown: engine)
    contact_normal: tuple[float, float] | None = None
    # Per-step contact records (a ContactTrack: the same as arrays); None: the engine kept none
    contacts: tuple[StepContacts, ...] | ContactTrack | None = None
    notes: tuple[str, ...] = field(default_factory=tuple)
    # The run's own caps on each body's speed |v| (m/s) and rate |ω| (rad/s), where they
    # depend on the settings (Box2D: per step); None: the engine's caps, if any, are fixed.
    speed_caps: tuple[float, float] | None = None


def numbers_from_output(engine: str, output: Mapping[str, Any]) -> RunNumbers:
    """:class:`RunNumbers` from the runner's engine-task output (see ``engine_task``)."""
    contacts = output.get("contacts")
    steps = None if contacts is None else ContactTrack.from_output(contacts)
    normal = output.get("contact_normal")
    return RunNumbers(
        engine=engine, status=str(output["status"]),
        u_after=np.array([v for body in output["velocities"] for v in body], dtype=float),
        max_penetration=output.get("max_penetration"),
        normal_impulse=output.get("engine_normal_impulse"),
        tangential_impulse=output.get("engine_tangential_impulse"),
        impulse_source=output.get("impulse_source"),
        contact_normal=None if normal is None else tuple(normal),
        contacts=steps, notes=tuple(output.get("notes") or ()),
        speed_caps=_run_caps(output.get("derived") or {}))


def _impulse_mismatch(run: RunNumbers, implied_n: float, implied_t: float,
                      scales: SceneScales, tolerances: Tolerances, *, engine: str,
                      implied: str, scale: str) -> list[Reason]:
    """``impulse-mismatch`` when the engine's own impulse (not one rebuilt from momentum)
    differs from the one Δu implies by more than the tolerance, relative to ``scales.impulse``
    (``engine``, ``implied`` and ``scale`` name the quantities in the message)."""
    if run.normal_impulse is None or run.impulse_source == "momentum":
        return []
    engine_t = run.tangential_impulse or 0.0
    gap = math.hypot(run.normal_impulse - implied_n, engine_t - implied_t)
    relative = gap / scales.impulse if scales.impulse > 0 else math.inf
    if relative <= tolerances.impulse:
        return []
    return [Reason(
        "impulse-mismatch", relative, tolerances.impulse,
        f"engine {engine} = ({run.normal_impulse:.4g}, {engine_t:.4g}) N s, implied "
        f"{implied} ({implied_n:.4g}, {implied_t:.4g}) N s: differ by {relative:.3g} of "
        f"{scale} = {scales.impulse:.3g} N s")]


def numbers_from_run(run) -> RunNumbers:
    """:class:`RunNumbers` from an ``EngineRun`` itself (the survey and the stress grid, which
    judge runs without going through the runner's task output)."""
    return RunNumbers(
        engine=run.engine, status=str(run.status), u_after=np.asarray(run.u_after, dtype=float),
        max_penetration=run.max_penetration, normal_impulse=run.normal_impulse,
        tangential_impulse=run.tangential_impulse, impulse_source=run.impulse_source,
        contact_normal=run.contact_normal,
        contacts=ContactTrack.from_record(run.contact_record),
        notes=tuple(run.notes), speed_caps=_run_caps(run.derived or {}))


def _run_caps(derived: Mapping[str, Any]) -> tuple[float, float] | None:
    """The run's own ``(speed, rate)`` caps from its ``derived`` values, if it reports them."""
    if "speed_cap" not in derived:
        return None
    return float(derived["speed_cap"]), float(derived["angular_speed_cap"])


@dataclass(frozen=True)
class SceneScales:
    """The scales the tolerances are relative to (see :func:`scene_scales`)."""

    approach_speed: float  # |v_n^A|, m/s
    impulse: float  # |v_n^A| / m_nn, N s
    speed_norm: float  # frame-free ‖u_before‖_M, sqrt(kg) m/s
    energy: float  # frame-free kinetic energy, J
    size: float  # smallest body extent, m


def scene_scales(scene, problem) -> SceneScales:
    """Scales of one scene's impact: approach speed, impulse, speed norm, energy, size."""
    mnn, _, _ = metrics.delassus(problem)
    return _scales(scene, problem, mnn, [body_extent(body.shape) for body in scene.bodies])


def _scales(scene, problem, mnn: float, extents: Sequence[float]) -> SceneScales:
    """:func:`scene_scales` from the scene's ``m_nn`` and its bodies' extents."""
    vn_approach, _ = metrics.contact_velocities(problem, problem.u)
    speed_norm = metrics.frame_free_scale(problem.mass_matrix, problem.u,
                                          free_bodies=not scene.ground)
    return SceneScales(approach_speed=abs(vn_approach), impulse=abs(vn_approach) / mnn,
                       speed_norm=speed_norm, energy=0.5 * speed_norm**2, size=min(extents))


@dataclass(frozen=True)
class SceneTerms:
    """What judging any run of one scene needs that no run changes (:func:`prepare`): worked
    out once per scene, not once per run."""

    scales: SceneScales
    delassus: tuple[float, float, float]  # (m_nn, m_nt, m_tt) of the scene's contact
    norm_before: float  # ‖u_before‖_M, the kinetic-energy norm before (sqrt(kg) m/s)
    features: tuple[BodyFeatures, ...]  # every body's point features, in scene order
    one_feature: bool  # every body a disk (:func:`_one_feature`)


def prepare(scene, problem) -> SceneTerms:
    """The :class:`SceneTerms` of ``scene`` and its impact ``problem``."""
    return _prepare(scene, problem, metrics.delassus(problem))


def _prepare(scene, problem, delassus: tuple[float, float, float]) -> SceneTerms:
    """:func:`prepare` with the scene's ``metrics.delassus`` given."""
    features = tuple(body_features(body.shape) for body in scene.bodies)
    scales = _scales(scene, problem, delassus[0], [f.extent for f in features])
    # Against the ground the frame-free norm is ke_norm(M, u) itself: not worked out twice.
    norm_before = (scales.speed_norm if scene.ground
                   else metrics.ke_norm(problem.mass_matrix, problem.u))
    return SceneTerms(scales, delassus, norm_before, features, _one_feature(scene))


def contact_features(scene, features: Sequence[BodyFeatures] | None = None,
                     tolerances: Tolerances | None = None) -> tuple[int, ...]:
    """Per body, the point feature (corner, end cap) at the scene's contact point in the
    scene's pose (the touching pose the reference describes), or -1 for a face.

    The engine's first recorded point alone cannot fix the contact's features: Box2D reports
    a point computed before its step with the pose after it, through its polygon skin, so on
    a spinning box the struck corner's first point lay 0.028 m from it and read as a face,
    and the corner's next point became a false ``multi-contact`` (box-corner-spin, Box2D
    ``defaults``). Both fix them (:func:`_second_features`).
    """
    from harness.scene import geometry

    tolerances = DEFAULT_TOLERANCES if tolerances is None else tolerances
    if features is None:
        features = [body_features(body.shape) for body in scene.bodies]
    point = np.asarray(geometry.scene_contact(scene).point, dtype=float)[:2]
    found = []
    for body, feature in zip(scene.bodies, features):
        pose = np.array([[*body.position, body.angle]], dtype=float)
        found.append(int(_features_at(feature, pose, point[None], np.zeros(1, dtype=np.int64),
                                      np.array([tolerances.penetration * feature.extent]))[0]))
    return tuple(found)


def judge(scene, problem, run: RunNumbers, *, law_energy_change: float | None = None,
          tolerances: Tolerances = DEFAULT_TOLERANCES, contacts=None,
          terms: SceneTerms | None = None,
          implied: tuple[float, float, float] | None = None,
          sequence: bool = False) -> Verdict:
    """The verdict of one engine run of ``scene``.

    Parameters
    ----------
    scene : harness.scene.Scene
        The scene the engine ran (poses at first touch).
    problem : planar_impact.builders.ImpactProblem
        The scene's impact (``M``, ``w_n``, ``w_t``, ``u_before``).
    run : RunNumbers
        The engine's numbers.
    law_energy_change : float, optional
        ``newton-lcp``'s energy change on ``problem`` (J), to attribute a gain; None: the
        attribution is ``numerics``. With ``contacts``: the Newton–Coulomb reference's.
    tolerances : Tolerances
        The named settings.
    contacts : sequence of harness.scene.Contact, optional
        The contacts a scene declares to touch at once (``contacts = "simultaneous"``, from
        :func:`declared_contacts`): the run is judged against all of them
        (:func:`judge_declared`). None: one contact, ``problem``'s. With ``sequence``, the
        features a tilt's reference sequence strikes (:func:`sequence_contacts`).
    sequence : bool
        ``contacts`` are struck one after another, a sequence the run must finish
        (``truncated-sequence``).
    terms : SceneTerms, optional
        ``prepare(scene, problem)``, when the caller judges several runs of one scene (the
        survey: one per engine and preset); None: worked out here.
    implied : tuple of float, optional
        ``metrics.impulses_from_velocities(problem, run.u_after, free_bodies=not
        scene.ground)`` when the caller has it with a finite residual: the same numbers
        :func:`impulse_from_velocities` works out (the same operations on the same values,
        over the same frame-free scale); None: worked out here.
    """
    if contacts is not None:
        return judge_declared(scene, problem, run, contacts,
                              law_energy_change=law_energy_change, tolerances=tolerances,
                              sequence=sequence)
    if terms is None:
        terms = prepare(scene, problem)
    reasons: list[Reason] = []
    if run.status == "multi-contact" and (run.contacts is not None or terms.one_feature):
        pass  # judged below from the features touched, not from a count of points
    elif run.status in ENGINE_STATUS_REASONS:
        reasons.append(Reason(run.status, None, None, f"the engine's status: {run.status}"))
    elif run.status != "ok":  # skipped or error: nothing to judge
        return Verdict(tuple(reasons))
    u_after = run.u_after
    if not np.isfinite(u_after).all():
        if run.status != "blow-up":
            reasons.append(Reason("blow-up", None, None, "non-finite velocities"))
        return Verdict(tuple(reasons))
    scales = terms.scales
    if run.speed_caps is not None:
        reasons += _clipped_magnitudes(run.engine, run.speed_caps, problem.u, u_after,
                                       tolerances)
    else:
        reasons += _clipped(run.engine, problem.u, u_after, tolerances)
    if run.contacts is not None:
        reasons += _second_features(scene, run.contacts, tolerances, terms.features)
    vn_after = float(problem.wn @ u_after)  # metrics.contact_velocities' v_n
    bound = tolerances.separation * scales.approach_speed
    reasons += _at_boundary("not-separated", vn_after, -bound, "v_n^S", "m/s",
                            float(np.abs(problem.wn * u_after).sum()))
    if run.max_penetration is not None:
        reasons += _at_boundary("penetration", run.max_penetration,
                                tolerances.penetration * scales.size, "deepest overlap", "m")
    if vn_after < -bound:
        reasons.append(Reason("not-separated", vn_after, -bound,
                              f"v_n^S = {vn_after:.4g} m/s < -{bound:.3g} m/s "
                              f"({tolerances.separation:g}·|v_n^A|)"))
    reasons += _penetration(run, scales, tolerances)
    implied_n, implied_t, residual = (
        implied if implied is not None
        else _implied_impulse(problem, terms.delassus, u_after, scales.speed_norm))
    reasons += _at_boundary("impulse-residual", residual, tolerances.impulse_residual,
                            "residual", "of the speed norm")
    if residual > tolerances.impulse_residual:
        reasons.append(Reason("impulse-residual", residual, tolerances.impulse_residual,
                              f"‖Δu − M⁻¹(w_n I_n + w_t I_t)‖_M = {residual:.3g} of the "
                              f"frame-free speed norm"))
    reasons += _impulse_mismatch(run, implied_n, implied_t, scales, tolerances,
                                 engine="(I_n, I_t)", implied="by Δu",
                                 scale="|v_n^A|/m_nn")
    gain = 0.5 * (metrics.ke_norm(problem.mass_matrix, u_after) ** 2 - terms.norm_before**2)
    reasons += _at_boundary("energy-gain", gain, tolerances.energy * scales.energy, "ΔE", "J",
                            terms.norm_before**2)
    reasons += _energy_gain(gain, scales, law_energy_change, tolerances, law=ENGINE_LAW)
    reasons.sort(key=lambda reason: _REASON_ORDER[reason.name])
    return Verdict(tuple(reasons))


def prepare_many(scenes: Sequence, problems: Sequence) -> list[SceneTerms]:
    """:func:`prepare` of every scene."""
    return [_prepare(scene, problem, delassus) for scene, problem, delassus
            in zip(scenes, problems, _delassus_many(problems), strict=True)]


def _delassus_many(problems: Sequence) -> list[tuple[float, float, float]]:
    """``metrics.delassus`` of every problem, its solves stacked by the mass matrix's size:
    numpy's stacked solve makes the same LAPACK call per matrix as a single one, and each
    product is the same 1-D product on the same operands, so the values are the same."""
    found: list = [None] * len(problems)
    sizes: dict[tuple[int, ...], list[int]] = {}
    for row, problem in enumerate(problems):
        sizes.setdefault(np.shape(problem.mass_matrix), []).append(row)
    for shape, rows in sizes.items():
        if len(shape) != 2:  # not a matrix: metrics.delassus says what is wrong
            for row in rows:
                found[row] = metrics.delassus(problems[row])
            continue
        matrices = np.array([problems[row].mass_matrix for row in rows], dtype=float)
        columns = np.array([np.stack([problems[row].wn, problems[row].wt], axis=1)
                            for row in rows], dtype=float)
        for row, inverse_w in zip(rows, np.linalg.solve(matrices, columns)):
            wn, wt = problems[row].wn, problems[row].wt
            wn_inv, wt_inv = inverse_w[:, 0], inverse_w[:, 1]
            found[row] = float(wn @ wn_inv), float(wn @ wt_inv), float(wt @ wt_inv)
    return found


#: Columns of :class:`TermArrays` (two bodies × ``(v_x, v_y, ω)``; a ground scene is padded).
ARRAY_WIDTH = 6
#: How near its bound (relative to the rounding scale of the quantity) a value of the batched
#: checks sends its run to :func:`judge`: the batched arithmetic (sums over the padded
#: columns, a diagonal ``M`` divided out) rounds differently from :func:`judge`'s in the last
#: bits, ~1e-16 of that scale; 1e-9 is a wide margin, and rarely reached (a value must lie
#: within 1e-9 of its bound).
NEAR = 1e-9


@dataclass(frozen=True)
class TermArrays:
    """The :class:`SceneTerms` and impacts of many scenes as row arrays (:func:`term_arrays`),
    for :func:`judge_many`. Rows whose mass matrix is not diagonal are ``diagonal`` False."""

    mass: np.ndarray  # (n, 6) diagonal of M, 1 where padded
    u: np.ndarray  # (n, 6) speeds before, 0 where padded
    wn: np.ndarray  # (n, 6)
    wt: np.ndarray  # (n, 6)
    dofs: np.ndarray  # (n,) 3 or 6
    diagonal: np.ndarray  # (n,) bool
    delassus: np.ndarray  # (n, 3) SceneTerms.delassus
    approach: np.ndarray  # (n,) SceneScales fields
    impulse: np.ndarray
    speed_norm: np.ndarray
    energy: np.ndarray
    size: np.ndarray
    norm_before: np.ndarray  # (n,) SceneTerms.norm_before
    one_feature: np.ndarray  # (n,) bool

    def rows(self, begin: int, end: int) -> TermArrays:
        """Rows ``begin:end``."""
        return TermArrays(*(getattr(self, name)[begin:end] for name in self.__dataclass_fields__))


def term_arrays(problems: Sequence, terms: Sequence[SceneTerms]) -> TermArrays:
    """The :class:`TermArrays` of ``problems`` and their :func:`prepare` ``terms``."""
    count = len(problems)
    mass = np.ones((count, ARRAY_WIDTH))
    u, wn, wt = (np.zeros((count, ARRAY_WIDTH)) for _ in range(3))
    dofs = np.zeros(count, dtype=np.int64)
    diagonal = np.zeros(count, dtype=bool)
    for row, problem in enumerate(problems):
        matrix = np.asarray(problem.mass_matrix, dtype=float)
        size = len(problem.u)
        if size > ARRAY_WIDTH:
            continue  # not diagonal: judged one by one
        dofs[row] = size
        diagonal[row] = not np.count_nonzero(matrix - np.diag(np.diag(matrix)))
        mass[row, :size] = np.diag(matrix)
        u[row, :size], wn[row, :size], wt[row, :size] = problem.u, problem.wn, problem.wt
    scales = [term.scales for term in terms]
    return TermArrays(
        mass, u, wn, wt, dofs, diagonal & np.all(mass > 0, axis=1),
        np.array([term.delassus for term in terms], dtype=float).reshape(count, 3),
        *(np.array([getattr(s, name) for s in scales], dtype=float)
          for name in ("approach_speed", "impulse", "speed_norm", "energy", "size")),
        np.array([term.norm_before for term in terms], dtype=float),
        np.array([term.one_feature for term in terms], dtype=bool))


def judge_many(scenes: Sequence, problems: Sequence, runs: Sequence, u_after: np.ndarray,
               terms: Sequence[SceneTerms], arrays: TermArrays, *,
               law_energy_change=None,
               tolerances: Tolerances = DEFAULT_TOLERANCES) -> list[tuple[str, str]]:
    """``(status, failing reasons comma-separated)`` of every engine run (``EngineRun``) of
    ``scenes``: :func:`judge`'s ``Verdict.status`` and ``names``, the same to the last run.

    The checks of :func:`judge` on every run at once, as arrays (``u_after``: the runs'
    speeds, ``(n, 6)`` padded like :class:`TermArrays`; ``arrays``: :func:`term_arrays` of the
    scenes). A run goes through :func:`judge` itself when the batch cannot settle it the same
    way: an engine status other than ok or multi-contact, non-finite speeds, a mass matrix
    that is not diagonal, or a value within :data:`NEAR` of its bound (where the batch's
    roundings could decide otherwise). The second-feature check (``multi-contact``) is
    :func:`judge`'s own, run by run.
    """
    count = len(runs)
    if not count:
        return []
    tol = tolerances
    # str(status) is a Python-level call per run; the values by status, one lookup each
    status = [_STATUS_VALUES.get(run.status) or run.status.value for run in runs]
    depths = [run.max_penetration for run in runs]
    penetration = np.array([math.nan if depth is None else depth for depth in depths],
                           dtype=float)
    engine_impulse = np.full((count, 2), np.nan)
    impulse_checked = np.zeros(count, dtype=bool)
    run_caps = np.full((count, 2), np.nan)
    # gathered in lists and written at once (an array's item assignment is a slow
    # Python call each)
    impulse_rows, impulses, cap_rows, caps_found = [], [], [], []
    for row, run in enumerate(runs):
        if run.normal_impulse is not None and run.impulse_source != "momentum":
            impulse_rows.append(row)
            impulses.append((run.normal_impulse, run.tangential_impulse or 0.0))
        caps = _run_caps(run.derived or {})
        if caps is not None:
            cap_rows.append(row)
            caps_found.append(caps)
    if impulse_rows:
        impulse_checked[impulse_rows] = True
        engine_impulse[impulse_rows] = impulses
    if cap_rows:
        run_caps[cap_rows] = caps_found
    batched = (np.isin(status, ("ok", "multi-contact")) & np.isfinite(u_after).all(axis=1)
               & arrays.diagonal & np.isfinite(penetration))
    near = np.zeros(count, dtype=bool)
    fails = {}
    with np.errstate(all="ignore"):
        # clipped: the run's own caps on |v| and |ω| (Box2D), else the engine's fixed ones
        clipped = np.zeros(count, dtype=bool)
        has_caps = ~np.isnan(run_caps[:, 0])
        band = 1.0 - max(tol.cap, RUN_CAP_BAND)
        for speeds in (arrays.u, u_after):
            for body in range(ARRAY_WIDTH // 3):
                present = has_caps & (arrays.dofs > 3 * body)
                speed = np.hypot(speeds[:, 3 * body], speeds[:, 3 * body + 1])
                rate = np.abs(speeds[:, 3 * body + 2])
                for value, cap in ((speed, band * run_caps[:, 0]), (rate, band * run_caps[:, 1])):
                    clipped |= present & (value >= cap)
                    near |= present & (np.abs(value - cap) <= NEAR * np.abs(cap))
        engines = {run.engine for run in runs}
        for name in sorted(engines):
            caps = speed_caps(name)
            if caps is None:
                continue
            rows = np.array([run.engine == name for run in runs]) & ~has_caps
            linear, angular = caps
            bounds = np.array([linear, linear, angular] * (ARRAY_WIDTH // 3)) * (1.0 - tol.cap)
            for speeds in (arrays.u, u_after):
                clipped |= rows & (np.abs(speeds) >= bounds).any(axis=1)
        fails["clipped"] = clipped
        # not-separated
        products = arrays.wn * u_after
        vn_after = products.sum(axis=1)
        bound = tol.separation * arrays.approach
        fails["not-separated"] = vn_after < -bound
        near |= np.abs(vn_after + bound) <= NEAR * (np.abs(products).sum(axis=1) + bound)
        # penetration: the same product and comparison as _penetration
        fails["penetration"] = ~(penetration <= tol.penetration * arrays.size)
        # impulse-residual: (A22)/(A23) with M diagonal
        delta = u_after - arrays.u
        dvn, dvt = (arrays.wn * delta).sum(axis=1), (arrays.wt * delta).sum(axis=1)
        mnn, mnt, mtt = arrays.delassus.T
        det = mnn * mtt - mnt * mnt
        conditioning = 1.0 + (mnn * mtt + mnt * mnt) / np.abs(det)
        normal = (mtt * dvn - mnt * dvt) / det
        tangential = (mnn * dvt - mnt * dvn) / det
        explained = (arrays.wn * normal[:, None] + arrays.wt * tangential[:, None]) / arrays.mass
        rest = np.sqrt(np.sum(arrays.mass * (delta - explained) ** 2, axis=1))
        residual = rest / arrays.speed_norm
        fails["impulse-residual"] = residual > tol.impulse_residual
        spread = (np.sqrt(np.sum(arrays.mass * delta**2, axis=1))
                  + np.sqrt(np.sum(arrays.mass * explained**2, axis=1))) / arrays.speed_norm
        near |= ~(np.abs(residual - tol.impulse_residual) > NEAR * conditioning * (1.0 + spread))
        # impulse-mismatch: the engine's own impulse against the implied one
        gap = np.hypot(engine_impulse[:, 0] - normal, engine_impulse[:, 1] - tangential)
        relative = gap / arrays.impulse
        fails["impulse-mismatch"] = impulse_checked & (relative > tol.impulse)
        sizes = (np.abs(engine_impulse).sum(axis=1) + np.abs(normal)
                 + np.abs(tangential)) / arrays.impulse
        near |= impulse_checked & ~(np.abs(relative - tol.impulse)
                                    > NEAR * conditioning * (1.0 + sizes))
        # energy-gain: only a gain beyond the law's fails
        after = np.sum(arrays.mass * u_after**2, axis=1)
        before = arrays.norm_before**2
        gain = 0.5 * (after - before)
        energy_bound = tol.energy * arrays.energy
        rounding = NEAR * (after + before)
        gains = gain > energy_bound
        near |= ~(np.abs(gain - energy_bound) > rounding)
        if law_energy_change is not None:
            law = np.asarray(law_energy_change, dtype=float)
            beyond = law + tol.energy_beyond_law * arrays.energy
            by_law = (law > energy_bound) & (gain <= beyond)
            near |= (law > energy_bound) & ~(np.abs(gain - beyond) > rounding + NEAR * np.abs(law))
            gains &= ~by_law
        fails["energy-gain"] = gains
    batched &= ~near
    checked = {name: flags.tolist() for name, flags in fails.items()}
    featured = np.flatnonzero(batched & ~arrays.one_feature).tolist()
    checked["multi-contact"] = [False] * count
    for row, second in zip(featured, _second_features_many(
            [runs[row].contact_record for row in featured],
            [terms[row].features for row in featured], tol,
            [scenes[row] for row in featured])):
        checked["multi-contact"][row] = second
    failing = np.zeros(count, dtype=bool)  # a batched reason fails (names to list)
    for flags in fails.values():
        failing |= flags
    failing |= np.asarray(checked["multi-contact"], dtype=bool)
    unjudged = (~batched).tolist()
    failing = failing.tolist()
    results = []
    for row, run in enumerate(runs):
        if unjudged[row]:
            gain = None if law_energy_change is None else float(law_energy_change[row])
            verdict = judge(scenes[row], problems[row], numbers_from_run(run),
                            law_energy_change=gain, tolerances=tol, terms=terms[row])
            results.append((verdict.status(status[row]), ",".join(verdict.names)))
        elif failing[row]:
            names = tuple(name for name in _BATCHED_REASONS if checked[name][row])
            results.append((_status(status[row], names), ",".join(names)))
        else:
            results.append((_status(status[row], ()), ""))
    return results


#: Every engine status's value, by status (:func:`judge_many`).
_STATUS_VALUES = {status: status.value for status in Status}
#: The reasons :func:`judge_many` checks as arrays, in :data:`REASONS` order.
_BATCHED_REASONS = tuple(name for name in REASONS
                         if name in ("clipped", "multi-contact", "not-separated", "penetration",
                                     "impulse-residual", "impulse-mismatch", "energy-gain"))


def _at_boundary(check: str, value: float, bound: float, what: str, unit: str,
                 scale: float = 0.0) -> list[Reason]:
    """An ``at-boundary`` remark (never a failure) when ``value`` lies within
    :data:`BOUNDARY_BAND` of ``bound`` (relative to the larger of their magnitudes and
    ``scale``), naming the check and both outcomes; else nothing."""
    if not (math.isfinite(value) and math.isfinite(bound)):
        return []
    band = BOUNDARY_BAND * max(abs(value), abs(bound), scale)
    if abs(value - bound) > band:
        return []
    return [Reason("at-boundary", value, bound,
                   f"{check}: {what} = {value!r} {unit} is within {band:.3g} of the bound "
                   f"{bound!r}: passes | fails {check} on the last bit", fails=False)]


def _penetration(run: RunNumbers, scales: SceneScales, tolerances: Tolerances) -> list[Reason]:
    """``penetration`` when the deepest overlap exceeds its bound (0 or 1 reason)."""
    if run.max_penetration is None:
        return []
    bound = tolerances.penetration * scales.size
    if run.max_penetration <= bound:
        return []
    return [Reason("penetration", run.max_penetration, bound,
                   f"deepest overlap {run.max_penetration:.3g} m > {bound:.3g} m "
                   f"({tolerances.penetration:g} of the smallest body extent "
                   f"{scales.size:g} m)")]


def _energy_gain(gain: float, scales: SceneScales, law_energy_change: float | None,
                 tolerances: Tolerances, *, law: str) -> list[Reason]:
    """``energy-gain`` when kinetic energy grew by ``gain`` (J), attributed to ``law`` (the
    reference the run is judged against) when it gains too, else to the numerics (0 or 1
    reason)."""
    bound = tolerances.energy * scales.energy
    if gain <= bound:
        return []
    by_law = (law_energy_change is not None and law_energy_change > bound
              and gain <= law_energy_change + tolerances.energy_beyond_law * scales.energy)
    return [Reason(
        "energy-gain", gain, bound,
        f"ΔE = +{gain:.4g} J ({gain / scales.energy:.3g} of the frame-free kinetic energy); "
        + (f"{law} gains {law_energy_change:.4g} J on this problem" if by_law
           else f"{law} does not gain energy here" if not law_energy_change
           or law_energy_change <= bound
           else f"beyond {law}'s own gain of {law_energy_change:.4g} J"),
        attribution="law" if by_law else "numerics", fails=not by_law)]


def impulse_from_velocities(problem, u_after, speed_norm: float) -> tuple[float, float, float]:
    """``(I_n, I_t, residual)``: the impulse at the contact implied by ``Δu = u_after − u``.

    ``M Δu`` is the generalised impulse the engine applied; projected on the contact's rows
    ``w_n``, ``w_t`` in the metric of ``M⁻¹`` it gives the one contact impulse that explains
    ``Δu`` best, (A22)/(A23): ``[[m_nn, m_nt], [m_nt, m_tt]] (I_n, I_t) = (w_n·Δu, w_t·Δu)``
    (docs/theory.md, 'Contact terms'). The residual ``‖Δu − M⁻¹(w_n I_n + w_t I_t)‖_M`` is
    divided by ``speed_norm``; it is 0 when ``Δu`` is one impulse at that point.
    """
    return _implied_impulse(problem, metrics.delassus(problem), u_after, speed_norm)


def _implied_impulse(problem, delassus: tuple[float, float, float], u_after,
                     speed_norm: float) -> tuple[float, float, float]:
    """:func:`metrics.impulses_from_velocities` with the contact's ``(m_nn, m_nt, m_tt)`` given: the
    impulse of ``metrics.impulses_from_velocities``, the same operations in the same order
    (so the same roundings), without working the Delassus terms out again."""
    delta_u = np.asarray(u_after, dtype=float) - problem.u
    normal, tangential = metrics.impulse_of(problem, delassus, delta_u)
    explained = np.linalg.solve(problem.mass_matrix,
                                problem.wn * normal + problem.wt * tangential)
    rest = metrics.ke_norm(problem.mass_matrix, delta_u - explained)
    return normal, tangential, (rest / speed_norm if speed_norm > 0 else math.nan)


def _clipped(engine: str, u_before: np.ndarray, u_after: np.ndarray,
             tolerances: Tolerances) -> list[Reason]:
    caps = speed_caps(engine)
    if caps is None:
        return []
    found = []
    for when, u in (("before", u_before), ("after", u_after)):
        for index, value in enumerate(u):
            cap = caps[1] if index % 3 == 2 else caps[0]
            if abs(value) >= (1.0 - tolerances.cap) * cap:
                name = ("v_x", "v_y", "ω")[index % 3]
                unit = "rad/s" if index % 3 == 2 else "m/s"
                found.append((when, index // 3, name, float(value), cap, unit))
    if not found:
        return []
    when, body, name, value, cap, unit = found[0]
    more = f" (and {len(found) - 1} more)" if len(found) > 1 else ""
    return [Reason("clipped", abs(value), cap,
                   f"body {body} {name} {when} = {value:.6g} {unit}, at {engine}'s cap "
                   f"{cap:g} {unit}{more}")]


def _clipped_magnitudes(engine: str, caps: tuple[float, float], u_before: np.ndarray,
                        u_after: np.ndarray, tolerances: Tolerances) -> list[Reason]:
    """``clipped`` for caps on each body's speed ``|v|`` and rate ``|ω|`` (Box2D's)."""
    band = 1.0 - max(tolerances.cap, RUN_CAP_BAND)
    speed_cap, rate_cap = caps
    found = []
    for when, u in (("before", u_before), ("after", u_after)):
        values = np.asarray(u, dtype=float).tolist()
        for body in range(len(values) // 3):
            vx, vy, omega = values[3 * body : 3 * body + 3]
            if math.hypot(vx, vy) >= band * speed_cap:
                found.append((when, body, "|v|", math.hypot(vx, vy), speed_cap, "m/s"))
            if abs(omega) >= band * rate_cap:
                found.append((when, body, "|ω|", abs(omega), rate_cap, "rad/s"))
    if not found:
        return []
    when, body, name, value, cap, unit = found[0]
    more = f" (and {len(found) - 1} more)" if len(found) > 1 else ""
    return [Reason("clipped", value, cap,
                   f"body {body} {name} {when} = {value:.6g} {unit}, at {engine}'s cap "
                   f"{cap:.6g} {unit} for this run's settings{more}")]


# --------------------------------------------------------------------------------------------
# Features: which corner / end cap of a body a contact point belongs to
# --------------------------------------------------------------------------------------------
def feature_points(shape) -> tuple[np.ndarray, float, tuple[str, ...]]:
    """Body-frame centres of a shape's point features, their radius (m) and names.

    A box or polygon has its vertices (radius 0), a rod its two end-cap centres (its cap
    radius), a disk none: its whole surface is one feature.
    """
    kind = shape.kind
    if kind == "disk":
        return np.zeros((0, 2)), float(shape.radius), ()
    if kind == "rod":
        half = shape.length / 2.0
        return (np.array([[-half, 0.0], [half, 0.0]]), float(shape.radius),
                ("end cap at -length/2", "end cap at +length/2"))
    # an ellipse: its stand-in polygon's vertices (MuJoCo's ellipsoid rolls far from them)
    vertices = np.asarray((shape.stand_in() if kind == "ellipse" else shape).vertices(),
                          dtype=float)
    return vertices, 0.0, tuple(f"corner {i}" for i in range(len(vertices)))


@dataclass(frozen=True)
class BodyFeatures:
    """One body's point features in its own frame (:func:`feature_points`) and its extent
    (:func:`body_extent`): what placing a contact point needs that no pose changes."""

    centres: np.ndarray  # (k, 2), m, body frame
    radius: float  # m
    names: tuple[str, ...]
    extent: float  # m


def body_features(shape) -> BodyFeatures:
    """The :class:`BodyFeatures` of ``shape``."""
    centres, radius, names = feature_points(shape)
    return BodyFeatures(centres, radius, names, body_extent(shape))


def feature_at(shape, state: Sequence[float], point: Sequence[float],
               reach: float) -> int | None:
    """Index of the point feature of ``shape`` (in pose ``state = (x, y, θ, …)``) within
    ``reach`` of ``point`` (m, beyond the feature's radius); None when the point lies on a
    face or side instead (or the shape is a disk)."""
    found = _features_at(body_features(shape), np.array([state[:3]], dtype=float),
                         np.array([point[:2]], dtype=float), np.zeros(1, dtype=np.int64),
                         np.array([reach], dtype=float))
    return None if found[0] < 0 else int(found[0])


def _rotations(poses: np.ndarray) -> np.ndarray:
    """Each pose's ``(x, y, θ)`` rotation as the matrix ``R`` with ``p @ R`` turning a row
    vector ``p`` by ``θ``; stacked, shape ``(n, 2, 2)``."""
    # math's cos and sin, one pose at a time: numpy's array ones may round differently
    angles = poses[:, 2].tolist()
    cos = np.fromiter(map(math.cos, angles), float, len(angles))
    sin = np.fromiter(map(math.sin, angles), float, len(angles))
    rotations = np.empty((len(angles), 2, 2))
    rotations[:, 0, 0] = rotations[:, 1, 1] = cos
    rotations[:, 0, 1] = sin
    rotations[:, 1, 0] = -sin
    return rotations


def _features_at(features: BodyFeatures, poses: np.ndarray, points: np.ndarray,
                 pose_of: np.ndarray, reach: np.ndarray) -> np.ndarray:
    """For every point ``points[i] = (x, y, …)`` with the body in pose
    ``poses[pose_of[i]] = (x, y, θ)``: the index of the body's point feature within
    ``reach[i]`` of it (beyond the feature's radius), or -1 (a face or side; always for a
    disk). The nearest feature is the one that counts, the first of equally near ones."""
    count = len(points)
    if not len(features.centres) or not count:
        return np.full(count, -1, dtype=np.int64)
    rotations = _rotations(poses)
    # centres @ R per pose (a stack of the same 2-D products), then moved to the pose
    world = (features.centres @ rotations + poses[:, None, :2])[pose_of]
    distances = np.hypot(world[:, :, 0] - points[:, None, 0],
                         world[:, :, 1] - points[:, None, 1]) - features.radius
    # the least distance is the nearest one's (NaN, as argmin's pick, when there is one)
    within = distances.min(axis=1) <= reach
    return np.where(within, np.argmin(distances, axis=1), -1)


def _touched(features: Sequence[BodyFeatures], track: ContactTrack,
             tolerances: Tolerances) -> np.ndarray:
    """``(P, B)``: per point of ``track`` and per body, the body's feature at that point
    (:func:`_features_at` within ``penetration·extent`` plus the point's depth), or -1."""
    depth = np.maximum(track.points[:, 2], 0.0)
    touched = np.full((len(track.points), len(features)), -1, dtype=np.int64)
    for index, body in enumerate(features):
        touched[:, index] = _features_at(body, track.poses[:, index], track.points,
                                         track.record,
                                         tolerances.penetration * body.extent + depth)
    return touched


def _one_feature(scene) -> bool:
    """Whether every body is a disk: its whole surface is one feature, so points an engine
    reports in one step are one contact region (a 3-D engine's cylinder gives two)."""
    return all(body.shape.kind == "disk" for body in scene.bodies)


def _second_features(scene, contacts: Sequence[StepContacts] | ContactTrack,
                     tolerances: Tolerances,
                     features: Sequence[BodyFeatures] | None = None) -> list[Reason]:
    """``multi-contact`` when a point touches a feature other than the contact's.

    The first point of the first step and the scene's contact point
    (:func:`contact_features`, worked out only when a later point is at another feature than
    the first's) fix the contact's features (per body: a corner, an end cap, or -1 for a
    face). A later point belongs to another feature when, on some body, it lies at a point
    feature that is neither. ``features``: the bodies' :class:`BodyFeatures` (None: from
    ``scene``).
    """
    if features is None:
        features = [body_features(body.shape) for body in scene.bodies]
    if all(not len(body.centres) for body in features):
        return []  # disks only: one feature each
    track = _track(contacts)
    if track.size < 2:
        return []
    touched = _touched(features, track, tolerances)
    first = touched[0]
    other = (touched[1:] >= 0) & (touched[1:] != first)
    if other.any():
        other &= touched[1:] != np.asarray(contact_features(scene, features, tolerances),
                                           dtype=np.int64)
    later = np.flatnonzero(other.any(axis=1))
    if not len(later):
        return []
    row = int(later[0])
    index = int(np.argmax(other[row]))
    now, then = int(touched[row + 1, index]), int(first[index])
    step = int(track.steps[track.record[row + 1]])
    body, names = scene.bodies[index], features[index].names
    return [Reason("multi-contact", float(step), None,
                   f"{body.name}'s {names[now]} touched at step {step} (the first contact "
                   "was at " + (names[then] if then >= 0 else "a face") + ")")]


_FIRST, _SECOND, _THIRD = itemgetter(0), itemgetter(1), itemgetter(2)


def _records_many(contact_records: Sequence) -> tuple[np.ndarray, ...]:
    """Many runs' raw contact records ``(shift, raw)`` (``EngineRun.contact_record``) as flat
    arrays in the scene frame, read in a few passes over all of them (not run by run).

    Returns ``(poses, points, record_of_point, run_of_record, run_of_point, point_counts)``:
    ``poses`` ``(R, 2, 3)`` every record's bodies' ``(x, y, θ)`` (a one-body run's second
    body NaN), ``points`` ``(P, 3)`` every point's ``(x, y, depth)``, run by run and record by
    record in order, the record (row of ``poses``) and run of each point, the run of each
    record, and ``(runs,)`` each run's number of points. The numbers of :class:`ContactTrack`
    (the same subtraction of each run's shift).
    """
    raws = [raw for _, raw in contact_records]
    record_counts = np.fromiter(map(len, raws), np.int64, len(raws))
    every = list(chain.from_iterable(raws))
    # (step, contacts, poses) records: contacts[0] the points (C-level getters, not a loop)
    point_lists = list(map(_FIRST, map(_SECOND, every)))
    pose_lists = list(map(_THIRD, every))
    per_record = np.fromiter(map(len, point_lists), np.int64, len(every))
    total = int(per_record.sum())
    # every point is (x, y, depth) and every pose (x, y, θ): each read as one flat run
    points = np.fromiter(chain.from_iterable(chain.from_iterable(point_lists)), float,
                         3 * total).reshape(-1, 3)
    bodies = np.fromiter(map(len, pose_lists), np.int64, len(every))
    rows = np.fromiter(chain.from_iterable(chain.from_iterable(pose_lists)), float,
                       3 * int(bodies.sum())).reshape(-1, 3)
    run_of_record = np.repeat(np.arange(len(raws)), record_counts)
    record_of_point = np.repeat(np.arange(len(every)), per_record)
    run_of_point = run_of_record[record_of_point]
    shifts = np.array([shift for shift, _ in contact_records], dtype=float).reshape(-1, 2)
    points[:, :2] -= shifts[run_of_point]
    record_of_row = np.repeat(np.arange(len(every)), bodies)
    rows[:, :2] -= shifts[run_of_record[record_of_row]]
    first_rows = np.cumsum(bodies) - bodies
    poses = np.full((len(every), 2, 3), np.nan)
    poses[record_of_row, np.arange(len(rows)) - first_rows[record_of_row]] = rows
    point_counts = np.bincount(run_of_point, minlength=len(raws))
    return poses, points, record_of_point, run_of_record, run_of_point, point_counts


def _second_features_many(contact_records: Sequence,
                          features: Sequence[Sequence[BodyFeatures]],
                          tolerances: Tolerances,
                          scenes: Sequence | None = None) -> list[bool]:
    """Whether :func:`_second_features` finds a second feature, for many runs at once
    (``contact_records[i]``, an ``EngineRun.contact_record``, of a scene whose bodies have
    ``features[i]``).

    The arithmetic of :func:`_features_at`, operation for operation on the same operands
    (math's cos and sin per pose, the same ``(k, 2) @ (2, 2)`` products per pose), over the
    points of every run whose body has ``k`` point features at once. A run of fewer than two
    points has no second one. ``scenes[i]``: run ``i``'s scene, whose contact point fixes
    the contact's features too, as in :func:`_second_features` (worked out only for a run
    with a candidate); None: the first points alone.
    """
    if not contact_records:
        return []
    (poses, points, record_of_point, run_of_record, run_of_point,
     counts) = _records_many(contact_records)
    if not len(points):
        return [False] * len(contact_records)
    touched = np.full((len(points), 2), -1, dtype=np.int64)
    eligible = counts >= 2
    groups: dict[tuple[int, int], list[int]] = {}
    for run in np.flatnonzero(eligible).tolist():
        for body, feature in enumerate(features[run]):
            if len(feature.centres):
                groups.setdefault((body, len(feature.centres)), []).append(run)
    depth = np.maximum(points[:, 2], 0.0)
    for (body, _), runs in groups.items():
        in_group = np.zeros(len(contact_records), dtype=bool)
        in_group[runs] = True
        position = np.full(len(contact_records), -1, dtype=np.int64)
        position[runs] = np.arange(len(runs))
        records = in_group[run_of_record]
        at = np.flatnonzero(in_group[run_of_point])
        group_poses = poses[records, body]
        rotations = _rotations(group_poses)
        centres = np.stack([features[run][body].centres for run in runs])[
            position[run_of_record[records]]]
        pose_of = (np.cumsum(records) - 1)[record_of_point[at]]
        group_points = points[at]
        owner = position[run_of_point[at]]
        radius = np.array([features[run][body].radius for run in runs])[owner]
        reach = (np.array([tolerances.penetration * features[run][body].extent
                           for run in runs])[owner] + depth[at])
        world = (centres @ rotations + group_poses[:, None, :2])[pose_of]
        distances = np.hypot(world[:, :, 0] - group_points[:, None, 0],
                             world[:, :, 1] - group_points[:, None, 1]) - radius[:, None]
        within = distances.min(axis=1) <= reach
        touched[at, body] = np.where(within, np.argmin(distances, axis=1), -1)
    starts = np.cumsum(counts) - counts
    first = touched[np.minimum(starts, max(len(points) - 1, 0))][run_of_point]
    other = (touched >= 0) & (touched != first)
    other[starts[counts > 0]] = False
    if scenes is not None:  # the scene's contact point: only where a run has a candidate
        fixed = np.full((len(contact_records), 2), -1, dtype=np.int64)
        for run in np.unique(run_of_point[other.any(axis=1)]).tolist():
            found = contact_features(scenes[run], features[run], tolerances)
            fixed[run, :len(found)] = found
        other &= touched != fixed[run_of_point]
    return ((np.bincount(run_of_point, weights=other.any(axis=1),
                         minlength=len(contact_records)) > 0) & eligible).tolist()


# --------------------------------------------------------------------------------------------
# Declared simultaneous contacts: a face lying flat (contacts = "simultaneous")
# --------------------------------------------------------------------------------------------
def declared_contacts(scenario, scene) -> tuple | None:
    """The contacts ``scene`` touches at once when its scenario declares them
    (``contacts = "simultaneous"``), as the references take them
    (:func:`harness.scene.geometry.scene_contacts` within the one-point tolerance); None for a
    scenario of one contact (docs/verdicts.md, 'Declared simultaneous contacts')."""
    from harness.run import references

    if references.kind_of(scenario) != references.SIMULTANEOUS:
        return None
    from harness.scenarios.schema import ONE_POINT_TOLERANCE
    from harness.scene import geometry

    return tuple(geometry.scene_contacts(scene, tolerance=ONE_POINT_TOLERANCE))


def sequence_contacts(scenario, scene) -> tuple | None:
    """The features a tilt's reference sequence strikes (``expect_sequence``: the
    event-driven sequence with ``newton-lcp``), each as a contact at its ground point in the
    scene's pose (as the references take them), in order of first strike; None for a
    scenario whose reference is not a sequence (docs/verdicts.md, 'Sequences of impacts')."""
    from harness.run import references

    if references.kind_of(scenario) != references.EVENT_DRIVEN or not scene.ground:
        return None
    from harness.reference.event_driven import sequence_outline
    from harness.scene import Contact, geometry

    world, radius = geometry.world_core(scene.bodies[0])
    return tuple(Contact(point=np.array([world[k, 0], world[k, 1] - radius]),
                         normal=np.array([0.0, 1.0]), gap=float(world[k, 1] - radius))
                 for k in sequence_outline(scene).features)


def truncated_sequence(scene, run: RunNumbers, scales: SceneScales,
                       tolerances: Tolerances = DEFAULT_TOLERANCES) -> list[Reason]:
    """``truncated-sequence`` when the run's end state strikes the ground again: the body in
    the pose of the run's last contact step, with the run's final speeds, in free flight,
    has a feature that meets the ground faster than the separation tolerance
    (``separation · |v_n^A|``). Such a run is only the first impacts of a sequence. Needs the
    contact records and one body on the ground (else no reason)."""
    from harness.reference.event_driven import next_strike

    if run.contacts is None or not scene.ground:
        return []
    track = _track(run.contacts)
    if not len(track.steps):
        return []
    x, y, angle = (float(v) for v in track.poses[-1, 0])
    v_x, v_y, omega = (float(v) for v in run.u_after[:3])
    body = scene.bodies[0].moved(position=(x, y), angle=angle, velocity=(v_x, v_y),
                                 angular_velocity=omega)
    found = next_strike(body, tolerances.separation * scales.approach_speed)
    if found is None:
        return []
    feature, when = found
    names = body_features(body.shape).names
    step = int(track.steps[-1])
    return [Reason("truncated-sequence", when, None,
                   f"the run ended with {body.name}'s {names[feature]} still reaching the "
                   f"ground {when:.3g} s after its last contact step ({step}): only the "
                   "first impacts of the sequence")]


def judge_declared(scene, problem, run: RunNumbers, contacts, *,
                   law_energy_change: float | None = None,
                   tolerances: Tolerances = DEFAULT_TOLERANCES,
                   sequence: bool = False) -> Verdict:
    """The verdict of an engine run of a scene declared to touch at ``contacts`` at once.

    The checks of :func:`judge`, held against every declared contact instead of one: a
    touching feature outside them is ``multi-contact`` (the engine's count of points is not a
    reason: two points are what was declared); each contact must separate; ``Δu`` must be
    explained by impulses at the declared contacts together (:func:`declared_impulses`), and
    the engine's summed impulse must match their sum; an energy gain is the law's when the
    Newton–Coulomb reference gains too (``law_energy_change``). docs/verdicts.md, 'Declared
    simultaneous contacts'.

    ``sequence``: the contacts are the features a tilt's reference sequence strikes one after
    another (:func:`sequence_contacts`), not at once; the run must also have finished the
    sequence (:func:`truncated_sequence`), and its energy is held against the sequence's.
    """
    from harness.scene import geometry

    reasons: list[Reason] = []
    if run.status in ENGINE_STATUS_REASONS and run.status != "multi-contact":
        reasons.append(Reason(run.status, None, None, f"the engine's status: {run.status}"))
    elif run.status not in ("ok", "multi-contact"):  # skipped or error: nothing to judge
        return Verdict(tuple(reasons))
    u_after = run.u_after
    if not np.all(np.isfinite(u_after)):
        if run.status != "blow-up":
            reasons.append(Reason("blow-up", None, None, "non-finite velocities"))
        return Verdict(tuple(reasons))
    wn, wt = geometry.contact_rows(scene, contacts)
    scales = declared_scales(scene, problem, wn)
    if run.speed_caps is not None:
        reasons += _clipped_magnitudes(run.engine, run.speed_caps, problem.u, u_after,
                                       tolerances)
    else:
        reasons += _clipped(run.engine, problem.u, u_after, tolerances)
    if run.contacts is not None:
        reasons += _undeclared_features(scene, contacts, run.contacts, tolerances)
        if not sequence:
            reasons += staggered_strikes(scene, contacts, run.contacts, tolerances)
    if sequence:
        reasons += truncated_sequence(scene, run, scales, tolerances)
    reasons += _declared_separation(contacts, wn @ u_after, scales, tolerances)
    reasons += _penetration(run, scales, tolerances)
    impulses, residual = declared_impulses(problem.mass_matrix, wn, wt, problem.u, u_after,
                                           scales.speed_norm)
    reasons += _at_boundary("impulse-residual", residual, tolerances.impulse_residual,
                            "residual", "of the speed norm")
    if residual > tolerances.impulse_residual:
        reasons.append(Reason("impulse-residual", residual, tolerances.impulse_residual,
                              f"‖Δu − M⁻¹Σ_i(w_n^(i) I_n^(i) + w_t^(i) I_t^(i))‖_M = "
                              f"{residual:.3g} of the frame-free speed norm, over the "
                              f"{len(contacts)} declared contacts"))
    reasons += _impulse_mismatch(
        run, float(np.sum(impulses[0])), float(np.sum(impulses[1])), scales, tolerances,
        engine="(ΣI_n, ΣI_t)", implied=f"by Δu over the {len(contacts)} declared contacts",
        scale="max_i |v_n^A(i)|/m_nn(i)")
    reasons += _energy_gain(metrics.energy_change(problem.mass_matrix, problem.u, u_after),
                            scales, law_energy_change, tolerances,
                            law=SEQUENCE_LAW if sequence else NEWTON_COULOMB)
    reasons.sort(key=lambda reason: _REASON_ORDER[reason.name])
    return Verdict(tuple(reasons))


def declared_scales(scene, problem, wn: np.ndarray) -> SceneScales:
    """:func:`scene_scales` over declared contacts with rows ``wn`` (one per contact): the
    approach speed is the largest ``|v_n^A(i)|`` and the impulse scale the largest
    ``|v_n^A(i)| / m_nn(i)`` (a plastic frictionless impact at that contact alone)."""
    single = scene_scales(scene, problem)
    approach = np.abs(wn @ problem.u)
    mnn = np.einsum("ij,ij->i", wn, np.linalg.solve(problem.mass_matrix, wn.T).T)
    return SceneScales(approach_speed=float(approach.max()),
                       impulse=float(np.max(approach / mnn)),
                       speed_norm=single.speed_norm, energy=single.energy, size=single.size)


def declared_impulses(mass_matrix, wn, wt, u_before, u_after,
                      speed_norm: float) -> tuple[np.ndarray, float]:
    """``((I_n, I_t), residual)``: the impulses at ``m`` contacts that best explain
    ``Δu = u_after − u_before``, and what they leave unexplained.

    ``M Δu`` is the generalised impulse the engine applied; at the contacts it is
    ``Σ_i (w_n^(i) I_n^(i) + w_t^(i) I_t^(i))`` (eq. (75); docs/multi-contact.md, 'Setting:
    eq. (75)'). The impulses minimise ``‖Δu − M⁻¹ W I‖_M`` over all ``2m`` columns of
    ``M⁻¹W``, ``W = [w_n^(i), w_t^(i)]``: with ``M = L Lᵀ`` this is the least-squares problem
    ``L⁻¹W I ≈ Lᵀ Δu`` (minimum-norm ``I`` where the columns are dependent, as two points of
    one body on the ground are). For ``m = 1`` it is :func:`impulse_from_velocities`. The
    split between contacts need not be unique, but the sums ``Σ I_n^(i)``, ``Σ I_t^(i)``
    are when the contacts share a normal (a dependent combination moves no centre of mass,
    so its normal and tangential parts each sum to zero). Returns ``(2, m)`` impulses (row 0
    normal, row 1 tangential, N s) and the residual divided by ``speed_norm``.
    """
    mass_matrix = np.asarray(mass_matrix, dtype=float)
    wn, wt = np.atleast_2d(wn), np.atleast_2d(wt)
    delta_u = np.asarray(u_after, dtype=float) - np.asarray(u_before, dtype=float)
    lower = np.linalg.cholesky(mass_matrix)
    columns = np.linalg.solve(lower, np.vstack([wn, wt]).T)  # L⁻¹W: (p, 2m)
    target = lower.T @ delta_u  # ‖x‖_M = ‖Lᵀx‖
    impulses, *_ = np.linalg.lstsq(columns, target, rcond=None)
    rest = float(np.linalg.norm(target - columns @ impulses))
    return (impulses.reshape(2, len(wn)),
            rest / speed_norm if speed_norm > 0 else math.nan)


def _contact_name(contacts, index: int) -> str:
    x, y = (float(v) for v in contacts[index].point)
    return f"contact {index + 1} of {len(contacts)} at ({x:.4g}, {y:.4g}) m"


def _declared_separation(contacts, vn_after: np.ndarray, scales: SceneScales,
                         tolerances: Tolerances) -> list[Reason]:
    """``not-separated`` when a declared contact still closes: ``v_n^S(i) < −tol·|v_n^A|``
    (the worst one named; 0 or 1 reason)."""
    bound = tolerances.separation * scales.approach_speed
    closing = [i for i, v in enumerate(vn_after) if v < -bound]
    if not closing:
        return []
    worst = min(closing, key=lambda i: vn_after[i])
    more = f" (and {len(closing) - 1} more)" if len(closing) > 1 else ""
    return [Reason("not-separated", float(vn_after[worst]), -bound,
                   f"{_contact_name(contacts, worst)}: v_n^S = {vn_after[worst]:.4g} m/s "
                   f"< -{bound:.3g} m/s ({tolerances.separation:g}·max_i |v_n^A(i)|){more}")]


def _undeclared_features(scene, contacts, records: Sequence[StepContacts] | ContactTrack,
                         tolerances: Tolerances) -> list[Reason]:
    """``multi-contact`` when a point touches a feature none of the declared contacts has.

    Each declared contact fixes, per body, the feature at its point in the scene's pose (a
    corner, an end cap, or a face: -1). A recorded point belongs to a declared contact when
    on every body it lies on a face or at that contact's feature; else it is reported with
    the body, the feature and the step.
    """
    features = [body_features(body.shape) for body in scene.bodies]
    track = _track(records)
    if not track.size:
        return []
    poses = np.array([[(*body.position, body.angle) for body in scene.bodies]], dtype=float)
    at_declared = ContactTrack(np.zeros(1, dtype=np.int64), poses,
                               np.array([[*contact.point[:2], 0.0] for contact in contacts],
                                        dtype=float).reshape(-1, 3),
                               np.zeros(len(contacts), dtype=np.int64))
    declared = _touched(features, at_declared, tolerances)  # (contacts, bodies)
    touched = _touched(features, track, tolerances)  # (points, bodies)
    # per point and declared contact: on every body a face or that contact's feature
    fits = ((touched[:, None, :] < 0) | (touched[:, None, :] == declared[None])).all(axis=2)
    outside = np.flatnonzero(~fits.any(axis=1))
    if not len(outside):
        return []
    row = int(outside[0])
    features_now = touched[row]
    index = next(k for k, now in enumerate(features_now)
                 if now >= 0 and np.any(now != declared[:, k]))
    body, names = scene.bodies[index], features[index].names
    held = sorted({int(allowed) for allowed in declared[:, index]})
    listed = ", ".join("a face" if f < 0 else names[f] for f in held)
    step = int(track.steps[track.record[row]])
    return [Reason("multi-contact", float(step), None,
                   f"{body.name}'s {names[features_now[index]]} touched at step {step}, "
                   f"outside the {len(contacts)} declared contacts ({listed})")]


def first_strikes(scene, contacts, records: Sequence[StepContacts] | ContactTrack,
                  tolerances: Tolerances = DEFAULT_TOLERANCES) -> list[int | None]:
    """Per declared contact, the first step at which a recorded point lies at it (None:
    never). A point lies at the declared contact whose feature (corner, end cap) it touches
    on some body (:func:`_touched`, in the pose of its step); a point at no declared
    contact's feature belongs to the nearest declared point (a face against a face)."""
    features = [body_features(body.shape) for body in scene.bodies]
    track = _track(records)
    found: list[int | None] = [None] * len(contacts)
    if not track.size:
        return found
    poses = np.array([[(*body.position, body.angle) for body in scene.bodies]], dtype=float)
    where = np.array([[*contact.point[:2], 0.0] for contact in contacts],
                     dtype=float).reshape(-1, 3)
    declared = _touched(features, ContactTrack(np.zeros(1, dtype=np.int64), poses, where,
                                               np.zeros(len(contacts), dtype=np.int64)),
                        tolerances)  # (contacts, bodies)
    touched = _touched(features, track, tolerances)  # (points, bodies)
    at = ((touched[:, None, :] >= 0) & (touched[:, None, :] == declared[None])).any(axis=2)
    distances = np.hypot(track.points[:, None, 0] - where[None, :, 0],
                         track.points[:, None, 1] - where[None, :, 1])
    nearest = np.argmin(distances, axis=1)
    owner = np.where(at.any(axis=1), np.argmax(at, axis=1), nearest)
    steps = track.steps[track.record]
    for index in range(len(contacts)):
        mine = steps[owner == index]
        if len(mine):
            found[index] = int(mine.min())
    return found


def staggered_strikes(scene, contacts, records: Sequence[StepContacts] | ContactTrack,
                      tolerances: Tolerances = DEFAULT_TOLERANCES) -> list[Reason]:
    """``not-simultaneous`` when two declared contacts were first struck at different steps
    (:func:`first_strikes`): the engine did a sequence of impacts where the file declares
    one simultaneous impact. The residual cannot tell: for one body on the ground the
    declared contacts' columns span its speeds, so it is zero by construction. Contacts
    never struck are not counted here (their separation is checked)."""
    firsts = first_strikes(scene, contacts, records, tolerances)
    struck = [(step, index) for index, step in enumerate(firsts) if step is not None]
    if len(struck) < 2 or len({step for step, _ in struck}) == 1:
        return []
    (early, first), (late, last) = min(struck), max(struck)
    return [Reason("not-simultaneous", float(late - early), 0.0,
                   f"{_contact_name(contacts, first)} first struck at step {early}, "
                   f"{_contact_name(contacts, last)} at step {late}: a sequence of impacts, "
                   "not the simultaneous impact declared")]


def reason_counts(reasons_per_run: Sequence[Sequence[Mapping[str, Any]]]) -> dict[str, int]:
    """``{reason: runs failing it}`` over many runs' ``reasons`` lists (law-attributed
    energy gains counted as ``energy-gain (law)``, not failing; remarks such as
    ``at-boundary`` under their own name)."""
    counts: dict[str, int] = {}
    for reasons in reasons_per_run:
        for reason in reasons:
            name = (reason["name"] if reason.get("fails", True) or reason["name"] in REMARKS
                    else f"{reason['name']} (law)")
            counts[name] = counts.get(name, 0) + 1
    return counts


__all__ = ["BOUNDARY_BAND", "DEFAULT_TOLERANCES", "REASONS", "REMARKS", "speed_caps",
           "BodyFeatures", "ContactTrack", "Reason", "RunNumbers", "SceneScales", "SceneTerms",
           "StepContacts", "Tolerances", "Verdict", "body_features", "contact_features",
           "declared_contacts", "declared_impulses", "first_strikes", "sequence_contacts",
           "staggered_strikes", "truncated_sequence",
           "declared_scales", "feature_at", "feature_points", "impulse_from_velocities",
           "TermArrays", "judge", "judge_declared", "judge_many", "numbers_from_output",
           "numbers_from_run", "prepare", "prepare_many", "reason_counts", "scene_scales",
           "term_arrays"]
