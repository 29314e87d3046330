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

The package, one job a module:

* :mod:`~harness.run.verdicts.reasons` -- the reasons, remarks and tolerances, a
  :class:`Reason` and a :class:`Verdict`;
* :mod:`~harness.run.verdicts.tracks` -- a run's per-step contact records as arrays;
* :mod:`~harness.run.verdicts.checks` -- the numbers of a run and the scales of its scene, and
  the checks every verdict makes;
* :mod:`~harness.run.verdicts.touching` -- which features of the bodies the points touch
  (``multi-contact``);
* :mod:`~harness.run.verdicts.single` -- the verdict of a run at one contact
  (:func:`judge`);
* :mod:`~harness.run.verdicts.declared` -- the verdict against declared contacts
  (:func:`judge_declared`);
* :mod:`~harness.run.verdicts.many` -- the verdicts of many runs at once (:func:`judge_many`).

A shape's point features (corners, end caps) are the scene's: :mod:`harness.scene.features`.
"""

from __future__ import annotations

from harness.run.verdicts.checks import (
    RUN_CAP_BAND,
    RunNumbers,
    SceneScales,
    numbers_from_output,
    numbers_from_run,
    scene_scales,
    speed_caps,
)
from harness.run.verdicts.declared import (
    declared_contacts,
    declared_impulses,
    declared_scales,
    first_strikes,
    judge_declared,
    sequence_contacts,
    staggered_strikes,
    truncated_sequence,
)
from harness.run.verdicts.many import ARRAY_WIDTH, TermArrays, judge_many, prepare_many, term_arrays
from harness.run.verdicts.reasons import (
    BOUNDARY_BAND,
    DEFAULT_TOLERANCES,
    ENGINE_LAW,
    ENGINE_STATUS_REASONS,
    FLAGGED,
    NEWTON_COULOMB,
    REASONS,
    REMARKS,
    SEQUENCE_LAW,
    SINGLE_IMPACT,
    Reason,
    Tolerances,
    Verdict,
    reason_counts,
)
from harness.run.verdicts.single import SceneTerms, impulse_from_velocities, judge, prepare
from harness.run.verdicts.touching import contact_features
from harness.run.verdicts.tracks import ContactTrack, StepContacts

__all__ = ["ARRAY_WIDTH", "BOUNDARY_BAND", "DEFAULT_TOLERANCES", "ENGINE_LAW",
           "ENGINE_STATUS_REASONS", "FLAGGED", "NEWTON_COULOMB", "REASONS", "REMARKS",
           "RUN_CAP_BAND", "SEQUENCE_LAW", "SINGLE_IMPACT", "ContactTrack", "Reason",
           "RunNumbers", "SceneScales", "SceneTerms", "StepContacts", "TermArrays",
           "Tolerances", "Verdict", "contact_features", "declared_contacts",
           "declared_impulses", "declared_scales", "first_strikes", "impulse_from_velocities",
           "judge", "judge_declared", "judge_many", "numbers_from_output", "numbers_from_run",
           "prepare", "prepare_many", "reason_counts", "scene_scales", "sequence_contacts",
           "speed_caps", "staggered_strikes", "term_arrays", "truncated_sequence"]
