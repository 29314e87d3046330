"""Which features of the bodies a run's contact points touch: ``multi-contact`` judged from
the physics, not from a count of points.

A point touches a body's corner or end cap (:mod:`harness.scene.features`) when it lies
within the penetration reach of it in the pose of its step. The contact's own features are
those of the run's first point and of the scene's contact point (:func:`contact_features`);
a later point at another feature is a second contact (:func:`second_features`, and for many
runs at once :func:`second_features_many`).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from harness.run.verdicts.reasons import DEFAULT_TOLERANCES, Reason, Tolerances
from harness.run.verdicts.tracks import ContactTrack, StepContacts, as_track, records_many
from harness.scene import geometry
from harness.scene.features import BodyFeatures, body_features, centres_at_poses, features_at


def contact_features(scene, features: Sequence[BodyFeatures] | None = None,
                     tolerances: Tolerances | None = None) -> tuple[int, ...]:
    """Per body, the point feature (corner, end cap) at the scene's contact point in the
    scene's pose (the touching pose the reference describes), or -1 for a face.

    The engine's first recorded point alone cannot fix the contact's features: Box2D reports
    a point computed before its step with the pose after it, through its polygon skin, so on
    a spinning box the struck corner's first point lay 0.028 m from it and read as a face,
    and the corner's next point became a false ``multi-contact`` (box-corner-spin, Box2D
    ``defaults``). Both fix them (:func:`second_features`).
    """
    tolerances = DEFAULT_TOLERANCES if tolerances is None else tolerances
    if features is None:
        features = [body_features(body.shape) for body in scene.bodies]
    point = np.asarray(geometry.scene_contact(scene).point, dtype=float)[:2]
    found = []
    for body, feature in zip(scene.bodies, features):
        pose = np.array([[*body.position, body.angle]], dtype=float)
        found.append(int(features_at(feature, pose, point[None], np.zeros(1, dtype=np.int64),
                                      np.array([tolerances.penetration * feature.extent]))[0]))
    return tuple(found)


def touched_features(features: Sequence[BodyFeatures], track: ContactTrack,
             tolerances: Tolerances) -> np.ndarray:
    """``(P, B)``: per point of ``track`` and per body, the body's feature at that point
    (:func:`features_at` within ``penetration·extent`` plus the point's depth), or -1."""
    depth = np.maximum(track.points[:, 2], 0.0)
    touched = np.full((len(track.points), len(features)), -1, dtype=np.int64)
    for index, body in enumerate(features):
        touched[:, index] = features_at(body, track.poses[:, index], track.points,
                                         track.record,
                                         tolerances.penetration * body.extent + depth)
    return touched


def one_feature(scene) -> bool:
    """Whether every body is a disk: its whole surface is one feature, so points an engine
    reports in one step are one contact region (a 3-D engine's cylinder gives two)."""
    return all(body.shape.kind == "disk" for body in scene.bodies)


def second_features(scene, contacts: Sequence[StepContacts] | ContactTrack,
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
    track = as_track(contacts)
    if track.size < 2:
        return []
    touched = touched_features(features, track, tolerances)
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


def second_features_many(contact_records: Sequence,
                          features: Sequence[Sequence[BodyFeatures]],
                          tolerances: Tolerances,
                          scenes: Sequence | None = None) -> list[bool]:
    """Whether :func:`second_features` finds a second feature, for many runs at once
    (``contact_records[i]``, an ``EngineRun.contact_record``, of a scene whose bodies have
    ``features[i]``).

    The arithmetic of :func:`features_at`, operation for operation on the same operands
    (math's cos and sin per pose, the same ``(k, 2) @ (2, 2)`` products per pose), over the
    points of every run whose body has ``k`` point features at once. A run of fewer than two
    points has no second one. ``scenes[i]``: run ``i``'s scene, whose contact point fixes
    the contact's features too, as in :func:`second_features` (worked out only for a run
    with a candidate); None: the first points alone.
    """
    if not contact_records:
        return []
    (poses, points, record_of_point, run_of_record, run_of_point,
     counts) = records_many(contact_records)
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
        centres = np.stack([features[run][body].centres for run in runs])[
            position[run_of_record[records]]]
        pose_of = (np.cumsum(records) - 1)[record_of_point[at]]
        group_points = points[at]
        owner = position[run_of_point[at]]
        radius = np.array([features[run][body].radius for run in runs])[owner]
        reach = (np.array([tolerances.penetration * features[run][body].extent
                           for run in runs])[owner] + depth[at])
        world = centres_at_poses(centres, group_poses)[pose_of]
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


__all__ = ["contact_features", "one_feature", "second_features", "second_features_many",
           "touched_features"]
