"""Declared contacts: the verdict of a run on a face lying flat (``contacts =
"simultaneous"``) or of a tilt's sequence of impacts (:func:`judge_declared`).

The run is judged against every declared contact instead of one: features outside them,
each contact's separation, the impulses at all of them together, contacts first struck at
different steps, a sequence the run did not finish, energy against the Newton–Coulomb
reference or the sequence's (docs/verdicts.md, 'Declared simultaneous contacts').
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from harness.reference.event_driven import next_strike, sequence_outline
from harness.run import metrics, references
from harness.run.verdicts.checks import (
    RunNumbers,
    SceneScales,
    boundary_remarks,
    clipped_magnitude_reasons,
    clipped_reasons,
    energy_gain_reasons,
    impulse_mismatch_reasons,
    penetration_reasons,
    scene_scales,
)
from harness.run.verdicts.reasons import (
    DEFAULT_TOLERANCES,
    ENGINE_STATUS_REASONS,
    NEWTON_COULOMB,
    REASON_ORDER,
    SEQUENCE_LAW,
    Reason,
    Tolerances,
    Verdict,
)
from harness.run.verdicts.touching import touched_features
from harness.run.verdicts.tracks import ContactTrack, StepContacts, as_track
from harness.scenarios.schema import ONE_POINT_TOLERANCE
from harness.scene import Contact, geometry
from harness.scene.features import body_features


def declared_contacts(scenario, scene) -> tuple | None:
    """The contacts ``scene`` touches at once when its scenario declares them
    (``contacts = "simultaneous"``), as the references take them
    (:func:`harness.scene.geometry.scene_contacts` within the one-point tolerance); None for a
    scenario of one contact (docs/verdicts.md, 'Declared simultaneous contacts')."""
    if references.kind_of(scenario) != references.SIMULTANEOUS:
        return None
    return tuple(geometry.scene_contacts(scene, tolerance=ONE_POINT_TOLERANCE))


def sequence_contacts(scenario, scene) -> tuple | None:
    """The features a tilt's reference sequence strikes (``expect_sequence``: the
    event-driven sequence with ``newton-lcp``), each as a contact at its ground point in the
    scene's pose (as the references take them), in order of first strike; None for a
    scenario whose reference is not a sequence (docs/verdicts.md, 'Sequences of impacts')."""
    if references.kind_of(scenario) != references.EVENT_DRIVEN or not scene.ground:
        return None
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
    if run.contacts is None or not scene.ground:
        return []
    track = as_track(run.contacts)
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
                   sequence: bool = False, reference: str | None = None) -> Verdict:
    """The verdict of an engine run of a scene declared to touch at ``contacts`` at once.

    The checks of :func:`judge`, held against every declared contact instead of one: a
    touching feature outside them is ``multi-contact`` (the engine's count of points is not a
    reason: two points are what was declared); each contact must separate; ``Δu`` must be
    explained by impulses at the declared contacts together (:func:`declared_impulses`), and
    the engine's summed impulse must match their sum; an energy gain is the law's when the
    primary reference gains too (``law_energy_change`` of ``reference``, Newton–Coulomb
    unless it broke admissibility; an inadmissible solution is never primary, so a gain is
    never excused against one: docs/multi-contact.md, 'Admissible references').
    docs/verdicts.md, 'Declared simultaneous contacts'.

    ``sequence``: the contacts are the features a tilt's reference sequence strikes one after
    another (:func:`sequence_contacts`), not at once; the run must also have finished the
    sequence (:func:`truncated_sequence`), and its energy is held against the sequence's.
    """
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
        reasons += clipped_magnitude_reasons(run.engine, run.speed_caps, problem.u, u_after,
                                       tolerances)
    else:
        reasons += clipped_reasons(run.engine, problem.u, u_after, tolerances)
    if run.contacts is not None:
        reasons += _undeclared_features(scene, contacts, run.contacts, tolerances)
        if not sequence:
            reasons += staggered_strikes(scene, contacts, run.contacts, tolerances)
    if sequence:
        reasons += truncated_sequence(scene, run, scales, tolerances)
    reasons += _declared_separation(contacts, wn @ u_after, scales, tolerances)
    reasons += penetration_reasons(run, scales, tolerances)
    impulses, residual = declared_impulses(problem.mass_matrix, wn, wt, problem.u, u_after,
                                           scales.speed_norm)
    reasons += boundary_remarks("impulse-residual", residual, tolerances.impulse_residual,
                            "residual", "of the speed norm")
    if residual > tolerances.impulse_residual:
        reasons.append(Reason("impulse-residual", residual, tolerances.impulse_residual,
                              f"‖Δu − M⁻¹Σ_i(w_n^(i) I_n^(i) + w_t^(i) I_t^(i))‖_M = "
                              f"{residual:.3g} of the frame-free speed norm, over the "
                              f"{len(contacts)} declared contacts"))
    reasons += impulse_mismatch_reasons(
        run, float(np.sum(impulses[0])), float(np.sum(impulses[1])), scales, tolerances,
        engine="(ΣI_n, ΣI_t)", implied=f"by Δu over the {len(contacts)} declared contacts",
        scale="max_i |v_n^A(i)|/m_nn(i)")
    reasons += energy_gain_reasons(metrics.energy_change(problem.mass_matrix, problem.u, u_after),
                            scales, law_energy_change, tolerances,
                            law=reference or (SEQUENCE_LAW if sequence else NEWTON_COULOMB))
    reasons.sort(key=lambda reason: REASON_ORDER[reason.name])
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
    track = as_track(records)
    if not track.size:
        return []
    poses = np.array([[(*body.position, body.angle) for body in scene.bodies]], dtype=float)
    at_declared = ContactTrack(np.zeros(1, dtype=np.int64), poses,
                               np.array([[*contact.point[:2], 0.0] for contact in contacts],
                                        dtype=float).reshape(-1, 3),
                               np.zeros(len(contacts), dtype=np.int64))
    declared = touched_features(features, at_declared, tolerances)  # (contacts, bodies)
    touched = touched_features(features, track, tolerances)  # (points, bodies)
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
    on some body (:func:`touched_features`, in the pose of its step); a point at no declared
    contact's feature belongs to the nearest declared point (a face against a face)."""
    features = [body_features(body.shape) for body in scene.bodies]
    track = as_track(records)
    found: list[int | None] = [None] * len(contacts)
    if not track.size:
        return found
    poses = np.array([[(*body.position, body.angle) for body in scene.bodies]], dtype=float)
    where = np.array([[*contact.point[:2], 0.0] for contact in contacts],
                     dtype=float).reshape(-1, 3)
    declared = touched_features(features, ContactTrack(np.zeros(1, dtype=np.int64), poses, where,
                                               np.zeros(len(contacts), dtype=np.int64)),
                        tolerances)  # (contacts, bodies)
    touched = touched_features(features, track, tolerances)  # (points, bodies)
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


__all__ = ["declared_contacts", "declared_impulses", "declared_scales", "first_strikes",
           "judge_declared", "sequence_contacts", "staggered_strikes", "truncated_sequence"]
