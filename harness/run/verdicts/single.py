"""The verdict of one engine run against its scene's one contact (:func:`judge`).

What a scene alone determines (its scales, Delassus terms, bodies' features:
:class:`SceneTerms`) is worked out once by :func:`prepare` and passed to :func:`judge` for
every run of that scene. A scene that declares several contacts is judged against them
(:func:`harness.run.verdicts.declared.judge_declared`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from harness.run import metrics
from harness.run.verdicts.checks import (
    RunNumbers,
    SceneScales,
    boundary_remarks,
    clipped_magnitude_reasons,
    clipped_reasons,
    energy_gain_reasons,
    impulse_mismatch_reasons,
    penetration_reasons,
    scales_from,
)
from harness.run.verdicts.declared import judge_declared
from harness.run.verdicts.reasons import (
    DEFAULT_TOLERANCES,
    ENGINE_LAW,
    ENGINE_STATUS_REASONS,
    REASON_ORDER,
    Reason,
    Tolerances,
    Verdict,
)
from harness.run.verdicts.touching import one_feature, second_features
from harness.scene.features import BodyFeatures, body_features


@dataclass(frozen=True)
class SceneTerms:
    """What judging any run of one scene needs that no run changes (:func:`prepare`): worked
    out once per scene, not once per run."""

    scales: SceneScales
    delassus: tuple[float, float, float]  # (m_nn, m_nt, m_tt) of the scene's contact
    norm_before: float  # ‖u_before‖_M, the kinetic-energy norm before (sqrt(kg) m/s)
    features: tuple[BodyFeatures, ...]  # every body's point features, in scene order
    one_feature: bool  # every body a disk (:func:`one_feature`)


def prepare(scene, problem) -> SceneTerms:
    """The :class:`SceneTerms` of ``scene`` and its impact ``problem``."""
    return prepare_from(scene, problem, metrics.delassus(problem))


def prepare_from(scene, problem, delassus: tuple[float, float, float]) -> SceneTerms:
    """:func:`prepare` with the scene's ``metrics.delassus`` given."""
    features = tuple(body_features(body.shape) for body in scene.bodies)
    scales = scales_from(scene, problem, delassus[0], [f.extent for f in features])
    # Against the ground the frame-free norm is ke_norm(M, u) itself: not worked out twice.
    norm_before = (scales.speed_norm if scene.ground
                   else metrics.ke_norm(problem.mass_matrix, problem.u))
    return SceneTerms(scales, delassus, norm_before, features, one_feature(scene))


def judge(scene, problem, run: RunNumbers, *, law_energy_change: float | None = None,
          tolerances: Tolerances = DEFAULT_TOLERANCES, contacts=None,
          terms: SceneTerms | None = None,
          implied: tuple[float, float, float] | None = None,
          sequence: bool = False, reference: str | None = None) -> Verdict:
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
    reference : str, optional
        With ``contacts``: the name of the reference ``law_energy_change`` is of (a flat
        face's primary, always admissible: docs/multi-contact.md, 'Admissible references');
        None: Newton–Coulomb, or the sequence's law with ``sequence``.
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
                              sequence=sequence, reference=reference)
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
        reasons += clipped_magnitude_reasons(run.engine, run.speed_caps, problem.u, u_after,
                                       tolerances)
    else:
        reasons += clipped_reasons(run.engine, problem.u, u_after, tolerances)
    if run.contacts is not None:
        reasons += second_features(scene, run.contacts, tolerances, terms.features)
    vn_after = float(problem.wn @ u_after)  # metrics.contact_velocities' v_n
    bound = tolerances.separation * scales.approach_speed
    reasons += boundary_remarks("not-separated", vn_after, -bound, "v_n^S", "m/s",
                            float(np.abs(problem.wn * u_after).sum()))
    if run.max_penetration is not None:
        reasons += boundary_remarks("penetration", run.max_penetration,
                                tolerances.penetration * scales.size, "deepest overlap", "m")
    if vn_after < -bound:
        reasons.append(Reason("not-separated", vn_after, -bound,
                              f"v_n^S = {vn_after:.4g} m/s < -{bound:.3g} m/s "
                              f"({tolerances.separation:g}·|v_n^A|)"))
    reasons += penetration_reasons(run, scales, tolerances)
    implied_n, implied_t, residual = (
        implied if implied is not None
        else _implied_impulse(problem, terms.delassus, u_after, scales.speed_norm))
    reasons += boundary_remarks("impulse-residual", residual, tolerances.impulse_residual,
                            "residual", "of the speed norm")
    if residual > tolerances.impulse_residual:
        reasons.append(Reason("impulse-residual", residual, tolerances.impulse_residual,
                              f"‖Δu − M⁻¹(w_n I_n + w_t I_t)‖_M = {residual:.3g} of the "
                              f"frame-free speed norm"))
    reasons += impulse_mismatch_reasons(run, implied_n, implied_t, scales, tolerances,
                                 engine="(I_n, I_t)", implied="by Δu",
                                 scale="|v_n^A|/m_nn")
    gain = 0.5 * (metrics.ke_norm(problem.mass_matrix, u_after) ** 2 - terms.norm_before**2)
    reasons += boundary_remarks("energy-gain", gain, tolerances.energy * scales.energy, "ΔE", "J",
                            terms.norm_before**2)
    reasons += energy_gain_reasons(gain, scales, law_energy_change, tolerances, law=ENGINE_LAW)
    reasons.sort(key=lambda reason: REASON_ORDER[reason.name])
    return Verdict(tuple(reasons))


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


__all__ = ["SceneTerms", "impulse_from_velocities", "judge", "prepare", "prepare_from"]
